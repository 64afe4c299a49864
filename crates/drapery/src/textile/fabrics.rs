//! Fabric presets in SI units, every number traceable to a published measurement.
//!
//! The mechanical data are the zero-strain, zero-curvature samples of the database of measured
//! cloth by Wang, O'Brien & Ramamoorthi (2011), "Data-driven elastic models for cloth: modeling
//! and measurement", ACM Transactions on Graphics 30(4) (SIGGRAPH), as distributed with the
//! ARCSim simulator in `materials/*.json` (read from the copy in github.com/wxhaooo/lyra,
//! commit 5158f74, whose `materials/README` attributes the files to that database and lists
//! each fabric's garment and fibre content). The conversion to the quantities here is derived
//! in docs/MATERIALS.md:
//!
//! * density: the file's `density` (kg/m²), as is;
//! * the file's zero-strain stretching sample `s = [s₀, s₁, s₂, s₃]` (N/m) is the stiffness
//!   `k = 2 s` of the energy density `½k₀ε₀₀² + k₁ε₀₀ε₁₁ + ½k₂ε₁₁² + k₃ε₀₁²` in the Green strain
//!   `ε` (ARCSim's `dde.cpp` doubles the sample, `physics.cpp` writes the energy), which
//!   inverts to `E_u t = 2(s₀ − s₁²/s₂)`, `E_v t = 2(s₂ − s₁²/s₀)`, Poisson's ratio (warp
//!   strain from weft stress) `ν = s₁/s₀` and shear modulus `G t = s₃`;
//! * bending: the file's bending samples at zero curvature (N·m), `d[0]` for hinges along the
//!   material's u axis (so strips cut along v) and `d[2]` for hinges along v (strips along u).
//!
//! The database does not say which material axis is the warp; the presets take u as warp.
//! None of Wang et al.'s fabrics is silk, wool or leather, and no source read for this module
//! gives a complete set for those: [`fabric`] returns `None` for them and [`UNAVAILABLE`] says
//! why. The database has no drape coefficients and no other source read reports one for these
//! samples or their fabric types, so [`Fabric::drape_range`] is `None` throughout; the drape
//! coefficients that were read (for other fabrics) are in [`DRAPE_MEASUREMENTS`], with their
//! sources. Damping is a modelling choice, not a measurement ([`DAMPING`]).

/// A fabric's mechanical constants in SI units, for the shell model (`model::Shell`).
#[derive(Clone, Debug, PartialEq)]
pub struct Fabric {
    /// The preset's name.
    pub name: &'static str,
    /// Mass per unit area, kg/m².
    pub density: f64,
    /// Young's modulus × thickness along `[warp, weft]`, N/m (small strain).
    pub stretch_modulus: [f64; 2],
    /// Poisson's ratio: warp strain from weft stress (`−ε_warp/ε_weft` under weft tension).
    pub poisson: f64,
    /// In-plane shear modulus × thickness, N/m.
    pub shear_modulus: f64,
    /// Bending rigidity of strips cut along `[warp, weft]`, N·m (moment per unit width per
    /// unit curvature).
    pub bending_rigidity: [f64; 2],
    /// Stiffness-proportional damping, s: a modelling choice ([`DAMPING`]), not a measurement.
    pub damping: f64,
    /// The range `[low, high]` of Cusick drape coefficients (30 cm specimen on an 18 cm
    /// support, as a fraction) that the preset's source, or a published study of the same
    /// fabric type, reports; `None` where no source read reports one (every preset here:
    /// docs/MATERIALS.md §2.5).
    pub drape_range: Option<[f64; 2]>,
    /// Where the numbers come from: the database entry, its garment and fibre content.
    pub source: &'static str,
}

impl Fabric {
    /// The fabric as a shell material: its moduli, rigidity, damping and density.
    pub fn material(&self) -> crate::model::Material {
        use crate::model::{ClothModel, MassSpec, Material, Shell};
        Material {
            mass: MassSpec::Density(self.density),
            model: ClothModel::Shell,
            shell: Shell {
                stretch_modulus: self.stretch_modulus,
                poisson: self.poisson,
                shear_modulus: Some(self.shear_modulus),
                bending_rigidity: self.bending_rigidity,
                damping: self.damping,
            },
            ..Material::default()
        }
    }
}

