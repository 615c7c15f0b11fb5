//! Scenes for the granular MPM solver: what a run is, independent of the front end that starts
//! it (the `mpm` command, `cargo xtask`, bindings, a GUI).
//!
//! - [`file`] is the TOML scene format's data model (`docs/scene-format.md` its reference);
//!   [`load_scene_str`] and [`load_scene_file`] parse and validate a scene into a [`Scene`]:
//!   the grid, the materials, the particle seeds, the solver configuration, the first Δt and the
//!   output plan ([`Resolved`]). Every refusal is a [`SceneError`] naming the file, line and
//!   column, field path, value, admissible range and fix. Validation runs one module per section
//!   (`validate/`: solver, grid, materials, bodies, boundaries, output).
//! - [`embedded_scene`] returns the paper's scenes compiled in (the default is the dry-sand flume
//!   of §7); [`presets`] the measured speed/accuracy settings.
//! - [`envelope`]: hazard envelopes along the path (maxima of thickness, speed and impact
//!   pressure per ground station, first arrival, final deposit).
//! - [`observed`]: comparison of the deposit with an observed one (front, tail, RMS
//!   thickness error, overlap).
//! - [`summary`]: what a run reports ([`RunSummary`]) and the runout measures it is built from.
//! - [`materials`] is the registry of constitutive models a scene can name (`kind = "elastic" |
//!   "drucker_prager" | "mu_i"`), one line per model.
//! - [`dispatch`] is the one place where a scene's run-time choices (constitutive model, shape
//!   functions) become types: it builds them and calls a generic [`Job`], so that nothing below
//!   dispatches per particle.
//!
//! ```
//! use mpm_scene::{embedded_scene, load_scene_str};
//!
//! let scene = load_scene_str(embedded_scene("flume").unwrap(), "embedded:flume").unwrap();
//! assert_eq!(scene.particle_count(), 336);
//! // The first Δt follows eq 13 with the paper's Courant number 0.1.
//! assert!(scene.initial_dt() > 0.0 && scene.initial_dt() < 1e-3);
//! ```

// A SceneError carries everything a user needs to fix a scene (file, line, column, path, value,
// range, fix); it is returned once, before any step, so its size costs nothing.
#![allow(clippy::result_large_err)]

pub mod dispatch;
pub mod edges;
pub mod envelope;
mod error;
pub mod file;
mod ground;
pub mod inputs;
pub mod limits;
pub mod materials;
mod names;
pub mod observed;
pub mod plan;
pub mod presets;
mod scene;
mod scenes;
mod source;
pub mod space;
pub mod summary;
mod validate;

pub use dispatch::{Job, SavedState, SceneModel, dispatch};
pub use error::SceneError;
pub use ground::{ground_height, segment_at, surface};
pub use scene::{
    DEFAULT_ENERGY_ALARM, DEFAULT_MAX_STEPS, EnergyAlarm, GRANULAR_PIC_FRACTION,
    GRANULAR_SEPARATION_DENSITY, GridBuilt, InitialState, MaterialsBuilt, Reference, Resolved,
    ResolvedOutput, Scene, SectionLine, Seed, StopAtRest, Warning, fnv1a,
};
pub use scenes::{
    DEFAULT_SCENE, SCENES, embedded_scene, nearest_scene, title_of, unknown_scene_message,
};
pub use space::{SpaceGrid, SpaceScene, declared_dimension, dispatch_space};
pub use summary::{
    DtStats, EnergyReport, InitialStateSummary, RunStatus, RunSummary, RunoutIndicators,
    RunoutMetrics, RunoutReport,
};
pub use validate::plausible::WARNINGS;
pub use validate::{
    checkpoint_copy, load_scene_str, load_scene_str_in, load_space_str, load_space_str_in,
};

/// Reads and validates the scene file at `path` (an I/O error is reported as a [`SceneError`]
/// for the file). Files above [`limits::MAX_SCENE_BYTES`] and files that are not UTF-8 text are
/// refused before parsing; at most that many bytes are read, whatever the file is.
pub fn load_scene_file(path: &std::path::Path) -> Result<Scene, SceneError> {
    let text = read_scene_text(path)?;
    let dir = path.parent().unwrap_or(std::path::Path::new(""));
    load_scene_str_in(&text, &path.display().to_string(), dir)
}

/// A validated scene of either dimension.
#[derive(Clone, Debug)]
pub enum AnyScene {
    /// a plane-strain scene (the default).
    Plane(Box<Scene>),
    /// a 3D scene (`[grid] dimension = 3`).
    Space(Box<SpaceScene>),
}

impl AnyScene {
    /// validates a scene text, 2D or 3D as its `[grid] dimension` says; `origin` is how
    /// messages name it (files a 2D scene names are relative to the working directory).
    pub fn from_str(text: &str, origin: &str) -> Result<AnyScene, SceneError> {
        Ok(if declared_dimension(text) == 3 {
            AnyScene::Space(Box::new(load_space_str(text, origin)?))
        } else {
            AnyScene::Plane(Box::new(load_scene_str(text, origin)?))
        })
    }

    /// validates a scene text whose named files (DEMs, rasters, polylines) are relative to
    /// `dir`: a scene carried elsewhere (another process) as its text and
    /// [`AnyScene::files_dir`].
    pub fn from_str_in(
        text: &str,
        origin: &str,
        dir: &std::path::Path,
    ) -> Result<AnyScene, SceneError> {
        Ok(if declared_dimension(text) == 3 {
            AnyScene::Space(Box::new(load_space_str_in(text, origin, dir)?))
        } else {
            AnyScene::Plane(Box::new(load_scene_str_in(text, origin, dir)?))
        })
    }

