//! From scene text to a [`Scene`] that can run: parse, check every value, build the grid, the
//! materials and the particle seeds, and map every refusal to its field path, line and column.
//!
//! Order of checks: TOML syntax and types (serde) → solver settings → grid → materials → bodies
//! (shape, inside the grid, no overlap) → boundaries → output. The first problem found is
//! reported; nothing runs until the whole scene is consistent.
//!
//! A scene uses one constitutive model for all bodies (the solver is generic over it, with no
//! per-particle dispatch): a scene whose bodies use both elastic and Drucker-Prager materials is
//! refused with an error that says so.

use std::collections::BTreeMap;

use mpm_constitutive::{
    ConeMatch, ConstitutiveError, ConstitutiveModel, DpPerfectState, DpState, DruckerPrager,
    DruckerPragerParams, LinearElastic,
};
use mpm_contact::{Boundary, ContactError, Friction};
use mpm_grid::{GridError, KinkPolicy, LocateError, RegularGrid, TerrainGrid, TerrainGridSpec};
use mpm_solver::generate::{self, Shape};
use mpm_solver::{Boundaries, Scheme, SolverConfig, SolverError, TimeStep, Vector};

use crate::error::SceneError;
use crate::presets;
use crate::scene::*;
use crate::source::SourceMap;

/// Most particles a scene may generate (a guard against a typo such as a 1e-6 m cell, which
/// would otherwise exhaust memory before any message).
pub const MAX_PARTICLES: usize = 20_000_000;

/// Most bodies a scene may declare (the overlap check compares every pair's bounding boxes).
pub const MAX_BODIES: usize = 10_000;

/// Most vertices of a polygon (the simplicity check compares every pair of edges).
pub const MAX_VERTICES: usize = 10_000;

/// Most probes a scene may declare.
pub const MAX_PROBES: usize = 10_000;

/// Largest `particles_per_cell` (n × n per cell).
pub const MAX_PARTICLES_PER_CELL: i64 = 16;

/// A validated scene, ready to run.
#[derive(Clone, Debug)]
pub struct Scene {
    pub(crate) origin: String,
    pub(crate) text: String,
    pub(crate) file: SceneFile,
    pub(crate) r: Resolved,
}

/// The background grid, built.
#[derive(Clone, Debug)]
pub(crate) enum GridBuilt {
    Terrain(TerrainGrid),
    Regular(RegularGrid),
}

/// The materials, built, all of one kind.
#[derive(Clone, Debug)]
pub(crate) enum MaterialsBuilt {
    Elastic(Vec<LinearElastic>),
    Plastic(Vec<DruckerPrager>),
}

impl MaterialsBuilt {
    /// the Drucker-Prager materials storing only ε̄ᵖ per particle, when none of them hardens
    /// (H = 0): a scene pays for the hardening variables only if it hardens.
    pub(crate) fn without_hardening(&self) -> Option<Vec<DruckerPrager<DpPerfectState>>> {
        match self {
            MaterialsBuilt::Elastic(_) => None,
            MaterialsBuilt::Plastic(m) => m.iter().map(DruckerPrager::without_hardening).collect(),
        }
    }

    /// bytes of constitutive state per particle a run of these materials stores.
    pub(crate) fn state_bytes(&self) -> usize {
        match self {
            MaterialsBuilt::Elastic(_) => 0,
            _ if self.without_hardening().is_some() => std::mem::size_of::<DpPerfectState>(),
            MaterialsBuilt::Plastic(_) => std::mem::size_of::<DpState>(),
        }
    }
}

/// One material point before the constitutive state is attached.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Seed {
    pub position: Vector,
    pub velocity: Vector,
    pub volume: f64,
    pub density: f64,
    pub material: u16,
    pub body: u16,
}

/// An analytic reference curve with its parameters taken from the scene.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reference {
    pub curve: ReferenceCurve,
    /// basal friction coefficient.
    pub mu: f64,
    /// |gravity| (m/s²).
    pub g: f64,
    /// initial speed along `direction` (m/s).
    pub v0: f64,
    /// slope angle θ (rad, positive), eq 22.
    pub theta: f64,
    /// unit direction the probe displacement is measured along.
    pub direction: Vector,
}

impl Reference {
    /// the reference displacement along `direction` at time t (s).
    pub fn displacement(&self, t: f64) -> f64 {
        match self.curve {
            ReferenceCurve::Abe2005Eq21 => {
                let decel = self.mu * self.g;
                let t_stop = if decel > 0.0 { self.v0 / decel } else { f64::INFINITY };
                let t = t.min(t_stop);
                self.v0 * t - 0.5 * decel * t * t
            }
            ReferenceCurve::Abe2005Eq22 => {
                let a = self.g * (self.theta.sin() - self.mu * self.theta.cos());
                0.5 * a.max(0.0) * t * t
            }
        }
    }
}

/// Resolved output settings.
#[derive(Clone, Debug)]
pub(crate) struct ResolvedOutput {
    pub interval: f64,
    pub series_interval: f64,
    pub fields: Vec<VtkField>,
    pub vtk: bool,
    pub vtk_format: VtkFormat,
    pub plots: bool,
    pub probes: Vec<usize>,
    pub reference: Option<Reference>,
    pub checkpoint_interval: Option<f64>,
}

/// Everything the run needs, derived from the file.
#[derive(Clone, Debug)]
pub(crate) struct Resolved {
    pub grid: GridBuilt,
    pub shape_function: ShapeFunctionKind,
    /// particles per cell used by uGIMP (the largest of the bodies').
    pub gimp_ppc: usize,
    pub materials: MaterialsBuilt,
    pub seeds: Vec<Seed>,
    pub config: SolverConfig,
    pub end_time: f64,
    pub output: ResolvedOutput,
    /// the ground polyline (terrain profile, or the floor of a regular grid).
    pub ground: Vec<Vector>,
    /// smallest particle spacing (m).
    pub spacing: f64,
    /// the time step the first step will take (s) and its Courant number.
    pub initial_dt: f64,
    /// when the energy residual stops or flags a run.
    pub alarm: EnergyAlarm,
    /// most steps the run may take.
    pub max_steps: u64,
}

/// Default `[solver] energy_alarm`: the largest |residual| / energy scale a run may reach
/// before it is flagged (see `mpm_solver::EnergyCheck` for the scale). Measured: the embedded
/// scenes and collapsing columns of every scheme stay within 4 %, the paper's node contact on the
/// free fall reaches 7–10 %; an elastic block of E = 1 kPa crushed flat on the floor reaches
/// −40 %, a sand block dropped 100 m between walls −22 % (it bounces 8 m high).
pub const DEFAULT_ENERGY_ALARM: f64 = 0.2;

/// Default `[solver] max_steps`.
pub const DEFAULT_MAX_STEPS: u64 = 100_000_000;

/// The energy alarm of a run.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EnergyAlarm {
    /// largest admissible |residual| / scale.
    pub threshold: f64,
    /// stop the run when it trips.
    pub stop: bool,
}

impl Scene {
    /// where the text came from (a path or `embedded:NAME`).
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// the scene's text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// the parsed file.
    pub fn file(&self) -> &SceneFile {
        &self.file
    }

    /// a stable hash of the scene text (FNV-1a 64, hex).
    pub fn hash(&self) -> String {
        format!("{:016x}", fnv1a(self.text.as_bytes()))
    }

    /// number of particles the scene generates.
    pub fn particle_count(&self) -> usize {
        self.r.seeds.len()
    }

    /// simulated end time (s).
    pub fn end_time(&self) -> f64 {
        self.r.end_time
    }

    /// the Δt of the first step (s).
    pub fn initial_dt(&self) -> f64 {
        self.r.initial_dt
    }

    /// the solver settings the run will use (after presets and defaults).
    pub fn solver_config(&self) -> &SolverConfig {
        &self.r.config
    }

    /// the shape functions the run will use.
    pub fn shape_function(&self) -> ShapeFunctionKind {
        self.r.shape_function
    }

    /// the same scene with `edit` applied to its file, re-rendered as TOML and validated again
    /// (for studies that vary a setting).
    pub fn modified(&self, edit: impl FnOnce(&mut SceneFile)) -> Result<Scene, SceneError> {
        let mut file = self.file.clone();
        edit(&mut file);
        let text = toml::to_string(&file).map_err(|e| SceneError {
            origin: self.origin.clone(),
            line: None,
            column: None,
            path: String::new(),
            value: None,
            problem: format!("the modified scene cannot be written as TOML: {e}"),
            admissible: String::new(),
            fix: "use finite values".into(),
        })?;
        load_scene_str(&text, &format!("{} (modified)", self.origin))
    }
}

