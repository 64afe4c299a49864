//! Laplace's law: a closed sphere of shell membrane inflated by a pressure settles at the radius
//! where the membrane tension balances the pressure, `T = p R / 2`.
//!
//! The membrane is St. Venant–Kirchhoff in plane stress (docs/MATH.md §20). Under an equibiaxial
//! stretch `λ = R / R₀`, `F = λ I` (in the plane), `E11 = E22 = ½ (λ² − 1)`, `E12 = 0`, so the
//! second Piola–Kirchhoff stress is `S = (C11 + C12) E = Y / (1 − ν) · ½ (λ² − 1)` on both axes
//! (`C11 = Y / (1 − ν²)`, `C12 = ν C11`). The membrane's Cauchy stress (force per current length)
//! is `σ = (1/J) F S Fᵀ` with `J = λ²` the area ratio: `σ = S`. Laplace's law `S = p λ R₀ / 2`
//! gives `Y/(1 − ν) (λ² − 1) = p R₀ λ`, a quadratic with one root `λ > 1`.
//!
//! The same equation follows from the energy: `4π R₀² · Y/(1−ν) · ¼ (λ² − 1)²` against
//! `p · (4π/3) R₀³ λ³`. On a polyhedron of rest area `A` and volume `V` scaled by `λ` the balance
//! reads the same with `R₀` replaced by `3 V / A` (which is `R₀` for the sphere), the discrete
//! radius the test also reports.

use drapery::math::Vec3;
use drapery::mesh::{Face, Mesh};
use drapery::model::{ClothDesc, ClothModel, MassSpec, Material, Model, Shell};
use drapery::{Simulation, SolverSettings};
use std::collections::HashMap;

