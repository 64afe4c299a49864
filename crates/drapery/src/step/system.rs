//! Which matrices a step uses and why.
//!
//! * The **system matrix** `A = M - h D - h² K` of the Newton iteration is kept in two parts,
//!   `A = P + C` ([`Split`]).
//! * `P` is on the fixed pattern of the model's forces (the **base matrix**): the mass, the
//!   model's forces, the contacts whose pairs add no block to that pattern (the cloth–collider
//!   pairs, whose cloth particles share a triangle or an edge; cloth–cloth stencils too when
//!   every pair of their particles is already coupled by the model's forces), and the
//!   diagonal blocks of the other contacts plus a block-diagonal majorant of their coupling
//!   ([`Coupling::move_majorant_into`]). The preconditioner is built from `P`, so the
//!   multigrid keeps one structure for the whole run, and PCG's products read its half-size
//!   copy of `P`.
//! * `C` holds the off-diagonal blocks of the other contacts (cloth–cloth stencils between
//!   distant parts of a cloth), minus that majorant on its diagonal, on a small pattern of
//!   their own ([`Coupling`]), rebuilt when the contacts change; without such contacts there
//!   is no `C` and `A = P`.
//! * So `P ≥ A`: the preconditioner is positive definite, lacks the contacts' coupling, and is
//!   nowhere softer than the system (with the contacts' diagonal blocks alone it was softer
//!   where two layers press into each other, and PCG took 1.4 and 1.8 times the iterations at
//!   two saved 290² states, docs/MATH.md §11).

use crate::forces::{Force, Linearization};
use crate::linalg::BlockMatrix;
use crate::linalg::split::{Coupling, Split};
use crate::math::{Mat3, Vec3};
use std::sync::OnceLock;

/// The matrices of the step's linear systems (see the module docs).
pub(crate) struct System {
    /// `P`: mass, model forces, the contacts inside its pattern, the others' diagonal blocks.
    base: BlockMatrix,
    /// The contacts outside the base pattern, when this step has any.
    coupling: Option<Coupling>,
    /// Per contact force of this step: whether all its pairs are in the base pattern.
    inner: Vec<bool>,
    /// `P + C` on one merged pattern, built on request after each assembly.
    merged: OnceLock<BlockMatrix>,
}

impl System {
    /// The matrices of a model with `n` particles and these forces, without contacts.
    pub fn new(n: usize, forces: &[Box<dyn Force>]) -> System {
        let mut pairs = Vec::new();
        for f in forces {
            f.add_pattern(&mut pairs);
        }
        System {
            base: BlockMatrix::from_pairs(n, &pairs),
            coupling: None,
            inner: Vec::new(),
            merged: OnceLock::new(),
        }
    }