/// FNV-1a 64-bit hash: stable across platforms and versions.
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Formats a number for a message: plain for ordinary magnitudes, scientific otherwise.
pub(crate) fn num(x: f64) -> String {
    if x != 0.0 && x.is_finite() && (x.abs() >= 1e6 || x.abs() < 1e-3) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn pair(p: [f64; 2]) -> String {
    format!("[{}, {}]", num(p[0]), num(p[1]))
}

/// Builds errors located in one scene text.
struct Ctx<'a> {
    origin: &'a str,
    map: &'a SourceMap,
}

impl Ctx<'_> {
    fn err(
        &self,
        path: &str,
        value: Option<String>,
        problem: impl Into<String>,
        admissible: impl Into<String>,
        fix: impl Into<String>,
    ) -> SceneError {
        let (line, column) = match self.map.locate(path) {
            Some((l, c)) => (Some(l), Some(c)),
            None => (None, None),
        };
        SceneError {
            origin: self.origin.to_string(),
            line,
            column,
            path: path.to_string(),
            value,
            problem: problem.into(),
            admissible: admissible.into(),
            fix: fix.into(),
        }
    }

    /// a required-by-kind field is missing.
    fn missing(&self, path: &str, why: &str, example: &str) -> SceneError {
        self.err(
            path,
            None,
            format!("missing field ({why})"),
            String::new(),
            format!("add `{} = {example}`", path.rsplit('.').next().unwrap_or(path)),
        )
    }

    /// a field that does not belong to this kind.
    fn foreign(&self, path: &str, why: &str) -> SceneError {
        self.err(
            path,
            None,
            format!("this field does not apply here ({why})"),
            String::new(),
            "remove it, or change the `kind`/`shape` it belongs to",
        )
    }

    /// a number outside its range.
    fn range(&self, path: &str, value: f64, admissible: &str, fix: &str) -> SceneError {
        self.err(path, Some(num(value)), "value out of range", admissible, fix)
    }
}

/// Parses and validates a scene; `origin` names the text in messages (a path, or
/// `embedded:NAME`).
pub fn load_scene_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
    let map = SourceMap::new(text);
    let ctx = Ctx { origin, map: &map };
    let file: SceneFile = toml::from_str(text).map_err(|e| serde_error(&ctx, &e))?;
    let r = resolve(&ctx, &file)?;
    Ok(Scene { origin: origin.to_string(), text: text.to_string(), file, r })
}

/// Maps a TOML syntax or serde error to a located [`SceneError`].
fn serde_error(ctx: &Ctx<'_>, e: &toml::de::Error) -> SceneError {
    let message = e.message().trim().to_string();
    let span = e.span();
    let mut path = span.as_ref().map(|s| ctx.map.path_at(s.start)).unwrap_or_default();
    let quoted = |prefix: &str| -> Option<String> {
        let rest = message.strip_prefix(prefix)?;
        let rest = rest.strip_prefix('`')?;
        rest.find('`').map(|k| rest[..k].to_string())
    };
    let (problem, admissible, fix) = if let Some(field) = quoted("unknown field ") {
        if !path.ends_with(&field) {
            path = join(&path, &field);
        }
        let admissible = message
            .split_once(", expected ")
            .map(|(_, a)| a.to_string())
            .or_else(|| message.contains("there are no fields").then(|| "no fields".into()))
            .unwrap_or_default();
        (
            format!("unknown field `{field}`"),
            admissible,
            format!(
                "remove `{field}` or correct its spelling (every field is listed in \
                 docs/scene-format.md)"
            ),
        )
    } else if let Some(field) = quoted("missing field ") {
        // A span covering the whole text is the top-level table, and so are the top-level
        // sections, whatever key the span starts at (a file beginning with `title` that lacks
        // `[grid]` must not be told to add `grid` to `title`).
        let top = ["grid", "materials", "bodies", "solver"].contains(&field.as_str());
        if top || span.as_ref().is_some_and(|s| s.start == 0 && s.end + 1 >= ctx.map.len()) {
            path.clear();
        }
        if !path.ends_with(&field) {
            path = join(&path, &field);
        }
        let table = path.rsplit_once('.').map_or("the top level", |(t, _)| t).to_string();
        (
            format!("missing field `{field}`"),
            String::new(),
            if !top {
                format!("add `{field} = ...` to `{table}` (see docs/scene-format.md)")
            } else if field == "bodies" {
                "add a `[[bodies]]` table (see docs/scene-format.md)".to_string()
            } else {
                format!("add a `[{field}]` table (see docs/scene-format.md)")
            },
        )
    } else if let Some(v) = quoted("unknown variant ") {
        let admissible =
            message.split_once(", expected ").map(|(_, a)| a.to_string()).unwrap_or_default();
        (format!("unknown name `{v}`"), admissible, "use one of the admissible names".to_string())
    } else if message.starts_with("invalid type") || message.starts_with("invalid length") {
        let admissible =
            message.split_once(", expected ").map(|(_, a)| a.to_string()).unwrap_or_default();
        (message.clone(), admissible, "write the value with the expected type".to_string())
    } else if message.starts_with("expected exactly 2 values") {
        (
            message.clone(),
            "two numbers [x, y]".to_string(),
            "write exactly two values, e.g. `[0.25, 0.25]`".to_string(),
        )
    } else if span.is_some() && path.is_empty() {
        (
            format!("TOML syntax error: {message}"),
            String::new(),
            "correct the TOML syntax at this position".to_string(),
        )
    } else {
        (message.clone(), String::new(), "see docs/scene-format.md".to_string())
    };
    let (line, column) = match span {
        Some(s) => {
            let (l, c) = ctx.map.line_col(s.start);
            (Some(l), Some(c))
        }
        None => match ctx.map.locate(&path) {
            Some((l, c)) => (Some(l), Some(c)),
            None => (None, None),
        },
    };
    SceneError {
        origin: ctx.origin.to_string(),
        line,
        column,
        path,
        value: None,
        problem,
        admissible,
        fix,
    }
}

fn join(a: &str, b: &str) -> String {
    if a.is_empty() { b.to_string() } else { format!("{a}.{b}") }
}

