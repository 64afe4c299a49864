//! The simulated system: particles (structure of arrays), springs and per-cloth bookkeeping.
//!
//! A [`Model`] is built once from one or more [`ClothDesc`]s; all cloths share one particle
//! array, each cloth owning a contiguous range of it ([`ClothInfo`]).

use crate::error::{Error, Result};
use crate::math::{Mat3, Vec3};
use crate::mesh::Mesh;
use crate::validate;

/// How particle masses are given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MassSpec {
    /// The same mass for every vertex, kg.
    PerVertex(f64),
    /// Area density in kg/m², lumped to vertices (a third of each triangle's area, quads split in two).
    Density(f64),
}

/// Material parameters of one cloth. Stiffness in N/m per spring, damping in N·s/m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Stiffness of the springs along mesh edges and line elements, N/m.
    pub stretch_stiffness: f64,
    /// Stiffness of the quad-diagonal springs, N/m.
    pub shear_stiffness: f64,
    /// Stiffness of the bend springs (across shared edges), N/m.
    pub bend_stiffness: f64,
    /// Damping along every spring, N·s/m.
    pub damping: f64,
    /// Linear air drag per vertex, N·s/m (`f = -c v`).
    pub air_drag: f64,
    /// Particle masses.
    pub mass: MassSpec,
    /// Which forces resist deformation: the seeds' springs or the shell (membrane and hinge
    /// bending in physical units, docs/MATERIALS.md).
    pub model: ClothModel,
    /// The shell model's parameters (read when `model` is [`ClothModel::Shell`]).
    pub shell: Shell,
    /// No edge ends a step longer than `(1 + limit)` times its rest length (none when `None`).
    pub strain_limit: Option<f64>,
    /// Pressure inside a closed cloth, Pa (0: none).
    pub pressure: f64,
}

impl Material {
    /// One line for summaries: the model and its parameters, the strain limit and pressure.
    pub fn describe(&self) -> String {
        let pair = |p: [f64; 2]| match p[0] == p[1] {
            true => sig4(p[0]),
            false => format!("[{}, {}] (warp, weft)", sig4(p[0]), sig4(p[1])),
        };
        let mut out = match self.model {
            ClothModel::Springs => format!(
                "springs: stretch {} N/m, shear {} N/m, bend {} N/m, damping {} N·s/m",
                self.stretch_stiffness, self.shear_stiffness, self.bend_stiffness, self.damping
            ),
            ClothModel::Shell => {
                let s = &self.shell;
                let shear = match s.shear_modulus {
                    Some(g) => format!("{} N/m", sig4(g)),
                    None => format!(
                        "{} N/m (isotropic)",
                        sig4(crate::forces::membrane::MembraneLaw::isotropic_shear(
                            s.stretch_modulus,
                            s.poisson
                        ))
                    ),
                };
                format!(
                    "shell: stretch modulus {} N/m, poisson {}, shear modulus {shear}, bending rigidity {} N·m, damping {} s",
                    pair(s.stretch_modulus),
                    sig4(s.poisson),
                    pair(s.bending_rigidity),
                    s.damping
                )
            }
        };
        if let Some(l) = self.strain_limit {
            out.push_str(&format!(", strain limit {l}"));
        }
        if self.pressure != 0.0 {
            out.push_str(&format!(", pressure {} Pa", self.pressure));
        }
        out
    }
}

/// `x` to 4 significant digits, trailing zeros dropped (`1e-5`, `85.74`, `0.0036`).
fn sig4(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = 3 - x.abs().log10().floor() as i32;
    if (0..=6).contains(&digits) {
        let t = format!("{x:.*}", digits as usize);
        let t = if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.')
        } else {
            &t
        };
        t.to_string()
    } else {
        format!("{x:.3e}")
    }
}

/// Which forces resist a cloth's deformation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClothModel {
    /// Stretch, shear and bend springs in N/m per spring (the seeds' model).
    #[default]
    Springs,
    /// A membrane on triangles and hinge bending on interior edges, in physical units.
    Shell,
}

