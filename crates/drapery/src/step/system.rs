//! Which matrices a step uses and why.
//!
//! * The **system matrix** `A = M - h D - h² K` of the Newton iteration, on the pattern of the
//!   model's forces, enlarged by this step's cloth–cloth contact pairs when there are any.
//! * Without contacts the mass and the model's forces are assembled straight into it.
//! * With contacts they are assembled into the **base matrix** (the fixed pattern of the model's
//!   forces), copied into the enlarged system matrix, and the contact blocks added there; the
//!   **preconditioner matrix** is the base matrix plus the contacts' diagonal blocks (their
//!   coupling left out), so the multigrid keeps one structure for the whole run.

use crate::forces::{Force, Linearization, Repulsions};
use crate::linalg::BlockMatrix;
use crate::math::{Mat3, Vec3};

/// The matrices of the step's linear systems (see the module docs).
pub(crate) struct System {
    /// Particle pairs of the model's forces.
    base_pairs: Vec<(u32, u32)>,
    /// Mass and model forces on their fixed pattern; stale while `with_contacts` is false
    /// (the system matrix then holds those values itself, on the same pattern).
    base: BlockMatrix,
    /// Position in `matrix` of each block of `base` (while `with_contacts`).
    base_slots: Vec<u32>,
    /// What the preconditioner is built from while `with_contacts`.
    precond: BlockMatrix,
    /// The system matrix.
    matrix: BlockMatrix,
    /// Whether this step's contact pairs enlarge the system matrix's pattern.
    with_contacts: bool,
}

impl System {
    /// The matrices of a model with `n` particles and these forces, without contacts.
    pub fn new(n: usize, forces: &[Box<dyn Force>]) -> System {
        let mut pairs = Vec::new();
        for f in forces {
            f.add_pattern(&mut pairs);
        }
        let matrix = BlockMatrix::from_pairs(n, &pairs);
        System {
            base_pairs: pairs,
            base: matrix.clone(),
            base_slots: Vec::new(),
            precond: matrix.clone(),
            matrix,
            with_contacts: false,
        }
    }

    /// The system matrix of the last linearization.
    pub fn matrix(&self) -> &BlockMatrix {
        &self.matrix
    }

    /// What the preconditioner is built from: the system matrix itself without contacts (PCG
    /// then multiplies by the multigrid's compact copy), the base matrix when the contacts add
    /// no block to its pattern, else the base plus the contacts' diagonal blocks.
    pub fn preconditioner(&self) -> &BlockMatrix {
        if !self.with_contacts {
            &self.matrix
        } else if self.matrix.same_pattern(&self.base) {
            &self.base
        } else {
            &self.precond
        }
    }

    /// A zeroed copy of the base pattern (for the multigrid's reference matrix).
    pub fn base_pattern(&self) -> BlockMatrix {
        self.base.clone()
    }

    /// Sets the system matrix's pattern for this step: the base pattern, or the base plus the
    /// contact pairs (then also where each base block goes in it).
    pub fn use_contacts(&mut self, contact: Option<&Repulsions>) {
        let n = self.base.n();
        match contact {
            Some(r) => {
                let mut pairs = self.base_pairs.clone();
                r.add_pattern(&mut pairs);
                self.matrix = BlockMatrix::from_pairs(n, &pairs);
                let (base, merged) = (&self.base, &self.matrix);
                self.base_slots.clear();
                for i in 0..n {
                    let (cols, _) = base.row(i);
                    let (mcols, mr) = merged.row(i);
                    let mut k = 0;
                    for c in cols {
                        while mcols[k] != *c {
                            k += 1;
                        }
                        self.base_slots.push((mr.start + k) as u32);
                    }
                }
                self.with_contacts = true;
            }
            None if self.with_contacts => {
                // shares the base pattern again (the forces' gather lists stay valid)
                self.matrix = self.base.clone();
                self.with_contacts = false;
            }
            None => {}
        }
    }

    /// Assembles `A = M + a K + b D` at `(at.x, at.v)` with `(a, b) = at.matrix` (`-h²`, `-h`
    /// in a step): the mass and the model's `forces`, then the `contact` force if any (see the
    /// module docs for where each goes). With `vectors = (f, kw)`, also adds every force
    /// (contacts last) to `f` and the products with `at.product` and `at.w` to `kw`, from the
    /// same evaluation ([`Force::add_linearization`]).
    pub fn assemble(
        &mut self,
        mass: &[f64],
        forces: &[Box<dyn Force>],
        at: &Linearization,
        contact: Option<&Repulsions>,
        mut vectors: Option<(&mut [Vec3], &mut [Vec3])>,
    ) {
        let base = if contact.is_some() {
            &mut self.base
        } else {
            &mut self.matrix
        };
        set_mass(mass, base);
        let mut add = |force: &dyn Force, m: &mut BlockMatrix| match &mut vectors {
            Some((f, kw)) => force.add_linearization(at, f, m, kw),
            None => force.add_jacobian(at.x, at.v, at.matrix.0, at.matrix.1, m),
        };
        for force in forces {
            add(force.as_ref(), base);
        }
        let Some(c) = contact else {
            return;
        };
        self.matrix.clear();
        for (k, &slot) in self.base_slots.iter().enumerate() {
            self.matrix.values[slot as usize] = self.base.values[k];
        }
        add(c, &mut self.matrix);
        let p = &mut self.precond;
        p.values.copy_from_slice(&self.base.values);
        for i in 0..mass.len() {
            let k = p.diag_index(i);
            p.values[k] = self.matrix.values[self.matrix.diag_index(i)];
        }
    }
}

/// `m = M - h D - h² K` of the mass and the model's `forces` at `(x, v)` (no contacts).
pub(crate) fn assemble_base(
    mass: &[f64],
    forces: &[Box<dyn Force>],
    x: &[Vec3],
    v: &[Vec3],
    h: f64,
    m: &mut BlockMatrix,
) {
    set_mass(mass, m);
    for f in forces {
        f.add_jacobian(x, v, -h * h, -h, m);
    }
}

/// Sets `m` to the mass matrix (on `m`'s pattern).
fn set_mass(mass: &[f64], m: &mut BlockMatrix) {
    m.set_block_diagonal(|i| Mat3::from_diagonal(Vec3::splat(mass[i])));
}
