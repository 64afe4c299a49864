//! Per-cloth statistics of a model: what each cloth is made of (vertices, faces, line
//! elements, springs by kind, pins, mass), for a front end's summary (`drapery validate`).

use crate::model::{Model, SpringKind};

/// What one cloth of a model is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothStats {
    /// Vertices (particles) of the cloth.
    pub vertices: usize,
    /// Faces of its mesh (triangles and quads).
    pub faces: usize,
    /// Line elements of its mesh.
    pub line_elements: usize,
    /// Stretch springs (mesh edges and line elements).
    pub stretch_springs: usize,
    /// Shear springs (quad diagonals).
    pub shear_springs: usize,
    /// Bend springs (across shared edges).
    pub bend_springs: usize,
    /// Pinned vertices.
    pub pinned: usize,
    /// Total mass, kg (the lumped masses summed in particle order).
    pub mass: f64,
}

impl ClothStats {
    /// All springs of the cloth.
    pub fn springs(&self) -> usize {
        self.stretch_springs + self.shear_springs + self.bend_springs
    }
}

/// The statistics of every cloth of `model`, in the order of [`Model::cloths`]. A spring
/// belongs to the cloth of its first particle.
pub fn cloth_stats(model: &Model) -> Vec<ClothStats> {
    let mut out: Vec<ClothStats> = model
        .cloths
        .iter()
        .map(|c| {
            let range = c.range();
            ClothStats {
                vertices: c.mesh.vertex_count(),
                faces: c.mesh.faces.len(),
                line_elements: c.mesh.lines.len(),
                stretch_springs: 0,
                shear_springs: 0,
                bend_springs: 0,
                pinned: model.pinned[range.clone()].iter().filter(|&&p| p).count(),
                mass: model.mass[range].iter().sum(),
            }
        })
        .collect();
    let mut cloth_of = vec![usize::MAX; model.particle_count()];
    for (k, c) in model.cloths.iter().enumerate() {
        cloth_of[c.range()].fill(k);
    }
    for (&i, kind) in model.springs.i.iter().zip(&model.springs.kind) {
        let Some(s) = cloth_of.get(i as usize).and_then(|&k| out.get_mut(k)) else {
            continue;
        };
        match kind {
            SpringKind::Stretch => s.stretch_springs += 1,
            SpringKind::Shear => s.shear_springs += 1,
            SpringKind::Bend => s.bend_springs += 1,
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::mesh::Mesh;
    use crate::model::{ClothDesc, MassSpec, Material};

    fn cloth(name: &str, mesh: Mesh, vertex_mass: f64, pins: Vec<u32>) -> ClothDesc {
        ClothDesc {
            name: name.into(),
            mesh,
            material: Material {
                mass: MassSpec::PerVertex(vertex_mass),
                ..Default::default()
            },
            pins,
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }
    }

    #[test]
    fn each_cloth_counts_its_own_springs_pins_and_mass() {
        // A 4 × 3 quad grid: 3·3 + 4·2 edges, 2 diagonals in each of 3·2 quads, bend springs
        // two steps apart along rows (3 rows · 2) and columns (4 columns · 1).
        let grid = Mesh::grid([1.0, 1.0], [4, 3], Vec3::ZERO, Vec3::Z).unwrap();
        // After it, a chain of four particles and three line elements.
        let chain = Mesh {
            positions: (0..4).map(|k| Vec3::new(k as f64, 2.0, 0.0)).collect(),
            faces: Vec::new(),
            lines: vec![[0, 1], [1, 2], [2, 3]],
            face_uv: Vec::new(),
        };
        let model = Model::new(
            vec![
                cloth("sheet", grid, 0.01, vec![0, 3]),
                cloth("chain", chain, 0.25, vec![0]),
            ],
            Vec3::ZERO,
        )
        .unwrap();
        let s = cloth_stats(&model);
        assert_eq!(s.len(), 2);
        let sheet = &s[0];
        assert_eq!(
            (sheet.vertices, sheet.faces, sheet.line_elements),
            (12, 6, 0)
        );
        assert_eq!(
            (
                sheet.stretch_springs,
                sheet.shear_springs,
                sheet.bend_springs
            ),
            (17, 12, 10)
        );
        assert_eq!(sheet.pinned, 2);
        assert!((sheet.mass - 0.12).abs() < 1e-15);
        let chain = &s[1];
        assert_eq!(
            (chain.vertices, chain.faces, chain.line_elements),
            (4, 0, 3)
        );
        assert_eq!(
            (
                chain.stretch_springs,
                chain.shear_springs,
                chain.bend_springs
            ),
            (3, 0, 0)
        );
        assert_eq!((chain.pinned, chain.mass), (1, 1.0));
        assert_eq!(sheet.springs() + chain.springs(), model.springs.len());
    }
}