/// Parameters of the shell model, in physical units. Warp and weft are the rest shape's `u` and
/// `v` directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shell {
    /// Stretch modulus (Young's modulus times thickness), N/m, along `[warp, weft]`.
    pub stretch_modulus: [f64; 2],
    /// Poisson's ratio: weft strain from warp stress (`ν₁₂` of docs/MATH.md §20).
    pub poisson: f64,
    /// In-plane shear modulus, N/m (`None`: the isotropic value from the stretch moduli and
    /// Poisson's ratio).
    pub shear_modulus: Option<f64>,
    /// Bending rigidity, N·m, of a strip cut along `[warp, weft]` (docs/MATERIALS.md).
    pub bending_rigidity: [f64; 2],
    /// Stiffness-proportional damping, s (the damping force is `-damping · H v`, `H` the
    /// elastic Hessian).
    pub damping: f64,
}

impl Default for Shell {
    fn default() -> Self {
        Shell {
            stretch_modulus: [1000.0, 1000.0],
            poisson: 0.3,
            shear_modulus: None,
            bending_rigidity: [1e-5, 1e-5],
            damping: 0.0,
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            stretch_stiffness: 1000.0,
            shear_stiffness: 100.0,
            bend_stiffness: 1.0,
            damping: 0.01,
            air_drag: 0.0,
            mass: MassSpec::Density(0.1),
            model: ClothModel::Springs,
            shell: Shell::default(),
            strain_limit: None,
            pressure: 0.0,
        }
    }
}

/// Checks the shell model's parameters; `field` makes a key's path (`cloth[0].poisson`).
fn validate_shell(s: &Shell, field: &dyn Fn(&str) -> String) -> Result<()> {
    for y in s.stretch_modulus {
        validate::positive(&field("stretch_modulus"), y)?;
    }
    for b in s.bending_rigidity {
        validate::nonneg(&field("bending_rigidity"), b)?;
    }
    validate::nonneg(&field("damping"), s.damping)?;
    if let Some(g) = s.shear_modulus {
        validate::positive(&field("shear_modulus"), g)?;
    }
    // ν₁₂ ν₂₁ = ν² E₂/E₁ < 1 keeps the plane-stress law positive definite (a knit's ν may be
    // negative)
    let nu = s.poisson;
    let [y1, y2] = s.stretch_modulus;
    if !(nu.is_finite() && nu * nu * y2 / y1 < 1.0) {
        return Err(Error::field(
            field("poisson"),
            format!(
                "must be finite with poisson² × weft/warp modulus < 1 (a positive definite law), got {nu} with moduli [{y1}, {y2}]"
            ),
        ));
    }
    Ok(())
}

/// Everything needed to add one cloth to a model.
#[derive(Clone, Debug)]
pub struct ClothDesc {
    /// Unique name (the `o` name in OBJ output).
    pub name: String,
    /// Geometry and topology; positions are the rest shape and the initial state.
    pub mesh: Mesh,
    /// Material.
    pub material: Material,
    /// 0-based vertex indices held in place.
    pub pins: Vec<u32>,
    /// Initial velocity of every vertex, m/s.
    pub initial_velocity: Vec3,
    /// Handles: vertices that follow a prescribed motion (moving pins).
    pub handles: Vec<crate::constraints::handles::HandleDesc>,
}

/// What kind of mesh feature a spring was generated from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpringKind {
    /// Mesh edge or line element.
    Stretch,
    /// Quad diagonal.
    Shear,
    /// Across a shared edge.
    Bend,
}

/// All springs of the model, as parallel arrays.
#[derive(Clone, Debug, Default)]
pub struct Springs {
    /// First particle.
    pub i: Vec<u32>,
    /// Second particle.
    pub j: Vec<u32>,
    /// Rest length, m.
    pub rest: Vec<f64>,
    /// Stiffness, N/m.
    pub stiffness: Vec<f64>,
    /// Damping along the spring, N·s/m.
    pub damping: Vec<f64>,
    /// Origin of each spring.
    pub kind: Vec<SpringKind>,
}

impl Springs {
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.i.len()
    }
    /// True when there are no springs.
    pub fn is_empty(&self) -> bool {
        self.i.is_empty()
    }
    /// Appends one spring.
    pub fn push(
        &mut self,
        i: u32,
        j: u32,
        rest: f64,
        stiffness: f64,
        damping: f64,
        kind: SpringKind,
    ) {
        self.i.push(i);
        self.j.push(j);
        self.rest.push(rest);
        self.stiffness.push(stiffness);
        self.damping.push(damping);
        self.kind.push(kind);
    }
    /// Number of springs of one kind.
    pub fn count(&self, kind: SpringKind) -> usize {
        self.kind.iter().filter(|&&k| k == kind).count()
    }
}