/// Stiffness-proportional damping of every preset, s. A modelling choice, not a measurement:
/// a mode of angular frequency ω gets the damping ratio `ω · DAMPING / 2`, so modes slower
/// than about 300 Hz (ω < 2/DAMPING) are underdamped and faster (mesh-scale) ones overdamped.
pub const DAMPING: f64 = 1e-3;

/// The fabrics [`fabric`] knows: three generic names (each one entry of the database) and the
/// database's own names.
pub const FABRICS: &[&str] = &[
    "cotton",
    "denim",
    "polyester",
    "11oz-black-denim",
    "camel-ponte-roma",
    "gray-interlock",
    "ivory-rib-knit",
    "pink-ribbon-brown",
    "royal-target",
    "tango-red-jet-set",
    "white-dots-on-blk",
    "white-swim-solid",
];

/// Fabrics asked for that have no preset, and why (the searches: docs/MATERIALS.md §2.6).
pub const UNAVAILABLE: &[(&str, &str)] = &[
    (
        "silk",
        "no silk in Wang et al. (2011); no source read gives its stretch, shear and bending \
         constants (Matsudaira's KES-FB study of silk filament weaves was read as an abstract \
         only)",
    ),
    (
        "wool",
        "no wool in Wang et al. (2011); Matsudaira et al. (2015), read second-hand, give one \
         wool's bending rigidity, mass and drape coefficient but no tensile or shear data \
         (DRAPE_MEASUREMENTS); Penava et al. (2014)'s wool moduli were seen only second-hand, \
         in a simulator's source, for another fabric",
    ),
    (
        "leather",
        "Memon et al. (2021) give sheep garment leather's drape coefficient (47.35-69.9 %) and \
         thickness (0.64-0.96 mm) but no mass per area or tensile data (DRAPE_MEASUREMENTS)",
    ),
    (
        "navy-sparkle-sweat",
        "its zero-strain stretching sample (Wang et al. 2011) is not positive definite \
         (s0 s2 < s1²), so it has no small-strain linear moduli",
    ),
];

/// One entry of the Wang et al. (2011) database: the zero-strain stretching sample (N/m) and
/// the zero-curvature bending samples `[d0, d45, d90]` (N·m).
struct Measured {
    name: &'static str,
    source: &'static str,
    density: f64,
    stretch: [f64; 4],
    bend: [f64; 3],
}

// Every number below is copied from the database file named in `source` (Wang, O'Brien &
// Ramamoorthi 2011, ARCSim materials/<name>.json): `density`, the first row of `stretching`,
// and the first column of `bending`.
const MEASURED: &[Measured] = &[
    Measured {
        name: "11oz-black-denim",
        source: "Wang et al. 2011, 11oz-black-denim: jeans, 99% cotton 1% spandex",
        density: 0.324,
        stretch: [205.352005, 10.234077, 1013.88629, 53.387184],
        bend: [64.196457e-6, 73.384567e-6, 96.951576e-6],
    },
    Measured {
        name: "camel-ponte-roma",
        source: "Wang et al. 2011, camel-ponte-roma: jacket, 60% polyester 40% rayon",
        density: 0.284,
        stretch: [31.146198, -12.802702, 44.028667, 31.896357],
        bend: [36.348366e-6, 33.013252e-6, 37.157593e-6],
    },
    Measured {
        name: "gray-interlock",
        source: "Wang et al. 2011, gray-interlock: t-shirt, 60% cotton 40% polyester",
        density: 0.187,
        stretch: [16.593832, -14.695990, 34.477123, 36.860302],
        bend: [23.191698e-6, 24.749964e-6, 14.267624e-6],
    },
    Measured {
        name: "ivory-rib-knit",
        source: "Wang et al. 2011, ivory-rib-knit: underwear, 95% cotton 5% spandex",
        density: 0.276,
        stretch: [42.871021, -0.234556, 65.166023, 83.175644],
        bend: [46.237591e-6, 30.015930e-6, 32.243889e-6],
    },
    Measured {
        name: "pink-ribbon-brown",
        source: "Wang et al. 2011, pink-ribbon-brown: blanket, 100% polyester",
        density: 0.228,
        stretch: [151.503906, 106.028160, 244.830673, 30.250183],
        bend: [117.070122e-6, 87.509773e-6, 59.774277e-6],
    },
    Measured {
        name: "royal-target",
        source: "Wang et al. 2011, royal-target: pants, 65% cotton 35% polyester",
        density: 0.220,
        stretch: [2016.55456, 9.170511, 2034.97644, 104.759674],
        bend: [125.409805e-6, 107.997696e-6, 125.409805e-6],
    },
    Measured {
        name: "tango-red-jet-set",
        source: "Wang et al. 2011, tango-red-jet-set: jacket, 100% polyester",
        density: 0.113,
        stretch: [43.067627, 54.373299, 171.424835, 14.314700],
        bend: [14.293814e-6, 21.951700e-6, 20.345654e-6],
    },
    Measured {
        name: "white-dots-on-blk",
        source: "Wang et al. 2011, white-dots-on-blk: tablecloth, 100% polyester",
        density: 0.128,
        stretch: [2002.08618, 0.345588, 2027.48559, 19.189022],
        bend: [51.713814e-6, 40.659470e-6, 31.282822e-6],
    },
    Measured {
        name: "white-swim-solid",
        source: "Wang et al. 2011, white-swim-solid: swimsuit, 87% nylon 13% spandex",
        density: 0.204,
        stretch: [47.971176, 6.834521, 104.615456, 60.773663],
        bend: [60.237942e-6, 58.803211e-6, 51.018833e-6],
    },
];

