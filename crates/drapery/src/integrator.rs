//! Linearized implicit Euler (Baraff & Witkin 1998), MATH.md §1, and its Newton extension.
//!
//! One step solves `(M - h D - h² K) Δv = h (f + h K v)` at `(x₀, v₀)`, then
//! `v₁ = v₀ + Δv`, `x₁ = x₀ + h v₁`. Pinned particles are filtered (MATH.md §5): their
//! velocity change is prescribed so that they end the step at rest, exactly where they were.
//!
//! With `newton_iterations > 1` the step keeps iterating Newton on the incremental potential
//! `Φ(v) = ½ (v - v₀)ᵀ M (v - v₀) + E(x₀ + h v) + h Ψ(x₀ + h v, v)`
//! (`Ψ` the dissipation potential of damping and drag). The first iteration is the linearized
//! step; each iteration backtracks along its direction until `Φ` does not increase.
//!
//! A step is transactional: when it fails (non-finite state, linear solver failure, energy
//! blow-up) the state is restored and an [`Error::StepFailed`] says what and where.

use crate::collision::broad_phase::candidates;
use crate::collision::friction;
use crate::collision::proximity::proximities;
use crate::collision::repulsion::Penalty;
use crate::collision::response::{self, ObstacleContact};
use crate::error::{Error, Result};
use crate::forces::{
    AirDrag, Force, Gravity, Linearization, Repulsions, SpringDamping, Springs, State,
};
use crate::linalg::BlockMatrix;
use crate::linalg::direct::DirectSolver;
use crate::linalg::pcg::{self, PcgScratch, PcgSettings, Preconditioner};
use crate::math::{Mat3, Vec3, outer};
use crate::model::Model;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Which linear solver handles the step's system.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Baraff–Witkin filtered PCG with a 3×3 block-Jacobi preconditioner (default).
    #[default]
    Pcg,
    /// Sparse Cholesky (faer) of the filtered system; LU when the matrix is not symmetric.
    Direct,
}

/// Tunables of the time step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Newton iterations per step; 1 is the seeds' linearized step (default: 1).
    pub newton_iterations: u32,
    /// PCG relative residual `‖r‖/‖b‖` (default: 1e-6).
    pub tolerance: f64,
    /// PCG iteration cap (default: 1000).
    pub max_iterations: usize,
    /// Linear solver (default: PCG).
    pub linear_solver: LinearSolver,
    /// Also put the (non-symmetric) position derivative of spring damping in the matrix
    /// (default: false, as Baraff & Witkin). Needs `linear_solver = Direct`.
    pub damping_x_jacobian: bool,
    /// PCG preconditioner (default: block Jacobi).
    pub preconditioner: Preconditioner,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            newton_iterations: 1,
            tolerance: 1e-6,
            max_iterations: 1000,
            linear_solver: LinearSolver::Pcg,
            damping_x_jacobian: false,
            preconditioner: Preconditioner::Multigrid,
        }
    }
}

