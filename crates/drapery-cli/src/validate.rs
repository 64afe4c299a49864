//! `drapery validate SCENE.toml`: load and check everything, simulate nothing, report.

use anyhow::Result;
use clap::Args;
use drapery::LinearSolver;
use drapery::scene::Scene;
use drapery::stats::cloth_stats;
use std::path::PathBuf;

/// Arguments of `drapery validate`.
#[derive(Args)]
pub struct ValidateArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
}

/// Loads the scene, builds the model and prints a summary on stdout.
pub fn validate(args: ValidateArgs) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    let sim = scene.build()?;
    let model = sim.model();
    let mut out = String::new();
    out.push_str(&format!("scene {}: ok\n", args.scene.display()));
    for (c, st) in model.cloths().iter().zip(cloth_stats(model)) {
        out.push_str(&format!(
            "cloth '{}': {} vertices, {} faces, {} line elements, {} springs ({} stretch, {} shear, {} bend), {} pinned, mass {} kg\n",
            c.name,
            st.vertices,
            st.faces,
            st.line_elements,
            st.springs(),
            st.stretch_springs,
            st.shear_springs,
            st.bend_springs,
            st.pinned,
            sig(st.mass),
        ));
        out.push_str(&format!("  material: {}\n", c.material.describe()));
    }
    match model.collision() {
        None => out.push_str("collision: off\n"),
        Some(c) => out.push_str(&format!(
            "collision: thickness {} m, self_collision {}, friction {}, stiffness {} N/m\n",
            c.thickness, c.self_collision, c.friction, c.stiffness
        )),
    }
    if model.obstacles().is_empty() {
        out.push_str("colliders: none\n");
    }
    for (i, o) in model.obstacles().iter().enumerate() {
        out.push_str(&format!("collider[{i}]: {}\n", o.describe()));
    }
    if let Some(c) = sim.start_check() {
        let (pairs, inside, t) = (c.intersecting_pairs, c.inside, c.tangled);
        if pairs == 0 && inside == 0 {
            out.push_str("initial state: no intersection\n");
        } else {
            let when = if scene.preroll_steps() > 0 {
                "the pre-roll"
            } else {
                "the first steps (no pre-roll)"
            };
            out.push_str(&format!(
                "initial state: tangled: {} cloth vertices start inside colliders, {} cloth triangle pairs start crossed; {when} pushes the vertices out and lets the crossings separate\n",
                t.inside, t.crossings
            ));
            if c.intersects_untreated() {
                out.push_str(&format!(
                    "initial state: INTERSECTS beyond that: {pairs} intersecting cloth triangle pairs, {inside} vertices inside colliders in all (pinned or handle vertices are not pushed; crossings need self_collision); they are not repaired\n"
                ));
            }
        }
        match c.close_pairs {
            Some((0, _)) => out.push_str("initial state: no cloth pair closer than the thickness\n"),
            Some((count, closest)) => out.push_str(&format!(
                "initial state: {count} cloth pairs closer than the thickness (the closest {} m apart)\n",
                sig(closest)
            )),
            None => {}
        }
    }
    out.push_str(&format!(
        "total: {} cloths, {} vertices, {} springs, mass {} kg\n",
        model.cloths().len(),
        model.particle_count(),
        model.springs().len(),
        sig(model.total_mass()),
    ));
    out.push_str(&format!(
        "time: duration {} s, frame_rate {} /s, dt {} s (step taken {} s), {} steps per frame, {} frames after frame 0 ({} files), {} steps\n",
        scene.duration,
        scene.frame_rate,
        scene.dt,
        scene.step_size(),
        scene.steps_per_frame(),
        scene.frame_count(),
        scene.frame_count() + 1,
        scene.step_count(),
    ));
    let s = &scene.solver;
    out.push_str(&format!(
        "solver: {}, tolerance {}, max_iterations {}, newton_iterations {} (at most {} where the linearization is far off), gravity [{}, {}, {}] m/s²\n",
        match s.linear_solver {
            LinearSolver::Pcg => "pcg",
            LinearSolver::Direct => "direct",
        },
        s.tolerance,
        s.max_iterations,
        s.newton_iterations,
        s.max_newton_iterations.max(s.newton_iterations),
        scene.gravity.x,
        scene.gravity.y,
        scene.gravity.z,
    ));
    print!("{out}");
    Ok(())
}

/// `x` rounded to 9 significant digits, printed shortest (0.09999999999999999 → 0.1).
fn sig(x: f64) -> f64 {
    format!("{x:.8e}").parse().unwrap_or(x)
}
