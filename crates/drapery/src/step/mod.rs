//! Linearized implicit Euler (Baraff & Witkin 1998, docs/MATH.md §1), as a list of named stages.
//!
//! One step solves `(M - h D - h² K) Δv = h (f + h K v)` at `(x₀, v₀)`, then `v₁ = v₀ + Δv`,
//! `x₁ = x₀ + h v₁`, with pins and obstacle contacts as velocity filters. [`Simulation::step`]
//! reads as its stages, each a function in its own module with explicit inputs and outputs:
//!
//! | stage | module | does |
//! |---|---|---|
//! | guard | [`guard`] | a valid step size and a finite starting state |
//! | pose | [`pose`] | colliders and pin targets over `[t, t + h]`; cloth starting inside a collider pushed out ([`tangles`]) |
//! | detect | [`detect`] | obstacle contact candidates, self-contact stencils |
//! | linearize | [`linearize`] | forces, `A`, right-hand side (per Newton iteration) |
//! | constrain, solve | [`solve`] | filter `S` and `z`, filtered PCG on the obstacle active set |
//! | update | [`newton`] | new velocities and positions, line search with several iterations; where obstacle contact begins, more iterations while the linearization is far off |
//! | friction | [`friction`] | cloth–cloth, then obstacle friction |
//! | strain | [`strain`] | over-long edges of strain-limited cloths shortened (momentum kept) |
//! | failsafe | [`failsafe`] | continuous collision detection: nothing crosses anything |
//! | commit | [`guard`] | energy blow-up test, warm start, time |
//!
//! docs/MATH.md §18 walks through one step in this order.
//!
//! A step is transactional: the state changes only at commit, so when any stage fails the
//! simulation is left as it was and an [`crate::Error::StepFailed`] says what and where.

mod detect;
mod failsafe;
mod friction;
mod guard;
mod linearize;
mod newton;
mod pose;
pub mod report;
pub mod settings;
mod solve;
pub mod start_check;
mod strain;
mod system;
pub mod tangles;
#[cfg(test)]
mod testing;

pub use report::{StageTimes, StepReport};
pub use settings::{FIRST_CONTACT_TOLERANCE, IMPACT_SHARE, LinearSolver, SolverSettings};
pub use start_check::StartCheck;
pub use tangles::Tangled;

use crate::animation::Motion;
use crate::collision::broad_phase::Candidates;
use crate::collision::bvh::TreeCache;
use crate::collision::seam_crossings::SeamCrossings;
use crate::collision::seams::Seams;
use crate::constraints::obstacle::{self, ActiveSet};
use crate::constraints::strain_limit::StrainLimits;
use crate::error::Result;
use crate::forces::{
    AirDrag, Force, Gravity, Linearization, Pressure, SpringDamping, Springs, State, Stitches,
    WindForce,
};
use crate::linalg::BlockMatrix;
use crate::linalg::pcg::Preconditioner;
use crate::math::Vec3;
use crate::model::Model;
use guard::At;
use linearize::{Iterate, Linearized};
use newton::{Outcome, Potential};
use report::timed;
use solve::{Problem, Scratch, Solvers};
use system::System;
use tangles::Tangles;