    /// The system matrix of the last linearization, `P + C`; the preconditioner is built
    /// from its `P`.
    pub fn matrix(&self) -> Split<'_> {
        Split {
            p: &self.base,
            coupling: self.coupling.as_ref(),
        }
    }

    /// The system matrix of the last linearization on one pattern (built on first request:
    /// for the direct solver and inspection).
    pub fn merged(&self) -> &BlockMatrix {
        if self.coupling.is_none() {
            return &self.base;
        }
        self.merged.get_or_init(|| self.matrix().merged())
    }

    /// A copy of the base pattern (for the multigrid's reference matrix).
    pub fn base_pattern(&self) -> BlockMatrix {
        self.base.clone()
    }

    /// Sets this step's contacts: those of the `contacts` forces whose pairs are not all in
    /// the base pattern go into a coupling on their own pairs.
    pub fn use_contacts(&mut self, contacts: &[&dyn Force]) {
        let n = self.base.n();
        let mut pairs = Vec::new();
        self.inner.clear();
        for r in contacts {
            let mut own = Vec::new();
            r.add_pattern(&mut own);
            let inner = own
                .iter()
                .all(|&(i, j)| self.base.find(i as usize, j as usize).is_some());
            self.inner.push(inner);
            if !inner {
                pairs.extend(own);
            }
        }
        self.coupling = self
            .inner
            .contains(&false)
            .then(|| Coupling::new(n, &pairs));
        self.merged = OnceLock::new();
    }

    /// Assembles `A = M + a K + b D` at `(at.x, at.v)` with `(a, b) = at.matrix` (`-h²`, `-h`
    /// in a step): the mass and the model's `forces`, then the `contacts` forces if any (those
    /// of the last [`System::use_contacts`]; see the module docs for where each goes). With
    /// `vectors = (f, kw)`, also adds every force (contacts last) to `f` and the products with
    /// `at.product` and `at.w` to `kw`, from the same evaluation ([`Force::add_linearization`]).
    pub fn assemble(
        &mut self,
        mass: &[f64],
        forces: &[Box<dyn Force>],
        at: &Linearization,
        contacts: &[&dyn Force],
        mut vectors: Option<(&mut [Vec3], &mut [Vec3])>,
    ) {
        debug_assert!(contacts.is_empty() || contacts.len() == self.inner.len());
        self.merged = OnceLock::new();
        let base = &mut self.base;
        set_mass(mass, base);
        let mut add = |force: &dyn Force, m: &mut BlockMatrix| match &mut vectors {
            Some((f, kw)) => force.add_linearization(at, f, m, kw),
            None => force.add_jacobian(&at.state(), at.matrix.0, at.matrix.1, m),
        };
        for force in forces {
            add(force.as_ref(), base);
        }
        for (k, c) in contacts.iter().enumerate() {
            if self.inner[k] {
                add(*c, base);
            }
        }
        let Some(coupling) = &mut self.coupling else {
            return;
        };
        let m = coupling.matrix_mut();
        m.clear();
        for (k, c) in contacts.iter().enumerate() {
            if !self.inner[k] {
                add(*c, m);
            }
        }
        // P gets the outer contacts' diagonal blocks and the majorant of their coupling
        coupling.move_majorant_into(base);
    }
}

/// `m = M - h D - h² K` of the mass and the model's `forces` at `(x, v)` (no contacts).
pub(crate) fn assemble_base(
    mass: &[f64],
    forces: &[Box<dyn Force>],
    t: f64,
    x: &[Vec3],
    v: &[Vec3],
    h: f64,
    m: &mut BlockMatrix,
) {
    set_mass(mass, m);
    let at = crate::forces::State { t, x, v };
    for f in forces {
        f.add_jacobian(&at, -h * h, -h, m);
    }
}

