//! Obstacle contacts as constraints of the solve, on an active set (docs/MATH.md §14).
//!
//! [`find`] lists the candidates at the start of a step: free particles close to an obstacle
//! and not moving away from it fast enough. A held candidate prescribes the particle's normal
//! velocity (so it ends the step at the thickness) and leaves its tangential velocity free.
//! [`ActiveSet`] decides which candidates are held: a contact whose impulse would pull is
//! released, a released one whose particle would sink is held again, and the system is solved
//! again. What the last round holds stays for the step (friction uses those contacts and
//! impulses); the next step's first solve holds those of them that pushed, and the candidates
//! its initial guess says would sink ([`ActiveSet::continuing`]), unless contact begins there
//! or it is an impact ([`ActiveSet::new`] and its prediction).

use super::Constraints;
use crate::collision::settings::Obstacle;
use crate::linalg::split::Split;
use crate::math::Vec3;
use rayon::prelude::*;

/// A particle held against an obstacle during the solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleContact {
    /// Particle index.
    pub particle: u32,
    /// Unit normal pointing from the obstacle to the particle.
    pub normal: Vec3,
    /// Normal velocity the particle must have at the end of the step, m/s.
    pub normal_velocity: f64,
    /// Velocity of the obstacle surface at the contact.
    pub surface_velocity: Vec3,
    /// Coulomb coefficient.
    pub friction: f64,
    /// Coefficient of the friction in the solve, N·s/m ([`crate::forces::ObstacleFrictions`]):
    /// lagged Coulomb from the previous step's normal force, 0 without one.
    pub damping: f64,
}

impl ObstacleContact {
    /// Whether a particle at velocity `v` would sink: its normal velocity below the prescribed
    /// one by more than `tolerance` (a released contact that does is held again).
    fn sinks(&self, v: Vec3, tolerance: f64) -> bool {
        self.normal.dot(v) < self.normal_velocity - tolerance
    }
}

/// The closest contact of `p` with `o` at time `t`: (distance on the particle's side, unit
/// normal toward the particle, surface velocity).
fn contact(o: &Obstacle, p: Vec3, t: f64) -> (f64, Vec3, Vec3) {
    let c = o.collider.closest(p, t);
    if !o.collider.is_solid() {
        let d = p - c.point;
        let l = d.length();
        let n = if l > 1e-12 { d / l } else { c.normal * c.side };
        (l, n, c.velocity_at_point)
    } else {
        (c.signed_distance, c.normal, c.velocity_at_point)
    }
}

/// Contacts at the start of a step: free particles within twice the `thickness` of an obstacle
/// whose normal velocity relative to it is below what would bring them to the thickness in one
/// step, plus `slack` (use `|g| h`: gravity can turn a particle around within the step, and
/// rounding must not drop a particle resting exactly at the thickness). The constraint
/// prescribes exactly that normal velocity; the [`ActiveSet`] releases every contact whose
/// impulse would pull, so a particle only feels the obstacle when it would otherwise end closer
/// than the thickness. Resting contact therefore holds every step (no alternating contact and
/// free flight), which is what lets static friction hold. The deepest obstacle wins when there
/// are several.
#[allow(clippy::too_many_arguments)]
pub fn find(
    x: &[Vec3],
    v: &[Vec3],
    pinned: &[bool],
    obstacles: &[Obstacle],
    t: f64,
    h: f64,
    thickness: f64,
    slack: f64,
) -> Vec<ObstacleContact> {
    if obstacles.is_empty() {
        return Vec::new();
    }
    let per: Vec<Option<ObstacleContact>> = (0..x.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            if pinned[i] {
                return None;
            }
            let mut best: Option<(f64, ObstacleContact)> = None;
            for o in obstacles {
                let (d, n, vs) = contact(o, x[i], t);
                if d < 2.0 * thickness && best.as_ref().is_none_or(|(bd, _)| d < *bd) {
                    let target = n.dot(vs) + (thickness - d) / h;
                    if n.dot(v[i]) <= target + slack {
                        best = Some((
                            d,
                            ObstacleContact {
                                particle: i as u32,
                                normal: n,
                                normal_velocity: target,
                                surface_velocity: vs,
                                friction: o.friction,
                                damping: 0.0,
                            },
                        ));
                    }
                }
            }
            best.map(|(_, c)| c)
        })
        .collect();
    per.into_iter().flatten().collect()
}