fn finite_pos(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

fn resolve(ctx: &Ctx<'_>, f: &SceneFile) -> Result<Resolved, SceneError> {
    // ---- solver settings ------------------------------------------------------------------
    let s = &f.solver;
    if !(finite_pos(s.end_time) && s.end_time <= 1e7) {
        return Err(ctx.range(
            "solver.end_time",
            s.end_time,
            "0 < end_time ≤ 1e7 (s)",
            "give the simulated duration in seconds, e.g. `end_time = 3.0`",
        ));
    }
    let preset = s.preset.map(presets::settings);
    let scheme = s.scheme.or(preset.map(|p| p.scheme)).unwrap_or(Scheme::Usavg);
    let time_step = match (s.courant, s.dt) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                "solver.dt",
                s.dt.map(num),
                "both `courant` and `dt` are given",
                "one of them: a Courant number (adaptive Δt) or a fixed Δt",
                "remove `dt` (recommended) or `courant`",
            ));
        }
        (Some(c), None) => {
            if !(c > 0.0 && c <= 1.0) {
                return Err(ctx.range(
                    "solver.courant",
                    c,
                    "0 < courant ≤ 1 (explicit stability, eq 13)",
                    "use the paper's advice `courant = 0.1`; above 1 the explicit step is \
                     unstable",
                ));
            }
            TimeStep::Courant(c)
        }
        (None, Some(dt)) => {
            if !finite_pos(dt) {
                return Err(ctx.range(
                    "solver.dt",
                    dt,
                    "0 < dt < ∞ (s), with a Courant number ≤ 1",
                    "give a positive time step, or use `courant = 0.1` instead",
                ));
            }
            TimeStep::Fixed(dt)
        }
        (None, None) => TimeStep::Courant(preset.map_or(0.1, |p| p.courant)),
    };
    let gravity = s.gravity.unwrap_or([0.0, -mpm_solver::STANDARD_GRAVITY]);
    if !(gravity[0].is_finite() && gravity[1].is_finite()) {
        return Err(ctx.err(
            "solver.gravity",
            Some(pair(gravity)),
            "gravity is not finite",
            "finite components (m/s²)",
            "use `gravity = [0.0, -9.81]`",
        ));
    }
    let gravity_ramp = s.gravity_ramp.unwrap_or(0.0);
    if !(gravity_ramp.is_finite() && gravity_ramp >= 0.0) {
        return Err(ctx.range(
            "solver.gravity_ramp",
            gravity_ramp,
            "0 ≤ gravity_ramp < ∞ (s); 0 applies gravity at once",
            "remove it or give a non-negative time",
        ));
    }
    let small_mass_ratio = s.small_mass_ratio.unwrap_or(1e-4);
    if !(0.0..1.0).contains(&small_mass_ratio) {
        return Err(ctx.range(
            "solver.small_mass_ratio",
            small_mass_ratio,
            "0 ≤ small_mass_ratio < 1 (fraction of the mean particle mass)",
            "remove it to use the default 1e-4",
        ));
    }

    let alarm = EnergyAlarm {
        threshold: s.energy_alarm.unwrap_or(DEFAULT_ENERGY_ALARM),
        stop: s.energy_alarm_stop.unwrap_or(false),
    };
    if !(finite_pos(alarm.threshold)) {
        return Err(ctx.range(
            "solver.energy_alarm",
            alarm.threshold,
            "0 < energy_alarm < ∞ (fraction of the run's energy scale)",
            "remove it to use the default 0.2, or give e.g. `energy_alarm = 0.1`",
        ));
    }
    let max_steps = s.max_steps.unwrap_or(DEFAULT_MAX_STEPS as i64);
    if max_steps < 1 {
        return Err(ctx.range(
            "solver.max_steps",
            max_steps as f64,
            "max_steps ≥ 1",
            "remove it to use the default 100 000 000",
        ));
    }
    let max_steps = max_steps as u64;

    // ---- grid ------------------------------------------------------------------------------
    let g = &f.grid;
    let (grid, ground, cell_x) = match g.kind {
        GridKind::Terrain => {
            for (name, present) in [
                ("origin", g.origin.is_some()),
                ("cell", g.cell.is_some()),
                ("cells", g.cells.is_some()),
            ] {
                if present {
                    return Err(ctx.foreign(
                        &format!("grid.{name}"),
                        "a terrain grid is given by cell_width, row_height, rows and profile",
                    ));
                }
            }
            let cell_width = g
                .cell_width
                .ok_or_else(|| ctx.missing("grid.cell_width", "terrain grid", "0.1"))?;
            let row_height = g
                .row_height
                .ok_or_else(|| ctx.missing("grid.row_height", "terrain grid", "0.1"))?;
            let rows = g.rows.ok_or_else(|| ctx.missing("grid.rows", "terrain grid", "15"))?;
            let profile = g.profile.clone().ok_or_else(|| {
                ctx.missing("grid.profile", "terrain grid", "[[0.0, 1.0], [5.0, 0.0]]")
            })?;
            if !(1..=1_000_000).contains(&rows) {
                return Err(ctx.err(
                    "grid.rows",
                    Some(rows.to_string()),
                    "number of rows out of range",
                    "1 ≤ rows ≤ 1000000",
                    "give enough rows to hold the material above the ground at its highest",
                ));
            }
            let spec = TerrainGridSpec {
                profile: profile.iter().map(|p| Vector::new(p[0], p[1])).collect(),
                cell_width,
                row_height,
                rows: rows as usize,
                kink_policy: match g.kink_policy {
                    Some(KinkPolicySpec::Reject) => KinkPolicy::Reject,
                    _ => KinkPolicy::Snap,
                },
            };
            let grid = TerrainGrid::new(spec).map_err(|e| grid_error(ctx, e, &profile))?;
            let ground = grid.profile().to_vec();
            (GridBuilt::Terrain(grid), ground, cell_width)
        }
        GridKind::Regular => {
            for (name, present) in [
                ("cell_width", g.cell_width.is_some()),
                ("row_height", g.row_height.is_some()),
                ("rows", g.rows.is_some()),
                ("profile", g.profile.is_some()),
                ("kink_policy", g.kink_policy.is_some()),
            ] {
                if present {
                    return Err(ctx.foreign(
                        &format!("grid.{name}"),
                        "a regular grid is given by origin, cell and cells",
                    ));
                }
            }
            let origin = g.origin.unwrap_or([0.0, 0.0]);
            let cell =
                g.cell.ok_or_else(|| ctx.missing("grid.cell", "regular grid", "[0.1, 0.1]"))?;
            let cells =
                g.cells.ok_or_else(|| ctx.missing("grid.cells", "regular grid", "[50, 20]"))?;
            for (k, n) in cells.iter().enumerate() {
                if !(1..=100_000_000).contains(n) {
                    return Err(ctx.err(
                        &format!("grid.cells[{k}]"),
                        Some(n.to_string()),
                        "number of cells out of range",
                        "1 ≤ cells ≤ 1e8 along each axis",
                        "give a positive number of cells",
                    ));
                }
            }
            let grid = RegularGrid::new(
                Vector::new(origin[0], origin[1]),
                Vector::new(cell[0], cell[1]),
                [cells[0] as usize, cells[1] as usize],
            )
            .map_err(|e| grid_error(ctx, e, &[]))?;
            let lo = grid.origin();
            let hi = grid.upper_corner();
            (GridBuilt::Regular(grid), vec![lo, Vector::new(hi.x, lo.y)], cell[0])
        }
    };
    let shape_function = match (s.shape_function, &grid) {
        (
            Some(k @ (ShapeFunctionKind::Gimp | ShapeFunctionKind::Bspline)),
            GridBuilt::Terrain(_),
        ) => {
            return Err(ctx.err(
                "solver.shape_function",
                Some(format!("\"{}\"", k.name())),
                "this shape function needs a regular grid",
                "\"bilinear\" on a terrain grid; \"bilinear\", \"gimp\" or \"bspline\" on a \
                 regular grid",
                "use `shape_function = \"bilinear\"` or a `kind = \"regular\"` grid",
            ));
        }
        (Some(k), _) => k,
        (None, GridBuilt::Terrain(_)) => ShapeFunctionKind::Bilinear,
        (None, GridBuilt::Regular(_)) => {
            preset.map_or(ShapeFunctionKind::Bilinear, |p| p.shape_function)
        }
    };

    // ---- materials -------------------------------------------------------------------------
    if f.materials.is_empty() {
        return Err(ctx.err(
            "materials",
            None,
            "no material is defined",
            "at least one [materials.NAME] table",
            "add e.g. [materials.sand] with kind, young, poisson and density",
        ));
    }
    let mut built: BTreeMap<&str, (MaterialKind, Option<LinearElastic>, Option<DruckerPrager>)> =
        BTreeMap::new();
    for (name, m) in &f.materials {
        let base = format!("materials.{name}");
        let p = |field: &str| format!("{base}.{field}");
        if !(finite_pos(m.density) && m.density < 1e6) {
            return Err(ctx.range(
                &p("density"),
                m.density,
                "0 < density < 1e6 (kg/m³)",
                "give the material's density, e.g. 1600 for dry sand",
            ));
        }
        let elastic = LinearElastic::from_young_poisson(m.young, m.poisson)
            .map_err(|e| material_error(ctx, &base, e))?;
        match m.kind {
            MaterialKind::Elastic => {
                for (field, present) in [
                    ("cohesion", m.cohesion.is_some()),
                    ("friction_angle_deg", m.friction_angle_deg.is_some()),
                    ("dilatancy_angle_deg", m.dilatancy_angle_deg.is_some()),
                    ("hardening_modulus", m.hardening_modulus.is_some()),
                    ("mixing", m.mixing.is_some()),
                    ("cone_match", m.cone_match.is_some()),
                ] {
                    if present {
                        return Err(ctx.foreign(
                            &p(field),
                            "an elastic material has only young, poisson and density; \
                             use kind = \"drucker_prager\" for plasticity",
                        ));
                    }
                }
                built.insert(name, (m.kind, Some(elastic), None));
            }
            MaterialKind::DruckerPrager => {
                let cohesion = m.cohesion.ok_or_else(|| {
                    ctx.missing(&p("cohesion"), "Drucker-Prager material", "10.0")
                })?;
                let friction_angle_deg = m.friction_angle_deg.ok_or_else(|| {
                    ctx.missing(&p("friction_angle_deg"), "Drucker-Prager material", "40.0")
                })?;
                let params = DruckerPragerParams {
                    young: m.young,
                    poisson: m.poisson,
                    cohesion,
                    friction_angle_deg,
                    dilatancy_angle_deg: m.dilatancy_angle_deg.unwrap_or(0.0),
                    hardening_modulus: m.hardening_modulus.unwrap_or(0.0),
                    mixing: m.mixing.unwrap_or(1.0),
                    cone_match: match m.cone_match.unwrap_or(ConeMatchSpec::PlaneStrain) {
                        ConeMatchSpec::PlaneStrain => ConeMatch::PlaneStrain,
                        ConeMatchSpec::Inner => ConeMatch::Inner,
                        ConeMatchSpec::Outer => ConeMatch::Outer,
                    },
                };
                let dp = DruckerPrager::new(params).map_err(|e| material_error(ctx, &base, e))?;
                built.insert(name, (m.kind, None, Some(dp)));
            }
        }
    }

    // ---- bodies ----------------------------------------------------------------------------
    if f.bodies.is_empty() {
        return Err(ctx.err(
            "bodies",
            None,
            "no body is defined",
            "at least one [[bodies]] table",
            "add a [[bodies]] table with material, shape and its dimensions",
        ));
    }
    if f.bodies.len() > MAX_BODIES {
        return Err(ctx.err(
            "bodies",
            Some(f.bodies.len().to_string()),
            "too many bodies",
            format!("at most {MAX_BODIES} bodies"),
            "merge bodies of the same material (a polygon can hold any outline)",
        ));
    }
    // Material indices: the used materials, in name order.
    let mut used: Vec<&str> = Vec::new();
    let mut kind: Option<(MaterialKind, usize)> = None;
    for (b, body) in f.bodies.iter().enumerate() {
        let path = format!("bodies[{b}].material");
        let Some((k, _, _)) = built.get(body.material.as_str()) else {
            let names: Vec<String> = f.materials.keys().map(|n| format!("\"{n}\"")).collect();
            return Err(ctx.err(
                &path,
                Some(format!("\"{}\"", body.material)),
                "no material of this name",
                format!("one of {}", names.join(", ")),
                format!("define [materials.{}] or use a defined name", body.material),
            ));
        };
        match kind {
            Some((k0, b0)) if k0 != *k => {
                return Err(ctx.err(
                    &path,
                    Some(format!("\"{}\"", body.material)),
                    format!(
                        "this body is {} but bodies[{b0}] is {}: a run uses one constitutive \
                         model for all bodies, so elastic and Drucker-Prager bodies cannot be \
                         mixed in one scene",
                        k.name(),
                        k0.name()
                    ),
                    "all bodies of a scene with materials of one kind",
                    "give every body a material of the same kind (or run the bodies in \
                     separate scenes)",
                ));
            }
            None => kind = Some((*k, b)),
            _ => {}
        }
        if !used.contains(&body.material.as_str()) {
            used.push(body.material.as_str());
        }
    }
    used.sort_unstable();
    let (material_kind, _) = kind.unwrap_or((MaterialKind::Elastic, 0));
    let materials = match material_kind {
        MaterialKind::Elastic => MaterialsBuilt::Elastic(
            used.iter().filter_map(|n| built.get(n).and_then(|b| b.1)).collect(),
        ),
        MaterialKind::DruckerPrager => MaterialsBuilt::Plastic(
            used.iter().filter_map(|n| built.get(n).and_then(|b| b.2.clone())).collect(),
        ),
    };
    let p_modulus: Vec<f64> = match &materials {
        MaterialsBuilt::Elastic(v) => v.iter().map(|m| m.p_wave_modulus()).collect(),
        MaterialsBuilt::Plastic(v) => v.iter().map(|m| m.elasticity().p_wave_modulus()).collect(),
    };

    fits_in_memory(ctx, f, &grid, cell_x, shape_function, materials.state_bytes())?;
    let mut seeds: Vec<Seed> = Vec::new();
    // each earlier body's shape, bounding box and range of `seeds`.
    let mut shapes: Vec<(Shape, [Vector; 2], std::ops::Range<usize>)> = Vec::new();
    let mut spacing_min = f64::INFINITY;
    let mut gimp_ppc = 1usize;
    for (b, body) in f.bodies.iter().enumerate() {
        let base = format!("bodies[{b}]");
        let p = |field: &str| format!("{base}.{field}");
        let ppc = body.particles_per_cell.unwrap_or(2);
        if !(1..=MAX_PARTICLES_PER_CELL).contains(&ppc) {
            return Err(ctx.err(
                &p("particles_per_cell"),
                Some(ppc.to_string()),
                "particles per cell out of range",
                format!("1 ≤ particles_per_cell ≤ {MAX_PARTICLES_PER_CELL} (n × n per cell)"),
                "use 2 (the paper's 2 × 2 per cell)",
            ));
        }
        gimp_ppc = gimp_ppc.max(ppc as usize);
        let spacing = cell_x / ppc as f64;
        spacing_min = spacing_min.min(spacing);
        let velocity = body.velocity.unwrap_or([0.0, 0.0]);
        if !(velocity[0].is_finite()
            && velocity[1].is_finite()
            && velocity[0].hypot(velocity[1]) < 1e5)
        {
            return Err(ctx.err(
                &p("velocity"),
                Some(pair(velocity)),
                "initial velocity out of range",
                "finite components, speed < 1e5 m/s",
                "give the initial velocity in m/s, e.g. [10.0, 0.0]",
            ));
        }
        let shape = body_shape(ctx, &base, body, &grid)?;
        let area = shape_area(&shape);
        if !(area.is_finite() && area / (spacing * spacing) <= MAX_PARTICLES as f64) {
            return Err(ctx.err(
                &base,
                None,
                format!(
                    "this body would generate about {:.3e} particles",
                    area / (spacing * spacing)
                ),
                format!("at most {MAX_PARTICLES} particles in a scene"),
                "use a coarser grid, fewer particles per cell or a smaller body",
            ));
        }
        let fill = generate::fill(&shape, spacing);
        if fill.is_empty() {
            return Err(ctx.err(
                &base,
                None,
                format!(
                    "the body is smaller than one particle spacing ({} m) and holds no particle",
                    num(spacing)
                ),
                "a body at least one particle spacing wide and thick",
                "enlarge the body or raise particles_per_cell",
            ));
        }
        if seeds.len() + fill.len() > MAX_PARTICLES {
            return Err(ctx.err(
                &base,
                None,
                format!("the scene would generate more than {MAX_PARTICLES} particles"),
                format!("at most {MAX_PARTICLES} particles in a scene"),
                "use a coarser grid or fewer particles per cell",
            ));
        }
        let m_index = used.iter().position(|n| *n == body.material).unwrap_or(0);
        let density = f.materials.get(&body.material).map_or(1.0, |m| m.density);
        for s in &fill {
            let located = match &grid {
                GridBuilt::Terrain(t) => t.locate(s.position).map(|_| ()),
                GridBuilt::Regular(r) => r.locate(s.position).map(|_| ()),
            };
            if let Err(e) = located {
                return Err(outside_error(ctx, &base, body, e, &grid));
            }
        }
        // overlap with earlier bodies: a particle of one body strictly inside another's shape.
        // Only bodies whose bounding boxes meet can overlap: O(bodies²) box tests, and particle
        // tests only for the pairs that are close.
        let bounds = shape_box(&shape);
        for (other, (shape_o, bounds_o, range)) in shapes.iter().enumerate() {
            let apart =
                (0..2).any(|k| bounds[1][k] < bounds_o[0][k] || bounds_o[1][k] < bounds[0][k]);
            if apart {
                continue;
            }
            let hit =
                fill.iter().find(|s| contains(shape_o, s.position)).map(|s| s.position).or_else(
                    || {
                        seeds[range.clone()]
                            .iter()
                            .find(|s| contains(&shape, s.position))
                            .map(|s| s.position)
                    },
                );
            if let Some(at) = hit {
                return Err(ctx.err(
                    &base,
                    None,
                    format!(
                        "this body overlaps bodies[{other}] (a particle at ({}, {}) lies in both)",
                        num(at.x),
                        num(at.y)
                    ),
                    "bodies that do not overlap (they may touch)",
                    "move or shrink one of the two bodies",
                ));
            }
        }
        let first = seeds.len();
        seeds.extend(fill.iter().map(|s| Seed {
            position: s.position,
            velocity: Vector::new(velocity[0], velocity[1]),
            volume: s.area,
            density,
            material: m_index as u16,
            body: b as u16,
        }));
        shapes.push((shape, bounds, first..seeds.len()));
    }

    // ---- boundaries ------------------------------------------------------------------------
    let mut boundaries = Boundaries::default();
    for (name, spec, slot) in [
        ("ground", f.boundaries.ground, &mut boundaries.ground),
        ("left_wall", f.boundaries.left_wall, &mut boundaries.left_wall),
        ("right_wall", f.boundaries.right_wall, &mut boundaries.right_wall),
    ] {
        let Some(spec) = spec else { continue };
        let path = format!("boundaries.{name}");
        let friction = match spec {
            BoundarySpec::Friction(mu) => Boundary::new(Vector::Y, Friction::Coulomb { mu })
                .map_err(|e| contact_error(ctx, &format!("{path}.friction"), e))?
                .friction(),
            BoundarySpec::FrictionAngleDeg(a) => Boundary::with_friction_angle_deg(Vector::Y, a)
                .map_err(|e| contact_error(ctx, &format!("{path}.friction_angle_deg"), e))?
                .friction(),
            BoundarySpec::Rough => Friction::Rough,
            BoundarySpec::Fixed => Friction::Fixed,
            BoundarySpec::Frictionless => Friction::Coulomb { mu: 0.0 },
        };
        *slot = Some(friction);
    }

    let config = SolverConfig {
        scheme,
        time_step,
        gravity: Vector::new(gravity[0], gravity[1]),
        boundaries,
        small_mass_ratio,
        objective_stress: s
            .objective_stress
            .unwrap_or(material_kind == MaterialKind::DruckerPrager),
        gravity_ramp,
        transfer: s.transfer.unwrap_or_default(),
        contact: s.contact.unwrap_or_default(),
    };
    config.validate().map_err(|e| solver_error(ctx, e))?;

    // ---- the first time step (eq 13) -------------------------------------------------------
    let min_cell = match &grid {
        GridBuilt::Terrain(t) => t.min_cell_size(),
        GridBuilt::Regular(r) => r.min_cell_size(),
    };
    let (signal, fastest) = seeds.iter().enumerate().fold((0.0f64, 0usize), |acc, (i, s)| {
        let c = (p_modulus[usize::from(s.material)] / s.density).sqrt() + s.velocity.length();
        if c > acc.0 { (c, i) } else { acc }
    });
    let v_max = seeds.iter().map(|s| s.velocity.length()).fold(0.0, f64::max);
    let g_abs = config.gravity.length();
    let initial_dt = match time_step {
        TimeStep::Courant(c) => {
            (c * min_cell / signal).min(mpm_solver::displacement_dt(c * min_cell, v_max, g_abs))
        }
        TimeStep::Fixed(dt) => {
            let cells = (v_max * dt + 0.5 * g_abs * dt * dt) / min_cell;
            if cells > 1.0 {
                let most = mpm_solver::displacement_dt(min_cell, v_max, g_abs);
                return Err(ctx.err(
                    "solver.dt",
                    Some(num(dt)),
                    format!(
                        "with the fixed time step, gravity and the initial speed carry a \
                         particle {cells:.3} cells in the first step (smallest cell {} m)",
                        num(min_cell)
                    ),
                    format!("dt ≤ {} s (at most one cell per step)", num(most)),
                    "use `courant = 0.1` instead of `dt` (Δt then follows the material)",
                ));
            }
            let courant = dt * signal / min_cell;
            if courant > 1.0 {
                return Err(ctx.err(
                    "solver.dt",
                    Some(num(dt)),
                    format!(
                        "the fixed time step gives a Courant number {courant:.3} > 1 at t = 0 \
                         (particle {fastest}: wave speed + speed {} m/s, smallest cell {} m)",
                        num(signal),
                        num(min_cell)
                    ),
                    format!("dt ≤ {} s (Courant number ≤ 1, eq 13)", num(min_cell / signal)),
                    format!(
                        "use `dt = {}` (Courant 0.1) or replace `dt` by `courant = 0.1`",
                        num(0.1 * min_cell / signal)
                    ),
                ));
            }
            dt
        }
    };
    let steps = (s.end_time / initial_dt).ceil();
    if steps.is_nan() || steps > max_steps as f64 {
        let shown = if steps < 1e15 { format!("{steps:.0}") } else { format!("{steps:.3e}") };
        let (path, value) = match (s.dt, s.courant) {
            (Some(dt), _) => ("solver.dt", dt),
            (None, Some(c)) => ("solver.courant", c),
            (None, None) => ("solver.end_time", s.end_time),
        };
        return Err(ctx.err(
            path,
            Some(num(value)),
            format!(
                "the run would take {shown} steps or more (initial Δt {} s to end_time {} s), \
                 above max_steps = {max_steps}; the fastest signal is {} m/s at particle \
                 {fastest} (wave speed √(M/ρ) of its material plus its speed)",
                num(initial_dt),
                num(s.end_time),
                num(signal)
            ),
            format!("end_time / Δt ≤ max_steps = {max_steps}"),
            "check the material's density and stiffness and the Courant number or dt (they set \
             Δt, eq 13), shorten end_time, or raise `[solver] max_steps`",
        ));
    }

    // ---- output ----------------------------------------------------------------------------
    let o = &f.output;
    let end_time = s.end_time;
    let interval = o.interval.unwrap_or(end_time / 50.0);
    if !(finite_pos(interval) && end_time / interval <= 1e6) {
        return Err(ctx.range(
            "output.interval",
            interval,
            "0 < interval, at most 1e6 frames over end_time (s)",
            "give the time between frames in seconds, e.g. end_time / 50",
        ));
    }
    let series_interval = o.series_interval.unwrap_or(interval.min(end_time / 200.0));
    if !(finite_pos(series_interval) && end_time / series_interval <= 1e7) {
        return Err(ctx.range(
            "output.series_interval",
            series_interval,
            "0 < series_interval, at most 1e7 rows over end_time (s)",
            "remove it to use the default min(interval, end_time / 200)",
        ));
    }
    if let Some(c) = o.checkpoint_interval {
        if !finite_pos(c) {
            return Err(ctx.range(
                "output.checkpoint_interval",
                c,
                "0 < checkpoint_interval (s of simulated time)",
                "give the simulated time between checkpoints, or remove it",
            ));
        }
    }
    if let Some(fields) = &o.fields {
        if let Some(k) = (1..fields.len()).find(|&k| fields[..k].contains(&fields[k])) {
            let name = toml::Value::try_from(fields[k]).map(|v| v.to_string()).unwrap_or_default();
            return Err(ctx.err(
                &format!("output.fields[{k}]"),
                Some(name),
                "the field is listed twice (each .vtp would hold two arrays of that name)",
                "each field at most once",
                "remove the repeated entry",
            ));
        }
    }
    if let Some(list) = o.probes.as_ref().filter(|l| l.len() > MAX_PROBES) {
        return Err(ctx.err(
            "output.probes",
            Some(format!("{} probes", list.len())),
            "too many probes",
            format!("at most {MAX_PROBES} probes (each writes a row per series interval)"),
            "probe a few particles; the particle frames hold every particle",
        ));
    }
    let mut probes = Vec::new();
    for (k, probe) in o.probes.iter().flatten().enumerate() {
        let path = format!("output.probes[{k}]");
        match *probe {
            ProbeSpec::Index(i) => {
                if !(i >= 0 && (i as usize) < seeds.len()) {
                    return Err(ctx.err(
                        &path,
                        Some(i.to_string()),
                        "no particle has this index",
                        format!("0 ≤ index < {} (the scene's particle count)", seeds.len()),
                        "use a smaller index, or { nearest = [x, y] }",
                    ));
                }
                probes.push(i as usize);
            }
            ProbeSpec::Nearest(at) => {
                if !(at[0].is_finite() && at[1].is_finite()) {
                    return Err(ctx.err(
                        &path,
                        Some(pair(at)),
                        "the point is not finite",
                        "finite coordinates (m)",
                        "give a point inside a body",
                    ));
                }
                let at = Vector::new(at[0], at[1]);
                let nearest = seeds
                    .iter()
                    .enumerate()
                    .min_by(|a, b| {
                        a.1.position
                            .distance_squared(at)
                            .total_cmp(&b.1.position.distance_squared(at))
                    })
                    .map_or(0, |(i, _)| i);
                probes.push(nearest);
            }
        }
    }
    let reference = match o.reference {
        None => None,
        Some(curve) => {
            let path = "output.reference";
            let value = Some(format!("\"{}\"", curve.name()));
            let Some(&probe) = probes.first() else {
                return Err(ctx.err(
                    path,
                    value,
                    "a reference curve is compared with probe particles, but there are none",
                    "at least one entry in output.probes",
                    "add `probes = [0]` (or { nearest = [x, y] }) to [output]",
                ));
            };
            let mu = match boundaries.ground {
                Some(Friction::Coulomb { mu }) => mu,
                _ => {
                    return Err(ctx.err(
                        path,
                        value,
                        "the reference curve needs Coulomb friction on the ground",
                        "boundaries.ground = { friction = μ }, { friction_angle_deg = φ } or \
                         \"frictionless\"",
                        "declare the ground's friction in [boundaries]",
                    ));
                }
            };
            let g = Vector::new(gravity[0], gravity[1]).length();
            let start = seeds[probe].position;
            match curve {
                ReferenceCurve::Abe2005Eq21 => Some(Reference {
                    curve,
                    mu,
                    g,
                    v0: seeds[probe].velocity.x,
                    theta: 0.0,
                    direction: Vector::X,
                }),
                ReferenceCurve::Abe2005Eq22 => {
                    let GridBuilt::Terrain(_) = &grid else {
                        return Err(ctx.err(
                            path,
                            value,
                            "eq 22 is a slide down an inclined ground, but the grid is regular",
                            "a terrain grid whose ground under the probe is inclined",
                            "use `kind = \"terrain\"` with a sloping profile, or abe2005_eq21",
                        ));
                    };
                    let (a, b) = segment_at(&ground, start.x);
                    let d = (b - a).normalize_or_zero();
                    let down = if d.y <= 0.0 { d } else { -d };
                    Some(Reference {
                        curve,
                        mu,
                        g,
                        v0: 0.0,
                        theta: (-down.y).asin(),
                        direction: down,
                    })
                }
            }
        }
    };

    Ok(Resolved {
        grid,
        shape_function,
        gimp_ppc,
        materials,
        seeds,
        config,
        end_time,
        output: ResolvedOutput {
            interval,
            series_interval,
            fields: o.fields.clone().unwrap_or_else(|| VtkField::ALL.to_vec()),
            vtk: o.vtk.unwrap_or(true),
            vtk_format: o.vtk_format.unwrap_or_default(),
            plots: o.plots.unwrap_or(true),
            probes,
            reference,
            checkpoint_interval: o.checkpoint_interval,
        },
        ground,
        spacing: spacing_min,
        initial_dt,
        alarm,
        max_steps,
    })
}

