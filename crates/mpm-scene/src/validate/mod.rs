//! From scene text to a [`Scene`] that can run: parse, check every value, build the grid, the
//! materials and the particle seeds, and map every refusal to its field path, line and column.
//!
//! Order of checks: TOML syntax and types (serde) → solver settings → grid → materials → bodies
//! (shape, inside the grid, no overlap) → boundaries → the solver configuration as a whole → the
//! first Δt → initial state → output; each section has its module. The first problem found is reported; nothing
//! runs until the whole scene is consistent.
//!
//! The solver is generic over the constitutive model: a scene whose materials are all of one
//! model runs as that model; one whose bodies use several (sand on elastic bedrock) runs as
//! [`crate::materials::AnyModel`], each particle updated by its own material's model.

mod bodies;
mod boundaries;
pub(crate) mod edit;
mod grid;
mod initial_state;
mod materials;
mod output;
pub mod plausible;
mod polyline;
mod solver;
pub(super) mod space;

pub use bodies::checkpoint_copy;
pub use space::{load_space_str, load_space_str_in};

use crate::error::SceneError;
use crate::file::*;
use crate::scene::{Resolved, Scene};
use crate::source::SourceMap;

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
    /// the directory that files named in the scene are relative to (the scene file's).
    dir: Option<&'a std::path::Path>,
    /// the files the scene named, as named and as found, in the order it named them.
    inputs: std::cell::RefCell<Vec<(String, std::path::PathBuf)>>,
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
        let (line, column) = match self.locate(path) {
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

    /// (line, column) of `path`, or of the nearest enclosing table or array element that the
    /// text has (a missing field is reported at its table).
    fn locate(&self, path: &str) -> Option<(usize, usize)> {
        let mut p = path;
        loop {
            if let Some(at) = self.map.locate(p) {
                return Some(at);
            }
            p = &p[..p.rfind(['.', '['])?];
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

/// A scene text longer than a scene file may be ([`crate::limits::MAX_SCENE_BYTES`]) is refused
/// whatever its source (a file, a string, a Python edit): what `mpm` refuses to read is refused
/// everywhere, before any parsing.
pub(crate) fn bounded(text: &str, origin: &str) -> Result<(), SceneError> {
    let limit = crate::limits::MAX_SCENE_BYTES;
    if text.len() as u64 <= limit {
        return Ok(());
    }
    Err(SceneError {
        origin: origin.to_string(),
        line: None,
        column: None,
        path: String::new(),
        value: Some(format!("{} bytes", text.len())),
        problem: format!("the scene is larger than {} MiB", limit >> 20),
        admissible: format!("a TOML scene of at most {limit} bytes"),
        fix: "long outlines belong in fewer points (a polygon of at most 10 000 vertices)".into(),
    })
}

/// Parses and validates a scene; `origin` names the text in messages (a path, or
/// `embedded:NAME`). Files the scene names (DEMs, CSV polylines) are relative to the current
/// directory; [`load_scene_str_in`] gives them another.
pub fn load_scene_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
    load(text, origin, None)
}

/// [`load_scene_str`] for a scene whose named files are relative to `dir` (the directory of the
/// scene file).
pub fn load_scene_str_in(
    text: &str,
    origin: &str,
    dir: &std::path::Path,
) -> Result<Scene, SceneError> {
    load(text, origin, Some(dir))
}

fn load(text: &str, origin: &str, dir: Option<&std::path::Path>) -> Result<Scene, SceneError> {
    bounded(text, origin)?;
    let map = SourceMap::new(text);
    let ctx = Ctx { origin, map: &map, dir, inputs: Default::default() };
    if crate::space::declared_dimension(text) == 3 {
        return Err(ctx.err(
            "grid.dimension",
            Some("3".into()),
            "a 3D scene, given to a reader of 2D scenes",
            "a 2D scene here; 3D scenes are read by `load_space_str` and run by `mpm run`",
            "run it with `mpm run` (the Python package and the studies read 2D scenes only, \
             for now)",
        ));
    }
    let file: SceneFile = toml::from_str(text).map_err(|e| serde_error(&ctx, &e))?;
    let r = resolve(&ctx, &file)?;
    Ok(Scene {
        origin: origin.to_string(),
        text: text.to_string(),
        file,
        r,
        dir: dir.map(std::path::Path::to_path_buf),
        inputs: crate::inputs::fingerprints(ctx.inputs.take()),
        files_dir: crate::inputs::absolute_dir(origin, dir),
    })
}

impl Scene {
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
        load(&text, &format!("{} (modified)", self.origin), self.files_base())
    }
}

/// Maps a TOML syntax or serde error to a located [`SceneError`].
fn serde_error(ctx: &Ctx<'_>, e: &toml::de::Error) -> SceneError {
    let span = e.span();
    let path = span.as_ref().map(|s| ctx.map.path_at(s.start)).unwrap_or_default();
    describe(ctx, e.message(), path, span)
}

/// A serde `message` about the field at `path` (the span of the text it came from, when
/// known) as a located [`SceneError`] with the admissible values and a fix.
fn describe(
    ctx: &Ctx<'_>,
    message: &str,
    mut path: String,
    span: Option<std::ops::Range<usize>>,
) -> SceneError {
    let message = message.trim().to_string();
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
        None => match ctx.locate(&path) {
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

/// Checks the sections in the order the module docs give and derives what the run needs.
fn resolve(ctx: &Ctx<'_>, f: &SceneFile) -> Result<Resolved, SceneError> {
    if let Some(d) = f.grid.dimension.filter(|&d| d != 2) {
        return Err(ctx.err(
            "grid.dimension",
            Some(d.to_string()),
            "a scene is 2D (the default) or 3D",
            "2 or 3",
            "remove `dimension` for a 2D scene, or write `dimension = 3`",
        ));
    }
    let settings = solver::settings(ctx, &f.solver, 2)?;
    let (grid, ground, cell_x) = grid::build(ctx, &f.grid)?;
    let shape_function = grid::shape_function(ctx, &f.solver, settings.preset, &grid)?;
    let built = materials::build(ctx, &f.materials)?;
    bodies::count(ctx, f)?;
    let bodies: Vec<&str> = f.bodies.iter().map(|b| b.material.as_str()).collect();
    let (materials, used) = materials::select(ctx, &f.materials, &bodies, &built)?;
    let (seeds, spacing, gimp_ppc) =
        bodies::seeds(ctx, f, &grid, cell_x, shape_function, &materials, &used)?;
    let (boundaries, outflow) = boundaries::build(ctx, f, &grid)?;
    let periodic = boundaries::periodic(ctx, f, &grid)?;
    let walls = boundaries::walls(ctx, f, &grid, &seeds)?;
    let side_walls = boundaries::side_walls(ctx, f)?;
    let config = solver::config(
        ctx,
        &f.solver,
        &settings,
        (boundaries, periodic, walls, side_walls, outflow),
        &materials,
    )?;
    let initial_dt =
        solver::first_dt(ctx, &f.solver, &config, &grid, &materials, &seeds, settings.max_steps)?;
    let end_time = f.solver.end_time;
    let around = initial_state::Around {
        gravity_ramp: config.gravity_ramp,
        periodic: config.periodic.is_some(),
        initial_dt,
        max_steps: settings.max_steps,
    };
    let initial_state = initial_state::build(ctx, f.initial_state.as_ref(), &around)?;
    let output = output::build(
        ctx,
        &f.output,
        end_time,
        &seeds,
        (&grid, &ground),
        &config.boundaries,
        config.gravity,
    )?;
    output::no_probes_beside_outflow(ctx, config.outflow.any(), &output.probes)?;
    let warnings = plausible::warnings(ctx, f, config.gravity.length())?;
    Ok(Resolved {
        grid,
        shape_function,
        gimp_ppc,
        materials,
        material_names: used.iter().map(|n| n.to_string()).collect(),
        warnings,
        seeds,
        config,
        end_time,
        output,
        ground,
        spacing,
        initial_dt,
        alarm: settings.alarm,
        max_steps: settings.max_steps,
        stop_at_rest: settings.stop_at_rest,
        initial_state,
        section: match &f.grid.profile {
            Some(crate::file::PolylineSpec::File(crate::file::PolylineFile {
                dem: Some(dem),
                from: Some(from),
                to: Some(to),
                ..
            })) => Some(crate::scene::SectionLine { dem: dem.clone(), from: *from, to: *to }),
            _ => None,
        },
    })
}