/// The kinetic energy of the candidates' approach, J: `½ Σ m_i (u_i − n_i·v_i − slack)₊²`
/// over the candidates, where `u_i` is the normal velocity the contact prescribes and `slack`
/// a speed the approach may have without counting (use `|g| h`: a particle resting on an
/// obstacle gains that much toward it every step). Summed in candidate order.
pub fn impact_energy(candidates: &[ObstacleContact], v: &[Vec3], mass: &[f64], slack: f64) -> f64 {
    candidates
        .iter()
        .map(|c| {
            let i = c.particle as usize;
            let approach = (c.normal_velocity - c.normal.dot(v[i]) - slack).max(0.0);
            0.5 * (mass[i] * (approach * approach))
        })
        .sum()
}

/// Which candidate contacts are held, and the normal impulse each one's constraint exerted in
/// the last solve.
#[derive(Clone, Debug, Default)]
pub struct ActiveSet {
    candidates: Vec<ObstacleContact>,
    active: Vec<bool>,
    impulse: Vec<f64>,
    /// Whether the first solve's set is still to be predicted from the initial guess
    /// ([`ActiveSet::predict`]): set by [`ActiveSet::new`], not by [`ActiveSet::continuing`].
    guess: bool,
}

impl ActiveSet {
    /// Every candidate held, no impulse yet; [`ActiveSet::needs_prediction`] is true.
    pub fn new(candidates: Vec<ObstacleContact>) -> ActiveSet {
        let n = candidates.len();
        ActiveSet {
            candidates,
            active: vec![true; n],
            impulse: vec![0.0; n],
            guess: true,
        }
    }

    /// The set that goes on from the previous step, without [`ActiveSet::predict`]'s product
    /// (`needs_prediction` is false): a candidate is held when its particle's normal force at
    /// the end of that step, `normal_force[particle]`, is positive, or when the first solve's
    /// initial guess says it would sink: its velocity `v + dv` (`v` the step's start, `dv` the
    /// guess, the previous step's change) below the prescribed normal velocity by more than
    /// `sink_tolerance`, the re-hold test of [`ActiveSet::update`]. Where contact goes on, the
    /// previous step's set is a better first guess than every candidate held and the
    /// prediction: on spin-129 the rounds then took 4 011 CG iterations over 200 steps instead
    /// of 5 554, and the sinking ones held up front saved a further solve every second step at
    /// 290² (BENCHMARKS.md, twenty-seventh and twenty-eighth sessions). Not where contact
    /// begins: there no particle had a normal force and most candidates would start released
    /// (use [`ActiveSet::new`]).
    pub fn continuing(
        candidates: Vec<ObstacleContact>,
        normal_force: &[f64],
        v: &[Vec3],
        dv: &[Vec3],
        sink_tolerance: f64,
    ) -> ActiveSet {
        let active = (candidates.iter())
            .map(|c| {
                let i = c.particle as usize;
                let pushed = normal_force.get(i).is_some_and(|&f| f > 0.0);
                let guess = v[i] + dv.get(i).copied().unwrap_or(Vec3::ZERO);
                pushed || c.sinks(guess, sink_tolerance)
            })
            .collect();
        ActiveSet {
            impulse: vec![0.0; candidates.len()],
            candidates,
            active,
            guess: false,
        }
    }

    /// Whether the first solve's set should be predicted from the initial guess first.
    pub fn needs_prediction(&self) -> bool {
        self.guess && !self.candidates.is_empty()
    }

    /// How many candidates there are.
    pub fn len(&self) -> usize {
        self.candidates.len()
    }

    /// True when there are no candidates.
    pub fn is_empty(&self) -> bool {
        self.candidates.is_empty()
    }

    /// Writes the held contacts into `c` (after the pins), from the current velocities `v`.
    pub fn hold(&self, v: &[Vec3], c: &mut Constraints) {
        for (ct, _) in self
            .candidates
            .iter()
            .zip(&self.active)
            .filter(|(_, a)| **a)
        {
            let i = ct.particle as usize;
            c.hold_normal(i, ct.normal, ct.normal_velocity, v[i]);
        }
    }

    /// Before the first solve of a step: predicts from the initial guess `dv` which contacts
    /// would pull (`n·(A w - rhs) < 0` for `w = z + S dv`), and releases those whose guessed
    /// velocity leaves the surface anyway. `w` is scratch.
    pub fn predict(
        &mut self,
        a: Split,
        rhs: &[Vec3],
        v: &[Vec3],
        dv: &[Vec3],
        c: &mut Constraints,
        w: &mut [Vec3],
    ) {
        for i in 0..w.len() {
            w[i] = c.z[i] + c.filter[i] * dv[i];
        }
        for (ct, act) in self.candidates.iter().zip(self.active.iter_mut()) {
            let i = ct.particle as usize;
            let pulls = ct.normal.dot(a.row_product(i, w) - rhs[i]) < 0.0;
            let leaves = ct.normal.dot(v[i] + dv[i]) >= ct.normal_velocity;
            if pulls && leaves {
                *act = false;
                c.release(i);
            }
        }
    }