/// A model plus the solver's working memory. Advance it with [`Simulation::step`].
pub struct Simulation {
    /// The simulated state (positions and velocities are updated in place).
    pub(crate) model: Model,
    /// Step settings.
    pub(crate) settings: SolverSettings,
    /// Simulated time, s.
    pub(crate) time: f64,
    /// Steps taken so far.
    pub(crate) steps: u64,
    /// The previous step's velocity change, the PCG's initial guess for the next step (part of
    /// the state: save and restore it to resume a run bit for bit).
    pub(crate) warm_start: Vec<Vec3>,
    /// Each particle's obstacle normal force in the previous step (N, 0 where no contact held
    /// it): the lagged normal force of the friction in the solve (part of the state).
    pub(crate) normal_force: Vec<f64>,
    forces: Vec<Box<dyn Force>>,
    system: System,
    /// State the simulation was created in (the multigrid's reference, see [`Self::reference`]).
    initial: (Vec<Vec3>, Vec<Vec3>),
    pub(crate) triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// The stitched neighbourhoods exempt from cloth–cloth contact.
    seams: Seams,
    /// The triangles by the seams, whose crossings over a step the fail-safe undoes.
    seam_crossings: SeamCrossings,
    /// The edges of the cloths that have a strain limit.
    strain_limits: StrainLimits,
    /// Cloth that started inside colliders or crossed, still being untangled (part of the
    /// state: a snapshot holds it).
    pub(crate) tangles: Tangles,
    work: Work,
    /// The broad phase's tree orders, kept between steps (speed only: no result depends on
    /// them, and a snapshot does not hold them).
    trees: Trees,
    /// The cloth's pairs the last fail-safe found near its end positions, with those positions
    /// (used by the next detect stage only if the positions are still the same, bit for bit).
    next_pairs: Option<(Vec<Vec3>, Candidates)>,
    solvers: Solvers,
    /// The colliders' and handles' motions as the scene gave them: while the model's differ
    /// (a front end replaced one, [`Simulation::set_obstacle_motion`]), a snapshot holds them
    /// all; a snapshot without motions restores these.
    pub(crate) scene_motions: (Vec<Motion>, Vec<Motion>),
}

/// The tree orders of the detect and fail-safe stages' broad phases.
#[derive(Clone, Debug, Default)]
struct Trees {
    detect: TreeCache,
    failsafe: TreeCache,
}

/// Per-particle work vectors of a step, kept between steps.
#[derive(Default)]
struct Work {
    linearized: Linearized,
    solve: Scratch,
    dv: Vec<Vec3>,
}

/// Strength-of-connection threshold of the multigrid, applied to the system matrix at the
/// initial state (see [`Simulation::reference`]).
pub const MULTIGRID_STRENGTH: f64 = 0.08;

