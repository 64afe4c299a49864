//! `Simulation.last_report`: the library's [`StepReport`] as a dict.

use drapery::StepReport;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The report's fields under their Rust names, `stages` a dict of seconds per stage (in the
/// order the stages run) plus `total`.
pub fn report_dict<'py>(py: Python<'py>, r: &StepReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("newton_iterations", r.newton_iterations)?;
    d.set_item("cg_iterations", r.cg_iterations)?;
    d.set_item("linear_solves", r.linear_solves)?;
    d.set_item("rough_solves", r.rough_solves)?;
    d.set_item("residual", r.residual)?;
    d.set_item("tolerance", r.tolerance)?;
    d.set_item("assembly_seconds", r.assembly_seconds)?;
    d.set_item("solve_seconds", r.solve_seconds)?;
    d.set_item("collision_seconds", r.collision_seconds)?;
    d.set_item("obstacle_contacts", r.obstacle_contacts)?;
    d.set_item("self_contacts", r.self_contacts)?;
    d.set_item("ccd_hits", r.ccd_hits)?;
    d.set_item("strain_over", r.strain_over)?;
    let s = &r.stages;
    let stages = PyDict::new(py);
    for (name, t) in [
        ("guard", s.guard),
        ("pose", s.pose),
        ("detect", s.detect),
        ("linearize", s.linearize),
        ("constrain", s.constrain),
        ("solve", s.solve),
        ("update", s.update),
        ("friction", s.friction),
        ("strain", s.strain),
        ("failsafe", s.failsafe),
        ("commit", s.commit),
        ("total", s.total()),
    ] {
        stages.set_item(name, t)?;
    }
    d.set_item("stages", stages)?;
    Ok(d)
}
