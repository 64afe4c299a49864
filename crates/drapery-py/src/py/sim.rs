//! `drapery.Simulation`: a scene's simulation, stepped from Python.
//!
//! Every step is the library's [`Simulation::step`] with the scene's [`Scene::step_size`], as in
//! `drapery run`, so positions after `k` frames are the bits of the CLI's frame `k`. Steps run
//! with the GIL released, in the simulation's own rayon pool when `threads` is given (else in
//! rayon's global pool); [`PySimulation::advance`] checks for signals between steps, so Ctrl-C
//! interrupts it (the state is then that after the last whole step).
//!
//! [`Scene::step_size`]: drapery::scene::Scene::step_size

use super::arrays::{index_array, triangle_array, vec3_array, vec3s};
use super::control::{
    PosePair, collider_index, handle_cloth, handle_index, handle_names, pose_arg, pose_arrays, ramp,
};
use super::errors::{simulation_error, state_error};
use super::report::report_dict;
use super::scene::{Loaded, PyScene};
use drapery::snapshot::Snapshot;
use drapery::{Simulation, StepReport, Vec3};
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::ops::Range;
use std::sync::Arc;

/// What saved states carry after the scene fingerprint (the first 8 header bytes, little
/// endian, as in the CLI's `state.bin`).
const STATE_TAG: &[u8] = b"drapery-py";

/// A simulation of a scene: `Simulation(scene, threads=None)`.
#[pyclass(module = "drapery", name = "Simulation")]
pub struct PySimulation {
    sim: Simulation,
    loaded: Arc<Loaded>,
    /// The pool every step runs in (`threads`), or `None` for rayon's global pool.
    pool: Option<rayon::ThreadPool>,
    last: Option<StepReport>,
}

/// A pool of `threads` threads, or `None` for the global pool.
pub fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    let Some(n) = threads else {
        return Ok(None);
    };
    if n == 0 {
        return Err(PyValueError::new_err(
            "threads must be at least 1 (or None for all cores)",
        ));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("drapery-{i}"))
        .build()
        .map(Some)
        .map_err(|e| simulation_error(format!("cannot start {n} threads: {e}")))
}

impl PySimulation {
    fn build(scene: &PyScene, threads: Option<usize>) -> PyResult<PySimulation> {
        let loaded = scene.loaded.clone();
        let sim = loaded.scene.build().map_err(super::errors::scene_error)?;
        Ok(PySimulation {
            sim,
            loaded,
            pool: pool(threads)?,
            last: None,
        })
    }

    /// One step, here (the caller releases the GIL).
    fn step_here(&mut self) -> drapery::Result<StepReport> {
        let h = self.loaded.scene.step_size();
        let sim = &mut self.sim;
        match &self.pool {
            Some(pool) => pool.install(|| sim.step(h)),
            None => sim.step(h),
        }
    }

    /// One step with the GIL released.
    fn one_step(&mut self, py: Python<'_>) -> PyResult<()> {
        let report = py.detach(|| self.step_here()).map_err(simulation_error)?;
        self.last = Some(report);
        Ok(())
    }

    /// The time a pose set now is reached: `time`, or the end of the next step.
    fn until(&self, time: Option<f64>) -> f64 {
        time.unwrap_or_else(|| self.sim.time() + self.loaded.scene.step_size())
    }

    /// The particle range of `cloth` (a name), or every particle.
    fn range(&self, cloth: Option<&str>) -> PyResult<Range<usize>> {
        let model = self.sim.model();
        let Some(name) = cloth else {
            return Ok(0..model.particle_count());
        };
        match model.cloth(name) {
            Some(c) => Ok(c.range()),
            None => {
                let names: Vec<&str> = model.cloths().iter().map(|c| c.name.as_str()).collect();
                Err(PyValueError::new_err(format!(
                    "no cloth named '{name}' (the scene's cloths: {})",
                    names.join(", ")
                )))
            }
        }
    }

    /// `new` in place of the particles of `cloth` (or of all) in `all`.
    fn replace(
        &self,
        all: &[Vec3],
        new: &Bound<'_, PyAny>,
        cloth: Option<&str>,
        what: &str,
    ) -> PyResult<Vec<Vec3>> {
        let r = self.range(cloth)?;
        let what = match cloth {
            Some(c) => format!("{what} of cloth '{c}'"),
            None => what.to_string(),
        };
        let part = vec3s(new, r.len(), &what)?;
        let mut v = all.to_vec();
        v[r].copy_from_slice(&part);
        Ok(v)
    }
}