/// The generic names and the database entry each one is: the entry with the most of that fibre
/// (cotton: 95 %; denim: the database's one denim; polyester: the 100 % polyester woven).
const GENERIC: &[(&str, &str)] = &[
    ("cotton", "ivory-rib-knit"),
    ("denim", "11oz-black-denim"),
    ("polyester", "white-dots-on-blk"),
];

/// 1 gf·cm²/cm (KES-F bending rigidity B) in N·m: 1 gf = 9.80665e-3 N, 1 cm²/cm = 1e-2 m.
pub const GF_CM2_PER_CM: f64 = 9.80665e-5;

/// 1 mg/cm² (KES-F mass per area W) in kg/m²: 1e-6 kg / 1e-4 m².
pub const MG_PER_CM2: f64 = 1e-2;

/// A published Cusick drape measurement of a fabric that is not a preset (its source lacks the
/// tensile and shear constants), kept to compare simulated drape coefficients with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrapeMeasurement {
    /// The fabric as the source names it.
    pub name: &'static str,
    /// KES-F bending rigidity B as the source gives it, gf·cm²/cm, if it gives one.
    pub kes_bending: Option<f64>,
    /// KES-F mass per area W as the source gives it, mg/cm², if it gives one.
    pub kes_weight: Option<f64>,
    /// The drape coefficient range `[low, high]` the source reports, as a fraction (a single
    /// mean value is `[v, v]`).
    pub drape_range: [f64; 2],
    /// Authors, year, title, table; and whether the numbers were read first- or second-hand.
    pub source: &'static str,
}

impl DrapeMeasurement {
    /// The bending rigidity in N·m (B × [`GF_CM2_PER_CM`]).
    pub fn bending_rigidity(&self) -> Option<f64> {
        self.kes_bending.map(|b| b * GF_CM2_PER_CM)
    }

    /// The mass per area in kg/m² (W × [`MG_PER_CM2`]).
    pub fn density(&self) -> Option<f64> {
        self.kes_weight.map(|w| w * MG_PER_CM2)
    }
}

const MATSUDAIRA_2015: &str = "M. Matsudaira, T. Masuda, M. Wada, H. Yokura (2015), Shape \
    factor of flared skirts compared with that of circular fabrics, J. Textile Engineering \
    61(6) 69-73, doi:10.4188/jte.61.69, Tables 1 and 2; read second-hand (as transcribed, with \
    this citation, in a public repository's source file)";