impl Simulation {
    /// Prepares a simulation: builds the forces from the model, the matrix pattern and the
    /// solver scratch.
    pub fn new(model: Model, settings: SolverSettings) -> Result<Self> {
        settings.validate()?;
        if let Some(c) = &model.collision {
            c.validate()?;
        }
        let forces = model_forces(&model, &settings);
        let n = model.particle_count();
        let system = System::new(n, &forces);
        let (triangles, edges) = (model.triangles(), model.edges());
        let initial = (model.x.clone(), model.v.clone());
        let stitched: Vec<[u32; 2]> = model.stitches.iter().map(|p| [p.a, p.b]).collect();
        let seams = Seams::new(n, &triangles, &stitched);
        let seam_crossings = SeamCrossings::new(n, &triangles, &stitched, &seams);
        let strain_limits = StrainLimits::of(&model);
        let scene_motions = model.motions();
        Ok(Simulation {
            warm_start: vec![Vec3::ZERO; n],
            normal_force: vec![0.0; n],
            model,
            settings,
            time: 0.0,
            steps: 0,
            forces,
            system,
            initial,
            triangles,
            edges,
            seams,
            seam_crossings,
            strain_limits,
            tangles: Tangles::default(),
            trees: Trees::default(),
            next_pairs: None,
            work: Work::default(),
            solvers: Solvers::default(),
            scene_motions,
        })
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
        let mut report = StepReport::default();
        let at = At {
            steps: self.steps,
            time: self.time,
        };
        let start = timed(&mut report.stages.guard, || {
            guard::start(&self.model, at, h)
        })?;
        timed(&mut report.stages.pose, || self.reference(h));
        // the starting tangles are found at the first step (kept only if the step succeeds)
        let mut fresh = None;
        let tangles = (self.tangles).or_find(&self.model, &self.triangles, self.time, &mut fresh);
        let pose = timed(&mut report.stages.pose, || {
            let mut pose = pose::at(&self.model, self.time, h);
            if let Some(c) = &self.model.collision {
                tangles.push(&self.model, c.thickness, &mut pose);
            }
            pose
        });
        let n = self.model.particle_count();
        let contacts = timed(&mut report.stages.detect, || {
            let c = detect::contacts(
                &self.model,
                &self.triangles,
                &self.edges,
                &start,
                &pose,
                &self.normal_force,
                &|ids| self.seams.exempt(ids) || tangles.exempt(ids, n),
                &mut self.trees.detect,
                (self.next_pairs.as_ref())
                    .filter(|(x, _)| *x == start.x0)
                    .map(|(_, c)| c),
            );
            self.system.use_contacts(&c.forces());
            c
        });
        let repulsions = contacts.repulsions.as_ref();
        let contact_forces = contacts.forces();
        report.self_contacts = repulsions.map_or(0, |r| r.stencils.len());
        report.proximity_candidates = contacts.candidates;
        report.broad_phase_builds = contacts.builds;

        // Newton iterations on v; x = x₀ + h v except at the first linearization point.
        let mut work = std::mem::take(&mut self.work);
        work.linearized.resize(n);
        work.solve.resize(n);
        work.dv.resize(n, Vec3::ZERO);
        let (mut x, mut v) = (start.x0.clone(), start.v0.clone());
        // where obstacle contact begins (no candidate had a normal force in the previous step)
        // and at an impact, the step is solved to FIRST_CONTACT_TOLERANCE or tighter
        let candidates = &contacts.obstacle;
        let first_contact = !candidates.is_empty()
            && (candidates.iter()).all(|c| self.normal_force[c.particle as usize] == 0.0);
        let gh = self.model.gravity.length() * h;
        // a released contact is held again when it would sink faster than this (m/s)
        let sink_tolerance = 1e-2 * gh;
        let impact = !candidates.is_empty() && {
            let e = obstacle::impact_energy(candidates, &start.v0, &self.model.mass, gh);
            e > 0.0 && e >= IMPACT_SHARE * start.ke0
        };
        let solver_settings = SolverSettings {
            tolerance: match first_contact || impact {
                true => self.settings.tolerance.min(FIRST_CONTACT_TOLERANCE),
                false => self.settings.tolerance,
            },
            ..self.settings
        };
        report.tolerance = solver_settings.tolerance;
        // the first solve's contacts: those that pushed at the end of the previous step and
        // those the warm start says would sink, but every candidate (less the predicted pulls)
        // where contact begins or at an impact
        let mut active = match first_contact || impact {
            true => ActiveSet::new(contacts.obstacle.clone()),
            false => ActiveSet::continuing(
                contacts.obstacle.clone(),
                &self.normal_force,
                &start.v0,
                &self.warm_start,
                sink_tolerance,
            ),
        };
        let newton = self.settings.newton_iterations;
        // where obstacle contact begins, a step whose linearization is far off iterates up to
        // this many times (MATH §10)
        let most = match first_contact {
            true => self.settings.max_newton_iterations.max(newton),
            false => newton,
        };
        let mut limit = newton;
        let potential = Potential {
            t0: self.time,
            mass: &self.model.mass,
            forces: &self.forces,
            contacts: &contact_forces,
            x0: &start.x0,
            v0: &start.v0,
            h,
        };
        let mut it = 0;
        while it < limit {
            timed(&mut report.stages.linearize, || {
                let iterate = Iterate {
                    t1: self.time + h,
                    x0: &start.x0,
                    v0: &start.v0,
                    x: &x,
                    v: &v,
                    h,
                };
                let (mass, forces) = (&self.model.mass, &self.forces[..]);
                linearize::run(
                    &mut self.system,
                    mass,
                    forces,
                    &contact_forces,
                    &iterate,
                    &mut work.linearized,
                );
            });
            let problem = Problem {
                pinned: &pose.pinned,
                pins: &pose.pins,
                v: &v,
                rhs: &work.linearized.rhs,
                warm: &self.warm_start,
                iteration: it,
                sink_tolerance,
            };
            solve::on_active_set(
                &self.system,
                &mut self.solvers,
                &solver_settings,
                &problem,
                &mut active,
                &mut work.dv,
                &mut work.solve,
                &mut report,
            )
            .map_err(|e| at.fail(e))?;
            report.newton_iterations = it + 1;
            // the last iteration so far: one more if its linearization is far off
            if it + 1 == limit && limit < most {
                let e = timed(&mut report.stages.update, || {
                    let springs = self.model.springs();
                    newton::linearization_error(springs, &x, &start.x0, &v, &work.dv, h)
                });
                if e > newton::RELINEARIZE_STRAIN {
                    limit += 1;
                }
            }
            let outcome = timed(&mut report.stages.update, || {
                newton::update(&potential, &mut x, &mut v, &work.dv, it, limit, gh)
            });
            it += 1;
            match outcome {
                Outcome::Continue => {}
                Outcome::Converged => break,
                Outcome::NonFinite(p) => {
                    let name = guard::particle_name(&self.model, p);
                    return Err(at.fail(format!("non-finite position or velocity at {name}")));
                }
            }
        }
        let (held, impulse) = active.held();
        report.obstacle_contacts = held.len();

        let mut untangled = None;
        if let Some(c) = &self.model.collision {
            timed(&mut report.stages.friction, || {
                friction::run(
                    &self.model,
                    &pose.pinned,
                    c,
                    repulsions,
                    &held,
                    &impulse,
                    &start.x0,
                    h,
                    &mut x,
                    &mut v,
                )
            });
        }
        report.strain_over = timed(&mut report.stages.strain, || {
            let (limits, mass) = (&self.strain_limits, &self.model.mass);
            strain::run(limits, mass, &pose.pinned, h, &mut x, &mut v)
        });
        if let Some(c) = &self.model.collision {
            let r = timed(&mut report.stages.failsafe, || {
                failsafe::run(
                    &self.model,
                    c,
                    &self.triangles,
                    &self.edges,
                    &pose,
                    &|ids| self.seams.exempt(ids) || tangles.exempt(ids, n),
                    &self.seam_crossings,
                    &start.x0,
                    &mut x,
                    &mut v,
                    &mut self.trees.failsafe,
                )
            })
            .map_err(|e| at.fail(e))?;
            self.next_pairs = r.pairs.map(|p| (x.clone(), p));
            report.ccd_hits = r.ccd_hits;
            report.ccd_candidates = r.candidates;
            report.ccd_rounds = r.rounds;
            report.broad_phase_builds += r.builds;
            let t1 = self.time + h;
            untangled = Some(tangles.update(&self.model, &self.triangles, &x, t1, c.thickness));
        }

        let t = std::time::Instant::now();
        let energies = guard::Energies {
            ke0: start.ke0,
            // the air, like a moving obstacle, can bring the cloth to its speed
            surface_speed: (pose.surface_speed)
                .max(crate::forces::wind::speed_bound(&self.model.wind)),
            h,
        };
        if let Some(why) = guard::blow_up(&self.model, &v, &energies, || {
            potential.stored_energy(&start.x0) + pressure_allowance(&self.model, &start.x0, h)
        }) {
            return Err(at.fail(why));
        }
        for i in 0..n {
            self.warm_start[i] = v[i] - start.v0[i];
        }
        self.normal_force.fill(0.0);
        for (ct, l) in held.iter().zip(&impulse) {
            self.normal_force[ct.particle as usize] = l.max(0.0) / h;
        }
        self.model.x = x;
        self.model.v = v;
        if let Some(t) = untangled {
            self.tangles = t;
        }
        self.time += h;
        self.steps += 1;
        report.stages.commit += t.elapsed().as_secs_f64();
        self.work = work;
        report.sum_up(self.model.collision.is_some());
        Ok(report)
    }