/// Where one cloth lives in the model.
#[derive(Clone, Debug)]
pub struct ClothInfo {
    /// The cloth's name.
    pub name: String,
    /// Index of its first particle.
    pub offset: usize,
    /// The input mesh (topology for output; positions = initial state).
    pub mesh: Mesh,
    /// Its material.
    pub material: Material,
}

impl ClothInfo {
    /// Particle range of this cloth.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.mesh.positions.len()
    }
}

/// Particles, springs and external-force parameters. Built and validated once by
/// [`Model::new`] (and [`Model::with_collisions`]); read through its accessors. Only the state
/// (positions, velocities) can change afterwards, through checked setters.
#[derive(Clone, Debug)]
pub struct Model {
    /// Positions, m.
    pub(crate) x: Vec<Vec3>,
    /// Velocities, m/s.
    pub(crate) v: Vec<Vec3>,
    /// Lumped masses, kg (all > 0).
    pub(crate) mass: Vec<f64>,
    /// Pinned particles keep their position exactly.
    pub(crate) pinned: Vec<bool>,
    /// Linear air drag coefficient per particle, N·s/m.
    pub(crate) drag: Vec<f64>,
    /// Springs.
    pub(crate) springs: Springs,
    /// Gravitational acceleration, m/s².
    pub(crate) gravity: Vec3,
    /// The cloths, in order.
    pub(crate) cloths: Vec<ClothInfo>,
    /// Collision handling; `None` turns collisions off (default: `None`).
    pub(crate) collision: Option<crate::collision::settings::CollisionSettings>,
    /// Obstacles (used when `collision` is set).
    pub(crate) obstacles: Vec<crate::collision::settings::Obstacle>,
    /// Handles of every cloth (global particle indices).
    pub(crate) handles: Vec<crate::constraints::handles::Handle>,
    /// Stitched particle pairs (see [`Model::with_stitches`]).
    pub(crate) stitches: Vec<Stitch>,
    /// Pressure inside each cloth, Pa (0: none), in cloth order.
    pub(crate) pressure: Vec<f64>,
    /// The winds, whose air velocities add (see [`Model::with_wind`]).
    pub(crate) wind: Vec<crate::forces::Wind>,
    /// Each cloth's strain limit ([`Material::strain_limit`]), in cloth order.
    pub(crate) strain_limits: Vec<Option<f64>>,
}

/// One side of a stitch: a cloth by name and vertices of its mesh, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct StitchEnd {
    /// The cloth's name.
    pub cloth: String,
    /// Vertex indices into that cloth's mesh.
    pub vertices: Vec<u32>,
}

/// A seam: `a.vertices[k]` is sewn to `b.vertices[k]` for every `k` (docs/MATH.md §2.1).
#[derive(Clone, Debug, PartialEq)]
pub struct StitchDesc {
    /// The first side.
    pub a: StitchEnd,
    /// The second side (as many vertices as `a`).
    pub b: StitchEnd,
    /// Stiffness of each pair's zero-length spring, N/m (> 0).
    pub stiffness: f64,
    /// Damping of each pair's relative velocity, N·s/m (≥ 0).
    pub damping: f64,
}

/// One stitched pair, in global particle indices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stitch {
    /// First particle.
    pub a: u32,
    /// Second particle (never `a`).
    pub b: u32,
    /// Stiffness, N/m.
    pub stiffness: f64,
    /// Damping, N·s/m.
    pub damping: f64,
}

/// `values` has one finite entry per particle (`n`).
pub(crate) fn check_state(field: &str, values: &[Vec3], n: usize) -> Result<()> {
    if values.len() != n {
        return Err(Error::field(
            field,
            format!("{} values given for {n} particles", values.len()),
        ));
    }
    if let Some(i) = values.iter().position(|p| !p.is_finite()) {
        return Err(Error::field(
            field,
            format!("particle {i} is not finite: {}", values[i]),
        ));
    }
    Ok(())
}

