//! Scene files: TOML, SI units, y up.
//!
//! A scene names the time span and step ([`Scene::duration`], [`Scene::dt`],
//! [`Scene::frame_rate`]), gravity, solver settings and one or more cloths, each from an OBJ mesh
//! or a generated grid. [`Scene::load`] reads the file and every mesh and checks everything
//! before anything is simulated; every problem is an [`Error::Input`] naming the file and the
//! field (or the mesh line) at fault. Unknown keys and tables are errors, so a typo is never
//! silently ignored.
//!
//! ```toml
//! [simulation]
//! duration = 2.0                # s, a whole number of frames
//! dt = 0.005                    # s; 1/(frame_rate*dt) must be a whole number of steps
//! frame_rate = 50               # frames per simulated second
//! gravity = [0.0, -9.81, 0.0]   # m/s² (default)
//!
//! [solver]                      # optional; defaults shown
//! newton_iterations = 1
//! max_newton_iterations = 3     # where the linearized step is far off (docs/MATH.md §10)
//! tolerance = 1e-6
//! max_iterations = 1000
//! linear_solver = "pcg"         # or "direct"
//! damping_x_jacobian = false
//!
//! [[cloth]]
//! name = "sheet"
//! grid = { size = [1.0, 1.0], resolution = [33, 33], center = [0.0, 1.0, 0.0], normal = [0.0, 0.0, 1.0] }
//! density = 0.1                 # kg/m² (or vertex_mass = kg per vertex)
//! pin = [0, 32]
//!
//! [collision]                   # optional; defaults shown
//! thickness = 0.005             # m
//! self_collision = true
//! friction = 0.3                # Coulomb, every contact (cloth–cloth and obstacles)
//! stiffness = 1000.0            # N/m, cloth–cloth repulsion
//!
//! [[collider]]                  # zero or more
//! shape = "sphere"              # plane: point, normal · sphere: center, radius ·
//! center = [0.0, 0.25, 0.0]     # capsule: a, b, radius · box: center, half_extents,
//! radius = 0.25                 # rotation = [x, y, z, w] · mesh: mesh = "body.obj",
//!                               # center (optional pivot, default the file's origin)
//! friction = 0.5                # optional, overrides [collision].friction
//! velocity = [0.0, 0.0, 0.0]    # optional, m/s
//! angular_velocity = [0.0, 3.14, 0.0]  # optional, rad/s about the collider's center
//!
//! [[stitch]]                    # zero or more seams, cloth–cloth or within one cloth
//! a = { cloth = "sheet", vertices = [0, 1, 2] }
//! b = { cloth = "sheet", vertices = [30, 31, 32] }  # paired one to one, in order
//! stiffness = 1000.0            # N/m, optional (default shown)
//! damping = 0.0                 # N·s/m, optional (default shown)
//! ```
//!
//! Collisions are on when the scene has a `[collision]` table or any `[[collider]]` (colliders
//! alone use the default settings). A collider turns about its [`Collider::center`]: for a mesh
//! that is its optional `center` key, by default the origin of its OBJ file's coordinates (the
//! vertices are used as they are in the file, with no placement offset).
//!
//! Timing: the number of steps per frame is `round(1/(frame_rate·dt))` and must be whole within
//! 1e-6 relative and at least 1; the step actually taken is `1/(frame_rate·steps_per_frame)`
//! (equal to `dt` up to that rounding), so frame `k` is exactly the state at `k/frame_rate`.
//! `duration·frame_rate` must be a whole number of frames (within 1e-6 relative), at least 1;
//! frames `0..=frame_count` are produced, frame 0 being the initial state.

use crate::collision::colliders::Keys;
use crate::collision::settings::{CollisionSettings, Obstacle};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::mesh::Mesh;
use crate::model::{ClothDesc, Model, StitchDesc};
use crate::step::{LinearSolver, Simulation, SolverSettings};
use serde::Deserialize;
use std::path::{Path, PathBuf};

mod collider;
mod garment;
mod handle;
mod material;
mod stitch;
mod wind;

/// Relative tolerance for "whole number" checks on steps per frame and frame counts.
pub const WHOLE_TOLERANCE: f64 = 1e-6;

/// Largest accepted number of steps per frame and of frames (guards against absurd inputs).
pub const MAX_COUNT: f64 = 1e9;

