//! The `mpm` front end as a library: scene files in, ParaView/CSV/PNG files out.
//!
//! - [`load_scene_str`] parses and validates a TOML scene ([`scene`] is the data model,
//!   `docs/scene-format.md` its reference). Every refusal is a [`SceneError`] naming the file,
//!   line and column, field path, value, admissible range and fix.
//! - [`embedded_scene`] returns the paper's scenes compiled into the binary (the default is the
//!   dry-sand flume of §7).
//! - [`run_scene`] runs a scene with [`RunOptions`] and returns a [`RunSummary`] (also written
//!   as `summary.json`); [`resume`] continues a run from its checkpoint bit-identically;
//!   [`check_scene`] validates fully without stepping.
//! - [`run_element_test`] runs the constitutive element tests.
//!
//! The solver is generic over the constitutive model and the shape functions; this crate picks
//! them once per scene (`model.rs`), so no per-particle dynamic dispatch happens.
//!
//! Output directory layout of a run:
//! ```text
//! scene.toml            the scene text that ran
//! summary.json          RunSummary
//! particles.pvd         ParaView collection of frames/particles_NNNNNN.vtp
//! energy.csv            energy ledger over time
//! probes.csv            probe particles (when the scene declares probes)
//! runout.csv            front, tail, max thickness, centre-of-mass travel over time
//! plots/*.png           energy, probes (with the analytic curve), runout, deposit
//! checkpoint.bin        written every output.checkpoint_interval and on Ctrl-C
//! ```
//!
//! ```
//! use mpm_cli::{RunOptions, embedded_scene, load_scene_str, run_scene};
//!
//! let text = embedded_scene("free_fall").unwrap();
//! let scene = load_scene_str(text, "embedded:free_fall").unwrap();
//! let short = scene.modified(|f| f.solver.end_time = 0.01).unwrap();
//! let summary = run_scene(&short, &RunOptions { quiet: true, ..Default::default() }).unwrap();
//! assert!(summary.steps > 0);
//! ```

// A SceneError carries everything a user needs to fix a scene (file, line, column, path, value,
// range, fix); it is returned once, before any step, so its size costs nothing.
#![allow(clippy::result_large_err)]

mod checkpoint;
mod element;
mod error;
pub mod limits;
mod model;
pub mod output;
pub mod presets;
mod progress;
mod run;
pub mod scene;
mod scenes;
mod source;
mod summary;
mod validate;

pub use checkpoint::FILE_NAME as CHECKPOINT_FILE;
pub use element::{ElementCaseResult, ElementTest, ElementTestOptions, run_element_test};
pub use error::{RunError, SceneError};
pub use run::{CheckReport, RunOptions, check_scene, resume, run_scene};
pub use scenes::{DEFAULT_SCENE, SCENES, embedded_scene, title_of};
pub use summary::{DtStats, RunStatus, RunSummary, RunoutMetrics};
pub use validate::{
    DEFAULT_ENERGY_ALARM, MAX_PARTICLES, MAX_PARTICLES_PER_CELL, Scene, load_scene_str,
};

/// Reads and validates the scene file at `path` (an I/O error is reported as a [`SceneError`]
/// for the file). Files above [`limits::MAX_SCENE_BYTES`] and files that are not UTF-8 text are
/// refused before parsing; at most that many bytes are read, whatever the file is.
pub fn load_scene_file(path: &std::path::Path) -> Result<Scene, SceneError> {
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
    load_scene_str(&text, &origin)
}
