//! What one step did: counts, and the time spent in each stage.

use std::time::Instant;

/// Seconds spent in each stage of [`crate::Simulation::step`], in the order they run
/// (linearize, constrain and solve once per Newton iteration, and once per contact round for
/// the last two).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Checks of the starting state and the step size.
    pub guard: f64,
    /// Colliders and pin targets over the step, and the multigrid's reference.
    pub pose: f64,
    /// Obstacle contacts and self-contact stencils at the start of the step.
    pub detect: f64,
    /// Forces, system matrix and right-hand side.
    pub linearize: f64,
    /// The velocity filter and prescribed changes (pins, held obstacle contacts).
    pub constrain: f64,
    /// Linear solves and the obstacle active set's updates.
    pub solve: f64,
    /// Line search and position update of each Newton iteration.
    pub update: f64,
    /// Cloth–cloth and obstacle friction.
    pub friction: f64,
    /// The strain limits' correction.
    pub strain: f64,
    /// The continuous collision fail-safe.
    pub failsafe: f64,
    /// Blow-up test and warm start.
    pub commit: f64,
}

impl StageTimes {
    /// The stages' names, in the order of [`StageTimes::fields`].
    pub const NAMES: [&'static str; 11] = [
        "guard",
        "pose",
        "detect",
        "linearize",
        "constrain",
        "solve",
        "update",
        "friction",
        "strain",
        "failsafe",
        "commit",
    ];

    /// Every stage's seconds, in the order they run.
    pub fn fields(&self) -> [f64; 11] {
        [
            self.guard,
            self.pose,
            self.detect,
            self.linearize,
            self.constrain,
            self.solve,
            self.update,
            self.friction,
            self.strain,
            self.failsafe,
            self.commit,
        ]
    }

    /// Every stage's seconds, mutably, in the order of [`StageTimes::fields`].
    pub fn fields_mut(&mut self) -> [&mut f64; 11] {
        [
            &mut self.guard,
            &mut self.pose,
            &mut self.detect,
            &mut self.linearize,
            &mut self.constrain,
            &mut self.solve,
            &mut self.update,
            &mut self.friction,
            &mut self.strain,
            &mut self.failsafe,
            &mut self.commit,
        ]
    }

    /// The sum of every stage.
    pub fn total(&self) -> f64 {
        self.fields().iter().sum()
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
    /// Of the linear solves, the *rough* rounds of the obstacle active set: solved only to
    /// `1e-4` in a step solved tighter, because the round before flipped many contacts
    /// (docs/MATH.md §14).
    pub rough_solves: usize,
    /// Preconditioner set-ups (multigrid refreshes) over the linear solves: a solve whose
    /// initial guess already met the tolerance needs none.
    pub preconditioner_setups: usize,
    /// Final relative residual of the last PCG solve (0 with the direct solver).
    pub residual: f64,
    /// The PCG tolerance the step's solves used: the solver's, or at most
    /// [`crate::step::FIRST_CONTACT_TOLERANCE`] at a first obstacle contact or an impact
    /// ([`crate::step::IMPACT_SHARE`]).
    pub tolerance: f64,
    /// Seconds spent assembling forces and matrices (the linearize stage).
    pub assembly_seconds: f64,
    /// Seconds spent in the linear solver and its constraints (constrain and solve stages).
    pub solve_seconds: f64,
    /// Seconds spent finding contacts, in friction and in the collision fail-safe (detect,
    /// friction and failsafe stages; only with collisions on).
    pub collision_seconds: f64,
    /// Time of every stage.
    pub stages: StageTimes,
    /// Particles held against obstacles in the solve.
    pub obstacle_contacts: usize,
    /// Cloth–cloth repulsion stencils in the solve.
    pub self_contacts: usize,
    /// Pairs the continuous collision fail-safe had to stop.
    pub ccd_hits: usize,
    /// Candidate pairs of the self-contacts at the start of the step (the broad phase's, or
    /// those the previous step's fail-safe passed on; the narrow phase keeps those closer than
    /// the thickness as stencils).
    pub proximity_candidates: usize,
    /// Candidate pairs whose times of impact the fail-safe tested, over its rounds.
    pub ccd_candidates: usize,
    /// Rounds of the fail-safe's continuous collision detection.
    pub ccd_rounds: usize,
    /// Broad-phase builds (moving boxes and their hierarchies): the detect stage's (none when
    /// the previous fail-safe passed its pairs on) and the fail-safe's.
    pub broad_phase_builds: usize,
    /// Edges left longer than their strain limit allows: the correction's sweeps ran out
    /// because pins or handles hold them apart (0 without strain limits).
    pub strain_over: usize,
}

impl StepReport {
    /// Fills the summary times from the stage times.
    pub(crate) fn sum_up(&mut self, collisions: bool) {
        let s = &self.stages;
        self.assembly_seconds = s.linearize;
        self.solve_seconds = s.constrain + s.solve;
        self.collision_seconds = if collisions {
            s.detect + s.friction + s.failsafe
        } else {
            0.0
        };
    }
}

/// Runs `f`, adding its wall time to `*seconds`.
pub(crate) fn timed<T>(seconds: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = f();
    *seconds += t.elapsed().as_secs_f64();
    out
}