    /// Gives the multigrid its reference (once, at the first step): the base system matrix
    /// for step `h` at the state the simulation was created in, filtered by the pins. The
    /// hierarchy's structure follows that matrix's strong couplings; since it depends only on
    /// the scene and `h`, a run resumed from a saved state builds the same hierarchy.
    fn reference(&mut self, h: f64) {
        if self.settings.preconditioner != Preconditioner::Multigrid
            || self.solvers.pcg.multigrid().has_reference()
        {
            return;
        }
        let mut r = self.system.base_pattern();
        let (x, v) = &self.initial;
        system::assemble_base(&self.model.mass, &self.forces, 0.0, x, v, h, &mut r);
        let pins = crate::constraints::pins::filter(&self.model.pinned);
        let mg = self.solvers.pcg.multigrid();
        mg.params.strength = MULTIGRID_STRENGTH;
        mg.set_reference(r, pins);
    }

    /// The model being simulated (its particles' current state included).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The step settings the simulation was built with.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Current positions of every particle (cloths in order, each its vertices in order), m.
    pub fn positions(&self) -> &[Vec3] {
        &self.model.x
    }

    /// Current velocities, m/s.
    pub fn velocities(&self) -> &[Vec3] {
        &self.model.v
    }

    /// Sets every particle's position (for control from a front end between steps). An error,
    /// changing nothing, when the length differs from the particle count or a value is not
    /// finite. Pinned particles move too: a pin holds a particle where it is.
    pub fn set_positions(&mut self, x: &[Vec3]) -> Result<()> {
        crate::model::check_state("positions", x, self.model.particle_count())?;
        self.model.x.copy_from_slice(x);
        Ok(())
    }

