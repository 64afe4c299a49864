//! The shell model's forces (`model = "shell"`): for each shell cloth, a membrane on its
//! triangles ([`super::membrane`]) and hinge bending on its interior edges ([`super::hinge`]),
//! both in physical units from its [`Shell`] parameters and its rest shape.
//!
//! Warp and weft are the rest shape's `u` and `v` directions: the mesh's texture coordinates
//! when it has them (OBJ `vt`; a grid's own axes; a pattern panel's 2-D coordinates), else the
//! fallback of [`material_coordinates`]. Texture coordinates belong to face corners, so a
//! triangle's frame comes from its own corners even across a seam of the uv layout.

use super::Force;
use super::hinge::{Hinges, interior_edges, rigidity_across};
use super::membrane::{Membrane, MembraneLaw, material_coordinates};
use crate::math::Vec3;
use crate::model::{ClothInfo, ClothModel, Model, Shell};

/// The membrane and hinge forces of every shell cloth of `model`, in cloth order.
pub fn forces(model: &Model) -> Vec<Box<dyn Force>> {
    let shells: Vec<&ClothInfo> = (model.cloths().iter())
        .filter(|c| c.material.model == ClothModel::Shell)
        .collect();
    if shells.is_empty() {
        return Vec::new();
    }
    // rest positions of every particle (a handle may have moved some at t = 0)
    let mut rest = vec![Vec3::ZERO; model.particle_count()];
    for c in model.cloths() {
        rest[c.range()].copy_from_slice(&c.mesh.positions);
    }
    let mut out: Vec<Box<dyn Force>> = Vec::new();
    for c in shells {
        let s = &c.material.shell;
        let triangles = c.mesh.triangles();
        let coords = frames(c, &triangles);
        let o = c.offset as u32;
        let membrane_triangles = triangles.iter().map(|t| t.map(|i| i + o)).collect();
        out.push(Box::new(Membrane::new(
            membrane_triangles,
            coords.clone(),
            law(s),
            s.damping,
        )));
        if s.bending_rigidity.iter().any(|&b| b > 0.0) {
            let hinges = interior_edges(&triangles);
            let x = &c.mesh.positions;
            let area = |t: &[u32; 3]| {
                let [a, b, d] = t.map(|i| x[i as usize]);
                0.5 * (b - a).cross(d - a).length()
            };
            let pinned = &model.pinned[c.range()];
            let rigid = |t: &[u32; 3]| t.iter().all(|&i| pinned[i as usize]);
            let rigidity: Vec<f64> = (hinges.iter())
                .map(|(h, [ti, ui])| {
                    let (t, u) = (&triangles[*ti], &triangles[*ui]);
                    let edge = edge_in_frame(t, &coords[*ti], [h[0], h[1]]);
                    rigidity_across(edge, s.bending_rigidity)
                        * clamp_factor([area(t), area(u)], [rigid(t), rigid(u)])
                })
                .collect();
            let stencils = (hinges.iter())
                .map(|(h, _)| h.map(|i| i + o))
                .collect();
            out.push(Box::new(Hinges::new(&rest, stencils, rigidity, s.damping)));
        }
    }
    out
}

/// The membrane law of shell parameters (the isotropic shear modulus when none is given).
pub fn law(s: &Shell) -> MembraneLaw {
    MembraneLaw {
        stretch_modulus: s.stretch_modulus,
        poisson: s.poisson,
        shear_modulus: s
            .shear_modulus
            .unwrap_or_else(|| MembraneLaw::isotropic_shear(s.stretch_modulus, s.poisson)),
    }
}

/// Each triangle's rest coordinates in its material frame, from its own corners' texture
/// coordinates when the mesh has them.
fn frames(c: &ClothInfo, triangles: &[[u32; 3]]) -> Vec<[[f64; 2]; 3]> {
    let x = &c.mesh.positions;
    match c.mesh.triangle_uvs() {
        Some(uv) => {
            // each triangle on its own three corners, so a uv seam splits nothing
            let corners: Vec<Vec3> = (triangles.iter())
                .flat_map(|t| t.map(|i| x[i as usize]))
                .collect();
            let corner_uv: Vec<[f64; 2]> = uv.iter().flatten().copied().collect();
            let own: Vec<[u32; 3]> = (0..triangles.len() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect();
            material_coordinates(&corners, &own, Some(&corner_uv))
        }
        None => material_coordinates(x, triangles, None),
    }
}

/// The factor on a hinge's rigidity when a wing is held rigid (all three of its vertices
/// pinned: a clamp). Its bend then happens over the free wing alone: the angle is spread over
/// the free wing's height instead of both (`|e| κ ∝ θ |e|² / A_free`) and acts on the free
/// wing's area only, so the weight `|e|²/(A₁ + A₂)` becomes `|e|²/A_free` (docs/MATH.md §21,
/// clamped edges). Without this the clamp of a cantilever would reach half a cell into the
/// free strip, an error of the order of the edge length.
fn clamp_factor(area: [f64; 2], rigid: [bool; 2]) -> f64 {
    match rigid {
        [false, false] => 1.0,
        [true, true] => 0.0,
        [true, false] => (area[0] + area[1]) / area[1],
        [false, true] => (area[0] + area[1]) / area[0],
    }
}

/// The vector from vertex `e[0]` to `e[1]` of triangle `t` (local indices) in the triangle's
/// material frame.
fn edge_in_frame(t: &[u32; 3], coords: &[[f64; 2]; 3], e: [u32; 2]) -> [f64; 2] {
    let corner = |v: u32| t.iter().position(|&i| i == v).unwrap_or(0);
    let (a, b) = (coords[corner(e[0])], coords[corner(e[1])]);
    [b[0] - a[0], b[1] - a[1]]
}