/// The Cusick drape coefficients read for this work, with their sources (docs/MATERIALS.md
/// §2.6–2.7). None is of a preset's fabric.
pub const DRAPE_MEASUREMENTS: &[DrapeMeasurement] = &[
    DrapeMeasurement {
        name: "sheep garment leather (four samples)",
        // flexural rigidity "9.2 to 22" in the abstract, unit not stated there: not used
        kes_bending: None,
        kes_weight: None,
        drape_range: [0.4735, 0.699],
        source: "H. Memon, E. B. Chaklie, H. M. Yesuf, C. Zhu (2021), Study on effect of \
                 leather rigidity and thickness on drapability of sheep garment leather, \
                 Materials 14(16) 4553, doi:10.3390/ma14164553, abstract; read first-hand",
    },
    DrapeMeasurement {
        name: "cotton broad (100% cotton, plain weave)",
        kes_bending: Some(0.118),
        kes_weight: Some(12.38),
        drape_range: [0.829, 0.829],
        source: MATSUDAIRA_2015,
    },
    DrapeMeasurement {
        name: "wool tropical (100% wool, plain weave)",
        kes_bending: Some(0.067),
        kes_weight: Some(16.29),
        drape_range: [0.498, 0.498],
        source: MATSUDAIRA_2015,
    },
    DrapeMeasurement {
        name: "polyester tropical",
        kes_bending: Some(0.077),
        kes_weight: Some(11.65),
        drape_range: [0.507, 0.507],
        source: MATSUDAIRA_2015,
    },
    DrapeMeasurement {
        name: "polyester faille",
        kes_bending: Some(0.019),
        kes_weight: Some(10.43),
        drape_range: [0.283, 0.283],
        source: MATSUDAIRA_2015,
    },
];

/// The Fabric from one database entry (the conversion of the module docs).
fn convert(m: &Measured, name: &'static str) -> Fabric {
    let [s0, s1, s2, s3] = m.stretch;
    Fabric {
        name,
        density: m.density,
        stretch_modulus: [2.0 * (s0 - s1 * s1 / s2), 2.0 * (s2 - s1 * s1 / s0)],
        // weft strain from warp stress, the convention of model::Shell and the membrane
        poisson: s1 / s2,
        shear_modulus: s3,
        // strips along u bend about hinges along v (d90), strips along v about u (d0)
        bending_rigidity: [m.bend[2], m.bend[0]],
        damping: DAMPING,
        drape_range: None,
        source: m.source,
    }
}

