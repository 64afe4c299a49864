//! Helpers shared by the integration tests.
#![allow(dead_code)]

use drapery::math::{Mat3, Vec3};
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Mesh, Simulation, SolverSettings};

/// Dense Gaussian elimination with partial pivoting.
pub fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            if f != 0.0 {
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

pub fn flat(v: &[Vec3]) -> Vec<f64> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

pub fn unflat(v: &[f64]) -> Vec<Vec3> {
    v.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()
}

/// Block of a dense matrix.
pub fn block(d: &[Vec<f64>], i: usize, j: usize) -> Mat3 {
    Mat3::from_cols_array(&[
        d[3 * i][3 * j],
        d[3 * i + 1][3 * j],
        d[3 * i + 2][3 * j],
        d[3 * i][3 * j + 1],
        d[3 * i + 1][3 * j + 1],
        d[3 * i + 2][3 * j + 1],
        d[3 * i][3 * j + 2],
        d[3 * i + 1][3 * j + 2],
        d[3 * i + 2][3 * j + 2],
    ])
}

/// A square cloth of `n × n` vertices, 1 m wide, hanging in the xy plane, pinned at its top corners.
pub fn hanging_cloth(n: usize, settings: SolverSettings, material: Material) -> Simulation {
    let mesh = Mesh::grid([1.0, 1.0], [n, n], Vec3::new(0.0, 1.0, 0.0), Vec3::Z).unwrap();
    let cloth = ClothDesc {
        name: "sheet".into(),
        mesh,
        material,
        pins: vec![0, (n - 1) as u32],
        initial_velocity: Vec3::ZERO,
        handles: Vec::new(),
    };
    Simulation::new(
        Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0)).unwrap(),
        settings,
    )
    .unwrap()
}

pub fn material(mass: MassSpec) -> Material {
    Material {
        stretch_stiffness: 1000.0,
        shear_stiffness: 100.0,
        bend_stiffness: 1.0,
        damping: 0.01,
        air_drag: 0.0,
        mass,
        ..Default::default()
    }
}

/// Deterministic pseudo-random numbers in [-1, 1).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    pub fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// Runs `f` on a rayon pool of `threads` threads.
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The exact bits of every coordinate.
pub fn bits<'a>(v: impl IntoIterator<Item = &'a Vec3>) -> Vec<u64> {
    v.into_iter()
        .flat_map(|p| p.to_array().map(f64::to_bits))
        .collect()
}