/// the ground segment under x (the last one for x beyond the profile).
pub(crate) fn segment_at(ground: &[Vector], x: f64) -> (Vector, Vector) {
    for w in ground.windows(2) {
        if x < w[1].x {
            return (w[0], w[1]);
        }
    }
    let n = ground.len();
    if n >= 2 { (ground[n - 2], ground[n - 1]) } else { (Vector::ZERO, Vector::X) }
}

/// ground height at x along the polyline (end segments extended).
pub(crate) fn ground_height(ground: &[Vector], x: f64) -> f64 {
    let (a, b) = segment_at(ground, x);
    if b.x == a.x { a.y } else { a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x) }
}

fn body_shape(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    grid: &GridBuilt,
) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let kind = body.shape;
    let allowed: &[&str] = match kind {
        ShapeKind::Rectangle => &["min", "max"],
        ShapeKind::Polygon => &["vertices"],
        ShapeKind::OnSlope => &["base_start", "base_x", "angle_deg", "length", "thickness"],
    };
    for (field, present) in [
        ("min", body.min.is_some()),
        ("max", body.max.is_some()),
        ("vertices", body.vertices.is_some()),
        ("base_start", body.base_start.is_some()),
        ("base_x", body.base_x.is_some()),
        ("angle_deg", body.angle_deg.is_some()),
        ("length", body.length.is_some()),
        ("thickness", body.thickness.is_some()),
    ] {
        if present && !allowed.contains(&field) {
            return Err(ctx.foreign(
                &p(field),
                &format!("a shape = \"{}\" body takes {}", shape_name(kind), allowed.join(", ")),
            ));
        }
    }
    let finite2 = |v: [f64; 2]| v[0].is_finite() && v[1].is_finite();
    match kind {
        ShapeKind::Rectangle => {
            let min = body.min.ok_or_else(|| ctx.missing(&p("min"), "rectangle", "[0.0, 0.0]"))?;
            let max = body.max.ok_or_else(|| ctx.missing(&p("max"), "rectangle", "[1.0, 1.0]"))?;
            for (f, v) in [("min", min), ("max", max)] {
                if !finite2(v) {
                    return Err(ctx.err(
                        &p(f),
                        Some(pair(v)),
                        "corner is not finite",
                        "finite coordinates (m)",
                        "give the corner in metres",
                    ));
                }
            }
            if !(max[0] > min[0] && max[1] > min[1]) {
                return Err(ctx.err(
                    &p("max"),
                    Some(pair(max)),
                    format!("the upper-right corner is not above and right of min = {}", pair(min)),
                    "max[0] > min[0] and max[1] > min[1]",
                    "swap the corners or correct them",
                ));
            }
            Ok(Shape::Rectangle {
                min: Vector::new(min[0], min[1]),
                max: Vector::new(max[0], max[1]),
            })
        }
        ShapeKind::Polygon => {
            let v = body.vertices.clone().ok_or_else(|| {
                ctx.missing(&p("vertices"), "polygon", "[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]")
            })?;
            if v.len() < 3 || v.len() > MAX_VERTICES {
                return Err(ctx.err(
                    &p("vertices"),
                    Some(format!("{} vertices", v.len())),
                    format!("a polygon needs at least three vertices and at most {MAX_VERTICES}"),
                    format!("3 to {MAX_VERTICES} vertices, in order"),
                    "list the polygon's corners in order",
                ));
            }
            if let Some(k) = v.iter().position(|x| !finite2(*x)) {
                return Err(ctx.err(
                    &format!("{}[{k}]", p("vertices")),
                    Some(pair(v[k])),
                    "vertex is not finite",
                    "finite coordinates (m)",
                    "give the vertex in metres",
                ));
            }
            let mut vertices: Vec<Vector> = v.iter().map(|x| Vector::new(x[0], x[1])).collect();
            // A closing vertex that repeats the first one is a common way to write an outline.
            if vertices.len() > 3 && vertices.first() == vertices.last() {
                vertices.pop();
            }
            if let Some((a, b)) = self_intersection(&vertices) {
                return Err(ctx.err(
                    &format!("{}[{a}]", p("vertices")),
                    Some(pair(v[a])),
                    format!(
                        "the polygon is not simple: its edge from vertex {a} crosses the edge from \
                         vertex {b} (a bow-tie has no inside)"
                    ),
                    "a simple polygon: edges meet only at their shared corners",
                    "list the corners in order around the outline (clockwise or counter-\
                     clockwise), or split the shape into two bodies",
                ));
            }
            Ok(Shape::Polygon { vertices })
        }
        ShapeKind::OnSlope => {
            let length = body.length.ok_or_else(|| ctx.missing(&p("length"), "on_slope", "1.2"))?;
            let thickness =
                body.thickness.ok_or_else(|| ctx.missing(&p("thickness"), "on_slope", "0.7"))?;
            for (f, v) in [("length", length), ("thickness", thickness)] {
                if !finite_pos(v) {
                    return Err(ctx.range(
                        &p(f),
                        v,
                        "0 < value < ∞ (m)",
                        "give the body's size in metres",
                    ));
                }
            }
            let ground_of = |x: f64| -> Option<(f64, f64)> {
                match grid {
                    GridBuilt::Terrain(t) => {
                        let y = t.ground_height(x)?;
                        let (a, b) = segment_at(t.profile(), x);
                        Some((y, (b.y - a.y).atan2(b.x - a.x)))
                    }
                    GridBuilt::Regular(r) => {
                        let (lo, hi) = (r.origin(), r.upper_corner());
                        (lo.x..=hi.x).contains(&x).then_some((lo.y, 0.0))
                    }
                }
            };
            let (start, ground_angle) = match (body.base_start, body.base_x) {
                (Some(_), Some(_)) => {
                    return Err(ctx.err(
                        &p("base_x"),
                        body.base_x.map(num),
                        "both `base_start` and `base_x` are given",
                        "one of them",
                        "keep `base_x` to put the body on the ground, or `base_start` for an \
                         explicit corner",
                    ));
                }
                (Some(bs), None) => {
                    if !finite2(bs) {
                        return Err(ctx.err(
                            &p("base_start"),
                            Some(pair(bs)),
                            "corner is not finite",
                            "finite coordinates (m)",
                            "give the corner in metres",
                        ));
                    }
                    (Vector::new(bs[0], bs[1]), ground_of(bs[0]).map(|g| g.1))
                }
                (None, Some(x)) => {
                    let Some((y, angle)) = ground_of(x).filter(|_| x.is_finite()) else {
                        return Err(ctx.err(
                            &p("base_x"),
                            Some(num(x)),
                            "this x is not over the grid's ground",
                            "an x within the grid's horizontal extent (m)",
                            "give an x between the grid's left and right ends",
                        ));
                    };
                    (Vector::new(x, y), Some(angle))
                }
                (None, None) => {
                    return Err(ctx.missing(&p("base_x"), "on_slope: base_x or base_start", "0.1"));
                }
            };
            let angle_rad = match body.angle_deg {
                Some(a) => {
                    if !(a.is_finite() && a > -90.0 && a < 90.0) {
                        return Err(ctx.range(
                            &p("angle_deg"),
                            a,
                            "-90 < angle_deg < 90 (degrees from +x; negative descends to the \
                             right)",
                            "remove it to follow the ground's slope",
                        ));
                    }
                    a.to_radians()
                }
                None => ground_angle.unwrap_or(0.0),
            };
            Ok(Shape::OnSlope { base_start: start, angle_rad, length, thickness })
        }
    }
}