    /// the folder the scene's named files were found in (`None` for a scene that names none
    /// from a file).
    pub fn files_dir(&self) -> Option<&str> {
        match self {
            AnyScene::Plane(s) => s.files_dir(),
            AnyScene::Space(s) => s.files_dir(),
        }
    }

    /// 2 or 3.
    pub fn dimension(&self) -> u8 {
        match self {
            AnyScene::Plane(_) => 2,
            AnyScene::Space(_) => 3,
        }
    }

    /// where the text came from (a path, `embedded:NAME` or the name given).
    pub fn origin(&self) -> &str {
        match self {
            AnyScene::Plane(s) => s.origin(),
            AnyScene::Space(s) => s.origin(),
        }
    }

    /// the scene's text.
    pub fn text(&self) -> &str {
        match self {
            AnyScene::Plane(s) => s.text(),
            AnyScene::Space(s) => s.text(),
        }
    }

    /// a stable hash of the scene text (FNV-1a 64, hex), as `summary.json` names it.
    pub fn hash(&self) -> String {
        format!("{:016x}", fnv1a(self.text().as_bytes()))
    }

    /// number of particles the scene generates.
    pub fn particle_count(&self) -> usize {
        match self {
            AnyScene::Plane(s) => s.particle_count(),
            AnyScene::Space(s) => s.particle_count(),
        }
    }

    /// simulated end time (s).
    pub fn end_time(&self) -> f64 {
        match self {
            AnyScene::Plane(s) => s.end_time(),
            AnyScene::Space(s) => s.end_time,
        }
    }

    /// the Δt of the first step (s).
    pub fn initial_dt(&self) -> f64 {
        match self {
            AnyScene::Plane(s) => s.initial_dt(),
            AnyScene::Space(s) => s.initial_dt,
        }
    }

    /// the materials' names, in the order particles' `material` numbers them.
    pub fn material_names(&self) -> &[String] {
        match self {
            AnyScene::Plane(s) => &s.resolved().material_names,
            AnyScene::Space(s) => &s.material_names,
        }
    }

    /// the same scene with the field at `path` set to `value`, validated again
    /// ([`Scene::with_value`]).
    pub fn with_value(&self, path: &str, value: &str) -> Result<AnyScene, SceneError> {
        Ok(match self {
            AnyScene::Plane(s) => AnyScene::Plane(Box::new(s.with_value(path, value)?)),
            AnyScene::Space(s) => AnyScene::Space(Box::new(s.with_value(path, value)?)),
        })
    }

    /// the same scene without the field at `path` (its default applies), validated again
    /// ([`Scene::without_value`]).
    pub fn without_value(&self, path: &str) -> Result<AnyScene, SceneError> {
        Ok(match self {
            AnyScene::Plane(s) => AnyScene::Plane(Box::new(s.without_value(path)?)),
            AnyScene::Space(s) => AnyScene::Space(Box::new(s.without_value(path)?)),
        })
    }

    /// the value the scene's text gives at `path` (`None` if it gives none: its default
    /// applies); refused only when `path` is not a field path.
    pub fn value_at(&self, path: &str) -> Result<Option<toml::Value>, SceneError> {
        validate::edit::value_at(self.text(), self.origin(), path)
    }
}

/// Reads and validates the scene file at `path`, 2D or 3D as its `[grid] dimension` says
/// ([`declared_dimension`]); refusals as [`load_scene_file`]'s.
pub fn load_any_scene_file(path: &std::path::Path) -> Result<AnyScene, SceneError> {
    let text = read_scene_text(path)?;
    let origin = path.display().to_string();
    let dir = path.parent().unwrap_or(std::path::Path::new(""));
    if declared_dimension(&text) == 3 {
        return Ok(AnyScene::Space(Box::new(load_space_str_in(&text, &origin, dir)?)));
    }
    Ok(AnyScene::Plane(Box::new(load_scene_str_in(&text, &origin, dir)?)))
}

/// The text of the scene file at `path`, refused (as a [`SceneError`] for the file) when it is
/// not a regular file, is larger than [`limits::MAX_SCENE_BYTES`] or is not UTF-8.
fn read_scene_text(path: &std::path::Path) -> Result<String, SceneError> {
    use std::io::Read;
    let origin = path.display().to_string();
    let refuse = |problem: String, admissible: &str, fix: &str| SceneError {
        origin: origin.clone(),
        line: None,
        column: None,
        path: String::new(),
        value: None,
        problem,
        admissible: admissible.into(),
        fix: fix.into(),
    };
    let limit = limits::MAX_SCENE_BYTES;
    if std::fs::metadata(path).is_ok_and(|m| !m.file_type().is_file()) {
        // a FIFO would block the open for ever, a device never end
        return Err(refuse(
            "not a regular file (a directory, a FIFO or a device)".into(),
            "a TOML scene file",
            "give the path of the scene file",
        ));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path).and_then(|f| f.take(limit + 1).read_to_end(&mut bytes)).map_err(
        |e| {
            refuse(
                format!("cannot read the scene file: {e}"),
                "",
                "check the path (`mpm scenes` lists the embedded scenes)",
            )
        },
    )?;
    if bytes.len() as u64 > limit {
        return Err(refuse(
            format!("the scene file is larger than {} MiB", limit >> 20),
            &format!("a TOML scene of at most {limit} bytes"),
            "check that this is the scene file; long outlines belong in fewer points",
        ));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        refuse(
            format!(
                "not a text file: byte {} is not UTF-8 (a scene is TOML text)",
                e.utf8_error().valid_up_to()
            ),
            "a UTF-8 TOML file",
            "pass the scene's .toml file (`mpm scenes --write flume` writes an example)",
        )
    })?;
    Ok(text)
}