/// A loaded and validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file (as given); meshes are relative to its folder.
    pub path: PathBuf,
    /// Simulated time span, s.
    pub duration: f64,
    /// Requested step size, s.
    pub dt: f64,
    /// Frames written per simulated second.
    pub frame_rate: f64,
    /// Gravitational acceleration, m/s² (default `[0, -9.81, 0]`).
    pub gravity: Vec3,
    /// Seconds simulated before frame 0 with every collider and handle held at its pose at
    /// `t = 0` (`[simulation] preroll`, default 0): seams close, the cloth settles.
    pub preroll: f64,
    /// Step settings from `[solver]`.
    pub solver: SolverSettings,
    /// The cloths, in file order.
    pub cloths: Vec<ClothDesc>,
    /// Collision settings: `Some` when the scene has a `[collision]` table or any
    /// `[[collider]]` (colliders without `[collision]` use [`CollisionSettings::default`]).
    pub collision: Option<CollisionSettings>,
    /// The `[[collider]]`s, in file order.
    pub obstacles: Vec<Obstacle>,
    /// The `[[stitch]]`es, in file order.
    pub stitches: Vec<StitchDesc>,
    /// The `[[wind]]`s, in file order (their air velocities add; none: no air force).
    pub wind: Vec<crate::forces::Wind>,
}

// ---------------------------------------------------------------------------------------------
// File format (serde). Optional fields are `Option` so that presence can be checked.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    simulation: SimulationTable,
    #[serde(default)]
    solver: SolverTable,
    #[serde(default)]
    cloth: Vec<ClothTable>,
    collision: Option<CollisionTable>,
    #[serde(default)]
    collider: Vec<toml::Table>,
    #[serde(default)]
    stitch: Vec<toml::Table>,
    #[serde(default)]
    garment: Vec<toml::Table>,
    #[serde(default)]
    wind: Vec<toml::Table>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CollisionTable {
    thickness: Option<f64>,
    self_collision: Option<bool>,
    friction: Option<f64>,
    stiffness: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulationTable {
    duration: f64,
    dt: f64,
    frame_rate: f64,
    gravity: Option<[f64; 3]>,
    preroll: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SolverTable {
    newton_iterations: Option<u32>,
    max_newton_iterations: Option<u32>,
    tolerance: Option<f64>,
    max_iterations: Option<usize>,
    linear_solver: Option<SolverName>,
    damping_x_jacobian: Option<bool>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum SolverName {
    Pcg,
    Direct,
}

/// A `[[cloth]]`: its own keys here, the material keys ([`material::KEYS`]) in `rest`, read by
/// [`material::material`] like a garment's (unknown keys are reported from there).
#[derive(Deserialize)]
struct ClothTable {
    name: String,
    mesh: Option<String>,
    grid: Option<GridTable>,
    disc: Option<DiscTable>,
    #[serde(default)]
    pin: Vec<u32>,
    initial_velocity: Option<[f64; 3]>,
    #[serde(default)]
    handle: Vec<toml::Table>,
    #[serde(flatten)]
    rest: toml::Table,
}

/// The keys of `[[cloth]]` besides the material's.
const CLOTH_KEYS: &[&str] = &[
    "name",
    "mesh",
    "grid",
    "disc",
    "pin",
    "initial_velocity",
    "handle",
];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridTable {
    size: [f64; 2],
    resolution: [i64; 2],
    center: Option<[f64; 3]>,
    normal: Option<[f64; 3]>,
}

/// `disc = { radius, edge_length, ring, center, normal }`: a flat disc triangulated in rings
/// ([`crate::textile::drape::disc`]), e.g. a Cusick drape specimen; with `ring`, one ring on
/// that radius ([`crate::textile::drape::disc_with_ring`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DiscTable {
    radius: f64,
    edge_length: f64,
    ring: Option<f64>,
    center: Option<[f64; 3]>,
    normal: Option<[f64; 3]>,
}

/// Largest generated grid, in vertices (2²⁴), so that a typo cannot exhaust memory.
pub const MAX_GRID_VERTICES: usize = crate::mesh::MAX_GENERATED_VERTICES;

/// Default gravity, m/s².
pub const DEFAULT_GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];
/// Default grid centre, m.
pub const DEFAULT_GRID_CENTER: [f64; 3] = [0.0, 0.0, 0.0];
/// Default grid normal (a sheet in the x–y plane, row 0 on top).
pub const DEFAULT_GRID_NORMAL: [f64; 3] = [0.0, 0.0, 1.0];

/// 1-based line number of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Turns a TOML/serde error into one line naming the line and, when it can, the key.
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', " ");
    let Some(span) = e.span() else {
        return msg;
    };
    let line = line_of(text, span.start);
    let line_text = text.lines().nth(line - 1).unwrap_or("");
    let key = line_text
        .split_once('=')
        .map(|(k, _)| k.trim())
        .filter(|k| !k.is_empty() && !k.starts_with('[') && !k.starts_with('#'));
    let header = line_text.trim();
    match key {
        Some(k) if !msg.contains(k) => format!("line {line}, `{k}`: {msg}"),
        _ if header.starts_with('[') && header.len() <= 40 => {
            format!("line {line}, in {header}: {msg}")
        }
        _ => format!("line {line}: {msg}"),
    }
}

/// A finite number ≥ 0.
fn positive(what: &str, field: &str, v: f64) -> std::result::Result<f64, String> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!(
            "{what}{field} must be a finite number > 0, got {v}"
        ))
    }
}