    /// Sets every particle's velocity; as [`Simulation::set_positions`].
    pub fn set_velocities(&mut self, v: &[Vec3]) -> Result<()> {
        crate::model::check_state("velocities", v, self.model.particle_count())?;
        self.model.v.copy_from_slice(v);
        Ok(())
    }

    /// Replaces the motion of obstacle `index` from now on (obstacles are posed at every
    /// step from their motion, so this takes effect at the next step). An error when there is
    /// no such obstacle or the motion is not finite. While a motion differs from the scene's,
    /// a [`Simulation::snapshot`] holds every collider's and handle's motion, so a resumed run
    /// goes on with them.
    pub fn set_obstacle_motion(
        &mut self,
        index: usize,
        motion: crate::animation::Motion,
    ) -> Result<()> {
        let o = checked(&mut self.model.obstacles, index, "collider", &motion)?;
        o.collider.motion = motion;
        Ok(())
    }

    /// The pre-roll: `steps` steps of `h` ending at `t = 0`, from `t = -steps·h`, during which
    /// every prescribed motion holds its pose at 0 at rest ([`crate::animation::motion`]) and
    /// cloth that starts tangled is untangled ([`tangles`], [`Simulation::tangled`]); then
    /// the clock is set to exactly 0 and the step count to 0, so frame 0 is the settled state.
    /// Nothing happens for 0 steps. On a failed step the error is returned and the simulation
    /// is left at the last good step.
    pub fn preroll(&mut self, steps: usize, h: f64) -> Result<()> {
        if steps == 0 {
            return Ok(());
        }
        self.time = -(steps as f64) * h;
        for _ in 0..steps {
            self.step(h)?;
        }
        self.time = 0.0;
        self.steps = 0;
        Ok(())
    }

    /// Replaces the motion of handle `index` (in the order of [`Model::handles`]: the cloths'
    /// handles in scene order) from now on; it takes effect at the next step, whose end
    /// positions the new motion gives. An error when there is no such handle or the motion is
    /// not finite. A snapshot then holds the motions, as after
    /// [`Simulation::set_obstacle_motion`].
    pub fn set_handle_motion(
        &mut self,
        index: usize,
        motion: crate::animation::Motion,
    ) -> Result<()> {
        let h = checked(&mut self.model.handles, index, "handle", &motion)?;
        h.motion = motion;
        Ok(())
    }

    /// The forces acting on the model.
    pub fn forces(&self) -> &[Box<dyn Force>] {
        &self.forces
    }

