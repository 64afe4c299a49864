//! A snapshot of a simulation's state, to continue a run to the same bits later (the CLI's
//! `--resume`, a front end's save and load, tests).
//!
//! [`Simulation::snapshot`] takes what a step depends on that changes from step to step: every
//! position and velocity, the solver's warm start (the previous step's velocity change), the
//! simulated time, the step count and what is still being untangled ([`crate::step::tangles`]:
//! the vertices being pushed out of colliders and the crossed triangle pairs) and each particle's
//! obstacle normal force of the last step (the lagged normal force of the friction in the
//! solve). [`Simulation::restore_snapshot`] puts it back into a simulation
//! built from the same scene (same model and settings); stepping on from there gives bit for
//! bit what the uninterrupted run gives. Everything else a step uses is rebuilt from the model
//! at [`Simulation::new`] and does not change during a run.
//!
//! [`Snapshot::to_bytes`] / [`Snapshot::from_bytes`] store it exactly (every f64 as its bits)
//! with a free-form header of the front end's (the CLI keeps its frame index, output formats
//! and the scene fingerprint there, see [`crate::fingerprint`]). Layout, little endian: the
//! magic `DRAPERY-STATE-4\n`, u64 header length + header bytes, u64 steps, u64 time bits, u64
//! particle count n, 3n f64 positions, 3n f64 velocities, 3n f64 warm start, u64 1 when the
//! starting tangles were found (else 0), u64 count + that many (u64 particle, u64 obstacle)
//! being pushed out, u64 count + that many (u64, u64) crossed triangle pairs, n f64 normal
//! forces, and a u64 FNV-1a checksum ([`Fnv`]) of everything before it. A `DRAPERY-STATE-4`
//! file (the same without the normal forces) is read as having none, a `DRAPERY-STATE-3` file
//! (without the tangles either) as having no tangles left.
//!
//! When a collider's or a handle's motion is not the scene's (a front end replaced it,
//! [`Simulation::set_obstacle_motion`], [`Simulation::set_handle_motion`]: Python's
//! `set_collider_pose`, a control loop), the snapshot holds every collider's and handle's motion
//! too, and the run resumed from it goes on with them: the magic is then `DRAPERY-STATE-6\n`,
//! and after the normal forces come u64 collider count + their motions, u64 handle count + theirs
//! ([`motions`]). Otherwise the layout is `DRAPERY-STATE-5`'s, byte for byte, and restoring it
//! gives every collider and handle the scene's motion.

mod motions;

use crate::animation::Motion;
use crate::error::{Error, Result};
use crate::fingerprint::Fnv;
use crate::math::Vec3;
use crate::step::Simulation;

/// The magic of the current layout.
const MAGIC: &[u8] = b"DRAPERY-STATE-5\n";
/// The layout with the motions a front end set.
const MAGIC_MOTIONS: &[u8] = b"DRAPERY-STATE-6\n";
/// The layout before the normal forces.
const MAGIC_4: &[u8] = b"DRAPERY-STATE-4\n";
/// The layout before the tangles.
const MAGIC_3: &[u8] = b"DRAPERY-STATE-3\n";
/// What every version's magic starts with (`DRAPERY-STATE-2\n` was the CLI's own layout).
const MAGIC_FAMILY: &[u8] = b"DRAPERY-STATE-";

/// The state of a [`Simulation`] between two steps, exact to the bit.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    header: Vec<u8>,
    time: f64,
    steps: u64,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    warm_start: Vec<Vec3>,
    /// Whether the starting tangles were found, then the pushed vertices and the crossings.
    tangles: (bool, Vec<[u32; 2]>, Vec<[u32; 2]>),
    /// Each particle's obstacle normal force in the last step, N.
    normal_force: Vec<f64>,
    /// Every collider's and every handle's motion, when one is not the scene's.
    motions: Option<(Vec<Motion>, Vec<Motion>)>,
}