/// Sets `m` to the mass matrix (on `m`'s pattern).
fn set_mass(mass: &[f64], m: &mut BlockMatrix) {
    m.set_block_diagonal(|i| Mat3::from_diagonal(Vec3::splat(mass[i])));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::proximity::{Proximity, StencilKind};
    use crate::collision::repulsion::Penalty;
    use crate::forces::{ObstacleRepulsions, Repulsions};
    use crate::step::{SolverSettings, testing};

    /// A repulsion stencil between the corners of the sheet (far apart in the mesh, so its
    /// pairs are not in the springs' pattern), with the points 1 mm apart.
    fn contact(x: &mut [Vec3]) -> Repulsions {
        let (a, b, c, d) = (0u32, 1, 5, 24);
        x[a as usize] = x[c as usize] + Vec3::new(0.0, 0.001, 0.0);
        x[b as usize] = x[d as usize] + Vec3::new(0.0, 0.001, 0.0);
        Repulsions::new(
            vec![Proximity {
                kind: StencilKind::EdgeEdge,
                particles: [a, b, c, d],
                weights: [0.5, 0.5, -0.5, -0.5],
                dist: 0.001,
                normal: Vec3::Y,
            }],
            Penalty {
                thickness: 0.005,
                stiffness: 1000.0,
                tangential: false,
            },
        )
    }

    /// The step's linearization at the model's state (matrix `M - h D - h² K`).
    fn linearization(m: &crate::model::Model, h: f64) -> Linearization<'_> {
        Linearization {
            t: 0.0,
            x: &m.x,
            v: &m.v,
            matrix: (-h * h, -h),
            product: (0.0, 0.0),
            w: &m.v,
        }
    }

    /// The system assembled without contacts (its dense matrix returned; the preconditioner
    /// is the matrix itself), then with the `contact` force.
    fn base_then_contact(
        m: &crate::model::Model,
        forces: &[Box<dyn Force>],
        at: &Linearization,
        contact: &dyn Force,
    ) -> (System, Vec<Vec<f64>>) {
        let mut sys = System::new(m.particle_count(), forces);
        sys.assemble(&m.mass, forces, at, &[], None);
        let base = sys.merged().to_dense();
        assert!(sys.matrix().coupling.is_none());
        sys.use_contacts(&[contact]);
        sys.assemble(&m.mass, forces, at, &[contact], None);
        (sys, base)
    }

    /// The majorant's blocks of the dense contact blocks `only` on particle `i`'s diagonal:
    /// `Σ_{j≠i} |C_ij|`.
    fn majorant(only: &[Vec<f64>], i: usize) -> Mat3 {
        let mut sum = Mat3::ZERO;
        for j in (0..only.len() / 3).filter(|&j| j != i) {
            let b =
                Mat3::from_cols_array(&std::array::from_fn(|e| only[3 * i + e % 3][3 * j + e / 3]));
            sum += crate::linalg::split::abs(&b);
        }
        sum
    }

    #[test]
    fn with_contacts_the_system_is_the_base_plus_the_contact_blocks_and_the_preconditioner_bounds_it()
     {
        let mut m = testing::sheet(5, 0.5, vec![]);
        let r = contact(&mut m.x);
        let forces = super::super::model_forces(&m, &SolverSettings::default());
        let h = 0.01;
        let at = linearization(&m, h);
        let (mut sys, base) = base_then_contact(&m, &forces, &at, &r);
        let only = blocks_of(&r, m.particle_count(), &at);
        let full = sys.merged().to_dense();
        let pre = sys.matrix().p.to_dense();
        let mut coupled = 0;
        for i in 0..full.len() {
            let d = majorant(&only, i / 3);
            for j in 0..full.len() {
                assert!(
                    (full[i][j] - (base[i][j] + only[i][j])).abs()
                        <= 1e-15 * (1.0 + full[i][j].abs())
                );
                // the preconditioner keeps the contact's diagonal blocks plus the majorant of
                // its coupling, not the coupling
                let same_particle = i / 3 == j / 3;
                let want = if same_particle {
                    full[i][j] + d.col(j % 3)[i % 3]
                } else {
                    base[i][j]
                };
                assert!((pre[i][j] - want).abs() <= 1e-12 * (1.0 + want.abs()));
                coupled += (!same_particle && only[i][j] != 0.0) as usize;
            }
        }
        assert!(coupled > 0, "the contact must couple particles");
        // P - A is positive semi-definite: along random directions and the contact's own
        // normal directions with the stencil's weights
        let n = full.len();
        let mut v = 0.1f64;
        let form = |x: &[f64]| -> f64 {
            (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| x[i] * (pre[i][j] - full[i][j]) * x[j])
                        .sum::<f64>()
                })
                .sum()
        };
        for _ in 0..50 {
            let x: Vec<f64> = (0..n)
                .map(|_| {
                    v = (v * 7.31 + 0.17).fract();
                    v - 0.5
                })
                .collect();
            assert!(form(&x) >= -1e-9);
        }
        // back to no contacts: the base pattern again, and the same values as before
        sys.use_contacts(&[]);
        sys.assemble(&m.mass, &forces, &at, &[], None);
        assert_eq!(sys.merged().to_dense(), base);
        assert!(sys.matrix().coupling.is_none());
    }

    /// A cloth–collider stencil on a cloth edge (with its tangential damping) adds no block to
    /// the springs' pattern: the preconditioner is then the whole system matrix, the stencil's
    /// coupling included, not the base matrix without it (which cost the Cusick drape on the
    /// support's rim five times the CG iterations).
    #[test]
    fn contacts_inside_the_pattern_are_all_in_the_preconditioner() {
        let mut m = testing::sheet(5, 0.5, vec![]);
        let forces = super::super::model_forces(&m, &SolverSettings::default());
        let h = 0.01;
        let r = rim_pair(&m);
        m.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
        let at = linearization(&m, h);
        let (sys, base) = base_then_contact(&m, &forces, &at, &r);
        let full = sys.merged().to_dense();
        // the stencil couples its two particles in every direction (normal penalty, tangential
        // damping), and the preconditioner holds exactly the system matrix
        for (i, j) in [(0, 3), (1, 4), (2, 5)] {
            assert!((full[i][j] - base[i][j]).abs() > 1e-3 * full[i][i].abs());
        }
        assert_eq!(sys.matrix().p.to_dense(), full);
    }

    /// With a cloth–cloth pair outside the pattern as well, the preconditioner is the system
    /// matrix with the cloth–cloth pair's coupling replaced by its majorant: the rim pair's
    /// stays in it.
    #[test]
    fn with_both_kinds_only_the_outer_contacts_lose_their_coupling() {
        let mut m = testing::sheet(5, 0.5, vec![]);
        let cloth = contact(&mut m.x);
        let forces = super::super::model_forces(&m, &SolverSettings::default());
        let h = 0.01;
        let rim = rim_pair(&m);
        let at = linearization(&m, h);
        let mut sys = System::new(m.particle_count(), &forces);
        sys.use_contacts(&[&cloth, &rim]);
        sys.assemble(&m.mass, &forces, &at, &[&cloth, &rim], None);
        let full = sys.merged().to_dense();
        let pre = sys.matrix().p.to_dense();
        let only = blocks_of(&cloth, m.particle_count(), &at);
        let rim_only = blocks_of(&rim, m.particle_count(), &at);
        assert!(rim_only[0][3] != 0.0 && only[0][3] == 0.0);
        for i in 0..full.len() {
            for j in 0..full.len() {
                let want = if i / 3 == j / 3 {
                    full[i][j] + majorant(&only, i / 3).col(j % 3)[i % 3]
                } else {
                    full[i][j] - only[i][j]
                };
                assert!((pre[i][j] - want).abs() <= 1e-12 * (1.0 + full[i][j].abs()));
            }
        }
    }

    /// The dense blocks of the contact force `r` alone, `-h² K - h D` at `at`.
    fn blocks_of(r: &dyn Force, n: usize, at: &Linearization) -> Vec<Vec<f64>> {
        let mut only = BlockMatrix::from_pairs(n, &{
            let mut p = Vec::new();
            r.add_pattern(&mut p);
            p
        });
        r.add_jacobian(&at.state(), at.matrix.0, at.matrix.1, &mut only);
        only.to_dense()
    }

    /// A cloth–collider pair on the sheet's edge (0, 1), 1 mm from a collider edge below it,
    /// with a tangential damping.
    fn rim_pair(m: &crate::model::Model) -> ObstacleRepulsions {
        use crate::collision::obstacle_proximity::{ObstacleProximity, ObstacleStencilKind};
        let (a, b) = (0u32, 1u32);
        let mid = (m.x[a as usize] + m.x[b as usize]) * 0.5;
        ObstacleRepulsions::new(
            vec![ObstacleProximity {
                kind: ObstacleStencilKind::EdgeEdge,
                particles: [a, b, a],
                weights: [0.5, 0.5, 0.0],
                point: mid - Vec3::Y * 0.001,
                dist: 0.001,
                normal: Vec3::Y,
                obstacle: 0,
                velocity: Vec3::ZERO,
                damping: 300.0,
            }],
            Penalty {
                thickness: 0.005,
                stiffness: 1000.0,
                tangential: false,
            },
        )
    }
}
