//! The run driver as a library: scene files in, ParaView/CSV/PNG files out. The `mpm` command,
//! `cargo xtask` and the tests drive runs through it; any other front end (bindings, a GUI)
//! can too, with its own [`Progress`].
//!
//! - [`load_scene_str`] parses and validates a TOML scene ([`scene`] is the data model,
//!   `docs/scene-format.md` its reference). Every refusal is a [`SceneError`] naming the file,
//!   line and column, field path, value, admissible range and fix.
//! - [`embedded_scene`] returns the paper's scenes compiled into the binary (the default is the
//!   dry-sand flume of §7).
//! - [`run_scene`] runs a scene with [`RunOptions`] and returns a [`RunSummary`] (also written
//!   as `summary.json`); [`resume()`] continues a run from its checkpoint bit-identically;
//!   [`check_scene`] validates fully without stepping.
//! - [`Simulation`] is a run advanced by its caller, step by step or to a time, with the
//!   particles' fields, the energy ledger and checkpoints between calls (for bindings and
//!   coupling).
//! - [`run_space_scene`] and [`check_space_scene`] do the same for 3D scenes (`[grid]
//!   dimension = 3`, read by [`load_space_str`] or [`load_any_scene_file`]) with the 3D build
//!   of the solver.
//! - [`run_element_test`] runs the constitutive element tests.
//! - [`Progress`] receives a run's progress, warnings and reports; nothing is printed without
//!   one.
//!
//! The solver is generic over the constitutive model and the shape functions; `mpm_scene::dispatch`
//! picks them once per scene, so no per-particle dynamic dispatch happens.
//!
//! Output directory layout of a run:
//! ```text
//! scene.toml            the scene text that ran
//! summary.json          RunSummary
//! particles.pvd         ParaView collection of frames/particles_NNNNNN.vtp
//! energy.csv            energy ledger over time
//! probes.csv            probe particles (when the scene declares probes)
//! runout.csv            front, tail, max thickness, centre-of-mass travel over time
//! walls.csv             per grid side and declared wall: normal, shear and force vector on it
//! envelope.csv          per ground station: largest thickness, speeds, pressure, arrival
//! deposit.csv           per ground station: the final deposit's thickness (with envelope)
//! plots/*.png           energy, probes (with the analytic curve), runout, deposit, envelope
//! checkpoint.bin        written every output.checkpoint_interval, on Ctrl-C and SIGTERM
//! .mpm.lock             while a run writes here: the process that does
//! ```
//!
//! ```
//! use mpm_run::{RunOptions, embedded_scene, load_scene_str, run_scene};
//!
//! let text = embedded_scene("free_fall").unwrap();
//! let scene = load_scene_str(text, "embedded:free_fall").unwrap();
//! let short = scene.modified(|f| f.solver.end_time = 0.01).unwrap();
//! let summary = run_scene(&short, &RunOptions::default()).unwrap();
//! assert!(summary.steps > 0);
//! ```

// A SceneError carries everything a user needs to fix a scene (file, line, column, path, value,
// range, fix); it is returned once, before any step, so its size costs nothing.
#![allow(clippy::result_large_err)]

mod check;
mod common;
mod driver;
mod element;
mod error;
mod loads;
mod options;
mod progress;
mod resume;
mod run;
mod section;
mod simulation;
mod space;

pub use progress::{Progress, ProgressSink};

pub use check::{Checked, check};
pub use common::CheckReport;
pub use element::{ElementCaseResult, ElementTest, ElementTestOptions, run_element_test};
pub use error::RunError;
pub use mpm_output::OutputError;
pub use mpm_output::checkpoint::FILE_NAME as CHECKPOINT_FILE;
pub use mpm_scene::materials::AnyModel;
pub use mpm_scene::{DtStats, RunStatus, RunSummary, RunoutMetrics};
pub use options::{MAX_THREADS, available_threads};
pub use resume::resume;
pub use run::{RunOptions, check_scene, run_scene};
pub use section::{Section, section};
pub use simulation::{Advance, Limit, POLL, ParticleFields, Simulation, SpaceFields};
pub use space::{check_space_scene, run_space_scene};
// The scene library, re-exported so that a front end needs one import path.
pub use mpm_scene::limits::{MAX_PARTICLES, MAX_PARTICLES_PER_CELL};
pub use mpm_scene::{
    AnyScene, DEFAULT_ENERGY_ALARM, DEFAULT_SCENE, SCENES, Scene, SceneError, SpaceScene,
    declared_dimension, embedded_scene, load_any_scene_file, load_scene_file, load_scene_str,
    load_space_str, nearest_scene, title_of, unknown_scene_message,
};
pub use mpm_scene::{file as scene, limits, presets};