impl Simulation {
    /// The state now (empty header): restoring it into a simulation built from the same scene
    /// continues this run to the same bits.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            header: Vec::new(),
            time: self.time,
            steps: self.steps,
            x: self.model.x.clone(),
            v: self.model.v.clone(),
            warm_start: self.warm_start.clone(),
            tangles: (
                self.tangles.found,
                self.tangles.inside.clone(),
                self.tangles.crossings.clone(),
            ),
            normal_force: self.normal_force.clone(),
            motions: Some(self.model.motions()).filter(|m| *m != self.scene_motions),
        }
    }

    /// Puts a snapshot's state back (positions, velocities, warm start, time, step count, and
    /// the colliders' and handles' motions: those it holds, else the scene's). The simulation
    /// must be built from the same scene as the one the snapshot was taken from; an error,
    /// changing nothing, when the particle counts differ or the motions it holds are not as
    /// many as the scene's colliders and handles.
    pub fn restore_snapshot(&mut self, s: &Snapshot) -> Result<()> {
        let n = self.model.particle_count();
        if s.particle_count() != n {
            return Err(Error::Invalid(format!(
                "the snapshot holds {} particles but the simulation has {n}: not a state of this scene",
                s.particle_count()
            )));
        }
        let (found, inside, crossings) = &s.tangles;
        let (tris, obstacles) = (self.triangles.len(), self.model.obstacles.len());
        if inside
            .iter()
            .any(|&[p, k]| p as usize >= n || k as usize >= obstacles)
            || crossings
                .iter()
                .any(|c| c.iter().any(|&t| t as usize >= tris))
        {
            return Err(Error::Invalid(
                "the snapshot's tangles name particles, colliders or triangles this scene does not have: not a state of this scene".into(),
            ));
        }
        let handles = self.model.handles.len();
        if let Some((c, h)) = &s.motions
            && (c.len() != obstacles || h.len() != handles)
        {
            return Err(Error::Invalid(format!(
                "the snapshot holds the motions of {} colliders and {} handles but the scene has {obstacles} and {handles}: not a state of this scene",
                c.len(),
                h.len()
            )));
        }
        let (colliders, held) = match &s.motions {
            Some((c, h)) => (c, h),
            None => (&self.scene_motions.0, &self.scene_motions.1),
        };
        for (o, m) in self.model.obstacles.iter_mut().zip(colliders) {
            o.collider.motion = m.clone();
        }
        for (hd, m) in self.model.handles.iter_mut().zip(held) {
            hd.motion = m.clone();
        }
        self.tangles = crate::step::tangles::Tangles::restored(
            *found,
            inside.clone(),
            crossings.clone(),
            &self.triangles,
            n,
        );
        self.model.x.clone_from(&s.x);
        self.model.v.clone_from(&s.v);
        self.warm_start.clone_from(&s.warm_start);
        if s.normal_force.len() == n {
            self.normal_force.clone_from(&s.normal_force);
        } else {
            self.normal_force = vec![0.0; n];
        }
        self.time = s.time;
        self.steps = s.steps;
        Ok(())
    }
}

fn damaged(why: &str) -> Error {
    Error::Invalid(format!("damaged or not a drapery state file ({why})"))
}

impl Snapshot {
    /// The front end's header bytes (empty unless set).
    pub fn header(&self) -> &[u8] {
        &self.header
    }