fn shape_name(k: ShapeKind) -> &'static str {
    match k {
        ShapeKind::Rectangle => "rectangle",
        ShapeKind::Polygon => "polygon",
        ShapeKind::OnSlope => "on_slope",
    }
}

/// refuses a scene whose particles would not fit in the memory this process may use, before any
/// particle exists: the count comes from the bodies' areas (n² particles per cell), the bytes per
/// particle from the solver's own accounting (`mpm_solver::estimated_bytes`), plus the scene's
/// seeds and one particle frame being written.
fn fits_in_memory(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
    cell_x: f64,
    shape_function: ShapeFunctionKind,
    state: usize,
) -> Result<(), SceneError> {
    let mut particles = 0.0;
    for (b, body) in f.bodies.iter().enumerate() {
        let ppc = body.particles_per_cell.unwrap_or(2).clamp(1, MAX_PARTICLES_PER_CELL) as f64;
        // a body whose shape is invalid is reported, located, by the bodies' loop
        if let Ok(shape) = body_shape(ctx, &format!("bodies[{b}]"), body, grid) {
            particles += enclosed_area(&shape) * (ppc / cell_x).powi(2);
        }
    }
    if !(particles.is_finite() && particles <= MAX_PARTICLES as f64) {
        // the bodies' loop names the body and the limit
        return Ok(());
    }
    let n = particles.ceil() as usize;
    let (stencil, nodes) = match (grid, shape_function) {
        (GridBuilt::Terrain(t), _) => (4, (t.columns() + 1) * (t.rows() + 1)),
        (GridBuilt::Regular(g), kind) => {
            let [nx, ny] = g.cells();
            (if kind == ShapeFunctionKind::Bilinear { 4 } else { 9 }, (nx + 3) * (ny + 3))
        }
    };
    let apic = f.solver.transfer == Some(Transfer::Apic);
    let fields = f.output.fields.clone().unwrap_or_else(|| VtkField::ALL.to_vec());
    let frame =
        crate::output::vtk::frame_bytes(n, &fields, f.output.vtk_format.unwrap_or_default());
    let need =
        mpm_solver::estimated_bytes(n, nodes.min(n.saturating_mul(stencil)), stencil, state, apic)
            + (n * std::mem::size_of::<Seed>()) as u64
            + frame;
    let Some((available, source)) = crate::limits::available_memory() else { return Ok(()) };
    if need > available {
        return Err(ctx.err(
            "bodies",
            None,
            format!(
                "the scene needs about {:.0} MB for {n} particles ({:.0} B each, with the grid \
                 and one frame being written), but only {:.0} MB are available ({source})",
                need as f64 / 1e6,
                need as f64 / n.max(1) as f64,
                available as f64 / 1e6
            ),
            format!("at most about {:.0} MB", available as f64 / 1e6),
            "use a coarser grid, fewer particles per cell or smaller bodies, or run it on a \
             machine with more memory",
        ));
    }
    Ok(())
}