impl SolverSettings {
    /// Checks ranges and combinations.
    pub fn validate(&self) -> Result<()> {
        if self.newton_iterations < 1 {
            return Err(Error::Invalid(
                "solver.newton_iterations must be at least 1".into(),
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(Error::Invalid(format!(
                "solver.tolerance must be in (0, 1), got {}",
                self.tolerance
            )));
        }
        if self.max_iterations < 1 {
            return Err(Error::Invalid(
                "solver.max_iterations must be at least 1".into(),
            ));
        }
        if self.damping_x_jacobian && self.linear_solver != LinearSolver::Direct {
            return Err(Error::Invalid(
                "solver.damping_x_jacobian makes the matrix non-symmetric, which conjugate gradient cannot solve: use linear_solver = \"direct\"".into(),
            ));
        }
        Ok(())
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations taken.
    pub newton_iterations: u32,
    /// Total (P)CG iterations over the Newton iterations (0 with the direct solver).
    pub cg_iterations: usize,
    /// Linear solves (more than one per Newton iteration when contacts were released).
    pub linear_solves: usize,
    /// Final relative residual of the last PCG solve (0 with the direct solver).
    pub residual: f64,
    /// Seconds spent assembling forces and matrices.
    pub assembly_seconds: f64,
    /// Seconds spent in the linear solver.
    pub solve_seconds: f64,
    /// Seconds spent finding contacts and in the collision fail-safe.
    pub collision_seconds: f64,
    /// Particles held against obstacles in the solve.
    pub obstacle_contacts: usize,
    /// Cloth–cloth repulsion stencils in the solve.
    pub self_contacts: usize,
    /// Pairs the continuous collision fail-safe had to stop.
    pub ccd_hits: usize,
}

/// A model plus the solver's working memory. Advance it with [`Simulation::step`].
pub struct Simulation {
    /// The simulated state (positions and velocities are updated in place).
    pub model: Model,
    /// Step settings.
    pub settings: SolverSettings,
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken so far.
    pub steps: u64,
    /// The previous step's velocity change, the PCG's initial guess for the next step (part of
    /// the state: save and restore it to resume a run bit for bit).
    pub warm_start: Vec<Vec3>,
    forces: Vec<Box<dyn Force>>,
    base_pairs: Vec<(u32, u32)>,
    /// Mass and model forces, on the fixed pattern of the model's forces, while contacts
    /// enlarge the system matrix's pattern; without contacts `matrix` shares this pattern and
    /// takes these values itself (see [`Self::base_is_system`]), and these are stale.
    base_matrix: BlockMatrix,
    /// Position in `matrix` of each block of `base_matrix` (when contacts enlarge the pattern).
    base_slots: Vec<u32>,
    /// What the preconditioner is built from while contacts enlarge the pattern: the base
    /// blocks plus the contacts' diagonal blocks (their coupling left out), so the multigrid
    /// keeps one structure for the whole run.
    precond_matrix: BlockMatrix,
    /// State the simulation was created in (the multigrid's reference, see [`Self::reference`]).
    initial: (Vec<Vec3>, Vec<Vec3>),
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    matrix: BlockMatrix,
    filter: Vec<Mat3>,
    buffers: StepBuffers,
    pcg: PcgScratch,
    direct: DirectSolver,
}

/// Linear solves per Newton iteration at most. Obstacle contacts form an active set: before
/// the first solve, a contact is released when the initial guess (the previous step's change
/// of velocity) says it would pull and its particle would leave the surface anyway; after each
/// solve, held contacts whose impulse pulls are released, released ones whose particle would
/// sink below the prescribed normal velocity are held again, and the system is solved again
/// from the previous solution. What the last round leaves stays for this step (and is
/// re-examined at the next).
const CONTACT_ROUNDS: usize = 2;

/// Holds particle `c.particle` to the contact's normal velocity: filter `I - n nᵀ` and the
/// prescribed normal part of the change of velocity from `v`.
fn hold(c: &ObstacleContact, v: &[Vec3], filter: &mut [Mat3], z: &mut [Vec3]) {
    let i = c.particle as usize;
    filter[i] = Mat3::IDENTITY - outer(c.normal, c.normal);
    z[i] = c.normal * (c.normal_velocity - c.normal.dot(v[i]));
}

/// Strength-of-connection threshold of the multigrid, applied to the system matrix at the
/// initial state (see [`Simulation::reference`]).
const MULTIGRID_STRENGTH: f64 = 0.08;

/// Per-particle work vectors of a step, kept between steps.
#[derive(Default)]
struct StepBuffers {
    f: Vec<Vec3>,
    rhs: Vec<Vec3>,
    w: Vec<Vec3>,
    z: Vec<Vec3>,
    dv: Vec<Vec3>,
    kw: Vec<Vec3>,
    r: Vec<Vec3>,
}

/// Ratio of kinetic energies across one step above which the step counts as a blow-up.
const BLOWUP_RATIO: f64 = 1e4;

/// Particles per task in the step's per-particle parallel loops.
const PARTICLES: usize = 1024;

impl Simulation {
    /// Prepares a simulation: builds the forces from the model, the matrix pattern and the
    /// solver scratch.
    pub fn new(model: Model, settings: SolverSettings) -> Result<Self> {
        settings.validate()?;
        let s = &model.springs;
        let stiff: Vec<usize> = (0..s.len()).filter(|&k| s.stiffness[k] > 0.0).collect();
        let damped: Vec<usize> = (0..s.len()).filter(|&k| s.damping[k] > 0.0).collect();
        let mut forces: Vec<Box<dyn Force>> =
            vec![Box::new(Gravity::new(&model.mass, model.gravity))];
        if !stiff.is_empty() {
            forces.push(Box::new(Springs {
                i: stiff.iter().map(|&k| s.i[k]).collect(),
                j: stiff.iter().map(|&k| s.j[k]).collect(),
                rest: stiff.iter().map(|&k| s.rest[k]).collect(),
                k: stiff.iter().map(|&k| s.stiffness[k]).collect(),
                clamp_compression: true,
                sums: Default::default(),
            }));
        }
        if !damped.is_empty() {
            forces.push(Box::new(SpringDamping {
                i: damped.iter().map(|&k| s.i[k]).collect(),
                j: damped.iter().map(|&k| s.j[k]).collect(),
                c: damped.iter().map(|&k| s.damping[k]).collect(),
                position_jacobian: settings.damping_x_jacobian,
                sums: Default::default(),
            }));
        }
        if model.drag.iter().any(|&c| c > 0.0) {
            forces.push(Box::new(AirDrag {
                c: model.drag.clone(),
            }));
        }
        let mut pairs = Vec::new();
        for f in &forces {
            f.add_pattern(&mut pairs);
        }
        let n = model.particle_count();
        let matrix = BlockMatrix::from_pairs(n, &pairs);
        if let Some(c) = &model.collision {
            c.validate()?;
        }
        let filter = model.pin_filter();
        let (triangles, edges) = (model.triangles(), model.edges());
        let initial = (model.x.clone(), model.v.clone());
        Ok(Simulation {
            warm_start: vec![Vec3::ZERO; n],
            model,
            settings,
            time: 0.0,
            steps: 0,
            forces,
            base_matrix: matrix.clone(),
            base_slots: Vec::new(),
            precond_matrix: matrix.clone(),
            initial,
            base_pairs: pairs,
            triangles,
            edges,
            matrix,
            filter,
            buffers: StepBuffers::default(),
            pcg: PcgScratch::default(),
            direct: DirectSolver::default(),
        })
    }

    /// The forces acting on the model.
    pub fn forces(&self) -> &[Box<dyn Force>] {
        &self.forces
    }

    /// The system matrix of the last Newton iteration.
    pub fn matrix(&self) -> &BlockMatrix {
        &self.matrix
    }

    /// Total force at the current state.
    pub fn total_force(&self) -> Vec<Vec3> {
        let mut f = vec![Vec3::ZERO; self.model.particle_count()];
        for force in &self.forces {
            let at = State {
                t: self.time,
                x: &self.model.x,
                v: &self.model.v,
            };
            force.add_force(&at, &mut f);
        }
        f
    }

    /// Potential energy (springs and gravity) at the current positions.
    pub fn potential_energy(&self) -> f64 {
        self.forces
            .iter()
            .map(|f| f.energy(self.time, &self.model.x))
            .sum()
    }

    /// Kinetic plus potential energy.
    pub fn total_energy(&self) -> f64 {
        self.model.kinetic_energy() + self.potential_energy()
    }

    /// Assembles the system matrix `M - h D - h² K` at the current state without contacts
    /// (what the first iteration of a contact-free step solves) into [`Simulation::matrix`];
    /// for benchmarks and inspection.
    pub fn assemble_matrix(&mut self, h: f64) {
        let (x, v) = (self.model.x.clone(), self.model.v.clone());
        self.use_contact_pattern(None);
        let at = Linearization {
            t: self.time,
            x: &x,
            v: &v,
            matrix: (-h * h, -h),
            // unused: only the matrix is assembled
            product: (0.0, 0.0),
            w: &v,
        };
        self.linearize(&at, None, None);
    }

    /// Gives the multigrid its reference (once, at the first step): the base system matrix
    /// for step `h` at the state the simulation was created in, filtered by the pins. The
    /// hierarchy's structure follows that matrix's strong couplings; since it depends only on
    /// the scene and `h`, a run resumed from a saved state builds the same hierarchy.
    fn reference(&mut self, h: f64) {
        if self.settings.preconditioner != Preconditioner::Multigrid
            || self.pcg.multigrid().has_reference()
        {
            return;
        }
        let mut r = self.base_matrix.clone();
        let (x, v) = &self.initial;
        assemble_base(&self.model.mass, &self.forces, 0.0, x, v, h, &mut r);
        let pins = self.model.pin_filter();
        let mg = self.pcg.multigrid();
        mg.params.strength = MULTIGRID_STRENGTH;
        mg.set_reference(r, pins);
    }

    /// Sets the system matrix's pattern: the base pattern, or the base plus this step's
    /// contact pairs (then also where each base block goes in it).
    fn use_contact_pattern(&mut self, contact: Option<&Repulsions>) {
        let n = self.model.particle_count();
        match contact {
            Some(r) => {
                let mut pairs = self.base_pairs.clone();
                r.add_pattern(&mut pairs);
                self.matrix = BlockMatrix::from_pairs(n, &pairs);
                let (base, merged) = (&self.base_matrix, &self.matrix);
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
            }
            None if !self.base_is_system() => {
                self.matrix = self.base_matrix.clone();
            }
            None => {}
        }
    }

    /// Whether the system matrix has the base pattern itself (no contacts this step): the
    /// model's forces are then assembled straight into it, and `base_matrix` is left stale.
    fn base_is_system(&self) -> bool {
        Arc::ptr_eq(self.matrix.pattern(), self.base_matrix.pattern())
    }

    /// Assembles `A = M + a K + b D` at `(at.x, at.v)` with `(a, b) = at.matrix` (`-h²`,
    /// `-h` in a step): the mass and the model's forces into the system matrix, or with
    /// contacts into the base pattern and then into the enlarged system matrix with the contact
    /// blocks added (and the preconditioner's matrix). With `vectors = (f, kw)`, also adds every
    /// force (contacts last) to `f` and the products with `at.product` and `at.w` to `kw`, from
    /// the same evaluation ([`Force::add_linearization`]).
    fn linearize(
        &mut self,
        at: &Linearization,
        contact: Option<&Repulsions>,
        mut vectors: Option<(&mut [Vec3], &mut [Vec3])>,
    ) {
        let base = if contact.is_some() {
            &mut self.base_matrix
        } else {
            &mut self.matrix
        };
        set_mass(&self.model.mass, base);
        let mut add = |force: &dyn Force, m: &mut BlockMatrix| match &mut vectors {
            Some((f, kw)) => force.add_linearization(at, f, m, kw),
            None => force.add_jacobian(&at.state(), at.matrix.0, at.matrix.1, m),
        };
        for force in &self.forces {
            add(force.as_ref(), base);
        }
        let Some(c) = contact else {
            return;
        };
        self.matrix.clear();
        for (k, &slot) in self.base_slots.iter().enumerate() {
            self.matrix.values[slot as usize] = self.base_matrix.values[k];
        }
        add(c, &mut self.matrix);
        let p = &mut self.precond_matrix;
        p.values.copy_from_slice(&self.base_matrix.values);
        for i in 0..self.model.particle_count() {
            let k = p.diag_index(i);
            p.values[k] = self.matrix.values[self.matrix.diag_index(i)];
        }
    }

    /// Cloth triangle pairs that intersect and particles inside analytic obstacles, at the
    /// current state (what `drapery check` counts). A starting state with intersections is
    /// reported, not repaired.
    pub fn intersections(&self) -> (usize, usize) {
        let selfi =
            crate::collision::check::count_self_intersections(&self.model.x, &self.triangles);
        let colliders: Vec<_> = self
            .model
            .obstacles
            .iter()
            .map(|o| o.collider.clone())
            .collect();
        let pen =
            crate::collision::check::count_penetrations(&self.model.x, &colliders, self.time, 0.0);
        (selfi, pen)
    }

    /// `Φ(v)` of the module docs, for the line search.
    fn objective(
        &self,
        x0: &[Vec3],
        v0: &[Vec3],
        v: &[Vec3],
        h: f64,
        contact: Option<&Repulsions>,
    ) -> f64 {
        let x: Vec<Vec3> = x0.iter().zip(v).map(|(a, b)| *a + h * *b).collect();
        let t = self.time + h;
        let inertia: f64 = self
            .model
            .mass
            .iter()
            .zip(v.iter().zip(v0))
            .map(|(m, (a, b))| 0.5 * m * (*a - *b).length_squared())
            .sum();
        inertia
            + all_forces(&self.forces, contact)
                .map(|f| {
                    let at = State { t, x: &x, v };
                    f.energy(t, &x) + h * f.dissipation(&at)
                })
                .sum::<f64>()
    }

    /// Energy stored in the springs and contacts at `x` (all forces' potentials but gravity's,
    /// the first force, whose work over a step the blow-up test allows for separately).
    fn stored_energy(&self, x: &[Vec3], contact: Option<&Repulsions>) -> f64 {
        all_forces(&self.forces[1..], contact)
            .map(|f| f.energy(self.time, x))
            .sum()
    }

    fn fail(&self, reason: String) -> Error {
        Error::StepFailed {
            step: self.steps,
            time: self.time,
            reason,
        }
    }

    /// Names particle `p` as "vertex N of cloth 'name'".
    fn particle_name(&self, p: usize) -> String {
        match self.model.cloths.iter().find(|c| c.range().contains(&p)) {
            Some(c) => format!("vertex {} of cloth '{}'", p - c.offset, c.name),
            None => format!("particle {p}"),
        }
    }

    /// Advances by one step of `h` seconds. On error the state is left as it was before.
    ///
    /// The step runs on a thread of rayon's current pool (the caller waits), so that its many
    /// short parallel loops are forked from inside the pool instead of each one being sent to
    /// it from outside and waited for.
    pub fn step(&mut self, h: f64) -> Result<StepReport> {
        if rayon::current_thread_index().is_some() {
            self.step_here(h)
        } else {
            rayon::scope(|_| self.step_here(h))
        }
    }

    fn step_here(&mut self, h: f64) -> Result<StepReport> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(Error::Invalid(format!(
                "time step must be a finite number > 0, got {h}"
            )));
        }
        let n = self.model.particle_count();
        if let Some(p) =
            (0..n).find(|&i| !(self.model.x[i].is_finite() && self.model.v[i].is_finite()))
        {
            return Err(self.fail(format!(
                "non-finite position or velocity at {} before the step",
                self.particle_name(p)
            )));
        }
        let x0 = self.model.x.clone();
        let v0 = self.model.v.clone();
        let ke0 = self.model.kinetic_energy();
        let mut report = StepReport::default();
        let symmetric = !self.settings.damping_x_jacobian;
        let pcg_settings = PcgSettings {
            tolerance: self.settings.tolerance,
            max_iterations: self.settings.max_iterations,
            preconditioner: self.settings.preconditioner,
        };

        self.reference(h);
        // Contacts found at the start of the step.
        let tc = Instant::now();
        let collision = self.model.collision;
        let contacts: Vec<ObstacleContact> = match &collision {
            Some(c) => response::obstacle_contacts(
                &x0,
                &v0,
                &self.model.pinned,
                &self.model.obstacles,
                self.time,
                h,
                c.thickness,
                self.model.gravity.length() * h,
            ),
            None => Vec::new(),
        };
        let repulsions = match &collision {
            Some(c) if c.self_collision => {
                let cand = candidates(&x0, &x0, &self.triangles, &self.edges, c.thickness);
                let mut stencils =
                    proximities(&x0, &self.triangles, &self.edges, &cand, c.thickness);
                stencils.retain(|s| s.particles.iter().any(|&p| !self.model.pinned[p as usize]));
                (!stencils.is_empty()).then(|| {
                    Repulsions::new(
                        stencils,
                        Penalty {
                            thickness: c.thickness,
                            stiffness: c.stiffness,
                            tangential: false,
                        },
                    )
                })
            }
            _ => None,
        };
        report.self_contacts = repulsions.as_ref().map_or(0, |r| r.stencils.len());
        self.use_contact_pattern(repulsions.as_ref());
        let contact_force = repulsions.as_ref();
        report.collision_seconds += tc.elapsed().as_secs_f64();

        // Iterate on v; x = x0 + h v except at the first linearization point (x0, v0).
        let mut v = v0.clone();
        let mut x = x0.clone();
        // work vectors kept between steps (a failed step leaves them to be allocated again)
        let StepBuffers {
            mut f,
            mut rhs,
            mut w,
            mut z,
            mut dv,
            mut kw,
            mut r,
        } = std::mem::take(&mut self.buffers);
        for b in [&mut f, &mut rhs, &mut w, &mut z, &mut dv, &mut kw, &mut r] {
            b.resize(n, Vec3::ZERO);
        }
        // Obstacle contacts found at the start of the step, and which of them are held.
        let candidates = contacts;
        let mut active = vec![true; candidates.len()];
        let mut impulse = vec![0.0; candidates.len()];
        // a released contact is held again when its solved normal velocity is below the
        // prescribed one by more than this
        let sink_tolerance = 1e-2 * self.model.gravity.length() * h;
        let newton = self.settings.newton_iterations;
        for it in 0..newton {
            let t0 = Instant::now();
            // rhs = M (v0 - v) + h f + h K w with w = x0 + h v - x
            w.par_iter_mut()
                .zip(f.par_iter_mut())
                .zip(kw.par_iter_mut())
                .enumerate()
                .with_min_len(PARTICLES)
                .for_each(|(i, ((wi, fi), kwi))| {
                    *wi = x0[i] + h * v[i] - x[i];
                    *fi = Vec3::ZERO;
                    *kwi = Vec3::ZERO;
                });
            let at = Linearization {
                t: self.time + h,
                x: &x,
                v: &v,
                matrix: (-h * h, -h),
                product: (h, 0.0),
                w: &w,
            };
            self.linearize(&at, contact_force, Some((&mut f, &mut kw)));
            let mass = &self.model.mass;
            rhs.par_iter_mut()
                .enumerate()
                .with_min_len(PARTICLES)
                .for_each(|(i, r)| *r = mass[i] * (v0[i] - v[i]) + h * f[i] + kw[i]);
            report.assembly_seconds += t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            // Solve on an active set of the obstacle contacts (see `CONTACT_ROUNDS`).
            for round in 0..CONTACT_ROUNDS {
                let (pinned, warm) = (&self.model.pinned, &self.warm_start);
                z.par_iter_mut()
                    .zip(self.filter.par_iter_mut())
                    .zip(dv.par_iter_mut())
                    .enumerate()
                    .with_min_len(PARTICLES)
                    .for_each(|(i, ((zi, si), dvi))| {
                        (*zi, *si) = if pinned[i] {
                            (-v[i], Mat3::ZERO)
                        } else {
                            (Vec3::ZERO, Mat3::IDENTITY)
                        };
                        // initial guess: the previous step's change, then the previous round's
                        // solution (only the contacts that changed differ)
                        if round == 0 {
                            *dvi = if it == 0 {
                                warm.get(i).copied().unwrap_or(Vec3::ZERO)
                            } else {
                                Vec3::ZERO
                            };
                        }
                    });
                for (c, _) in candidates.iter().zip(&active).filter(|(_, a)| **a) {
                    hold(c, &v, &mut self.filter, &mut z);
                }
                if round == 0 && it == 0 && !candidates.is_empty() {
                    // predict from the guess which contacts would pull, and release those
                    // whose guessed velocity leaves the surface
                    for i in 0..n {
                        w[i] = z[i] + self.filter[i] * dv[i];
                    }
                    self.matrix.mul_vec(&w, &mut r);
                    for (c, a) in candidates.iter().zip(active.iter_mut()) {
                        let i = c.particle as usize;
                        let pulls = c.normal.dot(r[i] - rhs[i]) < 0.0;
                        let leaves = c.normal.dot(v[i] + dv[i]) >= c.normal_velocity;
                        if pulls && leaves {
                            *a = false;
                            self.filter[i] = Mat3::IDENTITY;
                            z[i] = Vec3::ZERO;
                        }
                    }
                }
                report.linear_solves += 1;
                if let Err(e) =
                    self.solve(&rhs, &z, &mut dv, &pcg_settings, symmetric, it, &mut report)
                {
                    self.restore(x0, v0);
                    return Err(e);
                }
                if candidates.is_empty() {
                    break;
                }
                self.matrix.mul_vec(&dv, &mut r);
                for (c, l) in candidates.iter().zip(impulse.iter_mut()) {
                    let i = c.particle as usize;
                    *l = c.normal.dot(r[i] - rhs[i]);
                }
                // The last round keeps the contact set its solve used, so the contact list
                // below (normal reset, friction) matches the velocities it comes with.
                if round + 1 == CONTACT_ROUNDS {
                    break;
                }
                let scale = candidates
                    .iter()
                    .zip(&impulse)
                    .zip(&active)
                    .filter(|(_, a)| **a)
                    .fold(0.0f64, |m, ((_, l), _)| m.max(l.abs()));
                let mut changed = false;
                for ((c, l), a) in candidates.iter().zip(&impulse).zip(active.iter_mut()) {
                    let i = c.particle as usize;
                    let flip = if *a {
                        *l < -1e-9 * scale
                    } else {
                        c.normal.dot(v[i] + dv[i]) < c.normal_velocity - sink_tolerance
                    };
                    if flip {
                        *a = !*a;
                        changed = true;
                    }
                }
                if !changed {
                    break;
                }
            }
            report.solve_seconds += t1.elapsed().as_secs_f64();
            report.newton_iterations = it + 1;
            // Full step: v + dv. With more than one iteration, backtrack on Φ.
            let mut alpha = 1.0;
            if newton > 1 {
                let start: Vec<Vec3> = if it == 0 {
                    vec![Vec3::ZERO; n]
                } else {
                    v.clone()
                };
                let phi0 = self.objective(&x0, &v0, &start, h, contact_force);
                let full: Vec<Vec3> = v.iter().zip(&dv).map(|(a, b)| *a + *b).collect();
                let mut cand = full.clone();
                for _ in 0..20 {
                    if self.objective(&x0, &v0, &cand, h, contact_force) <= phi0
                        || !phi0.is_finite()
                    {
                        break;
                    }
                    alpha *= 0.5;
                    for i in 0..n {
                        cand[i] = start[i] + alpha * (full[i] - start[i]);
                    }
                }
                v = cand;
            } else {
                for i in 0..n {
                    v[i] += dv[i];
                }
            }
            for i in 0..n {
                x[i] = x0[i] + h * v[i];
            }
            if let Some(p) = (0..n).find(|&i| !(x[i].is_finite() && v[i].is_finite())) {
                let name = self.particle_name(p);
                self.restore(x0, v0);
                return Err(self.fail(format!("non-finite position or velocity at {name}")));
            }
            let vmax = v.iter().fold(0.0f64, |m, e| m.max(e.abs().max_element()));
            let dmax = dv.iter().fold(0.0f64, |m, e| m.max(e.abs().max_element()));
            if it + 1 < newton
                && alpha == 1.0
                && dmax <= 1e-12 * vmax.max(self.model.gravity.length() * h).max(1e-300)
            {
                break;
            }
        }
        let (contacts, impulse): (Vec<ObstacleContact>, Vec<f64>) = candidates
            .iter()
            .zip(&impulse)
            .zip(&active)
            .filter(|(_, a)| **a)
            .map(|((c, l), _)| (*c, *l))
            .unzip();
        report.obstacle_contacts = contacts.len();

        // Friction, then the fail-safe: nothing crosses anything over the step.
        if let Some(c) = &collision {
            let tc = Instant::now();
            // The push back to the thickness is a position correction: the particle keeps the
            // solved normal displacement but ends the step at rest on the surface (inelastic
            // contact), not flying off it. Friction then acts on the tangential velocity:
            // cloth–cloth contacts first, then obstacles (which bound what holds the pile).
            let solved = v.clone();
            if let Some(r) = &repulsions {
                friction::apply_contact_friction(
                    &mut v,
                    &x,
                    &self.model.mass,
                    &self.model.pinned,
                    &r.stencils,
                    &r.penalty,
                    c.friction,
                    h,
                );
            }
            for ct in &contacts {
                let i = ct.particle as usize;
                let vn = ct.normal.dot(v[i]);
                v[i] += ct.normal * (ct.normal.dot(ct.surface_velocity) - vn);
            }
            response::apply_friction(&mut v, &self.model.mass, &contacts, &impulse);
            for i in 0..n {
                x[i] = x0[i] + h * v[i];
            }
            for ct in &contacts {
                let i = ct.particle as usize;
                x[i] += h * ct.normal * ct.normal.dot(solved[i] - v[i]);
            }
            let before = x.clone();
            let projected = match response::failsafe(
                &x0,
                &mut x,
                &self.model.pinned,
                &self.triangles,
                &self.edges,
                &self.model.obstacles,
                self.time,
                h,
                c.thickness,
                c.self_collision,
            ) {
                Ok(r) => {
                    report.ccd_hits = r.ccd_hits;
                    r.projected
                }
                Err(e) => {
                    self.restore(x0, v0);
                    return Err(self.fail(e));
                }
            };
            let mut keep_velocity = vec![false; n];
            projected
                .iter()
                .for_each(|&p| keep_velocity[p as usize] = true);
            for i in 0..n {
                if x[i] != before[i] && !keep_velocity[i] {
                    v[i] = (x[i] - x0[i]) / h;
                }
            }
            report.collision_seconds += tc.elapsed().as_secs_f64();
        }

        self.model.x = x;
        self.model.v = v;
        let ke1 = self.model.kinetic_energy();
        let surface_speed = self
            .model
            .obstacles
            .iter()
            .map(|o| o.collider.motion.velocity.length())
            .fold(0.0, f64::max);
        let allowance = 0.5
            * self.model.total_mass()
            * ((self.model.gravity.length() * h).powi(2) + surface_speed.powi(2));
        // a cloth let go from rest with stretched springs gains kinetic energy from zero; what
        // it may gain is bounded by the energy stored at the start of the step
        let limit = |stored: f64| BLOWUP_RATIO * (ke0 + allowance + stored) + 1e-300;
        if ke1 > limit(0.0) && ke1 > limit(self.stored_energy(&x0, contact_force)) {
            let p = (0..n)
                .max_by(|&a, &b| {
                    self.model.v[a]
                        .length()
                        .total_cmp(&self.model.v[b].length())
                })
                .unwrap_or(0);
            let name = self.particle_name(p);
            let speed = self.model.v[p].length();
            self.restore(x0, v0);
            return Err(self.fail(format!(
                "energy blow-up: kinetic energy grew from {ke0:.3e} J to {ke1:.3e} J in one step (fastest: {name} at {speed:.3e} m/s); try a smaller dt or more damping"
            )));
        }
        for i in 0..n {
            self.warm_start[i] = self.model.v[i] - v0[i];
        }
        self.buffers = StepBuffers {
            f,
            rhs,
            w,
            z,
            dv,
            kw,
            r,
        };
        self.time += h;
        self.steps += 1;
        Ok(report)
    }

    /// One linear solve with the current filter into `dv`.
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &mut self,
        rhs: &[Vec3],
        z: &[Vec3],
        dv: &mut [Vec3],
        pcg_settings: &PcgSettings,
        symmetric: bool,
        it: u32,
        report: &mut StepReport,
    ) -> Result<()> {
        match self.settings.linear_solver {
            LinearSolver::Pcg => {
                let p = if self.base_is_system() {
                    // the same matrix: PCG then multiplies by the multigrid's compact copy
                    &self.matrix
                } else if self.matrix.same_pattern(&self.base_matrix) {
                    &self.base_matrix
                } else {
                    &self.precond_matrix
                };
                let stats = pcg::solve_preconditioned_by(
                    &self.matrix,
                    p,
                    rhs,
                    &self.filter,
                    z,
                    dv,
                    pcg_settings,
                    &mut self.pcg,
                );
                report.cg_iterations += stats.iterations;
                report.residual = stats.relative_residual;
                if !stats.converged {
                    let why = if stats.indefinite {
                        "the system matrix is not positive definite"
                    } else if stats.bad_preconditioner {
                        "the multigrid preconditioner is not positive definite"
                    } else {
                        "conjugate gradient did not converge"
                    };
                    return Err(self.fail(format!(
                        "{why} (Newton iteration {}, {} CG iterations, relative residual {:.3e}, tolerance {:.1e}); try a smaller dt, a larger solver.max_iterations or linear_solver = \"direct\"",
                        it + 1,
                        stats.iterations,
                        stats.relative_residual,
                        self.settings.tolerance
                    )));
                }
            }
            LinearSolver::Direct => {
                if let Err(e) = self
                    .direct
                    .solve(&self.matrix, rhs, &self.filter, z, dv, symmetric)
                {
                    return Err(self.fail(e));
                }
            }
        }
        Ok(())
    }

    fn restore(&mut self, x0: Vec<Vec3>, v0: Vec<Vec3>) {
        self.model.x = x0;
        self.model.v = v0;
    }
}

/// `m = M - h D - h² K` of the mass and the model's `forces` at `(x, v)` (no contacts).
fn assemble_base(
    mass: &[f64],
    forces: &[Box<dyn Force>],
    t: f64,
    x: &[Vec3],
    v: &[Vec3],
    h: f64,
    m: &mut BlockMatrix,
) {
    set_mass(mass, m);
    for f in forces {
        f.add_jacobian(&State { t, x, v }, -h * h, -h, m);
    }
}

/// Sets `m` to the mass matrix (on `m`'s pattern).
fn set_mass(mass: &[f64], m: &mut BlockMatrix) {
    m.set_block_diagonal(|i| Mat3::from_diagonal(Vec3::splat(mass[i])));
}

/// The model's forces plus this step's contact force, if any.
fn all_forces<'a>(
    forces: &'a [Box<dyn Force>],
    contact: Option<&'a Repulsions>,
) -> impl Iterator<Item = &'a dyn Force> {
    forces
        .iter()
        .map(|f| f.as_ref())
        .chain(contact.map(|c| c as &dyn Force))
}
