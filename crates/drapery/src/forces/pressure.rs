//! Pressure inside a cloth, docs/MATH.md §23.
//!
//! A pressure `p` (Pa) on the volume a cloth encloses, `E = -p V`, `V = Σ (1/6) x_a·(x_b × x_c)`
//! over its triangles. The force on each vertex of a triangle is `p N/6`
//! (`N = (x_b - x_a) × (x_c - x_a)`, so `p A n/3`): the pressure load on that third of the
//! triangle. On a closed, consistently oriented mesh the sum over a vertex's triangles is
//! exactly `-∂E/∂x` (the terms that depend on the origin cancel around every vertex). On an
//! open mesh `V` depends on the origin and is no potential of anything; the force is still the
//! pressure difference `p` across the membrane pushing along its normals (a sail), and `E` is
//! only reported.
//!
//! `∂f_i/∂x_j = (p/6) skew(e_j)` (`e = [x_c - x_b, x_a - x_c, x_b - x_a]`): summed over a closed
//! mesh it is `p ∇²V`, symmetric but indefinite, so it stays out of the matrix (the pressure is
//! explicit in the step; [`Pressure::stiffness`] exposes it for the tests).

use super::State;
use super::stencil::{Full, Gather, StencilForce};
use super::wind::{area_normal, skew};
use crate::math::{Mat3, Vec3};

/// Pressure on sets of triangles.
#[derive(Clone, Debug)]
pub struct Pressure {
    /// The triangles (global particle indices), each cloth's oriented outward.
    pub triangles: Vec<[u32; 3]>,
    /// Pressure on each triangle, Pa.
    pub p: Vec<f64>,
    /// Gather lists for the parallel sums.
    pub sums: Gather<Full<3>>,
}

impl Pressure {
    /// The exact `∂f_i/∂x_j` blocks of triangle `s` (not in the matrix).
    pub fn stiffness(&self, s: usize, x: &[Vec3]) -> [[Mat3; 3]; 3] {
        let (_, e) = area_normal(self.triangles[s], x);
        let k = self.p[s] / 6.0;
        [std::array::from_fn(|j| k * skew(e[j])); 3]
    }
}