    /// After a solve: each candidate's normal impulse `n·(A dv - rhs)` (scaled by `1/h`, the
    /// force the constraint exerted), from the candidates' rows of `A dv` only.
    pub fn measure(&mut self, a: Split, rhs: &[Vec3], dv: &[Vec3]) {
        self.candidates
            .par_iter()
            .zip(self.impulse.par_iter_mut())
            .with_min_len(256)
            .for_each(|(ct, l)| {
                let i = ct.particle as usize;
                *l = ct.normal.dot(a.row_product(i, dv) - rhs[i]);
            });
    }

    /// Flips held contacts that pull (beyond a relative `1e-9` of the largest held impulse) and
    /// released ones whose solved normal velocity `n·(v + dv)` is below the prescribed one by
    /// more than `sink_tolerance`. Returns how many flipped.
    pub fn update(&mut self, v: &[Vec3], dv: &[Vec3], sink_tolerance: f64) -> usize {
        let scale = self
            .candidates
            .iter()
            .zip(&self.impulse)
            .zip(&self.active)
            .filter(|(_, a)| **a)
            .fold(0.0f64, |m, ((_, l), _)| m.max(l.abs()));
        let mut flipped = 0;
        for ((ct, l), a) in self
            .candidates
            .iter()
            .zip(&self.impulse)
            .zip(self.active.iter_mut())
        {
            let i = ct.particle as usize;
            let flip = if *a {
                *l < -1e-9 * scale
            } else {
                ct.sinks(v[i] + dv[i], sink_tolerance)
            };
            if flip {
                *a = !*a;
                flipped += 1;
            }
        }
        flipped
    }