/// The preset called `name` (case-insensitive, one of [`FABRICS`]), or `None` (see
/// [`UNAVAILABLE`] for fabrics without one).
pub fn fabric(name: &str) -> Option<Fabric> {
    let name = name.trim().to_ascii_lowercase();
    let (preset, entry) = GENERIC
        .iter()
        .find(|(g, _)| *g == name)
        .map(|&(g, e)| (g, e))
        .or_else(|| {
            MEASURED
                .iter()
                .find(|m| m.name == name)
                .map(|m| (m.name, m.name))
        })?;
    MEASURED
        .iter()
        .find(|m| m.name == entry)
        .map(|m| convert(m, preset))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_fabric_resolves_and_nothing_else_does() {
        for name in FABRICS {
            let f = fabric(name).unwrap_or_else(|| panic!("{name}"));
            assert_eq!(f.name, *name);
            assert!(fabric(&name.to_uppercase()).is_some());
        }
        for (name, why) in UNAVAILABLE {
            assert!(fabric(name).is_none() && !why.is_empty());
            assert!(!FABRICS.contains(name));
        }
        assert!(fabric("velvet").is_none());
        // every database entry is listed
        for m in MEASURED {
            assert!(FABRICS.contains(&m.name));
        }
    }

    #[test]
    fn the_moduli_reproduce_the_measured_stiffness() {
        // plane stress with E_u, E_v and ν = ν_uv (weft strain from warp stress, as the
        // membrane has it), ν_vu = ν E_v / E_u, gives
        // C = 1/(1 − ν_uv ν_vu) [[E_u, ν E_v], [ν E_v, E_v]] = 2 [[s0, s1], [s1, s2]]
        for m in MEASURED {
            let f = convert(m, m.name);
            let [eu, ev] = f.stretch_modulus;
            let nu = f.poisson;
            let d = 1.0 - nu * nu * ev / eu;
            let c = [eu / d, nu * ev / d, ev / d];
            // the membrane's own constants agree
            let law = crate::forces::membrane::MembraneLaw {
                stretch_modulus: f.stretch_modulus,
                poisson: nu,
                shear_modulus: f.shear_modulus,
            };
            assert!(law.is_stable(), "{}", m.name);
            let k = [2.0 * m.stretch[0], 2.0 * m.stretch[1], 2.0 * m.stretch[2]];
            for i in 0..3 {
                assert!(
                    (c[i] - k[i]).abs() <= 1e-12 * k[0].max(k[2]),
                    "{}: {c:?} vs {k:?}",
                    m.name
                );
            }
            // and the shear energy k3 ε01² = s3 γ²/2 (γ = 2 ε01) is ½ G γ²
            let gamma = 0.01;
            let energy = 2.0 * m.stretch[3] * (gamma / 2.0) * (gamma / 2.0);
            assert!((energy - 0.5 * f.shear_modulus * gamma * gamma).abs() < 1e-15);
        }
    }

    #[test]
    fn presets_are_stable_linear_materials() {
        for name in FABRICS {
            let f = fabric(name).unwrap();
            let [eu, ev] = f.stretch_modulus;
            // positive definite plane-stress stiffness: E > 0, G > 0, ν_uv ν_vu < 1
            assert!(eu > 0.0 && ev > 0.0 && f.shear_modulus > 0.0, "{name}");
            assert!(f.poisson * f.poisson * ev / eu < 1.0, "{name}");
            assert!(f.bending_rigidity.iter().all(|&b| b > 0.0));
            // fabrics of 100-350 g/m²
            assert!((0.1..0.35).contains(&f.density), "{name}");
            // Peirce's bending length c = (B / (ρ g))^{1/3} of woven and knitted cloth is a
            // centimetre or a few (ASTM D1388 reads c = L/2 with L a few cm)
            for b in f.bending_rigidity {
                let c = (b / (f.density * 9.80665)).cbrt();
                assert!((0.005..0.05).contains(&c), "{name}: c = {c}");
            }
            assert_eq!(f.damping, DAMPING);
            assert!(f.drape_range.is_none());
        }
        // the excluded entry is excluded for the reason given: s0 s2 < s1²
        let [s0, s1, s2] = [12.486332, -19.875324, 3.272434];
        assert!(s0 * s2 < s1 * s1);
    }

    #[test]
    fn generic_names_are_their_database_entries() {
        let denim = fabric("denim").unwrap();
        let entry = fabric("11oz-black-denim").unwrap();
        assert_eq!(denim.stretch_modulus, entry.stretch_modulus);
        assert_eq!(denim.source, entry.source);
        assert!(fabric("cotton").unwrap().source.contains("95% cotton"));
        assert!(
            fabric("polyester")
                .unwrap()
                .source
                .contains("100% polyester")
        );
        // 1 gf·cm²/cm = 9.80665e-3 N × 1e-4 m² / 1e-2 m
        assert!((GF_CM2_PER_CM - 9.80665e-3 * 1e-4 / 1e-2).abs() < 1e-18);
        // 1 mg/cm² = 1e-6 kg / 1e-4 m²
        assert!((MG_PER_CM2 - 1e-6 / 1e-4).abs() < 1e-15);
    }

    #[test]
    fn drape_measurements_are_coefficients_with_their_sources() {
        for m in DRAPE_MEASUREMENTS {
            let [lo, hi] = m.drape_range;
            // a drape coefficient lies between a skirt hanging from the rim (0) and a flat
            // disc (1)
            assert!(0.0 < lo && lo <= hi && hi < 1.0, "{}", m.name);
            assert!(m.source.contains("doi:"), "{}", m.name);
            assert_eq!(m.bending_rigidity().is_some(), m.density().is_some());
            if let (Some(b), Some(rho)) = (m.bending_rigidity(), m.density()) {
                // woven apparel fabrics: 100-200 g/m², Peirce bending length 1-3 cm
                assert!((0.1..0.2).contains(&rho), "{}", m.name);
                let c = (b / (rho * 9.80665)).cbrt();
                assert!((0.01..0.03).contains(&c), "{}: c = {c}", m.name);
            }
        }
    }
}