impl StencilForce for Pressure {
    type Shape = Full<3>;
    const NAME: &'static str = "pressure";
    fn gather(&self) -> &Gather<Full<3>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.triangles.len()
    }
    fn particles(&self, s: usize) -> [u32; 3] {
        self.triangles[s]
    }
    /// `-p (1/6) x_a·(x_b × x_c)`.
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        let [a, b, c] = self.triangles[s].map(|i| x[i as usize]);
        -self.p[s] * a.dot(b.cross(c)) / 6.0
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 3] {
        let (n, _) = area_normal(self.triangles[s], at.x);
        [self.p[s] / 6.0 * n; 3]
    }
    fn has_jacobian(&self, _a: f64, _b: f64) -> bool {
        false
    }
    fn local_jacobian(&self, _s: usize, _at: &State, _a: f64, _b: f64) -> [[Mat3; 3]; 3] {
        [[Mat3::ZERO; 3]; 3]
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use proptest::prelude::*;

    /// A regular octahedron's outward triangles.
    const OCTAHEDRON: [[u32; 3]; 8] = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];

    fn octahedron() -> Vec<Vec3> {
        vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
    }

    /// A perturbed, shifted octahedron under a random pressure.
    fn config() -> impl Strategy<Value = (Vec<Vec3>, Pressure)> {
        (
            prop::collection::vec(arb_vec3(0.3), 6),
            arb_vec3(5.0),
            -1000.0..1000.0f64,
        )
            .prop_map(|(d, shift, p)| {
                let x = octahedron()
                    .iter()
                    .zip(&d)
                    .map(|(a, b)| *a + *b + shift)
                    .collect();
                let f = Pressure {
                    triangles: OCTAHEDRON.to_vec(),
                    p: vec![p; 8],
                    sums: Gather::default(),
                };
                (x, f)
            })
    }

    fn exact(f: &Pressure, x: &[Vec3]) -> Vec<Vec<f64>> {
        let blocks = (0..f.count()).map(|s| f.stiffness(s, x));
        dense_blocks(x.len(), f.triangles.iter().copied().zip(blocks))
    }

    proptest! {
        #[test]
        fn pressure_force_is_minus_the_energy_gradient_on_a_closed_mesh((x, f) in config()) {
            let mut got = vec![Vec3::ZERO; 6];
            f.add_force(&at(&x, &x), &mut got);
            let fd = fd_gradient(&f, &x);
            let scale = got.iter().fold(1.0f64, |m, v| m.max(v.length()));
            for i in 0..6 {
                prop_assert!((got[i] - fd[i]).length() < 1e-6 * scale, "{} vs {}", got[i], fd[i]);
            }
        }

        /// The exact stiffness against differences of the force, on an open mesh (two of the
        /// octahedron's triangles) and on the closed one, where it is `p ∇²V`: symmetric, with
        /// zero diagonal blocks. The matrix gets nothing.
        #[test]
        fn pressure_stiffness_matches_central_differences((x, f) in config()) {
            let v = vec![Vec3::ZERO; 6];
            let k = exact(&f, &x);
            let fd = fd_jacobian(&f, &x, &v, false);
            prop_assert!(rel_diff(&k, &fd) < 1e-6, "{}", rel_diff(&k, &fd));
            let scale = k.iter().flatten().fold(1.0f64, |m, e| m.max(e.abs()));
            for r in 0..18 {
                for c in 0..18 {
                    prop_assert!((k[r][c] - k[c][r]).abs() <= 1e-12 * scale);
                }
                prop_assert!(k[r][3 * (r / 3)..3 * (r / 3) + 3].iter().all(|e| e.abs() <= 1e-12 * scale));
            }
            let open = Pressure { triangles: f.triangles[..2].to_vec(), p: f.p[..2].to_vec(), sums: Gather::default() };
            let (k, fd) = (exact(&open, &x), fd_jacobian(&open, &x, &v, false));
            prop_assert!(rel_diff(&k, &fd) < 1e-6, "open: {}", rel_diff(&k, &fd));
            prop_assert!(assembled(&f, &x, &v, 1.0, 1.0).iter().flatten().all(|&e| e == 0.0));
        }
    }

    /// A regular icosahedron of edge 1 with outward faces, as OBJ text.
    fn icosahedron_obj() -> String {
        let phi = (1.0 + 5f64.sqrt()) / 2.0;
        let mut x = Vec::new();
        for (a, b) in [(1.0, phi), (-1.0, phi), (1.0, -phi), (-1.0, -phi)] {
            x.push(Vec3::new(0.0, a, b) / 2.0);
            x.push(Vec3::new(a, b, 0.0) / 2.0);
            x.push(Vec3::new(b, 0.0, a) / 2.0);
        }
        // the 20 faces: triples of mutually adjacent vertices (edge 1), turned outward
        let mut text: String = x
            .iter()
            .map(|p| format!("v {} {} {}\n", p.x, p.y, p.z))
            .collect();
        let near = |i: usize, j: usize| ((x[i] - x[j]).length() - 1.0).abs() < 1e-9;
        for i in 0..12 {
            for j in i + 1..12 {
                for k in j + 1..12 {
                    if near(i, j) && near(j, k) && near(i, k) {
                        let n = (x[j] - x[i]).cross(x[k] - x[i]);
                        let (b, c) = if n.dot(x[i]) > 0.0 { (j, k) } else { (k, j) };
                        text += &format!("f {} {} {}\n", i + 1, b + 1, c + 1);
                    }
                }
            }
        }
        text
    }

    /// The icosahedron (springs of `k` along its edges only) with `extra` cloth keys, loaded
    /// end to end from files in a temporary folder and run for 2 s without gravity.
    fn balloon(extra: &str) -> crate::Simulation {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("ico.obj"), icosahedron_obj()).unwrap();
        let text = format!(
            "[simulation]\nduration = 2\ndt = 0.01\nframe_rate = 50\ngravity = [0, 0, 0]\n\n\
             [[cloth]]\nname = \"balloon\"\nmesh = \"ico.obj\"\nvertex_mass = 0.1\n\
             stretch_stiffness = 1000\nshear_stiffness = 0\nbend_stiffness = 0\ndamping = 5\n{extra}"
        );
        let path = dir.path().join("balloon.toml");
        std::fs::write(&path, text).unwrap();
        let scene = crate::scene::Scene::load(&path).unwrap();
        let mut sim = scene.start().unwrap();
        for _ in 0..scene.step_count() {
            sim.step(scene.step_size()).unwrap();
        }
        sim
    }

    /// A regular icosahedron of springs (stiffness `k`, rest length `L`) under pressure `p`
    /// stays regular; with edge `ℓ` and `V = (5/12)(3 + √5) ℓ³`, the five springs at a vertex
    /// pull it in by `5 k (ℓ - L) ℓ/(2R)` and the pressure pushes it out by `p (dV/dR)/12 =
    /// p V/(4R)`: `k (ℓ - L) = p (3 + √5) ℓ²/24`, whose smaller root is the stable state.
    #[test]
    fn a_pressurized_icosahedron_of_springs_inflates_to_its_analytic_equilibrium() {
        let (k, rest, p) = (1000.0, 1.0, 500.0);
        let sim = balloon(&format!("pressure = {p}\n"));
        let x = sim.positions();
        let a = p * (3.0 + 5f64.sqrt()) / 24.0;
        let edge = (k - (k * k - 4.0 * a * k * rest).sqrt()) / (2.0 * a);
        let m = sim.model();
        let tris = m.triangles();
        let volume: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| x[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let rest_volume = 5.0 / 12.0 * (3.0 + 5f64.sqrt());
        assert!(volume > 1.3 * rest_volume, "{volume} vs {rest_volume}");
        assert!(
            (volume - rest_volume * edge.powi(3)).abs() < 1e-4 * volume,
            "{volume}"
        );
        let s = m.springs();
        // (the bend pairs carry only damping)
        let edges = (0..s.len()).filter(|&e| s.kind[e] == crate::model::SpringKind::Stretch);
        assert_eq!(edges.clone().count(), 30);
        for e in edges {
            let l = (x[s.i[e] as usize] - x[s.j[e] as usize]).length();
            assert!((l - edge).abs() < 1e-4 * edge, "edge {e}: {l} vs {edge}");
        }
        // the force balance at every vertex: its springs against p × its area normal / 3
        let mut springs = vec![Vec3::ZERO; x.len()];
        let mut pressure = vec![Vec3::ZERO; x.len()];
        for e in 0..s.len() {
            let (i, j) = (s.i[e] as usize, s.j[e] as usize);
            let d = x[j] - x[i];
            let f = s.stiffness[e] * (d.length() - s.rest[e]) * d.normalize();
            springs[i] += f;
            springs[j] -= f;
        }
        for t in &tris {
            let [a, b, c] = t.map(|i| x[i as usize]);
            for i in t {
                pressure[*i as usize] += p * (b - a).cross(c - a) / 6.0;
            }
        }
        for i in 0..x.len() {
            let r = (springs[i] + pressure[i]).length();
            assert!(
                r < 1e-3 * pressure[i].length(),
                "vertex {i}: {} vs {}",
                springs[i],
                pressure[i]
            );
        }
        assert!(sim.velocities().iter().all(|v| v.length() < 1e-3));
    }

    #[test]
    fn zero_pressure_has_the_bits_of_no_pressure() {
        let (a, b) = (
            balloon("pressure = 0.0\ninitial_velocity = [0.1, 0.2, 0.3]\n"),
            balloon("initial_velocity = [0.1, 0.2, 0.3]\n"),
        );
        assert!(a.forces().iter().all(|f| f.name() != "pressure"));
        let bits = |s: &crate::Simulation| {
            s.positions()
                .iter()
                .flat_map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&a), bits(&b));
    }

    #[test]
    fn a_non_finite_pressure_is_an_error_naming_the_field() {
        let text = "[simulation]\nduration = 1\ndt = 0.01\nframe_rate = 50\n\n[[cloth]]\nname = \"s\"\n\
                    grid = { size = [1, 1], resolution = [3, 3] }\nvertex_mass = 0.1\npressure = nan\n";
        let e = crate::scene::Scene::from_str(text, std::path::Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "s.toml: line 10, cloth[0].pressure: must be a finite number, got NaN"
        );
    }

    #[test]
    fn a_closed_mesh_feels_p_times_its_area_normals_and_no_net_force() {
        let x = octahedron();
        let f = Pressure {
            triangles: OCTAHEDRON.to_vec(),
            p: vec![100.0; 8],
            sums: Gather::default(),
        };
        // volume 4/3, energy -pV
        assert!((f.energy(0.0, &x) + 100.0 * 4.0 / 3.0).abs() < 1e-12);
        let mut got = vec![Vec3::ZERO; 6];
        f.add_force(&at(&x, &x), &mut got);
        // each vertex: 4 faces of area √3/2 with normals (±1,±1,1)/√3 → p·(4·√3/2/3)·(1/√3)·1 = 2p/3 outward
        for (g, p) in got.iter().zip(&x) {
            assert!((*g - 100.0 * 2.0 / 3.0 * *p).length() < 1e-12, "{g}");
        }
        assert!(got.iter().sum::<Vec3>().length() < 1e-12);
    }
}
