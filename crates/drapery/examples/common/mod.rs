//! What the fail-safe diagnostics share (`cone_stats`, `margin_cost`): a saved `spin-N` state
//! and the step's motion taken as `x₁ = x₀ + h v₀`.

use drapery::presets::Preset;
use drapery::snapshot::Snapshot;
use drapery::{Simulation, Vec3};

/// A restored `spin-N` state with the motion of its next step.
pub struct SpinMotion {
    /// The simulation at the saved state.
    pub sim: Simulation,
    /// The cloth's self-collision thickness (0 without collisions).
    pub thickness: f64,
    /// Positions at the start of the step.
    pub x0: Vec<Vec3>,
    /// `x₀ + h v₀`.
    pub x1: Vec<Vec3>,
}

/// Restores the state saved in `file` into `spin-n` (PCG tolerance 1e-3, as `spin_counts`).
pub fn spin_motion(n: usize, file: &str) -> Result<SpinMotion, Box<dyn std::error::Error>> {
    let preset = Preset::Spin;
    let (h, _) = preset.step();
    let mut sim = preset.simulation(n, 1e-3)?;
    sim.restore_snapshot(&Snapshot::from_bytes(&std::fs::read(file)?)?)?;
    let thickness = sim.model().collision().map_or(0.0, |c| c.thickness);
    let x0 = sim.positions().to_vec();
    let x1 = x0
        .iter()
        .zip(sim.velocities())
        .map(|(x, v)| *x + h * *v)
        .collect();
    Ok(SpinMotion {
        sim,
        thickness,
        x0,
        x1,
    })
}