/// the first pair (i, j) of non-adjacent edges (edge k runs from vertex k to k + 1, the last one
/// back to vertex 0) that cross or touch, or a repeated vertex: `None` for a simple polygon.
/// O(n²) in the vertices, bounded by [`MAX_VERTICES`].
fn self_intersection(v: &[Vector]) -> Option<(usize, usize)> {
    let n = v.len();
    let edge = |k: usize| (v[k], v[(k + 1) % n]);
    let orient = |a: Vector, b: Vector, c: Vector| (b - a).perp_dot(c - a);
    let on_segment = |a: Vector, b: Vector, c: Vector| {
        c.x >= a.x.min(b.x) && c.x <= a.x.max(b.x) && c.y >= a.y.min(b.y) && c.y <= a.y.max(b.y)
    };
    let meet = |(p1, p2): (Vector, Vector), (q1, q2): (Vector, Vector)| {
        let (d1, d2) = (orient(q1, q2, p1), orient(q1, q2, p2));
        let (d3, d4) = (orient(p1, p2, q1), orient(p1, p2, q2));
        if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
            && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
        {
            return true;
        }
        (d1 == 0.0 && on_segment(q1, q2, p1))
            || (d2 == 0.0 && on_segment(q1, q2, p2))
            || (d3 == 0.0 && on_segment(p1, p2, q1))
            || (d4 == 0.0 && on_segment(p1, p2, q2))
    };
    for i in 0..n {
        let (lo_i, hi_i) = (edge(i).0.min(edge(i).1), edge(i).0.max(edge(i).1));
        for j in i + 1..n {
            // adjacent edges share a corner: only a repeated vertex or a fold back counts
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = (edge(j).0.min(edge(j).1), edge(j).0.max(edge(j).1));
            if a.x > hi_i.x || b.x < lo_i.x || a.y > hi_i.y || b.y < lo_i.y {
                continue;
            }
            if adjacent {
                // collinear and overlapping beyond the shared corner: a fold back
                let (shared, p, q) =
                    if j == i + 1 { (v[j], v[i], v[(j + 1) % n]) } else { (v[0], v[1], v[n - 1]) };
                let folded = orient(p, shared, q) == 0.0 && (p - shared).dot(q - shared) > 0.0;
                if folded || v[i] == v[(i + 1) % n] {
                    return Some((i, j));
                }
                continue;
            }
            if meet(edge(i), edge(j)) {
                return Some((i, j));
            }
        }
    }
    None
}