    /// The held contacts and their impulses.
    pub fn held(&self) -> (Vec<ObstacleContact>, Vec<f64>) {
        self.candidates
            .iter()
            .zip(&self.impulse)
            .zip(&self.active)
            .filter(|(_, a)| **a)
            .map(|((c, l), _)| (*c, *l))
            .unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[allow(unused_imports)]
    use crate::collision::colliders::{
        Capsule, Collider, Cuboid, Motion, Plane, Shape, Sphere, TriangleMesh,
    };
    use crate::math::Mat3;

    fn ground() -> Obstacle {
        Obstacle {
            name: None,
            collider: Collider::fixed(Shape::Plane(Plane {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            })),
            friction: 0.5,
        }
    }

    #[test]
    fn candidates_are_the_close_free_particles_not_leaving_fast_enough() {
        let (thickness, h) = (0.01, 0.01);
        let x = [
            Vec3::new(0.0, 0.005, 0.0), // inside the thickness, at rest
            Vec3::new(0.0, 0.015, 0.0), // within twice the thickness, falling
            Vec3::new(0.0, 0.015, 0.0), // within twice, leaving fast
            Vec3::new(0.0, 0.5, 0.0),   // far
            Vec3::new(0.0, 0.001, 0.0), // pinned
        ];
        let v = [
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::ZERO,
        ];
        let pinned = [false, false, false, false, true];
        let c = find(&x, &v, &pinned, &[ground()], 0.0, h, thickness, 0.0);
        let ids: Vec<u32> = c.iter().map(|c| c.particle).collect();
        assert_eq!(ids, vec![0, 1]);
        // the prescribed normal velocity brings the particle to the thickness in one step
        for ct in &c {
            let i = ct.particle as usize;
            assert!((x[i].y + h * ct.normal_velocity - thickness).abs() < 1e-15);
            assert_eq!((ct.normal, ct.friction), (Vec3::Y, 0.5));
        }
    }

    #[test]
    fn only_the_approach_beyond_one_step_of_gravity_counts_as_impact() {
        let (thickness, h, g) = (0.01, 0.01, 9.81);
        let x = [
            Vec3::new(0.0, 0.01, 0.0), // resting at the thickness, gravity's one step of speed
            Vec3::new(0.0, 0.012, 0.0), // falling at 2 m/s
            Vec3::new(0.0, 0.0105, 0.0), // sliding along the ground
        ];
        let v = [
            Vec3::new(0.0, -g * h, 0.0),
            Vec3::new(0.3, -2.0, 0.0),
            Vec3::new(1.0, -0.0, 0.0),
        ];
        let mass = [0.5, 0.25, 2.0];
        let c = find(&x, &v, &[false; 3], &[ground()], 0.0, h, thickness, g * h);
        assert_eq!(c.len(), 3);
        // the falling particle must reach u = (thickness - y)/h = -0.2 m/s from -2 m/s: of that
        // 1.8 m/s approach, all but g h counts
        let e = impact_energy(&c, &v, &mass, g * h);
        let want = 0.5 * 0.25 * (1.8 - g * h) * (1.8 - g * h);
        assert!((e - want).abs() < 1e-12 * want, "{e} {want}");
        assert_eq!(impact_energy(&c[..1], &v, &mass, g * h), 0.0);
        assert_eq!(impact_energy(&c[2..], &v, &mass, g * h), 0.0);
    }

    /// A contact of particle `i` against the ground, prescribing no normal velocity.
    fn ct(i: u32) -> ObstacleContact {
        ObstacleContact {
            particle: i,
            normal: Vec3::Y,
            normal_velocity: 0.0,
            surface_velocity: Vec3::ZERO,
            friction: 0.0,
            damping: 0.0,
        }
    }

    #[test]
    fn a_continuing_set_holds_the_candidates_that_pushed_or_would_sink_and_predicts_nothing() {
        // particle 3 pushed; 1, 0 and 4 had no force (0 and 4 are new); 2 pushed but is no
        // candidate now. With the guess `v + dv`, 4 would sink by 2 mm/s, 1 by 0.5 mm/s (within
        // the 1 mm/s tolerance), and 0 starts sinking but the guess turns it around.
        let force = [0.0, 0.0, 2.0, 0.5, 0.0];
        let v = [
            Vec3::new(0.0, -0.01, 0.0),
            Vec3::new(0.3, -0.0005, 0.0),
            Vec3::ZERO,
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, -0.001, 0.0),
        ];
        let dv = [
            Vec3::new(0.0, 0.02, 0.0),
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(0.0, -0.001, 0.0),
        ];
        let candidates = vec![ct(3), ct(1), ct(0), ct(4)];
        let set = ActiveSet::continuing(candidates, &force, &v, &dv, 1e-3);
        assert!(!set.needs_prediction());
        let mut c = Constraints::free(5);
        set.hold(&[Vec3::ZERO; 5], &mut c);
        let held: Vec<bool> = c.filter.iter().map(|f| *f != Mat3::IDENTITY).collect();
        assert_eq!(held, [false, false, false, true, true]);
        assert_eq!(set.held().0, vec![ct(3), ct(4)]);
        // a new set holds every candidate and is predicted first, unless it is empty
        let fresh = ActiveSet::new(vec![ct(3), ct(1)]);
        assert!(fresh.needs_prediction());
        assert_eq!(fresh.held().0.len(), 2);
        assert!(!ActiveSet::new(Vec::new()).needs_prediction());
    }

    #[test]
    fn a_contact_that_pulls_is_released_and_one_that_sinks_is_held_again() {
        let mut set = ActiveSet::new(vec![ct(0), ct(1)]);
        // identity matrix: the impulse of a contact is n·(dv - rhs)
        let mut a = crate::linalg::BlockMatrix::from_pairs(2, &[]);
        a.set_block_diagonal(|_| crate::math::Mat3::IDENTITY);
        let rhs = [Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let dv = [Vec3::ZERO, Vec3::ZERO];
        set.measure(Split::whole(&a), &rhs, &dv);
        // particle 0 is pushed up by the constraint (rhs pulls it down), particle 1 pulled down
        assert_eq!(set.update(&[Vec3::ZERO; 2], &dv, 1e-3), 1);
        let (held, impulse) = set.held();
        assert_eq!(held.len(), 1);
        assert_eq!((held[0].particle, impulse[0]), (0, 1.0));
        // released particle 1 now sinks below the prescribed normal velocity: held again
        let sinking = [Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0)];
        assert_eq!(set.update(&sinking, &dv, 1e-3), 1);
        assert_eq!(set.held().0.len(), 2);
        // nothing to flip: unchanged
        set.measure(Split::whole(&a), &[Vec3::new(0.0, -1.0, 0.0); 2], &dv);
        assert_eq!(set.update(&[Vec3::ZERO; 2], &dv, 1e-3), 0);
    }
}