#[pymethods]
impl PySimulation {
    /// A new simulation of `scene` at its initial state (after its `preroll`, if any). `threads`: the size of a thread pool
    /// of this simulation's own that every step runs in (default: rayon's global pool, one
    /// thread per core). The results are the same bits whatever the thread count.
    #[new]
    #[pyo3(signature = (scene, threads = None))]
    fn new(scene: PyRef<'_, PyScene>, threads: Option<usize>) -> PyResult<PySimulation> {
        let mut s = PySimulation::build(&scene, threads)?;
        // `[simulation] preroll`: settled before frame 0, as `drapery run` does
        let (steps, h) = (s.loaded.scene.preroll_steps(), s.loaded.scene.step_size());
        let sim = &mut s.sim;
        match &s.pool {
            Some(pool) => pool.install(|| sim.preroll(steps, h)),
            None => sim.preroll(steps, h),
        }
        .map_err(|e| simulation_error(e.to_string()))?;
        Ok(s)
    }

    /// A simulation of `scene` continuing from `state` (bytes from `save_state`, or a
    /// `drapery run` folder's state.bin): stepping on gives the same bits as the run that saved
    /// it. Raises StateError when the bytes are damaged or belong to another scene (or the
    /// scene or its meshes changed since).
    #[staticmethod]
    #[pyo3(signature = (scene, state, threads = None))]
    fn from_state(
        scene: PyRef<'_, PyScene>,
        state: &[u8],
        threads: Option<usize>,
    ) -> PyResult<PySimulation> {
        let mut s = PySimulation::build(&scene, threads)?;
        let snapshot = Snapshot::from_bytes(state).map_err(state_error)?;
        let saved = snapshot
            .header()
            .get(..8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes);
        match saved {
            None => {
                return Err(state_error(
                    "not a state saved by drapery (no scene fingerprint in its header)",
                ));
            }
            Some(f) if f != s.loaded.fingerprint => {
                return Err(state_error(format!(
                    "the state belongs to another scene than {} (or the scene or its meshes changed since it was saved)",
                    s.loaded.scene.path.display()
                )));
            }
            Some(_) => {}
        }
        s.sim.restore_snapshot(&snapshot).map_err(state_error)?;
        Ok(s)
    }

    /// One step of `scene.step_size` seconds. Raises SimulationError (the state is then that
    /// before the step).
    fn step(&mut self, py: Python<'_>) -> PyResult<()> {
        self.one_step(py)
    }