/// An icosahedron subdivided `levels` times (each triangle into four), its vertices on the
/// sphere of radius `r` around the origin, every face wound outward.
fn icosphere(r: f64, levels: usize) -> Mesh {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut x: Vec<Vec3> = Vec::new();
    for (a, b) in [(1.0, phi), (-1.0, phi), (1.0, -phi), (-1.0, -phi)] {
        x.push(Vec3::new(0.0, a, b));
        x.push(Vec3::new(a, b, 0.0));
        x.push(Vec3::new(b, 0.0, a));
    }
    let x: Vec<Vec3> = x.iter().map(|p| p.normalize() * r).collect();
    // the 20 faces: triples of mutually nearest vertices, turned outward
    let edge = (x[0] - x[1])
        .length()
        .min((x[0] - x[2]).length())
        .min((x[0] - x[3]).length());
    let near = |i: usize, j: usize| ((x[i] - x[j]).length() - edge).abs() < 1e-9 * r;
    let mut tris = Vec::new();
    for i in 0..12 {
        for j in i + 1..12 {
            for k in j + 1..12 {
                if near(i, j) && near(j, k) && near(i, k) {
                    let n = (x[j] - x[i]).cross(x[k] - x[i]);
                    tris.push(match n.dot(x[i]) > 0.0 {
                        true => [i as u32, j as u32, k as u32],
                        false => [i as u32, k as u32, j as u32],
                    });
                }
            }
        }
    }
    assert_eq!(tris.len(), 20);
    let mut x = x;
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, x: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                x.push((x[a as usize] + x[b as usize]).normalize() * r);
                x.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(4 * tris.len());
        for [a, b, c] in tris {
            let (ab, bc, ca) = (
                midpoint(a, b, &mut x),
                midpoint(b, c, &mut x),
                midpoint(c, a, &mut x),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        positions: x,
        faces: tris.into_iter().map(Face::Tri).collect(),
        lines: Vec::new(),
        face_uv: Vec::new(),
    }
}

/// The enclosed volume and the area of a closed mesh.
fn volume_and_area(x: &[Vec3], tris: &[[u32; 3]]) -> (f64, f64) {
    tris.iter().fold((0.0, 0.0), |(v, a), t| {
        let [p, q, r] = t.map(|i| x[i as usize]);
        (
            v + p.dot(q.cross(r)) / 6.0,
            a + (q - p).cross(r - p).length() / 2.0,
        )
    })
}

/// The root `λ > 1` of `Y/(1 − ν) (λ² − 1) = p R λ`, by bisection on `[1, 1 + p R (1 − ν)/Y + 1]`.
fn laplace_stretch(y: f64, nu: f64, p: f64, r: f64) -> f64 {
    let g = |l: f64| y / (1.0 - nu) * (l * l - 1.0) - p * r * l;
    let (mut lo, mut hi) = (1.0, 2.0 + p * r * (1.0 - nu) / y);
    assert!(g(lo) < 0.0 && g(hi) > 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The mean distance of the vertices from their centroid.
fn mean_radius(x: &[Vec3]) -> f64 {
    let c = x.iter().fold(Vec3::ZERO, |s, p| s + *p) / x.len() as f64;
    x.iter().map(|p| (*p - c).length()).sum::<f64>() / x.len() as f64
}

/// The icosphere (radius `r0`, `levels` subdivisions) of shell (`y`, `nu`, no bending) under
/// pressure `p`, run to rest without gravity; its positions at the end.
fn inflate(r0: f64, levels: usize, y: f64, nu: f64, p: f64) -> (Mesh, Vec<Vec3>) {
    let mesh = icosphere(r0, levels);
    let material = Material {
        model: ClothModel::Shell,
        shell: Shell {
            stretch_modulus: [y, y],
            poisson: nu,
            shear_modulus: None,
            bending_rigidity: [0.0, 0.0],
            damping: 0.002,
        },
        air_drag: 0.0,
        mass: MassSpec::Density(0.1),
        pressure: p,
        ..Default::default()
    };
    let model = Model::new(
        vec![ClothDesc {
            name: "balloon".into(),
            mesh: mesh.clone(),
            material,
            pins: Vec::new(),
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }],
        Vec3::ZERO,
    )
    .unwrap();
    let mut sim = Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-10,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..300 {
        sim.step(0.005).unwrap();
    }
    let speed = sim
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    assert!(speed < 1e-4 * r0, "not at rest: max speed {speed} m/s");
    (mesh, sim.positions().to_vec())
}

#[test]
fn a_pressurized_shell_sphere_settles_at_the_radius_of_laplaces_law() {
    let (r0, y, nu) = (0.5, 1000.0, 0.3);
    // pressures giving about 5 % and 20 % stretch: p = Y/(1−ν) (λ² − 1)/(R₀ λ)
    for target in [1.05, 1.2] {
        let p = y / (1.0 - nu) * (target * target - 1.0) / (r0 * target);
        let (mesh, x) = inflate(r0, 3, y, nu, p);
        let tris = mesh.triangles();
        let (v0, a0) = volume_and_area(&mesh.positions, &tris);
        let r_discrete = 3.0 * v0 / a0;
        let sphere = laplace_stretch(y, nu, p, r0) * r0;
        let discrete = laplace_stretch(y, nu, p, r_discrete) * r0;
        let simulated = mean_radius(&x);
        let (v, _) = volume_and_area(&x, &tris);
        eprintln!(
            "p = {p:.3} Pa ({} vertices, 3V/A = {r_discrete:.6} m): radius {simulated:.6} m, \
             Laplace on the sphere {sphere:.6} m, on 3V/A {discrete:.6} m; volume {:.4}× rest",
            x.len(),
            v / v0
        );
        assert!(
            (simulated - sphere).abs() < 0.02 * sphere,
            "p = {p}: {simulated} vs {sphere}"
        );
        // the stretch itself (5 % or 20 %), against the discrete balance, to 0.5 % of it
        let (s, d) = (simulated / r0 - 1.0, discrete / r0 - 1.0);
        assert!((s - d).abs() < 0.005 * d, "p = {p}: stretch {s} vs {d}");
    }
}