/// Copies `values` into `target` when there is one per item and each passes `check`.
fn set_each(
    field: &str,
    items: &str,
    target: &mut [f64],
    values: &[f64],
    check: fn(&str, f64) -> Result<f64>,
) -> Result<()> {
    if values.len() != target.len() {
        return Err(Error::field(
            field,
            format!("{} values given for {} {items}", values.len(), target.len()),
        ));
    }
    for (i, &v) in values.iter().enumerate() {
        check(&format!("{field}[{i}]"), v)?;
    }
    target.copy_from_slice(values);
    Ok(())
}

impl Model {
    /// Builds the model: validates every cloth, generates springs (stretch, shear, bend; a
    /// spring with zero stiffness and zero damping is left out), lumps masses and applies pins.
    pub fn new(cloths: Vec<ClothDesc>, gravity: Vec3) -> Result<Model> {
        validate::finite3("simulation.gravity", gravity)?;
        let mut m = Model {
            x: Vec::new(),
            v: Vec::new(),
            mass: Vec::new(),
            pinned: Vec::new(),
            handles: Vec::new(),
            stitches: Vec::new(),
            strain_limits: Vec::new(),
            drag: Vec::new(),
            springs: Springs::default(),
            gravity,
            cloths: Vec::new(),
            collision: None,
            obstacles: Vec::new(),
            pressure: Vec::new(),
            wind: Vec::new(),
        };
        for c in cloths {
            m.add_cloth(c)?;
        }
        if m.x.is_empty() {
            return Err(Error::field(
                "cloth",
                "the model has no particles (no cloth given)",
            ));
        }
        Ok(m)
    }

    /// Adds the handles of the cloth whose particles start at `offset` (positions already in
    /// `self.x`), places their vertices where their motion puts them at `t = 0` and gives them
    /// its velocity there. A vertex may belong to one handle at most, and not to `pin`.
    fn add_handles(
        &mut self,
        descs: &[crate::constraints::handles::HandleDesc],
        pinned: &[bool],
        offset: usize,
        at: &str,
    ) -> Result<()> {
        use crate::constraints::handles::Handle;
        let mut owner: Vec<Option<usize>> = vec![None; pinned.len()];
        for (k, d) in descs.iter().enumerate() {
            let field = format!("{at}.handle[{k}]");
            let hd = Handle::new(d, &self.x[offset..], offset as u32, &field)?;
            for &v in &d.vertices {
                let v = v as usize;
                if pinned[v] {
                    return Err(Error::field(
                        format!("{field}.vertices"),
                        format!(
                            "vertex {v} is also in `pin` (a vertex is pinned or in a handle, not both)"
                        ),
                    ));
                }
                if let Some(j) = owner[v].replace(k) {
                    return Err(Error::field(
                        format!("{field}.vertices"),
                        format!("vertex {v} is already in {at}.handle[{j}]"),
                    ));
                }
            }
            let (lin, ang) = hd.motion.velocity(0.0);
            let (_, tr) = hd.motion.pose(0.0);
            for (k, &p) in hd.particles.iter().enumerate() {
                let x = hd.position(k, 0.0);
                self.x[p as usize] = x;
                self.v[p as usize] = lin + ang.cross(x - (hd.pivot + tr));
            }
            self.handles.push(hd);
        }
        Ok(())
    }

