//! The strain stage (docs/MATH.md §22): after friction has fixed the end-of-step positions,
//! every over-long edge of a cloth with a `strain_limit` is brought back within
//! `(1 + limit)` times its rest length ([`crate::constraints::strain_limit`]); the fail-safe
//! then checks the corrected paths.
//!
//! Pinned particles and those a handle holds this step do not move (infinite mass); the others
//! move by inverse mass, which keeps the linear momentum. A moved particle's velocity changes by
//! its displacement over `h`, so that `x = x₀ + h v` still holds for a particle that had it
//! (and a held contact keeps its position correction as one, as in the friction stage).

use crate::constraints::strain_limit::{MAX_SWEEPS, StrainLimits};
use crate::math::Vec3;

/// Corrects `x` and `v` of the strain-limited particles; returns the edges still over their
/// bound when the sweeps' cap was hit (0 otherwise). Nothing is read or written when no cloth
/// has a limit, and nothing is written when every edge is within its bound.
pub(crate) fn run(
    limits: &StrainLimits,
    mass: &[f64],
    pinned: &[bool],
    h: f64,
    x: &mut [Vec3],
    v: &mut [Vec3],
) -> usize {
    if limits.is_empty() {
        return 0;
    }
    let p = &limits.particles;
    let before: Vec<Vec3> = p.iter().map(|&i| x[i as usize]).collect();
    let w: Vec<f64> = (p.iter().map(|&i| i as usize))
        .map(|i| if pinned[i] { 0.0 } else { 1.0 / mass[i] })
        .collect();
    let mut y = before.clone();
    let projection = limits.project(&mut y, &w, MAX_SWEEPS);
    if projection.projections > 0 {
        for (k, &i) in p.iter().enumerate() {
            if y[k] != before[k] {
                let i = i as usize;
                x[i] = y[k];
                v[i] += (y[k] - before[k]) / h;
            }
        }
    }
    projection.over
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::model::{ClothDesc, MassSpec, Material, Model};
    use crate::scene::Scene;
    use crate::step::{Simulation, SolverSettings};
    use proptest::prelude::*;

    /// A vertical `k × k` sheet of side `side` m (row 0 on top), `mass` kg per vertex, soft
    /// springs of stiffness `stiffness`, pins as given.
    fn sheet(k: usize, side: f64, stiffness: f64, pins: Vec<u32>, limit: Option<f64>) -> ClothDesc {
        ClothDesc {
            name: "sheet".into(),
            mesh: Mesh::grid([side, side], [k, k], Vec3::ZERO, Vec3::Z).unwrap(),
            material: Material {
                mass: MassSpec::PerVertex(0.01),
                stretch_stiffness: stiffness,
                shear_stiffness: 0.1 * stiffness,
                strain_limit: limit,
                ..Material::default()
            },
            pins,
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }
    }

    /// The largest strain `|x_b - x_a| / rest - 1` over the mesh edges of cloth `c` whose ends
    /// are not both pinned.
    fn largest_strain(m: &Model, c: usize, x: &[Vec3]) -> f64 {
        let cloth = &m.cloths()[c];
        let (rest, o) = (&cloth.mesh.positions, cloth.offset);
        (cloth.mesh.edges().into_iter())
            .filter(|&[a, b]| !(m.pins()[a as usize + o] && m.pins()[b as usize + o]))
            .map(|[a, b]| {
                let (a, b) = (a as usize, b as usize);
                (x[b + o] - x[a + o]).length() / (rest[b] - rest[a]).length() - 1.0
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// After every step, no edge of a strain-limited cloth is longer than its bound, however
        /// fast the cloth moves and however large the step.
        #[test]
        fn strain_is_within_the_limit_after_every_step(
            k in 3usize..10,
            stiffness in 1.0f64..200.0,
            limit in 0.01f64..0.2,
            pins in proptest::collection::vec(any::<prop::sample::Index>(), 0..4),
            velocities in proptest::collection::vec(
                (-4.0f64..4.0, -4.0f64..4.0, -4.0f64..4.0), 100),
            h in prop::sample::select(vec![1.0 / 30.0, 1.0 / 60.0, 0.01]),
        ) {
            let n = k * k;
            let pins: Vec<u32> = pins.iter().map(|i| i.index(n) as u32).collect();
            let cloth = sheet(k, 0.5, stiffness, pins, Some(limit));
            let mut m = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0)).unwrap();
            let v: Vec<Vec3> = (0..n)
                .map(|i| match m.pins()[i] {
                    true => Vec3::ZERO,
                    false => Vec3::new(velocities[i].0, velocities[i].1, velocities[i].2),
                })
                .collect();
            m.set_velocities(&v).unwrap();
            let mut sim = Simulation::new(m, SolverSettings::default()).unwrap();
            for step in 0..4 {
                let r = sim.step(h).unwrap();
                prop_assert_eq!(r.strain_over, 0);
                let s = largest_strain(sim.model(), 0, sim.positions());
                prop_assert!(
                    (1.0 + s) <= (1.0 + limit) * (1.0 + 1e-12),
                    "step {}: strain {} over the limit {}", step, s, limit
                );
            }
        }
    }

    /// `Σ mᵢ vᵢ`.
    fn momentum(mass: &[f64], v: &[Vec3]) -> Vec3 {
        mass.iter().zip(v).map(|(&m, &v)| m * v).sum()
    }

    #[test]
    fn the_correction_keeps_linear_momentum_and_shortens_every_edge_to_its_bound() {
        let m = Model::new(vec![sheet(6, 0.5, 10.0, vec![], Some(0.05))], Vec3::ZERO).unwrap();
        let limits = StrainLimits::of(&m);
        let n = m.particle_count();
        // unequal masses; the end of a step that stretched the sheet unevenly by up to 60 %
        let mass: Vec<f64> = (0..n).map(|i| 0.01 * (1.0 + (i % 7) as f64)).collect();
        let (h, x0) = (0.02, m.positions().to_vec());
        let mut v: Vec<Vec3> = (0..n)
            .map(|i| {
                let f = i as f64;
                Vec3::new(
                    3.0 * (0.9 * f).sin(),
                    2.0 * (1.7 * f).cos(),
                    (0.3 * f).sin(),
                )
            })
            .collect();
        let mut x: Vec<Vec3> = x0.iter().zip(&v).map(|(p, u)| *p + h * *u).collect();
        let before = largest_strain(&m, 0, &x);
        assert!(before > 0.3, "the test must stretch the sheet: {before}");
        let p0 = momentum(&mass, &v);
        let over = run(&limits, &mass, &vec![false; n], h, &mut x, &mut v);
        assert_eq!(over, 0);
        let after = largest_strain(&m, 0, &x);
        assert!(after <= 0.05 && after > 0.05 - 1e-3, "{after}");
        let p1 = momentum(&mass, &v);
        let scale: f64 = mass.iter().zip(&v).map(|(&m, v)| m * v.length()).sum();
        assert!((p1 - p0).length() <= 1e-14 * scale, "{p0} → {p1}");
        // and the velocities are those of the corrected paths
        for i in 0..n {
            assert!((x0[i] + h * v[i] - x[i]).length() < 1e-15, "particle {i}");
        }
    }

    #[test]
    fn a_limit_that_never_binds_changes_no_bit() {
        let run = |limit: Option<f64>| {
            let mut m = Model::new(
                vec![sheet(5, 0.4, 30.0, vec![0, 4], limit)],
                Vec3::new(0.0, -9.81, 0.0),
            )
            .unwrap();
            let v: Vec<Vec3> = (0..25)
                .map(|i| Vec3::new(0.0, 0.0, if i < 5 { 0.0 } else { 2.0 }))
                .collect();
            m.set_velocities(&v).unwrap();
            let mut sim = Simulation::new(m, SolverSettings::default()).unwrap();
            let mut strain: f64 = 0.0;
            for _ in 0..20 {
                assert_eq!(sim.step(0.01).unwrap().strain_over, 0);
                strain = strain.max(largest_strain(sim.model(), 0, sim.positions()));
            }
            (sim.positions().to_vec(), sim.velocities().to_vec(), strain)
        };
        let (x, v, strain) = run(None);
        assert!(strain > 0.05, "the sheet must stretch: {strain}");
        let (xl, vl, _) = run(Some(1e3));
        assert!(
            x.iter()
                .zip(&xl)
                .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits))
        );
        assert!(
            v.iter()
                .zip(&vl)
                .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits))
        );
        // while a limit that binds does change the motion
        let (xb, _, sb) = run(Some(0.02));
        assert!(sb <= 0.02 + 1e-12 && xb != x, "{sb}");
    }

    /// A 1 m sheet of 11 × 11 vertices, soft springs, hanging from its top row, from a scene
    /// file: its largest edge strain over 0.5 s.
    fn hanging_sheet_strain(limit: &str) -> f64 {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hang.toml");
        let text = format!(
            r#"
[simulation]
duration = 0.5
dt = 0.01
frame_rate = 50

[[cloth]]
name = "sheet"
grid = {{ size = [1, 1], resolution = [11, 11] }}
vertex_mass = 0.01
stretch_stiffness = 20
shear_stiffness = 2
pin = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10]
{limit}
"#
        );
        std::fs::write(&path, text).unwrap();
        let scene = Scene::load(&path).unwrap();
        let mut sim = scene.start().unwrap();
        let mut strain: f64 = 0.0;
        for _ in 0..scene.step_count() {
            let r = sim.step(scene.step_size()).unwrap();
            assert_eq!(r.strain_over, 0);
            strain = strain.max(largest_strain(sim.model(), 0, sim.positions()));
        }
        strain
    }

    #[test]
    fn a_hanging_sheet_of_soft_springs_stretches_to_its_strain_limit_and_no_further() {
        let free = hanging_sheet_strain("");
        assert!(free > 0.1, "without a limit: {free}");
        let limited = hanging_sheet_strain("strain_limit = 0.05");
        assert!(limited <= 0.05 * (1.0 + 1e-12), "with a limit: {limited}");
        // the limit binds: the sheet hangs at it, not well short of it
        assert!(limited > 0.04, "with a limit: {limited}");
    }

    #[test]
    fn a_strain_limit_not_a_finite_number_above_0_is_one_error_naming_the_field() {
        for bad in ["-0.1", "0", "nan", "inf"] {
            let text = format!(
                "[simulation]\nduration = 1\ndt = 0.01\nframe_rate = 25\n\n[[cloth]]\n\
                 name = \"sheet\"\ngrid = {{ size = [1, 1], resolution = [3, 3] }}\n\
                 vertex_mass = 0.01\nstrain_limit = {bad}\n"
            );
            let e = Scene::from_str(&text, std::path::Path::new("dir/s.toml"))
                .unwrap_err()
                .to_string();
            assert_eq!(e.matches("strain_limit").count(), 1, "{bad}: {e}");
            assert!(
                e.starts_with(
                    "dir/s.toml: line 10, cloth[0].strain_limit: must be a finite number > 0"
                ),
                "{bad}: {e}"
            );
        }
        let e = Scene::from_str(
            "[simulation]\nduration = 1\ndt = 0.01\nframe_rate = 25\n\n[[cloth]]\n\
             name = \"sheet\"\ngrid = { size = [1, 1], resolution = [3, 3] }\n\
             vertex_mass = 0.01\nstrain_limit = \"0.1\"\n",
            std::path::Path::new("dir/s.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 10") && e.contains("strain_limit"), "{e}");
    }

    #[test]
    fn a_handle_pulling_the_cloth_past_its_limit_is_counted_not_fought() {
        use crate::animation::Motion;
        use crate::constraints::handles::HandleDesc;
        // the top row, 4 edges of 0.1 m, from a pinned corner to a handle moving away at 1 m/s:
        // once the two are more than 4 × 0.105 m apart no position of the row meets its limit
        let mut cloth = sheet(5, 0.4, 30.0, vec![0], Some(0.05));
        cloth.handles.push(HandleDesc {
            vertices: vec![4],
            pivot: None,
            motion: Motion::Constant {
                velocity: Vec3::X,
                angular_velocity: Vec3::ZERO,
            },
            release: None,
            attach: None,
        });
        let m = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0)).unwrap();
        let (x0, x4) = (m.positions()[0], m.positions()[4]);
        let mut sim = Simulation::new(m, SolverSettings::default()).unwrap();
        let h = 0.01;
        for k in 1..=10 {
            let r = sim.step(h).unwrap();
            let x = sim.positions();
            assert_eq!(x[0], x0);
            // the handle goes where its motion says, whatever the limit
            assert!(
                (x[4] - (x4 + Vec3::X * (k as f64 * h))).length() < 1e-12,
                "step {k}"
            );
            let apart = (x[4] - x[0]).length();
            // (at exactly 0.42 m the row must be straight at its bound: left out)
            if apart > 0.42 * (1.0 + 1e-9) {
                assert!(r.strain_over > 0, "step {k}: {apart}");
            } else if apart < 0.42 * (1.0 - 1e-3) {
                assert_eq!(r.strain_over, 0, "step {k}: {apart}");
            }
            assert!(x.iter().chain(sim.velocities()).all(|p| p.is_finite()));
        }
        assert!(sim.steps() == 10 && (sim.positions()[4] - sim.positions()[0]).length() > 0.45);
    }
}