    /// Sets the header: free-form bytes stored and checksummed with the state.
    pub fn with_header(mut self, header: Vec<u8>) -> Snapshot {
        self.header = header;
        self
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    /// Positions, m.
    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    /// Velocities, m/s.
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Whether it holds motions other than the scene's (see the [module documentation](self)).
    pub fn has_motions(&self) -> bool {
        self.motions.is_some()
    }

    /// The bytes described in the [module documentation](self).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + self.header.len() + 72 * self.x.len());
        out.extend_from_slice(match self.motions {
            Some(_) => MAGIC_MOTIONS,
            None => MAGIC,
        });
        out.extend_from_slice(&(self.header.len() as u64).to_le_bytes());
        out.extend_from_slice(&self.header);
        for v in [self.steps, self.time.to_bits(), self.x.len() as u64] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for vecs in [&self.x, &self.v, &self.warm_start] {
            for p in vecs.iter() {
                for k in 0..3 {
                    out.extend_from_slice(&p[k].to_le_bytes());
                }
            }
        }
        let (found, inside, crossings) = &self.tangles;
        out.extend_from_slice(&(*found as u64).to_le_bytes());
        for list in [inside, crossings] {
            out.extend_from_slice(&(list.len() as u64).to_le_bytes());
            for e in list {
                for v in e {
                    out.extend_from_slice(&(*v as u64).to_le_bytes());
                }
            }
        }
        for f in &self.normal_force {
            out.extend_from_slice(&f.to_le_bytes());
        }
        if let Some((colliders, handles)) = &self.motions {
            for list in [colliders, handles] {
                out.extend_from_slice(&(list.len() as u64).to_le_bytes());
                list.iter().for_each(|m| motions::encode(m, &mut out));
            }
        }
        let sum = Fnv::new().bytes(&out).finish();
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// Reads [`Snapshot::to_bytes`]'s bytes back; an [`Error::Invalid`] saying what is wrong
    /// when they are not a snapshot of this version, are cut short or damaged.
    pub fn from_bytes(b: &[u8]) -> Result<Snapshot> {
        let v3 = b.starts_with(MAGIC_3);
        let v4 = b.starts_with(MAGIC_4);
        let v6 = b.starts_with(MAGIC_MOTIONS);
        if !b.starts_with(MAGIC) && !v3 && !v4 && !v6 {
            let head = &b[..b.len().min(32)];
            return Err(match head.iter().position(|&c| c == b'\n') {
                Some(end) if head.starts_with(MAGIC_FAMILY) => Error::Invalid(format!(
                    "a state file of another version of drapery ({}), which this one cannot read",
                    String::from_utf8_lossy(&head[..end])
                )),
                _ => damaged("no DRAPERY-STATE header"),
            });
        }
        if b.len() < MAGIC.len() + 8 {
            return Err(damaged("cut short"));
        }
        let (body, sum) = b.split_at(b.len() - 8);
        if Fnv::new().bytes(body).finish().to_le_bytes() != sum {
            return Err(damaged("checksum mismatch"));
        }
        let mut r = Reader {
            b: body,
            at: MAGIC.len(),
        };
        let short = || damaged("cut short");
        let header_len = usize::try_from(r.u64().ok_or_else(short)?).map_err(|_| short())?;
        let header = r.take(header_len).ok_or_else(short)?.to_vec();
        let steps = r.u64().ok_or_else(short)?;
        let time = f64::from_bits(r.u64().ok_or_else(short)?);
        let n = r.u64().ok_or_else(short)?;
        let rest = (body.len() - r.at) as u64;
        let state = n.checked_mul(72).filter(|&s| s <= rest);
        if state.is_none() || (v3 && state != Some(rest)) {
            return Err(damaged("the particle count does not match the length"));
        }
        let n = n as usize;
        let mut vecs = || decode_vecs(r.take(24 * n).unwrap_or_default());
        let (x, v, warm_start) = (vecs(), vecs(), vecs());
        let misfit = || damaged("the particle count or a list length does not match the length");
        let tangles = if v3 {
            (true, Vec::new(), Vec::new())
        } else {
            let found = r.u64().ok_or_else(misfit)? == 1;
            let mut list = || -> Result<Vec<[u32; 2]>> {
                let len = r.u64().ok_or_else(misfit)?;
                let left = (body.len() - r.at) as u64;
                if len.checked_mul(16).is_none_or(|b| b > left) {
                    return Err(misfit());
                }
                (0..len)
                    .map(|_| {
                        let mut e = [0u32; 2];
                        for v in &mut e {
                            let w = r.u64().ok_or_else(misfit)?;
                            *v = u32::try_from(w).map_err(|_| damaged("an index out of range"))?;
                        }
                        Ok(e)
                    })
                    .collect()
            };
            let (inside, crossings) = (list()?, list()?);
            (found, inside, crossings)
        };
        let normal_force = if v3 || v4 {
            Vec::new()
        } else {
            let raw = r.take(8 * n).unwrap_or_default();
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        };
        if !v3 && !v4 && normal_force.len() != n {
            return Err(misfit());
        }
        let motions = if v6 {
            let mut list = |what: &str| -> Result<Vec<Motion>> {
                let len = r.u64().ok_or_else(misfit)?;
                // (each motion takes 8 bytes at least)
                if len.checked_mul(8).is_none_or(|b| b > r.left() as u64) {
                    return Err(misfit());
                }
                (0..len as usize)
                    .map(|k| motions::decode(&mut r, &format!("{what}[{k}]")))
                    .collect()
            };
            let colliders = list("collider")?;
            Some((colliders, list("handle")?))
        } else {
            None
        };
        if r.at != body.len() {
            return Err(misfit());
        }
        Ok(Snapshot {
            header,
            time,
            steps,
            x,
            v,
            warm_start,
            tangles,
            normal_force,
            motions,
        })
    }
}

/// Reads the byte string from the front.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8)?.try_into().ok().map(u64::from_le_bytes)
    }
    /// Bytes not read yet.
    fn left(&self) -> usize {
        self.b.len() - self.at
    }
}