    fn add_cloth(&mut self, c: ClothDesc) -> Result<()> {
        let name = c.name.as_str();
        let at = format!("cloth[{}]", self.cloths.len());
        let field = |key: &str| format!("{at}.{key}");
        if name.is_empty() || name.chars().any(|ch| ch.is_whitespace()) {
            return Err(Error::field(
                field("name"),
                format!("'{name}' must be non-empty and contain no white space"),
            ));
        }
        if let Some(j) = self.cloths.iter().position(|o| o.name == name) {
            return Err(Error::field(
                field("name"),
                format!("'{name}' is already used by cloth[{j}]"),
            ));
        }
        c.mesh.validate(&format!("cloth '{name}' mesh"))?;
        let mat = &c.material;
        validate::nonneg(&field("stretch_stiffness"), mat.stretch_stiffness)?;
        validate::nonneg(&field("shear_stiffness"), mat.shear_stiffness)?;
        validate::nonneg(&field("bend_stiffness"), mat.bend_stiffness)?;
        validate::nonneg(&field("damping"), mat.damping)?;
        validate::nonneg(&field("air_drag"), mat.air_drag)?;
        validate::finite3(&field("initial_velocity"), c.initial_velocity)?;
        if let Some(limit) = mat.strain_limit {
            validate::positive(&field("strain_limit"), limit)?;
        }
        if !mat.pressure.is_finite() {
            return Err(Error::field(
                field("pressure"),
                format!("must be a finite number, got {}", mat.pressure),
            ));
        }
        if mat.model == ClothModel::Shell {
            validate_shell(&mat.shell, &field)?;
            if c.mesh.faces.is_empty() {
                return Err(Error::field(
                    field("model"),
                    format!(
                        "cloth '{name}' has no faces: the shell model acts on triangles and quads"
                    ),
                ));
            }
        }
        let n = c.mesh.positions.len();
        let masses: Vec<f64> = match mat.mass {
            MassSpec::PerVertex(mv) => {
                validate::positive(&field("vertex_mass"), mv)?;
                vec![mv; n]
            }
            MassSpec::Density(rho) => {
                validate::positive(&field("density"), rho)?;
                let areas = c.mesh.vertex_areas();
                if let Some(i) = areas.iter().position(|&a| a <= 0.0) {
                    return Err(Error::field(
                        field("density"),
                        format!(
                            "vertex {} of cloth '{name}' belongs to no face, so density gives it no mass; use vertex_mass",
                            i + 1
                        ),
                    ));
                }
                areas.iter().map(|a| a * rho).collect()
            }
        };
        let offset = self.x.len();
        let mut pinned = vec![false; n];
        for &p in &c.pins {
            if p as usize >= n {
                return Err(Error::field(
                    field("pin"),
                    format!(
                        "{p} is out of range: the mesh of cloth '{name}' has {n} vertices, numbered 0 to {} (0-based)",
                        n.saturating_sub(1)
                    ),
                ));
            }
            pinned[p as usize] = true;
        }
        let o = offset as u32;
        let pos = &c.mesh.positions;
        let add = |list: Vec<[u32; 2]>, k: f64, kind: SpringKind, springs: &mut Springs| {
            if k == 0.0 && mat.damping == 0.0 {
                return;
            }
            for [a, b] in list {
                let rest = (pos[a as usize] - pos[b as usize]).length();
                springs.push(a + o, b + o, rest, k, mat.damping, kind);
            }
        };
        match mat.model {
            ClothModel::Springs => {
                add(
                    c.mesh.edges(),
                    mat.stretch_stiffness,
                    SpringKind::Stretch,
                    &mut self.springs,
                );
                add(
                    c.mesh.quad_diagonals(),
                    mat.shear_stiffness,
                    SpringKind::Shear,
                    &mut self.springs,
                );
                add(
                    c.mesh.bend_pairs(),
                    mat.bend_stiffness,
                    SpringKind::Bend,
                    &mut self.springs,
                );
            }
            // the membrane and the hinges act on the faces (built with the forces, from
            // `ClothInfo::material`); line elements stay springs
            ClothModel::Shell => add(
                c.mesh.lines.clone(),
                mat.stretch_stiffness,
                SpringKind::Stretch,
                &mut self.springs,
            ),
        }
        if let Some(bad) = (0..self.springs.len()).find(|&s| !(self.springs.rest[s] > 0.0)) {
            return Err(Error::field(
                field("mesh"),
                format!(
                    "spring between vertices {} and {} of cloth '{name}' has zero rest length (coincident vertices)",
                    self.springs.i[bad] - o,
                    self.springs.j[bad] - o
                ),
            ));
        }
        self.x.extend_from_slice(pos);
        self.v.extend(std::iter::repeat_n(c.initial_velocity, n));
        for (i, v) in self.v[offset..].iter_mut().enumerate() {
            if pinned[i] {
                *v = Vec3::ZERO;
            }
        }
        self.add_handles(&c.handles, &pinned, offset, &at)?;
        self.mass.extend(masses);
        self.pinned.extend(pinned);
        self.drag.extend(std::iter::repeat_n(mat.air_drag, n));
        self.pressure.push(mat.pressure);
        self.strain_limits.push(mat.strain_limit);
        self.cloths.push(ClothInfo {
            name: c.name,
            offset,
            mesh: c.mesh,
            material: c.material,
        });
        Ok(())
    }