fn finite3(what: &str, field: &str, v: [f64; 3]) -> std::result::Result<Vec3, String> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vec3::from_array(v))
    } else {
        Err(format!(
            "{what}{field} must be finite, got [{}, {}, {}]",
            v[0], v[1], v[2]
        ))
    }
}

/// `round(x)` when `x` is a whole number within [`WHOLE_TOLERANCE`] relative, ≥ 1 and ≤ [`MAX_COUNT`].
fn whole(x: f64) -> Option<usize> {
    if !x.is_finite() {
        return None;
    }
    let n = x.round();
    if !(1.0..=MAX_COUNT).contains(&n) || (x - n).abs() > WHOLE_TOLERANCE * n {
        return None;
    }
    Some(n as usize)
}

impl Scene {
    /// Reads a scene file and every mesh it names, and validates everything (including building
    /// the model once, so that whatever [`Model::new`] would reject is reported here).
    pub fn load(path: &Path) -> Result<Scene> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path.display(), e))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            Error::input(
                path.display(),
                format!(
                    "not a text TOML file (invalid UTF-8 at byte {})",
                    e.utf8_error().valid_up_to()
                ),
            )
        })?;
        Scene::from_str(&text, path)
    }

    /// Parses scene text. `path` names the scene in messages and anchors relative mesh paths;
    /// meshes are read from disk.
    pub fn from_str(text: &str, path: &Path) -> Result<Scene> {
        let file_err = |m: String| Error::input(path.display(), m);
        if text.contains('\0') {
            return Err(file_err("not a text TOML file (contains NUL bytes)".into()));
        }
        let file: SceneFile = toml::from_str(text).map_err(|e| file_err(toml_message(text, &e)))?;
        let sim = &file.simulation;
        let s = "simulation.";
        let duration = positive(s, "duration", sim.duration).map_err(file_err)?;
        let dt = positive(s, "dt", sim.dt).map_err(file_err)?;
        let frame_rate = positive(s, "frame_rate", sim.frame_rate).map_err(file_err)?;
        let gravity = Vec3::from_array(sim.gravity.unwrap_or(DEFAULT_GRAVITY));
        let preroll = match sim.preroll {
            None => 0.0,
            Some(p) => crate::validate::nonneg("simulation.preroll", p)
                .map_err(|e| locate(e, text, path))?,
        };
        let steps = 1.0 / (frame_rate * dt);
        if whole(steps).is_none() {
            return Err(file_err(format!(
                "simulation: frame_rate × dt must divide 1 (a whole number of steps per frame): \
                 1/({frame_rate} × {dt}) = {steps}, which is not a whole number ≥ 1 within {WHOLE_TOLERANCE} relative"
            )));
        }
        let frames = duration * frame_rate;
        if whole(frames).is_none() {
            return Err(file_err(format!(
                "simulation.duration must be a whole number ≥ 1 of frames: duration × frame_rate = {duration} × {frame_rate} = {frames}"
            )));
        }

        // The loader parses; the settings and the model validate themselves (one validator
        // per fact), and their errors are worded here with the file and the line.
        let located = |e: Error| locate(e, text, path);
        let solver = solver_settings(&file.solver);
        solver.validate().map_err(located)?;

        if file.cloth.is_empty() && file.garment.is_empty() {
            return Err(file_err(
                "no [[cloth]] or [[garment]] table: a scene needs at least one cloth".into(),
            ));
        }
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut cloths: Vec<ClothDesc> = Vec::with_capacity(file.cloth.len());
        let mut attachments = Vec::new();
        for (i, c) in file.cloth.iter().enumerate() {
            let what = format!("cloth[{i}] '{}': ", c.name);
            let mesh = match (&c.mesh, &c.grid, &c.disc) {
                (Some(m), None, None) => {
                    let mesh_path = dir.join(m);
                    crate::io::obj::read_obj(&mesh_path).map_err(|e| match e {
                        Error::Io { path: p, cause } => Error::input(
                            path.display(),
                            format!("{what}mesh: cannot read '{p}': {cause}"),
                        ),
                        other => other,
                    })?
                }
                (None, Some(g), None) => grid_mesh(g, &what).map_err(file_err)?,
                (None, None, Some(d)) => disc_mesh(d, &what).map_err(file_err)?,
                (None, None, None) => {
                    return Err(file_err(format!(
                        "{what}missing field `mesh` (an OBJ file), `grid` or `disc`"
                    )));
                }
                _ => {
                    return Err(file_err(format!(
                        "{what}give one of mesh, grid and disc, not several"
                    )));
                }
            };
            let keys = Keys::new(&c.rest, format!("cloth[{i}]"), dir);
            let known: Vec<&str> = CLOTH_KEYS.iter().chain(material::KEYS).copied().collect();
            keys.only(&known, "[[cloth]]").map_err(located)?;
            let material = material::material(&keys).map_err(located)?;
            let mut handles = Vec::with_capacity(c.handle.len());
            for (k, t) in c.handle.iter().enumerate() {
                let (h, attach) = handle::handle(i, k, t, &mesh.positions, dir).map_err(located)?;
                if let Some(name) = attach {
                    attachments.push((i, k, name));
                }
                handles.push(h);
            }
            cloths.push(ClothDesc {
                name: c.name.clone(),
                mesh,
                material,
                pins: c.pin.clone(),
                initial_velocity: Vec3::from_array(c.initial_velocity.unwrap_or([0.0; 3])),
                handles,
            });
        }
        let mut collision = file.collision.as_ref().map(collision_settings);
        if let Some(c) = &collision {
            c.validate().map_err(located)?;
        }
        let mut obstacles = Vec::with_capacity(file.collider.len());
        let default_friction = collision.unwrap_or_default().friction;
        for (i, c) in file.collider.iter().enumerate() {
            obstacles.push(collider::obstacle(i, c, default_friction, dir).map_err(located)?);
        }
        collider::unique_names(&obstacles).map_err(located)?;
        handle::resolve_attachments(&mut cloths, &attachments, &obstacles).map_err(located)?;
        let mut stitches = (file.stitch.iter().enumerate())
            .map(|(i, t)| stitch::stitch(i, t, dir))
            .collect::<Result<Vec<_>>>()
            .map_err(located)?;
        for (i, t) in file.garment.iter().enumerate() {
            let (c, s) = garment::garment(i, t, dir).map_err(located)?;
            cloths.extend(c);
            stitches.extend(s);
        }
        let winds = (file.wind.iter().enumerate())
            .map(|(i, t)| wind::wind(i, t, dir))
            .collect::<Result<Vec<_>>>()
            .map_err(located)?;
        if collision.is_none() && !obstacles.is_empty() {
            collision = Some(CollisionSettings::default());
        }
        let scene = Scene {
            path: path.to_path_buf(),
            duration,
            dt,
            frame_rate,
            gravity,
            preroll,
            solver,
            cloths,
            collision,
            obstacles,
            stitches,
            wind: winds,
        };
        // Whatever the model itself rejects (cloth names, materials, pins, density on vertices
        // that belong to no face) is reported now, before anything is simulated or written.
        scene.unchecked_model().map_err(located)?;
        Ok(scene)
    }

    /// Steps per output frame: `round(1/(frame_rate·dt))` (checked whole and ≥ 1 at load).
    pub fn steps_per_frame(&self) -> usize {
        whole(1.0 / (self.frame_rate * self.dt)).unwrap_or(1)
    }

    /// Frames after frame 0: `round(duration·frame_rate)` (checked whole and ≥ 1 at load).
    /// A run writes `frame_count() + 1` frames.
    pub fn frame_count(&self) -> usize {
        whole(self.duration * self.frame_rate).unwrap_or(1)
    }

    /// Total steps of a run: `frame_count() · steps_per_frame()`.
    pub fn step_count(&self) -> usize {
        self.frame_count().saturating_mul(self.steps_per_frame())
    }

    /// The step actually taken, s: `1/(frame_rate·steps_per_frame)`, equal to `dt` up to the
    /// rounding allowed at load, so that frame `k` falls exactly at `k/frame_rate`.
    pub fn step_size(&self) -> f64 {
        1.0 / (self.frame_rate * self.steps_per_frame() as f64)
    }

    /// Builds the model of the scene. Model errors are reported against the scene file.
    pub fn model(&self) -> Result<Model> {
        self.unchecked_model().map_err(|e| self.blame(e))
    }

    /// The model, with the model's own errors.
    fn unchecked_model(&self) -> Result<Model> {
        let mut m = Model::new(self.cloths.clone(), self.gravity)?
            .with_stitches(&self.stitches)?
            .with_wind(&self.wind)?;
        m.collision = self.collision;
        m.obstacles = self.obstacles.clone();
        Ok(m)
    }

    /// Steps of the pre-roll: `ceil(preroll / step_size)` (0 without one).
    pub fn preroll_steps(&self) -> usize {
        let n = (self.preroll / self.step_size() - WHOLE_TOLERANCE).ceil();
        if n > 0.0 { n as usize } else { 0 }
    }

    /// [`Scene::build`], then the pre-roll ([`Simulation::preroll`]): the simulation at frame 0
    /// of a fresh run. (A resumed run uses [`Scene::build`] and restores its snapshot.)
    pub fn start(&self) -> Result<Simulation> {
        let mut sim = self.build()?;
        sim.preroll(self.preroll_steps(), self.step_size())?;
        Ok(sim)
    }

    /// Builds the model and the simulation, ready to step with [`Scene::step_size`].
    pub fn build(&self) -> Result<Simulation> {
        let model = self.model()?;
        Simulation::new(model, self.solver).map_err(|e| self.blame(e))
    }

    fn blame(&self, e: Error) -> Error {
        match e {
            Error::Invalid(m) => Error::input(self.path.display(), m),
            e @ Error::Field { .. } => Error::input(self.path.display(), e.to_string()),
            other => other,
        }
    }
}