/// the axis-aligned bounding box [min, max] of a shape.
fn shape_box(shape: &Shape) -> [Vector; 2] {
    let corners: Vec<Vector> = match shape {
        Shape::Rectangle { min, max } => vec![*min, *max],
        Shape::Polygon { vertices } => vertices.clone(),
        Shape::OnSlope { base_start, angle_rad, length, thickness } => {
            let d = Vector::new(angle_rad.cos(), angle_rad.sin());
            let n = Vector::new(-d.y, d.x);
            vec![
                *base_start,
                *base_start + *length * d,
                *base_start + *length * d + *thickness * n,
                *base_start + *thickness * n,
            ]
        }
    };
    let lo = corners.iter().fold(Vector::splat(f64::INFINITY), |a, &c| a.min(c));
    let hi = corners.iter().fold(Vector::splat(f64::NEG_INFINITY), |a, &c| a.max(c));
    [lo, hi]
}

/// the area the fill's lattice scans (a polygon's bounding box): what bounds generation work.
fn shape_area(shape: &Shape) -> f64 {
    match shape {
        Shape::Rectangle { min, max } => (max.x - min.x) * (max.y - min.y),
        Shape::OnSlope { length, thickness, .. } => length * thickness,
        Shape::Polygon { .. } => {
            let [lo, hi] = shape_box(shape);
            (hi.x - lo.x) * (hi.y - lo.y)
        }
    }
}

/// the area a shape encloses (a polygon's by the shoelace formula): what bounds its particles.
fn enclosed_area(shape: &Shape) -> f64 {
    match shape {
        Shape::Polygon { vertices } => {
            let n = vertices.len();
            0.5 * (0..n).map(|k| vertices[k].perp_dot(vertices[(k + 1) % n])).sum::<f64>().abs()
        }
        other => shape_area(other),
    }
}