    /// `frames` frames of `scene.steps_per_frame` steps each; Ctrl-C (any Python signal
    /// handler's exception) interrupts it between two steps.
    #[pyo3(signature = (frames = 1))]
    fn advance(&mut self, py: Python<'_>, frames: usize) -> PyResult<()> {
        let steps = frames
            .checked_mul(self.loaded.scene.steps_per_frame())
            .ok_or_else(|| PyValueError::new_err(format!("{frames} frames is too many steps")))?;
        for _ in 0..steps {
            self.one_step(py)?;
            py.check_signals()?;
        }
        Ok(())
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Steps taken since the initial state.
    #[getter]
    fn steps(&self) -> u64 {
        self.sim.steps()
    }

    /// What is still tangled, `(vertices inside colliders, crossed cloth triangle pairs)`:
    /// after the pre-roll, what it did not untangle (the next steps go on with it).
    #[getter]
    fn tangled(&self) -> (usize, usize) {
        let t = self.sim.tangled();
        (t.inside, t.crossings)
    }

    /// The cloth pairs (sharing no vertex, not exempt) closer than collision.thickness now,
    /// `(count, distance of the closest)`, or `None` without self-collision: at the start, a
    /// thickness beyond the mesh's own spacing or layers placed closer than it (the cloth then
    /// pushes itself apart; `drapery run` warns of it).
    #[getter]
    fn close_pairs(&self) -> Option<(usize, f64)> {
        self.sim.close_pairs()
    }

    /// What `drapery run` (and `drapery.run`) would warn of, were a run to start from the
    /// current state: intersections the steps will not untangle (pinned or handle vertices
    /// inside a collider, crossings without self-collision; after steps, such as the pre-roll,
    /// also crossings the steps made, those by a seam told apart) and, before any step, cloth
    /// pairs closer than collision.thickness (after steps those are contact); one text per
    /// problem, `[]` for a clean start or without collisions.
    #[getter]
    fn start_warnings(&self) -> Vec<String> {
        (self.sim.start_check())
            .map(|c| c.warnings())
            .unwrap_or_default()
    }

    /// Whole frames of steps taken: steps // scene.steps_per_frame (frame k is the state
    /// `drapery run` writes as frame_k).
    #[getter]
    fn frame(&self) -> u64 {
        self.sim.steps() / self.loaded.scene.steps_per_frame() as u64
    }

    /// The scene simulated.
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            loaded: self.loaded.clone(),
        }
    }

    /// The cloths' names, in particle order.
    #[getter]
    fn cloths(&self) -> Vec<String> {
        self.sim
            .model()
            .cloths()
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }

    /// The last step's report (iterations, contacts, seconds per stage), or None before the
    /// first step.
    #[getter]
    fn last_report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.last.as_ref().map(|r| report_dict(py, r)).transpose()
    }

    /// Positions, m, as a new float64 array of shape (n, 3): every particle (cloths in scene
    /// order) or those of the cloth named.
    #[pyo3(signature = (cloth = None))]
    fn positions<'py>(
        &self,
        py: Python<'py>,
        cloth: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_array(py, &self.sim.positions()[self.range(cloth)?])
    }

    /// Velocities, m/s, as `positions`.
    #[pyo3(signature = (cloth = None))]
    fn velocities<'py>(
        &self,
        py: Python<'py>,
        cloth: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_array(py, &self.sim.velocities()[self.range(cloth)?])
    }

    /// Sets positions (shape (n, 3), any real dtype) of every particle or of one cloth's,
    /// between steps. Raises ValueError, changing nothing, on a wrong shape or a non-finite
    /// value. Pinned particles move too: a pin holds a particle where it is.
    #[pyo3(signature = (positions, cloth = None))]
    fn set_positions(&mut self, positions: &Bound<'_, PyAny>, cloth: Option<&str>) -> PyResult<()> {
        let x = self.replace(self.sim.positions(), positions, cloth, "positions")?;
        self.sim
            .set_positions(&x)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Sets velocities, as `set_positions`.
    #[pyo3(signature = (velocities, cloth = None))]
    fn set_velocities(
        &mut self,
        velocities: &Bound<'_, PyAny>,
        cloth: Option<&str>,
    ) -> PyResult<()> {
        let v = self.replace(self.sim.velocities(), velocities, cloth, "velocities")?;
        self.sim
            .set_velocities(&v)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Triangles (quads split in two) as an int64 array of shape (m, 3): of the cloth named,
    /// indexing its rows of `positions(cloth)`, or of every cloth, indexing `positions()`.
    /// Line elements (`l` springs) are not included.
    #[pyo3(signature = (cloth = None))]
    fn faces<'py>(
        &self,
        py: Python<'py>,
        cloth: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let model = self.sim.model();
        let triangles = match cloth {
            None => model.triangles(),
            Some(name) => {
                self.range(Some(name))?;
                model
                    .cloth(name)
                    .map(|c| c.mesh.triangles())
                    .unwrap_or_default()
            }
        };
        triangle_array(py, &triangles)
    }

    /// The colliders' names (`name = "..."`), None for a collider without one, in scene order
    /// (the indices `set_collider_pose` takes).
    #[getter]
    fn colliders(&self) -> Vec<Option<String>> {
        self.sim
            .model()
            .obstacles()
            .iter()
            .map(|o| o.name.clone())
            .collect()
    }

    /// Every handle (`[[cloth.handle]]`) as `(cloth name, k)`, the cloth's k-th handle, in the
    /// order of the indices `set_handle_pose` takes (cloths in scene order, each cloth's
    /// handles in order).
    #[getter]
    fn handles(&self) -> Vec<(String, usize)> {
        handle_names(self.sim.model())
    }

    /// Moves collider `collider` (an index or its `name`) to the pose `translation`,
    /// `rotation` (a quaternion [x, y, z, w], normalized) at `time`: a point at x0 at t = 0
    /// is then at c + T + R (x0 - c), c the collider's center in the scene. From its pose at
    /// `sim.time` it moves linearly (lerp, slerp) to the new pose, reached at `time` (default:
    /// the end of the next step, sim.time + scene.step_size), and holds it afterwards; this
    /// replaces its motion from the scene (or an earlier call). Raises IndexError (index out
    /// of range), ValueError (unknown name, a non-finite number, a zero quaternion, `time`
    /// not after sim.time) or TypeError, naming the argument and changing nothing. The motion
    /// set is part of save_state(): a simulation continued from it goes on with it.
    #[pyo3(
        signature = (collider, translation, rotation = None, time = None),
        text_signature = "(self, collider, translation, rotation=(0.0, 0.0, 0.0, 1.0), time=None)"
    )]
    fn set_collider_pose(
        &mut self,
        collider: &Bound<'_, PyAny>,
        translation: &Bound<'_, PyAny>,
        rotation: Option<&Bound<'_, PyAny>>,
        time: Option<f64>,
    ) -> PyResult<()> {
        let i = collider_index(self.sim.model(), collider)?;
        let to = pose_arg(translation, rotation)?;
        let motion = &self.sim.model().obstacles()[i].collider.motion;
        let field = format!("collider[{i}]");
        let motion = ramp(motion, self.sim.time(), self.until(time), to, &field)?;
        self.sim
            .set_obstacle_motion(i, motion)
            .map_err(simulation_error)
    }

    /// Moves handle `handle` (an index into `handles`, or a `(cloth name, k)` pair) to the
    /// pose `translation`, `rotation` at `time`, as `set_collider_pose` does a collider: its
    /// vertices go from where the handle's motion puts them at sim.time linearly to
    /// p + T + R (x0 - p), x0 their initial positions and p the handle's pivot, reached at
    /// `time` (default: the end of the next step) and held afterwards. Raises as
    /// `set_collider_pose`, and ValueError for a handle already released.
    #[pyo3(
        signature = (handle, translation, rotation = None, time = None),
        text_signature = "(self, handle, translation, rotation=(0.0, 0.0, 0.0, 1.0), time=None)"
    )]
    fn set_handle_pose(
        &mut self,
        handle: &Bound<'_, PyAny>,
        translation: &Bound<'_, PyAny>,
        rotation: Option<&Bound<'_, PyAny>>,
        time: Option<f64>,
    ) -> PyResult<()> {
        let i = handle_index(self.sim.model(), handle)?;
        let to = pose_arg(translation, rotation)?;
        let now = self.sim.time();
        let h = &self.sim.model().handles()[i];
        if let Some(r) = h.release.filter(|_| !h.holds(now)) {
            return Err(PyValueError::new_err(format!(
                "handle: handle {i} was released at {r} s (sim.time = {now} s): its vertices are free"
            )));
        }
        let field = format!("handle[{i}]");
        let motion = ramp(&h.motion, now, self.until(time), to, &field)?;
        self.sim
            .set_handle_motion(i, motion)
            .map_err(simulation_error)
    }

    /// The pose of collider `collider` (an index or its name) at sim.time, as new float64
    /// arrays `(translation (3,), rotation (4,))`, rotation a unit quaternion [x, y, z, w]
    /// (q and -q are the same rotation).
    fn collider_pose<'py>(
        &self,
        py: Python<'py>,
        collider: &Bound<'_, PyAny>,
    ) -> PyResult<PosePair<'py>> {
        let i = collider_index(self.sim.model(), collider)?;
        let motion = &self.sim.model().obstacles()[i].collider.motion;
        Ok(pose_arrays(py, motion, self.sim.time()))
    }

    /// The pose of handle `handle` (an index or a `(cloth name, k)` pair) at sim.time, as
    /// `collider_pose` (after its release: the pose its motion would give).
    fn handle_pose<'py>(
        &self,
        py: Python<'py>,
        handle: &Bound<'_, PyAny>,
    ) -> PyResult<PosePair<'py>> {
        let i = handle_index(self.sim.model(), handle)?;
        let motion = &self.sim.model().handles()[i].motion;
        Ok(pose_arrays(py, motion, self.sim.time()))
    }

    /// The vertices handle `handle` holds, as an int64 array of the rows of
    /// `positions(cloth)` (cloth-local indices, in the scene's order), `cloth` being
    /// `handles[i][0]`.
    fn handle_vertices<'py>(
        &self,
        py: Python<'py>,
        handle: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let model = self.sim.model();
        let i = handle_index(model, handle)?;
        let offset = model.cloths()[handle_cloth(model, i)].offset;
        let local = model.handles()[i]
            .particles
            .iter()
            .map(|&p| p as i64 - offset as i64);
        Ok(index_array(py, local))
    }

    /// The whole state (positions, velocities, the solver's warm start, time, step count) as
    /// bytes, with the scene's fingerprint: `Simulation.from_state(scene, bytes)` continues
    /// from here to the same bits.
    fn save_state<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let mut header = self.loaded.fingerprint.to_le_bytes().to_vec();
        header.extend_from_slice(STATE_TAG);
        let bytes = self.sim.snapshot().with_header(header).to_bytes();
        PyBytes::new(py, &bytes)
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation({:?}, frame {}, t = {} s, {} particles)",
            self.loaded.scene.path.display().to_string(),
            self.frame(),
            self.sim.time(),
            self.sim.positions().len()
        )
    }
}