fn solver_settings(t: &SolverTable) -> SolverSettings {
    let d = SolverSettings::default();
    SolverSettings {
        newton_iterations: t.newton_iterations.unwrap_or(d.newton_iterations),
        max_newton_iterations: t.max_newton_iterations.unwrap_or(d.max_newton_iterations),
        tolerance: t.tolerance.unwrap_or(d.tolerance),
        max_iterations: t.max_iterations.unwrap_or(d.max_iterations),
        linear_solver: match t.linear_solver {
            None => d.linear_solver,
            Some(SolverName::Pcg) => LinearSolver::Pcg,
            Some(SolverName::Direct) => LinearSolver::Direct,
        },
        damping_x_jacobian: t.damping_x_jacobian.unwrap_or(d.damping_x_jacobian),
        ..d
    }
}

fn collision_settings(t: &CollisionTable) -> CollisionSettings {
    let d = CollisionSettings::default();
    CollisionSettings {
        thickness: t.thickness.unwrap_or(d.thickness),
        self_collision: t.self_collision.unwrap_or(d.self_collision),
        friction: t.friction.unwrap_or(d.friction),
        stiffness: t.stiffness.unwrap_or(d.stiffness),
    }
}

/// Words a library error about a field ([`Error::Field`]) for the scene file: its path and,
/// when the field (or its table) can be found in `text`, the line: `s.toml: line 12,
/// cloth[0].damping: must be ...`.
fn locate(e: Error, text: &str, path: &Path) -> Error {
    match e {
        Error::Field { field, message } => {
            let at = match field_line(text, &field) {
                Some(line) => format!("line {line}, "),
                None => String::new(),
            };
            Error::input(path.display(), format!("{at}{field}: {message}"))
        }
        Error::Invalid(m) => Error::input(path.display(), m),
        other => other,
    }
}