    /// The model with `winds` (checked: each one, and that they share density and drag).
    pub fn with_wind(mut self, winds: &[crate::forces::Wind]) -> Result<Model> {
        crate::forces::wind::validate_winds(winds)?;
        self.wind = winds.to_vec();
        Ok(self)
    }

    /// The triangles of every cloth under pressure and each one's pressure, Pa.
    pub(crate) fn pressure_triangles(&self) -> (Vec<[u32; 3]>, Vec<f64>) {
        let mut out = (Vec::new(), Vec::new());
        for (c, &p) in self.cloths.iter().zip(&self.pressure) {
            if p != 0.0 {
                for t in c.mesh.triangles() {
                    out.0.push(t.map(|i| i + c.offset as u32));
                    out.1.push(p);
                }
            }
        }
        out
    }

    /// Every cloth triangle (quads split), in global particle indices.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.cloths
            .iter()
            .flat_map(|c| {
                c.mesh
                    .triangles()
                    .into_iter()
                    .map(move |t| t.map(|i| i + c.offset as u32))
            })
            .collect()
    }

    /// Every edge of the collision surface, in global particle indices: the sides of every
    /// triangle of [`Model::triangles`] (so a quad's split diagonal too) and every line
    /// element, each once.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut seen = std::collections::HashSet::new();
        let mut out = Vec::new();
        let tri_edges = self
            .triangles()
            .into_iter()
            .flat_map(|[a, b, c]| [[a, b], [b, c], [c, a]]);
        let lines = self.cloths.iter().flat_map(|c| {
            c.mesh
                .lines
                .iter()
                .map(move |l| l.map(|i| i + c.offset as u32))
        });
        for [a, b] in tri_edges.chain(lines) {
            if seen.insert((a.min(b), a.max(b))) {
                out.push([a, b]);
            }
        }
        out
    }

    /// The same model with the stitches `descs` added; errors name the stitch
    /// (`stitch[1].b.vertices`): an unknown cloth, sides of unequal length or empty, a vertex
    /// out of its cloth's range, a vertex stitched to itself, a stiffness not > 0 or a damping
    /// not ≥ 0.
    pub fn with_stitches(mut self, descs: &[StitchDesc]) -> Result<Model> {
        for (i, d) in descs.iter().enumerate() {
            let at = format!("stitch[{i}]");
            validate::positive(&format!("{at}.stiffness"), d.stiffness)?;
            validate::nonneg(&format!("{at}.damping"), d.damping)?;
            let side = |e: &StitchEnd, name: &str| -> Result<Vec<u32>> {
                let info = self.cloth(&e.cloth).ok_or_else(|| {
                    let names: Vec<String> = self
                        .cloths
                        .iter()
                        .map(|c| format!("'{}'", c.name))
                        .collect();
                    Error::field(
                        format!("{at}.{name}.cloth"),
                        format!(
                            "no cloth named '{}' (the cloths are {})",
                            e.cloth,
                            names.join(", ")
                        ),
                    )
                })?;
                let n = info.mesh.vertex_count();
                if e.vertices.is_empty() {
                    return Err(Error::field(
                        format!("{at}.{name}.vertices"),
                        "is empty: a stitch needs at least one vertex on each side",
                    ));
                }
                e.vertices
                    .iter()
                    .map(|&v| match (v as usize) < n {
                        true => Ok(v + info.offset as u32),
                        false => Err(Error::field(
                            format!("{at}.{name}.vertices"),
                            format!(
                                "vertex {v} is out of range (cloth '{}' has {n} vertices)",
                                e.cloth
                            ),
                        )),
                    })
                    .collect()
            };
            let a = side(&d.a, "a")?;
            let b = side(&d.b, "b")?;
            if a.len() != b.len() {
                return Err(Error::field(
                    format!("{at}.b.vertices"),
                    format!("{} vertices, but a has {}", b.len(), a.len()),
                ));
            }
            if let Some(k) = (0..a.len()).find(|&k| a[k] == b[k]) {
                return Err(Error::field(
                    format!("{at}.b.vertices"),
                    format!(
                        "pair {k} stitches vertex {} of cloth '{}' to itself",
                        d.a.vertices[k], d.a.cloth
                    ),
                ));
            }
            self.stitches
                .extend(a.iter().zip(&b).map(|(&a, &b)| Stitch {
                    a,
                    b,
                    stiffness: d.stiffness,
                    damping: d.damping,
                }));
        }
        Ok(self)
    }

    /// The same model with collisions on: `settings` (validated) and the obstacles.
    pub fn with_collisions(
        mut self,
        settings: crate::collision::settings::CollisionSettings,
        obstacles: Vec<crate::collision::settings::Obstacle>,
    ) -> Result<Model> {
        settings.validate()?;
        self.collision = Some(settings);
        self.obstacles = obstacles;
        Ok(self)
    }

    /// Sets every particle's position; an error naming the field, changing nothing, unless
    /// there is one finite value per particle.
    pub fn set_positions(&mut self, x: &[Vec3]) -> Result<()> {
        check_state("positions", x, self.x.len())?;
        self.x.copy_from_slice(x);
        Ok(())
    }

    /// Sets every particle's mass (kg, each a finite number > 0), replacing what the cloths'
    /// densities or vertex masses gave: for hand-built systems (tests, a front end's own
    /// lumping). An error naming the field, changing nothing, otherwise.
    pub fn set_masses(&mut self, mass: &[f64]) -> Result<()> {
        set_each(
            "masses",
            "particles",
            &mut self.mass,
            mass,
            validate::positive,
        )
    }

    /// Sets every spring's rest length (m, each a finite number ≥ 0: zero-length springs pull
    /// their two particles together), replacing the lengths of the rest mesh. An error naming
    /// the field, changing nothing, otherwise.
    pub fn set_rest_lengths(&mut self, rest: &[f64]) -> Result<()> {
        set_each(
            "springs.rest",
            "springs",
            &mut self.springs.rest,
            rest,
            validate::nonneg,
        )
    }

    /// Sets every particle's velocity; as [`Model::set_positions`].
    pub fn set_velocities(&mut self, v: &[Vec3]) -> Result<()> {
        check_state("velocities", v, self.v.len())?;
        self.v.copy_from_slice(v);
        Ok(())
    }

    /// Positions, m.
    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    /// Velocities, m/s.
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Lumped masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// The stitched particle pairs, in the order of the stitches and of their vertices.
    pub fn stitches(&self) -> &[Stitch] {
        &self.stitches
    }

    /// The handles (moving pins) of every cloth.
    pub fn handles(&self) -> &[crate::constraints::handles::Handle] {
        &self.handles
    }

    /// Every collider's motion and every handle's, in their orders (what a snapshot holds of
    /// them, [`crate::snapshot`]).
    pub(crate) fn motions(&self) -> (Vec<crate::animation::Motion>, Vec<crate::animation::Motion>) {
        (
            (self.obstacles.iter())
                .map(|o| o.collider.motion.clone())
                .collect(),
            self.handles.iter().map(|h| h.motion.clone()).collect(),
        )
    }

    /// Which particles are pinned.
    pub fn pins(&self) -> &[bool] {
        &self.pinned
    }

    /// Gravitational acceleration, m/s².
    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// The springs.
    pub fn springs(&self) -> &Springs {
        &self.springs
    }

    /// The cloths, in order, each with its particle range and mesh.
    pub fn cloths(&self) -> &[ClothInfo] {
        &self.cloths
    }

    /// Each cloth's strain limit, in the order of [`Model::cloths`] (`None`: no limit).
    pub fn strain_limits(&self) -> &[Option<f64>] {
        &self.strain_limits
    }

    /// The cloth named `name`.
    pub fn cloth(&self, name: &str) -> Option<&ClothInfo> {
        self.cloths.iter().find(|c| c.name == name)
    }

    /// Collision settings (`None`: collisions off).
    pub fn collision(&self) -> Option<&crate::collision::settings::CollisionSettings> {
        self.collision.as_ref()
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &[crate::collision::settings::Obstacle] {
        &self.obstacles
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.x.len()
    }

    /// The velocity filter of the pins alone (docs/MATH.md §5): `0` for a pinned particle, `I`
    /// otherwise.
    pub fn pin_filter(&self) -> Vec<Mat3> {
        crate::constraints::pins::filter(&self.pinned)
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Kinetic energy ½ Σ m |v|².
    pub fn kinetic_energy(&self) -> f64 {
        self.mass
            .iter()
            .zip(&self.v)
            .map(|(m, v)| 0.5 * m * v.length_squared())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_cloth(mass: MassSpec) -> ClothDesc {
        ClothDesc {
            name: "c".into(),
            mesh: Mesh::grid([1.0, 2.0], [4, 5], Vec3::ZERO, Vec3::Z).unwrap(),
            material: Material {
                mass,
                ..Material::default()
            },
            pins: vec![0, 3],
            initial_velocity: Vec3::X,
            handles: Vec::new(),
        }
    }

    #[test]
    fn density_lumps_total_mass_equal_to_density_times_area() {
        let m = Model::new(vec![grid_cloth(MassSpec::Density(0.3))], Vec3::ZERO).unwrap();
        assert!((m.total_mass() - 0.3 * 2.0).abs() < 1e-12);
    }

    #[test]
    fn springs_of_each_kind_match_the_mesh_and_rest_lengths_match_geometry() {
        let m = Model::new(vec![grid_cloth(MassSpec::PerVertex(0.01))], Vec3::ZERO).unwrap();
        let s = &m.springs;
        assert_eq!(s.count(SpringKind::Stretch), 3 * 5 + 4 * 4);
        assert_eq!(s.count(SpringKind::Shear), 2 * 3 * 4);
        assert_eq!(s.count(SpringKind::Bend), 2 * 5 + 4 * 3);
        for k in 0..s.len() {
            let d = (m.x[s.i[k] as usize] - m.x[s.j[k] as usize]).length();
            assert!((d - s.rest[k]).abs() < 1e-15);
        }
        assert!(m.pinned[0] && m.pinned[3] && !m.pinned[1]);
        assert_eq!(m.v[0], Vec3::ZERO);
        assert_eq!(m.v[1], Vec3::X);
    }

    #[test]
    fn bad_values_are_rejected_with_the_field_named() {
        let mut c = grid_cloth(MassSpec::PerVertex(0.01));
        c.material.stretch_stiffness = -1.0;
        let e = Model::new(vec![c], Vec3::ZERO).unwrap_err().to_string();
        assert!(e.contains("stretch_stiffness"), "{e}");
        let mut c = grid_cloth(MassSpec::PerVertex(0.01));
        c.pins = vec![20];
        assert!(
            Model::new(vec![c], Vec3::ZERO)
                .unwrap_err()
                .to_string()
                .contains("cloth[0].pin: 20 is out of range")
        );
        let c = grid_cloth(MassSpec::PerVertex(f64::NAN));
        assert!(
            Model::new(vec![c], Vec3::ZERO)
                .unwrap_err()
                .to_string()
                .contains("vertex_mass")
        );
    }

    #[test]
    fn parameters_set_after_building_are_checked_and_all_or_nothing() {
        let mut m = Model::new(vec![grid_cloth(MassSpec::PerVertex(0.01))], Vec3::ZERO).unwrap();
        let n = m.particle_count();
        let before = m.masses().to_vec();
        let mut bad = vec![0.02; n];
        bad[7] = -1.0;
        let e = m.set_masses(&bad).unwrap_err().to_string();
        assert_eq!(e, "masses[7]: must be a finite number > 0, got -1");
        assert_eq!(m.masses(), &before[..]);
        let e = m.set_masses(&[1.0]).unwrap_err().to_string();
        assert_eq!(e, format!("masses: 1 values given for {n} particles"));
        m.set_masses(&vec![0.02; n]).unwrap();
        assert!((m.total_mass() - 0.02 * n as f64).abs() < 1e-15);
        let s = m.springs().len();
        let e = m
            .set_rest_lengths(&vec![f64::NAN; s])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("springs.rest[0]: must be a finite number ≥ 0"),
            "{e}"
        );
        m.set_rest_lengths(&vec![0.0; s]).unwrap();
        assert!(m.springs().rest.iter().all(|&r| r == 0.0));
        let e = m
            .with_collisions(
                crate::collision::settings::CollisionSettings {
                    thickness: 0.0,
                    ..Default::default()
                },
                vec![],
            )
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("collision.thickness: must be"), "{e}");
    }
}