    /// The system matrix of the last Newton iteration (on one pattern, merged on request when
    /// the step had contacts outside the model's pattern).
    pub fn matrix(&self) -> &BlockMatrix {
        self.system.merged()
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
        let (x, v) = (&self.model.x, &self.model.v);
        self.system.use_contacts(&[]);
        let at = Linearization {
            t: self.time,
            x,
            v,
            matrix: (-h * h, -h),
            // unused: only the matrix is assembled
            product: (0.0, 0.0),
            w: v,
        };
        self.system
            .assemble(&self.model.mass, &self.forces, &at, &[], None);
    }

    /// What is still tangled: free cloth vertices being pushed out of colliders and crossed
    /// cloth triangle pairs being let through the fail-safe ([`tangles`]). Before the first
    /// step, what the first step will find (a fresh simulation's starting tangles); after a
    /// pre-roll, what remains of them.
    pub fn tangled(&self) -> Tangled {
        let mut fresh = None;
        (self.tangles)
            .or_find(&self.model, &self.triangles, self.time, &mut fresh)
            .counts()
    }

    /// The cloth–cloth contacts at the current state: pairs of cloth primitives (vertex and
    /// triangle, or two edges) that share no vertex, are not exempt (a seam's neighbourhood, a
    /// starting tangle) and are closer than `collision.thickness`, so that the repulsion pushes
    /// them apart at the next step; `None` without self-collision. Returns their count and the
    /// distance of the closest. At the start of a run these are a thickness too large for the
    /// mesh (it exceeds the distance from a vertex to the triangles beyond its neighbours, about
    /// 0.7 edge lengths on a grid) or layers placed closer than it: the cloth then pushes itself
    /// apart from the first step.
    pub fn close_pairs(&self) -> Option<(usize, f64)> {
        let c = self.model.collision.as_ref().filter(|c| c.self_collision)?;
        let mut fresh = None;
        let tangles = (self.tangles).or_find(&self.model, &self.triangles, self.time, &mut fresh);
        Some(self.close_pairs_with(tangles, c.thickness))
    }

    /// [`Simulation::close_pairs`] with self-collision on, the starting tangles already found.
    fn close_pairs_with(&self, tangles: &tangles::Tangles, thickness: f64) -> (usize, f64) {
        let n = self.model.particle_count();
        let pose = pose::at(&self.model, self.time, 0.0);
        let (x, tris, edges) = (&self.model.x, &self.triangles, &self.edges);
        let cand = crate::collision::broad_phase::candidates(x, x, tris, edges, thickness);
        let exempt = |ids: &[u32; 4]| self.seams.exempt(ids) || tangles.exempt(ids, n);
        let close = detect::self_stencils(x, tris, edges, &cand, thickness, &pose, &exempt);
        let closest = close.iter().map(|s| s.dist).fold(f64::INFINITY, f64::min);
        (close.len(), closest)
    }

    /// What a run should say about the current state before stepping from it
    /// ([`StartCheck::warnings`]): its intersections ([`Simulation::intersections`]), what the
    /// steps untangle ([`Simulation::tangled`]) and the close pairs
    /// ([`Simulation::close_pairs`]), from one search for the starting tangles; `None` without
    /// collisions.
    pub fn start_check(&self) -> Option<StartCheck> {
        let c = self.model.collision.as_ref()?;
        let mut fresh = None;
        let tangles = (self.tangles).or_find(&self.model, &self.triangles, self.time, &mut fresh);
        // tangles found now, with self-collision, list the intersecting pairs the checker counts
        // (the same search); found at an earlier step, they are what is left of those
        // after steps (a pre-roll) the crossings are listed again, to tell those by a seam
        let settled = self.tangles.found;
        let (intersecting_pairs, by_seam) = match settled || !c.self_collision {
            false => (tangles.crossings.len(), 0),
            true => {
                let pairs = self.sewn_intersecting_pairs();
                let seam = |t: u32| {
                    self.triangles[t as usize]
                        .iter()
                        .any(|&p| self.seams.holds(p))
                };
                let by_seam = match settled {
                    true => pairs.iter().filter(|&&[a, b]| seam(a) || seam(b)).count(),
                    false => 0,
                };
                (pairs.len(), by_seam)
            }
        };
        Some(StartCheck {
            intersecting_pairs,
            inside: self.penetrations(),
            tangled: tangles.counts(),
            close_pairs: (c.self_collision && !settled)
                .then(|| self.close_pairs_with(tangles, c.thickness)),
            thickness: c.thickness,
            settled,
            by_seam,
        })
    }

