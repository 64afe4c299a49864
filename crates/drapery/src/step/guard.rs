//! Checks around a step: before it (a valid step size, a finite state) and after it (the
//! energy blow-up test, docs/MATH.md §17). A step that fails leaves the simulation as it was.

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::Model;

/// Ratio of kinetic energies across one step above which the step counts as a blow-up.
const BLOWUP_RATIO: f64 = 1e4;

/// Which step failed, for the error.
#[derive(Clone, Copy, Debug)]
pub(crate) struct At {
    /// Steps taken before this one.
    pub steps: u64,
    /// Time at the start of the step, s.
    pub time: f64,
}

impl At {
    /// The error of a step that failed for `reason`.
    pub fn fail(&self, reason: String) -> Error {
        Error::StepFailed {
            step: self.steps,
            time: self.time,
            reason,
        }
    }
}

/// The state a step starts from (what a failed step leaves in place).
pub(crate) struct Start {
    /// Positions at the start of the step.
    pub x0: Vec<Vec3>,
    /// Velocities at the start of the step.
    pub v0: Vec<Vec3>,
    /// Kinetic energy at the start of the step, J.
    pub ke0: f64,
}

/// Checks the step size and that the state is finite; returns the starting state.
pub(crate) fn start(model: &Model, at: At, h: f64) -> Result<Start> {
    if !(h > 0.0 && h.is_finite()) {
        return Err(Error::Invalid(format!(
            "time step must be a finite number > 0, got {h}"
        )));
    }
    if let Some(p) = first_non_finite(&model.x, &model.v) {
        return Err(at.fail(format!(
            "non-finite position or velocity at {} before the step",
            particle_name(model, p)
        )));
    }
    Ok(Start {
        x0: model.x.clone(),
        v0: model.v.clone(),
        ke0: model.kinetic_energy(),
    })
}

/// The first particle whose position or velocity is not finite.
pub(crate) fn first_non_finite(x: &[Vec3], v: &[Vec3]) -> Option<usize> {
    (0..x.len()).find(|&i| !(x[i].is_finite() && v[i].is_finite()))
}

/// Kinetic energy ½ Σ m |v|² of velocities `v`.
pub(crate) fn kinetic_energy(mass: &[f64], v: &[Vec3]) -> f64 {
    mass.iter()
        .zip(v)
        .map(|(m, v)| 0.5 * m * v.length_squared())
        .sum()
}

/// What the blow-up test needs to know about the step.
pub(crate) struct Energies {
    /// Kinetic energy at the start, J.
    pub ke0: f64,
    /// Largest speed of an obstacle's surface, m/s.
    pub surface_speed: f64,
    /// Step, s.
    pub h: f64,
}

/// The energy blow-up test: the step fails when the kinetic energy of the new velocities `v`
/// exceeds [`BLOWUP_RATIO`] times what the step could have supplied: the kinetic energy at the
/// start, gravity's and moving obstacles' work over one step (`½ m_total ((|g| h)² + u²)`), and
/// the energy stored at the start (springs, contacts) that a cloth released from rest turns
/// into motion. `stored` computes the last, only when the first test trips.
pub(crate) fn blow_up(
    model: &Model,
    v: &[Vec3],
    e: &Energies,
    stored: impl FnOnce() -> f64,
) -> Option<String> {
    let ke1 = kinetic_energy(&model.mass, v);
    let allowance = 0.5
        * model.total_mass()
        * ((model.gravity.length() * e.h).powi(2) + e.surface_speed.powi(2));
    let limit = |stored: f64| BLOWUP_RATIO * (e.ke0 + allowance + stored) + 1e-300;
    if !(ke1 > limit(0.0) && ke1 > limit(stored())) {
        return None;
    }
    let p = (0..v.len())
        .max_by(|&a, &b| v[a].length().total_cmp(&v[b].length()))
        .unwrap_or(0);
    let name = particle_name(model, p);
    let speed = v[p].length();
    Some(format!(
        "energy blow-up: kinetic energy grew from {:.3e} J to {ke1:.3e} J in one step (fastest: {name} at {speed:.3e} m/s); try a smaller dt or more damping",
        e.ke0
    ))
}

/// Names particle `p` as "vertex N of cloth 'name'".
pub(crate) fn particle_name(model: &Model, p: usize) -> String {
    match model.cloths.iter().find(|c| c.range().contains(&p)) {
        Some(c) => format!("vertex {} of cloth '{}'", p - c.offset, c.name),
        None => format!("particle {p}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::model::{ClothDesc, MassSpec, Material};

    fn model() -> Model {
        let cloth = ClothDesc {
            name: "sheet".into(),
            mesh: Mesh::grid([1.0, 1.0], [3, 3], Vec3::ZERO, Vec3::Y).unwrap(),
            material: Material {
                mass: MassSpec::PerVertex(0.5),
                ..Material::default()
            },
            pins: vec![],
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        };
        Model::new(vec![cloth], Vec3::new(0.0, -10.0, 0.0)).unwrap()
    }

    #[test]
    fn a_bad_step_size_or_a_non_finite_state_is_refused() {
        let mut m = model();
        let at = At {
            steps: 3,
            time: 0.5,
        };
        for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(start(&m, at, h).is_err());
        }
        m.v[4].y = f64::NAN;
        let e = start(&m, at, 0.01).err().unwrap().to_string();
        assert!(e.contains("vertex 4 of cloth 'sheet'"), "{e}");
    }

    #[test]
    fn the_blow_up_test_allows_gravity_and_stored_energy_and_names_the_fastest_vertex() {
        let m = model();
        let h = 0.01;
        let e = Energies {
            ke0: 0.0,
            surface_speed: 0.0,
            h,
        };
        // free fall from rest over one step: 9 particles of 0.5 kg at g h
        let fall = vec![Vec3::new(0.0, -10.0 * h, 0.0); 9];
        assert!(blow_up(&m, &fall, &e, || 0.0).is_none());
        // the allowance is ½ M (g h)² = 0.0225 J; 1e4 times that is 225 J: one particle at
        // 31 m/s (240 J) trips it, unless the step started with that much energy stored
        let mut v = vec![Vec3::ZERO; 9];
        v[7] = Vec3::new(31.0, 0.0, 0.0);
        let why = blow_up(&m, &v, &e, || 0.0).unwrap();
        assert!(why.contains("vertex 7 of cloth 'sheet'"), "{why}");
        assert!(blow_up(&m, &v, &e, || 1.0).is_none());
        v[7] = Vec3::new(29.0, 0.0, 0.0); // 210 J: below the limit
        assert!(blow_up(&m, &v, &e, || 0.0).is_none());
    }
}