/// `p` strictly inside `shape` (by more than round-off).
fn contains(shape: &Shape, p: Vector) -> bool {
    const EPS: f64 = 1e-9;
    match shape {
        Shape::Rectangle { min, max } => {
            p.x > min.x + EPS && p.x < max.x - EPS && p.y > min.y + EPS && p.y < max.y - EPS
        }
        Shape::OnSlope { base_start, angle_rad, length, thickness } => {
            let t = Vector::new(angle_rad.cos(), angle_rad.sin());
            let n = t.perp();
            let d = p - *base_start;
            let (s, h) = (d.dot(t), d.dot(n));
            s > EPS && s < length - EPS && h > EPS && h < thickness - EPS
        }
        Shape::Polygon { vertices } => mpm_solver::generate::inside_polygon(vertices, p),
    }
}

fn outside_error(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    e: LocateError,
    grid: &GridBuilt,
) -> SceneError {
    let extent = match grid {
        GridBuilt::Terrain(t) => {
            let (x0, x1) = t.x_range();
            format!(
                "x from {} to {} m, between the ground and {} m above it",
                num(x0),
                num(x1),
                num(t.rows() as f64 * t.row_height())
            )
        }
        GridBuilt::Regular(r) => {
            let (lo, hi) = (r.origin(), r.upper_corner());
            format!(
                "x from {} to {} m, y from {} to {} m",
                num(lo.x),
                num(hi.x),
                num(lo.y),
                num(hi.y)
            )
        }
    };
    let field = match body.shape {
        ShapeKind::Rectangle => "min",
        ShapeKind::Polygon => "vertices",
        ShapeKind::OnSlope => {
            if body.base_x.is_some() {
                "base_x"
            } else {
                "base_start"
            }
        }
    };
    let problem = match e {
        LocateError::BelowGround { x, y, ground_y } => format!(
            "the body lies outside the grid: its particle at ({}, {}) is below the ground \
             (ground height there {})",
            num(x),
            num(y),
            num(ground_y)
        ),
        LocateError::Outside { x, y } | LocateError::NonFinite { x, y } => format!(
            "the body lies outside the grid: its particle at ({}, {}) is left, right or above \
             the grid",
            num(x),
            num(y)
        ),
    };
    ctx.err(
        &format!("{base}.{field}"),
        None,
        problem,
        format!("every particle inside the grid: {extent}"),
        "move or shrink the body, or enlarge the grid (more rows, a longer profile or more cells)",
    )
}

fn grid_error(ctx: &Ctx<'_>, e: GridError, profile: &[[f64; 2]]) -> SceneError {
    let point = |i: usize| profile.get(i).map(|p| pair(*p));
    match e {
        GridError::TooFewProfilePoints { count } => ctx.err(
            "grid.profile",
            Some(format!("{count} point(s)")),
            "the ground profile needs at least two points",
            "2 or more [x, y] points with x increasing",
            "give the ground as [[x0, y0], [x1, y1], ...]",
        ),
        GridError::NonFiniteProfilePoint { index, .. } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            "profile point is not finite",
            "finite coordinates (m)",
            "give the point in metres",
        ),
        GridError::NonIncreasingProfile { index, x, previous_x } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!("profile x decreases (or repeats): x = {} after {}", num(x), num(previous_x)),
            "x strictly increasing from one profile point to the next",
            "order the points from left to right; an overhang cannot be represented",
        ),
        GridError::KinkOffColumnBoundary { index, x, nearest_boundary_x } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!("profile point x = {} is not on a column boundary", num(x)),
            "with kink_policy = \"reject\": x = x0 + k·cell_width",
            format!("move it to x = {} or use kink_policy = \"snap\"", num(nearest_boundary_x)),
        ),
        GridError::SnappedPointsCoincide { index, boundary_x, .. } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!(
                "this point and the previous one snap to the same column boundary x = {}",
                num(boundary_x)
            ),
            "profile points at least one cell_width apart",
            "drop the point or use a smaller cell_width",
        ),
        GridError::NonPositiveSize { what, value } => {
            let path = match what {
                "cell width" => "grid.cell_width",
                "row height" => "grid.row_height",
                "cell size dx" => "grid.cell[0]",
                "cell size dy" => "grid.cell[1]",
                _ => "grid",
            };
            ctx.range(path, value, "0 < size < ∞ (m)", "give the cell size in metres, e.g. 0.1")
        }
        GridError::NonFinitePoint { what, x, y } => ctx.err(
            "grid.origin",
            Some(pair([x, y])),
            format!("{what} is not finite"),
            "finite coordinates (m)",
            "give the origin and cell sizes in metres",
        ),
        GridError::CellCountOutOfRange { what, count, max } => {
            let path = match what {
                "rows" => "grid.rows",
                "cells along x" => "grid.cells[0]",
                "cells along y" => "grid.cells[1]",
                _ => "grid.profile",
            };
            ctx.err(
                path,
                Some(num(count)),
                format!("{what} out of range"),
                format!("1 ≤ {what} ≤ {max}"),
                "use a larger cell size or a shorter grid",
            )
        }
        GridError::DegenerateSegment { index, slope, .. } => ctx.err(
            &format!("grid.profile[{}]", index + 1),
            point(index + 1),
            format!("the ground segment ending here is too steep (slope {})", num(slope)),
            "finite slopes (a vertical step cannot be represented)",
            "spread the step over one or more columns",
        ),
        GridError::DegenerateCell { .. } => ctx.err(
            "grid.row_height",
            None,
            e.to_string(),
            "positive cell heights",
            "check row_height and the profile",
        ),
        GridError::InvalidParticleHalfSize { .. } => ctx.err(
            "solver.shape_function",
            None,
            e.to_string(),
            "particles per cell ≥ 1",
            "check particles_per_cell",
        ),
    }
}

fn material_error(ctx: &Ctx<'_>, base: &str, e: ConstitutiveError) -> SceneError {
    let (field, value, admissible) = match &e {
        ConstitutiveError::InvalidParameter { name, value, range } => {
            let field = match *name {
                "bulk" | "shear" => "young",
                other => other,
            };
            (field.to_string(), Some(num(*value)), range.to_string())
        }
        ConstitutiveError::IllPosedSoftening { hardening_modulus, lower_bound, .. } => (
            "hardening_modulus".into(),
            Some(num(*hardening_modulus)),
            format!("hardening_modulus > {} Pa", num(*lower_bound)),
        ),
        _ => (String::new(), None, String::new()),
    };
    let fix = match field.as_str() {
        "young" => "give Young's modulus in Pa, e.g. 2e6 for loose sand",
        "poisson" => "use a Poisson's ratio below 0.5, e.g. 0.3",
        "cohesion" => "use a cohesion ≥ 0 in Pa (10 Pa in the paper's sand)",
        "friction_angle_deg" => "use a friction angle below 90°, e.g. 40 for dry sand",
        "dilatancy_angle_deg" => "use 0 ≤ ψ ≤ φ (0 in the paper)",
        "mixing" => "use M between 0 (kinematic) and 1 (isotropic); 0.8 in the paper",
        "hardening_modulus" => "use H ≥ 0 (0 in the paper) or a milder softening",
        _ => "see docs/scene-format.md",
    };
    ctx.err(&join(base, &field), value, e.to_string(), admissible, fix)
}

fn contact_error(ctx: &Ctx<'_>, path: &str, e: ContactError) -> SceneError {
    match e {
        ContactError::InvalidFrictionCoefficient { mu, .. } => ctx.range(
            path,
            mu,
            "0 ≤ friction < ∞ (Coulomb coefficient μ)",
            "give μ ≥ 0, or use \"rough\" for no slip",
        ),
        ContactError::InvalidFrictionAngle { angle_deg, .. } => ctx.range(
            path,
            angle_deg,
            "0 ≤ friction_angle_deg < 90 (degrees)",
            "give the basal friction angle in degrees (27 in the paper's flume), or \"rough\"",
        ),
        other => ctx.err(path, None, other.to_string(), String::new(), "see docs/scene-format.md"),
    }
}

fn solver_error(ctx: &Ctx<'_>, e: SolverError) -> SceneError {
    match e {
        SolverError::InvalidSetting { name, value, expected } => ctx.range(
            &format!("solver.{name}"),
            value,
            expected,
            "see docs/scene-format.md for the admissible range",
        ),
        other => ctx.err("solver", None, other.to_string(), String::new(), String::new()),
    }
}