/// The 1-based line of `field` (`table.key`, `table[i].key`, `table[i]`) in scene `text`: the
/// key's line inside its table, or the table's header when the key is not written (a default).
fn field_line(text: &str, field: &str) -> Option<usize> {
    let (table, key) = match field.split_once('.') {
        Some((t, k)) => (t, Some(k.split(['.', '[']).next().unwrap_or(k))),
        None => (field, None),
    };
    let (name, index) = match table.split_once('[') {
        Some((n, i)) => (n, Some(i.trim_end_matches(']').parse::<usize>().ok()?)),
        None => (table, None),
    };
    let header = match index {
        Some(_) => format!("[[{name}]]"),
        None => format!("[{name}]"),
    };
    let lines: Vec<&str> = text.lines().collect();
    let starts: Vec<usize> = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.split('#').next().unwrap_or("").trim() == header)
        .map(|(i, _)| i)
        .collect();
    let start = *starts.get(index.unwrap_or(0))?;
    let Some(key) = key else {
        return Some(start + 1);
    };
    for (i, l) in lines.iter().enumerate().skip(start + 1) {
        let l = l.trim();
        if l.starts_with('[') {
            break;
        }
        if l.split_once('=').is_some_and(|(k, _)| k.trim() == key) {
            return Some(i + 1);
        }
    }
    Some(start + 1)
}

fn grid_mesh(g: &GridTable, what: &str) -> std::result::Result<Mesh, String> {
    let mut res = [0usize; 2];
    for k in 0..2 {
        res[k] = usize::try_from(g.resolution[k])
            .ok()
            .filter(|&r| r >= 2)
            .ok_or_else(|| {
                format!(
                    "{what}grid.resolution must be two whole numbers ≥ 2, got [{}, {}]",
                    g.resolution[0], g.resolution[1]
                )
            })?;
    }
    let vertices = res[0].saturating_mul(res[1]);
    if vertices > MAX_GRID_VERTICES {
        return Err(format!(
            "{what}grid.resolution [{}, {}] gives {vertices} vertices; at most {MAX_GRID_VERTICES} are allowed",
            res[0], res[1]
        ));
    }
    for k in 0..2 {
        positive(what, "grid.size", g.size[k])?;
    }
    let center = finite3(what, "grid.center", g.center.unwrap_or(DEFAULT_GRID_CENTER))?;
    let normal = finite3(what, "grid.normal", g.normal.unwrap_or(DEFAULT_GRID_NORMAL))?;
    if normal.length() == 0.0 {
        return Err(format!("{what}grid.normal must be a non-zero vector"));
    }
    Mesh::grid(g.size, res, center, normal).map_err(|e| format!("{what}grid: {e}"))
}