    /// Cloth triangle pairs that intersect and particles inside solid obstacles or closed
    /// meshes, at the current state (what `drapery check` counts). A starting state with
    /// intersections is untangled by the steps ([`Simulation::tangled`]).
    pub fn intersections(&self) -> (usize, usize) {
        (self.self_intersections(), self.penetrations())
    }

    /// The first count of [`Simulation::intersections`].
    fn self_intersections(&self) -> usize {
        self.sewn_intersecting_pairs().len()
    }

    /// The intersecting cloth triangle pairs `drapery check` counts: the two ends of a stitched
    /// pair count as one vertex (a closed seam's sides touch).
    fn sewn_intersecting_pairs(&self) -> Vec<[u32; 2]> {
        let sewn: Vec<[u32; 2]> = self.model.stitches.iter().map(|s| [s.a, s.b]).collect();
        crate::collision::check::sewn_intersecting_pairs(&self.model.x, &self.triangles, &sewn)
    }

    /// The second count of [`Simulation::intersections`].
    fn penetrations(&self) -> usize {
        let colliders: Vec<_> = (self.model.obstacles.iter())
            .map(|o| o.collider.clone())
            .collect();
        crate::collision::check::count_penetrations(&self.model.x, &colliders, self.time, 0.0)
    }
}

/// Item `index` of `items` (`what[index]` in errors) when it exists and `motion` is finite.
fn checked<'a, T>(
    items: &'a mut [T],
    index: usize,
    what: &str,
    motion: &crate::animation::Motion,
) -> Result<&'a mut T> {
    let (n, field) = (items.len(), format!("{what}[{index}]"));
    if index >= n {
        return Err(crate::Error::field(
            field,
            format!("no such {what}: the scene has {n}"),
        ));
    }
    motion.validate(&field)?;
    Ok(&mut items[index])
}

/// The forces of a model: gravity, then springs and spring damping (the springs with a
/// nonzero coefficient), then the stitches if any, then air drag if any particle has it.
/// What pressure adds to the blow-up test's stored energy (docs/MATH.md §23): in place of its
/// energy `-pV` (negative, and no potential at all on an open cloth), the kinetic energy its
/// impulse over one step gives from rest, `Σ |h f_i|² / (2 m_i)`.
fn pressure_allowance(model: &Model, x: &[Vec3], h: f64) -> f64 {
    let (triangles, p) = model.pressure_triangles();
    if triangles.is_empty() {
        return 0.0;
    }
    let force = Pressure {
        triangles,
        p,
        sums: Default::default(),
    };
    let mut f = vec![Vec3::ZERO; x.len()];
    force.add_force(&State { t: 0.0, x, v: x }, &mut f);
    let impulse: f64 = (f.iter().zip(&model.mass))
        .map(|(f, m)| (h * *f).length_squared() / (2.0 * m))
        .sum();
    impulse - force.energy(0.0, x)
}