/// Little-endian f64 triples.
fn decode_vecs(raw: &[u8]) -> Vec<Vec3> {
    raw.chunks_exact(24)
        .map(|c| {
            let f = |i: usize| f64::from_le_bytes(c[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
            Vec3::new(f(0), f(1), f(2))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::Preset;

    const H: f64 = 1.0 / 60.0;

    fn run(sim: &mut Simulation, steps: usize) {
        for _ in 0..steps {
            sim.step(H).unwrap();
        }
    }

    fn assert_same_bits(a: &Snapshot, b: &Snapshot) {
        assert_eq!(a.time.to_bits(), b.time.to_bits());
        assert_eq!(a.steps, b.steps);
        for (what, p, q) in [
            ("x", &a.x, &b.x),
            ("v", &a.v, &b.v),
            ("warm start", &a.warm_start, &b.warm_start),
        ] {
            assert_eq!(p.len(), q.len());
            for (i, (p, q)) in p.iter().zip(q.iter()).enumerate() {
                for k in 0..3 {
                    assert_eq!(p[k].to_bits(), q[k].to_bits(), "{what}[{i}][{k}]");
                }
            }
        }
    }

    /// Steps `n`, snapshots, goes through bytes, restores into a fresh simulation and steps `m`
    /// more: the same bits as `n + m` steps in one go.
    fn resumes_to_the_same_bits(preset: Preset, size: usize, n: usize, m: usize) {
        let fresh = || preset.simulation(size, 1e-3).unwrap();
        let mut whole = fresh();
        run(&mut whole, n + m);

        let mut first = fresh();
        run(&mut first, n);
        let bytes = first.snapshot().to_bytes();
        let mut second = fresh();
        assert_ne!(
            second.model.x, first.model.x,
            "the first part of the run must move the cloth"
        );
        second
            .restore_snapshot(&Snapshot::from_bytes(&bytes).unwrap())
            .unwrap();
        assert_same_bits(&second.snapshot(), &first.snapshot());
        run(&mut second, m);
        assert_same_bits(&second.snapshot(), &whole.snapshot());
    }

    #[test]
    fn a_restored_run_continues_to_the_bits_of_an_uninterrupted_one() {
        resumes_to_the_same_bits(Preset::Hang, 8, 7, 5);
    }

    #[test]
    fn a_restored_run_in_contact_continues_to_the_same_bits() {
        // The drape cloth reaches the sphere after about 9 steps: the second part is in contact.
        let mut probe = Preset::Drape.simulation(8, 1e-3).unwrap();
        run(&mut probe, 12);
        assert!(
            probe.model.x.iter().any(|p| p.length() < 0.3 + 0.01),
            "no contact yet"
        );
        resumes_to_the_same_bits(Preset::Drape, 8, 12, 8);
    }

    fn sample() -> Snapshot {
        Snapshot {
            header: b"frame 7".to_vec(),
            time: 7.0 / 60.0,
            steps: 14,
            x: vec![
                Vec3::new(0.1, -0.0, f64::MIN_POSITIVE),
                Vec3::new(1e300, 2.5, -3.0),
            ],
            v: vec![Vec3::new(1.0 / 3.0, 0.0, -1e-300), Vec3::ZERO],
            warm_start: vec![
                Vec3::new(0.25, -0.0, 1e-5),
                Vec3::new(f64::MIN_POSITIVE, 2.0, 3.0),
            ],
            tangles: (true, vec![[1, 0]], vec![[0, 3], [2, u32::MAX]]),
            normal_force: vec![0.125, -0.0],
            motions: None,
        }
    }

    /// A state of the layout before the tangles reads as the same state with none left.
    #[test]
    fn a_version_3_state_reads_with_no_tangles() {
        let mut s = sample();
        let b = s.to_bytes();
        // version 3: the same up to the warm start, without the tangles and normal forces
        let tangles = 8 + (8 + 16) + (8 + 2 * 16);
        let mut old = b[..b.len() - 8 - 16 - tangles].to_vec();
        old[..MAGIC.len()].copy_from_slice(MAGIC_3);
        let sum = Fnv::new().bytes(&old).finish();
        old.extend_from_slice(&sum.to_le_bytes());
        s.tangles = (true, Vec::new(), Vec::new());
        s.normal_force = Vec::new();
        assert_eq!(Snapshot::from_bytes(&old).unwrap(), s);
    }

    /// A state of the layout before the normal forces reads as the same state with none.
    #[test]
    fn a_version_4_state_reads_with_no_normal_forces() {
        let mut s = sample();
        let b = s.to_bytes();
        let mut old = b[..b.len() - 8 - 16].to_vec();
        old[..MAGIC.len()].copy_from_slice(MAGIC_4);
        let sum = Fnv::new().bytes(&old).finish();
        old.extend_from_slice(&sum.to_le_bytes());
        s.normal_force = Vec::new();
        assert_eq!(Snapshot::from_bytes(&old).unwrap(), s);
    }

    /// Steps `n`, lets `set` replace motions (a front end's control), snapshots, goes through
    /// bytes, restores into a fresh simulation and steps `m` more: the bits of the uninterrupted
    /// run with the same control. The same snapshot without its motions goes on with the
    /// scene's, also in a simulation whose motions had been replaced, and differs.
    fn resumes_with_the_motions_set(
        preset: Preset,
        size: usize,
        (n, m): (usize, usize),
        set: impl Fn(&mut Simulation),
    ) {
        let fresh = || preset.simulation(size, 1e-3).unwrap();
        let mut whole = fresh();
        run(&mut whole, n);
        set(&mut whole);
        run(&mut whole, m);

        let mut first = fresh();
        run(&mut first, n);
        assert!(!first.snapshot().has_motions(), "no motion set yet");
        set(&mut first);
        let bytes = first.snapshot().to_bytes();
        assert!(bytes.starts_with(MAGIC_MOTIONS));
        let state = Snapshot::from_bytes(&bytes).unwrap();
        assert!(state.has_motions());
        let mut second = fresh();
        second.restore_snapshot(&state).unwrap();
        run(&mut second, m);
        assert_same_bits(&second.snapshot(), &whole.snapshot());
        assert!(second.snapshot().has_motions(), "kept by the next snapshot");

        let scene_motions = Snapshot {
            motions: None,
            ..state
        };
        let mut own = fresh();
        own.restore_snapshot(&scene_motions).unwrap();
        run(&mut own, m);
        let mut controlled = fresh();
        set(&mut controlled);
        controlled.restore_snapshot(&scene_motions).unwrap();
        run(&mut controlled, m);
        assert_same_bits(&controlled.snapshot(), &own.snapshot());
        assert!(!controlled.snapshot().has_motions());
        assert_ne!(own.model.x, whole.model.x, "the motions set change the run");
    }

    #[test]
    fn a_run_resumed_after_a_collider_was_moved_goes_on_with_its_new_motion() {
        // the drape's sphere, in contact from about step 9, starts sliding sideways at step 12
        resumes_with_the_motions_set(Preset::Drape, 8, (12, 6), |sim| {
            let m = Motion::constant(Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
            sim.set_obstacle_motion(0, m).unwrap();
        });
    }

    #[test]
    fn a_run_resumed_after_a_handle_was_moved_goes_on_with_its_new_motion() {
        // the twist's first handle is keyed to rise instead (two keys, linear), the second
        // held where it is
        resumes_with_the_motions_set(Preset::Twist, 8, (5, 6), |sim| {
            use crate::animation::{Interpolation, Keyframe, Track};
            let now = sim.time();
            let (q, t) = sim.model().handles()[0].motion.pose(now);
            let keys = vec![
                Keyframe {
                    time: now,
                    translation: t,
                    rotation: q,
                },
                Keyframe {
                    time: now + 0.1,
                    translation: t + Vec3::new(0.0, 0.05, 0.0),
                    rotation: q,
                },
            ];
            let track = Track::new(keys, Interpolation::Linear, "").unwrap();
            sim.set_handle_motion(0, Motion::Keyframed(track)).unwrap();
            sim.set_handle_motion(1, Motion::Fixed).unwrap();
        });
    }

    #[test]
    fn motions_for_another_scene_are_refused_and_change_nothing() {
        let mut drape = Preset::Drape.simulation(8, 1e-3).unwrap();
        drape
            .set_obstacle_motion(0, Motion::constant(Vec3::X, Vec3::ZERO))
            .unwrap();
        // the hanging cloth has as many particles but no collider
        let mut hang = Preset::Hang.simulation(8, 1e-3).unwrap();
        run(&mut hang, 2);
        let before = hang.snapshot();
        let e = hang.restore_snapshot(&drape.snapshot()).unwrap_err();
        assert!(e.to_string().contains("motions of 1 colliders"), "{e}");
        assert_same_bits(&hang.snapshot(), &before);
    }

    #[test]
    fn bytes_round_trip_every_bit() {
        let s = sample();
        let b = s.to_bytes();
        assert!(
            b.starts_with(MAGIC),
            "without motions, the layout before them"
        );
        let r = Snapshot::from_bytes(&b).unwrap();
        assert_eq!(r, s);
        assert_eq!(r.header(), b"frame 7");
        let with = with_motions();
        let b = with.to_bytes();
        assert!(b.starts_with(MAGIC_MOTIONS));
        assert_eq!(Snapshot::from_bytes(&b).unwrap(), with);
        // cut anywhere in the motions: refused
        for cut in [b.len() - 9, b.len() - 40, b.len() - 100] {
            let mut c = b[..cut].to_vec();
            let sum = Fnv::new().bytes(&c).finish();
            c.extend_from_slice(&sum.to_le_bytes());
            assert!(Snapshot::from_bytes(&c).is_err(), "cut at {cut}");
        }
        assert_eq!(r.x[0].y.to_bits(), (-0.0f64).to_bits());
        assert_same_bits(&r, &s);
    }

    fn with_motions() -> Snapshot {
        let keys = vec![
            crate::animation::Keyframe::at(0.0),
            crate::animation::Keyframe {
                time: 0.5,
                translation: Vec3::new(0.1, 0.2, -0.3),
                rotation: glam::DQuat::from_rotation_z(0.3),
            },
        ];
        let track = crate::animation::Track::new(keys, Default::default(), "").unwrap();
        Snapshot {
            motions: Some((
                vec![Motion::Fixed, Motion::Keyframed(track)],
                vec![Motion::constant(Vec3::Y, Vec3::ZERO)],
            )),
            ..sample()
        }
    }

    proptest::proptest! {
        /// Any byte of a state with motions changed (and the checksum made to match): read
        /// back as some state or refused with an error, never a panic.
        #[test]
        fn a_changed_byte_with_a_matching_checksum_never_panics(at in 0usize..10_000, to in 0u8..=255) {
            let b = with_motions().to_bytes();
            let mut c = b[..b.len() - 8].to_vec();
            let i = at % c.len();
            c[i] = to;
            let sum = Fnv::new().bytes(&c).finish();
            c.extend_from_slice(&sum.to_le_bytes());
            let _ = Snapshot::from_bytes(&c);
        }
    }

    #[test]
    fn damaged_cut_or_foreign_bytes_are_refused_with_a_reason() {
        let b = sample().to_bytes();
        let message = |bytes: &[u8]| match Snapshot::from_bytes(bytes) {
            Ok(_) => panic!("accepted damaged bytes"),
            Err(e) => e.to_string(),
        };
        for i in [MAGIC.len() + 3, MAGIC.len() + 20, b.len() / 2, b.len() - 1] {
            let mut bad = b.clone();
            bad[i] ^= 1;
            assert!(message(&bad).contains("checksum"), "flip at {i}");
        }
        let mut bad = b.clone();
        bad[0] ^= 1;
        assert!(message(&bad).contains("no DRAPERY-STATE header"));
        assert!(message(&b[..b.len() - 9]).contains("damaged"));
        assert!(message(&b[..MAGIC.len() + 3]).contains("cut short"));
        assert!(message(b"").contains("damaged"));
        let mut old = b.clone();
        old[..MAGIC.len()].copy_from_slice(b"DRAPERY-STATE-2\n");
        let m = message(&old);
        assert!(
            m.contains("another version") && m.contains("DRAPERY-STATE-2"),
            "{m}"
        );

        // A consistent checksum over a particle count that does not fit the length.
        let mut lying = b[..b.len() - 8].to_vec();
        let at = MAGIC.len() + 8 + b"frame 7".len() + 16;
        lying[at..at + 8].copy_from_slice(&3u64.to_le_bytes());
        let sum = Fnv::new().bytes(&lying).finish();
        lying.extend_from_slice(&sum.to_le_bytes());
        assert!(message(&lying).contains("particle count"));
    }

    #[test]
    fn a_snapshot_of_another_particle_count_is_refused_and_changes_nothing() {
        let mut small = Preset::Hang.simulation(4, 1e-3).unwrap();
        run(&mut small, 2);
        let mut big = Preset::Hang.simulation(5, 1e-3).unwrap();
        let before = big.snapshot();
        let e = big
            .restore_snapshot(&small.snapshot())
            .unwrap_err()
            .to_string();
        assert!(e.contains("16 particles") && e.contains("25"), "{e}");
        assert_same_bits(&big.snapshot(), &before);
    }
}