/// The cloth of a `disc` key: [`crate::textile::drape::disc`] laid in the plane through
/// `center` normal to `normal`, its texture coordinates (warp `u`, weft `v`) the disc's own
/// 2-D coordinates in m.
fn disc_mesh(d: &DiscTable, what: &str) -> std::result::Result<Mesh, String> {
    let radius = positive(what, "disc.radius", d.radius)?;
    let edge = positive(what, "disc.edge_length", d.edge_length)?;
    let center = finite3(what, "disc.center", d.center.unwrap_or(DEFAULT_GRID_CENTER))?;
    let normal = finite3(what, "disc.normal", d.normal.unwrap_or(DEFAULT_GRID_NORMAL))?;
    if normal.length() == 0.0 {
        return Err(format!("{what}disc.normal must be a non-zero vector"));
    }
    if let Some(ring) = d.ring
        && !(ring.is_finite() && ring > 0.0 && ring < radius)
    {
        return Err(format!(
            "{what}disc.ring must lie strictly between 0 and disc.radius {radius}, got {ring}"
        ));
    }
    let flat = match d.ring {
        None => crate::textile::drape::disc(radius, edge),
        Some(ring) => crate::textile::drape::disc_with_ring(radius, edge, ring),
    }
    .map_err(|e| format!("{what}{e}"))?;
    Ok(flat.placed(center, normal))
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[simulation]
duration = 1
dt = 0.01
frame_rate = 25

[[cloth]]
name = "sheet"
grid = { size = [1, 2], resolution = [3, 4] }
vertex_mass = 0.01
pin = [0, 2]
"#;

    fn load(text: &str) -> Result<Scene> {
        Scene::from_str(text, Path::new("dir/s.toml"))
    }

    #[test]
    fn a_disc_cloth_lies_in_its_plane_and_bad_discs_are_errors() {
        let disc = BASE.replace(
            "grid = { size = [1, 2], resolution = [3, 4] }",
            "disc = { radius = 0.15, edge_length = 0.05, center = [0, 1, 0], normal = [0, 1, 0] }",
        );
        let s = load(&disc).unwrap();
        let m = &s.cloths[0].mesh;
        // 3 rings of 6k vertices and a centre, all at y = 1 within 0.15 of the centre
        assert_eq!(m.positions.len(), 1 + 6 + 12 + 18);
        for p in &m.positions {
            assert!(
                (p.y - 1.0).abs() < 1e-15 && p.x.hypot(p.z) < 0.15 + 1e-12,
                "{p}"
            );
        }
        // faces turned to face +y, and texture coordinates for warp and weft
        let t = m.triangles()[0].map(|i| m.positions[i as usize]);
        assert!((t[1] - t[0]).cross(t[2] - t[0]).y > 0.0);
        assert_eq!(m.face_uv.len(), m.faces.len());
        for (bad, message) in [
            (
                "radius = 0.15",
                "disc.radius must be a finite number > 0, got -1",
            ),
            (
                "edge_length = 0.05",
                "disc.edge_length must be a finite number > 0, got -1",
            ),
            (
                "normal = [0, 1, 0]",
                "disc.normal must be a non-zero vector",
            ),
        ] {
            let key = bad.split(" =").next().unwrap();
            let value = if key == "normal" { "[0, 0, 0]" } else { "-1" };
            let text = disc.replace(bad, &format!("{key} = {value}"));
            let e = load(&text).unwrap_err().to_string();
            assert!(e.contains(message) && e.contains("cloth[0] 'sheet'"), "{e}");
        }
        let both = disc.replace(
            "name = \"sheet\"",
            "name = \"sheet\"\ngrid = { size = [1, 1], resolution = [2, 2] }",
        );
        let e = load(&both).unwrap_err().to_string();
        assert!(e.contains("give one of mesh, grid and disc"), "{e}");
        // a ring of vertices inside the disc: on its circle; outside it: an error
        let ringed = disc.replace("edge_length = 0.05", "edge_length = 0.05, ring = 0.1");
        let m = &load(&ringed).unwrap().cloths[0].mesh;
        let on_ring = m
            .positions
            .iter()
            .filter(|p| ((p.x * p.x + p.z * p.z).sqrt() - 0.1).abs() < 1e-12)
            .count();
        assert_eq!(on_ring, 12);
        for ring in ["0.15", "0", "-0.1"] {
            let text = disc.replace(
                "edge_length = 0.05",
                &format!("edge_length = 0.05, ring = {ring}"),
            );
            let e = load(&text).unwrap_err().to_string();
            assert!(
                e.contains("disc.ring must lie strictly between 0 and disc.radius 0.15")
                    && e.contains("cloth[0] 'sheet'"),
                "{e}"
            );
        }
    }

    #[test]
    fn defaults_and_integer_numbers_are_accepted() {
        let s = load(BASE).unwrap();
        assert_eq!(s.steps_per_frame(), 4);
        assert_eq!(s.frame_count(), 25);
        assert_eq!(s.step_count(), 100);
        assert_eq!(s.gravity, Vec3::new(0.0, -9.81, 0.0));
        assert_eq!(s.solver, SolverSettings::default());
        assert_eq!(s.cloths[0].mesh.vertex_count(), 12);
        assert_eq!(s.cloths[0].material.stretch_stiffness, 1000.0);
        assert_eq!(s.cloths[0].pins, vec![0, 2]);
        assert!((s.step_size() - 0.01).abs() < 1e-15);
    }

    fn err(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    #[test]
    fn unknown_fields_and_tables_are_errors_naming_the_line() {
        let e = err(&BASE.replace("vertex_mass", "vertex_mas"));
        assert!(
            e.starts_with("dir/s.toml: line 10") && e.contains("vertex_mas"),
            "{e}"
        );
        let e = err(&format!("{BASE}\n[collisions]\nthickness = 1\n"));
        assert!(e.contains("collisions"), "{e}");
        let e = err(&BASE.replace("dt = 0.01\n", ""));
        assert!(e.contains("missing field `dt`"), "{e}");
    }

    #[test]
    fn non_physical_values_are_named() {
        let cases = [
            (BASE.replace("dt = 0.01", "dt = 0"), "simulation.dt"),
            (BASE.replace("dt = 0.01", "dt = -1"), "simulation.dt"),
            (
                BASE.replace("dt = 0.01", "dt = 0.003"),
                "whole number of steps",
            ),
            (
                BASE.replace("duration = 1", "duration = 1.01"),
                "simulation.duration",
            ),
            (
                BASE.replace("pin = [0, 2]", "pin = [0, 12]"),
                "line 11, cloth[0].pin: 12 is out of range",
            ),
            (
                BASE.replace("pin = [0, 2]", "stretch_stiffness = -1"),
                "line 11, cloth[0].stretch_stiffness: must be a finite number ≥ 0, got -1",
            ),
            (
                BASE.replace("vertex_mass = 0.01", "vertex_mass = -0.01"),
                "vertex_mass",
            ),
            (
                BASE.replace("vertex_mass = 0.01", "vertex_mass = 0.01\ndensity = 1"),
                "not both",
            ),
            (
                BASE.replace("name = \"sheet\"", "name = \"a b\""),
                "white space",
            ),
            (
                format!("{BASE}\n[solver]\ntolerance = 0\n"),
                "solver.tolerance",
            ),
            (
                format!("{BASE}\n[solver]\nmax_iterations = 0\n"),
                "solver.max_iterations",
            ),
            (
                format!("{BASE}\n[solver]\nmax_newton_iterations = 0\n"),
                "solver.max_newton_iterations",
            ),
            (
                format!("{BASE}\n[solver]\nlinear_solver = \"lu\"\n"),
                "line 14",
            ),
            (
                BASE.replace("resolution = [3, 4]", "resolution = [100000, 100000]"),
                "at most 16777216",
            ),
            (
                BASE.replace("resolution = [3, 4]", "resolution = [1, 4]"),
                "≥ 2",
            ),
        ];
        for (text, want) in cases {
            let e = err(&text);
            assert!(
                e.starts_with("dir/s.toml: ") && e.contains(want),
                "{e:?} lacks {want:?}"
            );
        }
        let two = format!("{BASE}{}", &BASE[BASE.find("[[cloth]]").unwrap()..]);
        let e = err(&two);
        assert!(
            e.contains("cloth[1].name: 'sheet' is already used by cloth[0]"),
            "{e}"
        );
    }

    #[test]
    fn missing_mesh_names_the_scene_the_cloth_and_the_mesh() {
        let text = BASE.replace(
            "grid = { size = [1, 2], resolution = [3, 4] }",
            "mesh = \"nope.obj\"",
        );
        let e = err(&text);
        assert!(
            e.starts_with("dir/s.toml: cloth[0] 'sheet': mesh: cannot read 'dir/nope.obj'"),
            "{e}"
        );
    }

    #[test]
    fn collision_table_and_colliders_are_parsed() {
        let s = load(BASE).unwrap();
        assert!(s.collision.is_none() && s.obstacles.is_empty());
        assert!(s.model().unwrap().collision.is_none());
        let text = format!(
            "{BASE}\n[collision]\nthickness = 0.01\nself_collision = false\n\n\
             [[collider]]\nshape = \"sphere\"\ncenter = [0, 1, 0]\nradius = 0.5\nfriction = 0.5\n\
             angular_velocity = [0, 3, 0]\n\n\
             [[collider]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 0.1, 1]\nrotation = [0, 0, 0, 2]\n\n\
             [[collider]]\nshape = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 2, 0]\n\n\
             [[collider]]\nshape = \"capsule\"\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\n"
        );
        let s = load(&text).unwrap();
        let c = s.collision.unwrap();
        assert_eq!(
            c,
            CollisionSettings {
                thickness: 0.01,
                self_collision: false,
                ..CollisionSettings::default()
            }
        );
        assert_eq!(s.obstacles.len(), 4);
        assert_eq!(s.obstacles[0].friction, 0.5);
        assert_eq!(s.obstacles[1].friction, 0.3);
        assert_eq!(
            s.obstacles[0].collider.motion.velocity(0.0).1,
            Vec3::new(0.0, 3.0, 0.0)
        );
        match &s.obstacles[1].collider.shape {
            crate::collision::colliders::Shape::Box(b) => {
                assert_eq!(b.rotation, glam::DQuat::IDENTITY)
            }
            other => panic!("{other:?}"),
        }
        let m = s.model().unwrap();
        assert_eq!(m.obstacles.len(), 4);
        assert!(m.collision.is_some());
        // colliders alone turn collisions on with the defaults
        let text = format!(
            "{BASE}\n[[collider]]\nshape = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\n"
        );
        assert_eq!(
            load(&text).unwrap().collision,
            Some(CollisionSettings::default())
        );
    }

    #[test]
    fn bad_collision_values_are_named() {
        let sphere = "[[collider]]\nshape = \"sphere\"\ncenter = [0, 1, 0]\nradius = 0.5\n";
        let cases = [
            ("[collision]\nthickness = -1\n".to_string(), "collision.thickness: must be a finite number > 0, got -1"),
            ("[collision]\nfriction = nan\n".to_string(), "collision.friction: must be a finite number ≥ 0, got NaN"),
            ("[collision]\nstiffness = 0\n".to_string(), "collision.stiffness"),
            ("[collision]\nthicknes = 1\n".to_string(), "unknown field `thicknes`"),
            (sphere.replace("0.5", "-0.5"), "line 16, collider[0].radius: must be a finite number > 0, got -0.5"),
            (sphere.replace("sphere", "cone"), "collider[0].shape: unknown shape 'cone', expected one of \"plane\", \"sphere\", \"capsule\", \"box\", \"mesh\""),
            (sphere.replace("center = [0, 1, 0]\n", ""), "collider[0].center: missing (this shape needs it)"),
            (format!("{sphere}friction = -1\n"), "line 17, collider[0].friction: must be a finite number ≥ 0, got -1"),
            (format!("{sphere}normal = [0, 1, 0]\n"), "collider[0].normal: not a key of a sphere (it belongs to plane)"),
            (format!("{sphere}spin = 1\n"), "collider[0].spin: unknown key of [[collider]]"),
            (format!("{sphere}velocity = [0, inf, 0]\n"), "collider[0].velocity: must be finite, got [0, inf, 0]"),
            ("[[collider]]\nshape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n".into(), "collider[0].normal: must be a non-zero vector"),
            ("[[collider]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 0, 1]\n".into(), "collider[0].half_extents: must be three finite numbers > 0, got [1, 0, 1]"),
            ("[[collider]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 1, 1]\nrotation = [0, 0, 0, 0]\n".into(), "collider[0].rotation: must be a finite non-zero quaternion [x, y, z, w], got [0, 0, 0, 0]"),
            ("[[collider]]\nshape = \"mesh\"\nmesh = \"nope.obj\"\n".into(), "collider[0].mesh: cannot read 'dir/nope.obj'"),
            ("[[collider]]\nshape = \"mesh\"\nmesh = \"nope.obj\"\ncenter = [0, nan, 0]\n".into(), "collider[0].center: must be finite, got [0, NaN, 0]"),
            ("[[collider]]\nshape = \"mesh\"\nmesh = \"nope.obj\"\ncenter = [0, 0]\n".into(), "center"),
            ("[[collider]]\nshape = \"capsule\"\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = 0.1\ncenter = [0, 0, 0]\n".into(), "collider[0].center: not a key of a capsule (it belongs to sphere, box, mesh)"),
        ];
        for (extra, want) in cases {
            let e = err(&format!("{BASE}\n{extra}"));
            assert!(
                e.starts_with("dir/s.toml: ") && e.contains(want),
                "{e:?} lacks {want:?}"
            );
        }
    }

    #[test]
    fn a_field_error_names_the_line_of_its_key_or_of_its_table() {
        let text =
            format!("{BASE}\n[[cloth]]\nname = \"b\"\ndamping = 2\n\n[solver]\ntolerance = 3\n");
        assert_eq!(field_line(&text, "cloth[0].pin"), Some(11));
        assert_eq!(field_line(&text, "cloth[1].damping"), Some(15));
        // not written: the default was used, the table's header is named
        assert_eq!(field_line(&text, "cloth[1].air_drag"), Some(13));
        assert_eq!(field_line(&text, "solver.tolerance"), Some(18));
        assert_eq!(field_line(&text, "collision.thickness"), None);
        assert_eq!(field_line(&text, "cloth[2].name"), None);
        let e = err(&BASE.replace("pin = [0, 2]", "damping = -3"));
        assert_eq!(
            e,
            "dir/s.toml: line 11, cloth[0].damping: must be a finite number ≥ 0, got -3"
        );
        let e = err(&format!("{BASE}\n[simulation.x]\n")
            .replace("frame_rate = 25", "frame_rate = 25\ngravity = [0, nan, 0]"));
        assert!(e.contains("simulation"), "{e}");
    }
}