fn model_forces(model: &Model, settings: &SolverSettings) -> Vec<Box<dyn Force>> {
    let s = &model.springs;
    let stiff: Vec<usize> = (0..s.len()).filter(|&k| s.stiffness[k] > 0.0).collect();
    let damped: Vec<usize> = (0..s.len()).filter(|&k| s.damping[k] > 0.0).collect();
    let mut forces: Vec<Box<dyn Force>> = vec![Box::new(Gravity::new(&model.mass, model.gravity))];
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
    forces.extend(crate::forces::shell::forces(model));
    if !model.stitches.is_empty() {
        let st = &model.stitches;
        forces.push(Box::new(Stitches {
            a: st.iter().map(|p| p.a).collect(),
            b: st.iter().map(|p| p.b).collect(),
            k: st.iter().map(|p| p.stiffness).collect(),
            c: st.iter().map(|p| p.damping).collect(),
            sums: Default::default(),
        }));
    }
    if model.drag.iter().any(|&c| c > 0.0) {
        forces.push(Box::new(AirDrag {
            c: model.drag.clone(),
        }));
    }
    if !model.wind.is_empty() {
        forces.push(Box::new(WindForce::new(
            model.triangles(),
            model.wind.clone(),
        )));
    }
    let (triangles, p) = model.pressure_triangles();
    if !triangles.is_empty() {
        forces.push(Box::new(Pressure {
            triangles,
            p,
            sums: Default::default(),
        }));
    }
    forces
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_state_can_be_set_between_steps_but_only_whole_and_finite() {
        let mut sim =
            Simulation::new(testing::sheet(3, 0.5, vec![0]), SolverSettings::default()).unwrap();
        let n = sim.positions().len();
        let e = sim.set_positions(&vec![Vec3::ZERO; n - 1]).unwrap_err();
        assert_eq!(e.to_string(), "positions: 8 values given for 9 particles");
        let mut v = sim.velocities().to_vec();
        v[4].z = f64::NAN;
        let e = sim.set_velocities(&v).unwrap_err().to_string();
        assert!(e.starts_with("velocities: particle 4 is not finite"), "{e}");
        let x: Vec<Vec3> = sim.positions().iter().map(|p| *p + Vec3::Y).collect();
        sim.set_positions(&x).unwrap();
        sim.step(0.01).unwrap();
        // the pinned particle stays where it was put
        assert_eq!(sim.positions()[0], x[0]);
        assert_eq!((sim.steps(), sim.time()), (1, 0.01));
    }

    /// On a grid of spacing `h` split into right triangles, the nearest primitive sharing no
    /// vertex with a vertex is a triangle across the opposite edge of one of its triangles, at
    /// the distance of a vertex to a diagonal, `h / √2`: a thickness below it starts with no
    /// close pair, one above it with many, the closest that far apart; two layers placed closer
    /// than the thickness are close pairs too, and none without self-collision.
    #[test]
    fn close_pairs_at_the_start_follow_the_thickness_and_the_spacing() {
        let scene = |thickness: f64, layers: &str, self_collision: bool| {
            let text = format!(
                "[simulation]\nduration = 0.1\ndt = 0.01\nframe_rate = 10\n\
                 [collision]\nthickness = {thickness}\nself_collision = {self_collision}\n\
                 [[cloth]]\nname = \"a\"\ndensity = 0.1\n\
                 grid = {{ size = [0.5, 0.5], resolution = [11, 11], normal = [0.0, 1.0, 0.0] }}\n{layers}"
            );
            crate::scene::Scene::from_str(&text, std::path::Path::new("close.toml"))
                .unwrap()
                .build()
                .unwrap()
                .close_pairs()
        };
        let diagonal = 0.05 / 2f64.sqrt();
        assert_eq!(scene(0.99 * diagonal, "", true).map(|c| c.0), Some(0));
        let (count, closest) = scene(1.01 * diagonal, "", true).unwrap();
        assert!(count > 100, "{count}");
        assert!((closest - diagonal).abs() < 1e-12, "{closest}");
        let second = "[[cloth]]\nname = \"b\"\ndensity = 0.1\n\
             grid = { size = [0.5, 0.5], resolution = [11, 11], center = [0.0, 0.003, 0.0], normal = [0.0, 1.0, 0.0] }\n";
        let (count, closest) = scene(0.005, second, true).unwrap();
        assert!(count > 100, "{count}");
        assert!((closest - 0.003).abs() < 1e-12, "{closest}");
        assert_eq!(scene(0.005, second, false), None);
    }
}
