//! `mpm resume`: a run continued from its folder's checkpoint, routed by the scene's dimension
//! to the 2D ([`crate::run`]) or the 3D ([`crate::space`]) driver.

use std::path::Path;

use mpm_output::checkpoint::{self, CheckpointFile};
use mpm_output::dir::DirLock;
use mpm_output::{OutputError, atomic};
use mpm_scene::dispatch;
use mpm_scene::summary::RunSummary;
use mpm_scene::{Scene, load_scene_str};

use crate::common::{files_dir, fits, with_pool};
use crate::error::RunError;
use crate::options::RunOptions;
use crate::run::RunJob;

/// The summary of a run whose checkpoint is its last state and which ended (not interrupted):
/// resuming it would only rewrite its files with a session of no steps.
fn finished(dir: &Path, c: &checkpoint::CheckpointFile) -> Option<RunSummary> {
    let s: RunSummary = serde_json::from_str(&summary_text(dir)?).ok()?;
    let (time, steps, _) = c.state.clock();
    let last = s.steps == steps && s.simulated_time == time;
    (last && s.status != mpm_scene::RunStatus::Interrupted).then_some(s)
}

/// the text of the folder's `summary.json`, if it is a regular file that reads.
fn summary_text(dir: &Path) -> Option<String> {
    use std::io::Read;
    let mut text = String::new();
    let path = dir.join("summary.json");
    // (a FIFO would block the open for ever)
    if !std::fs::metadata(&path).is_ok_and(|m| m.file_type().is_file()) {
        return None;
    }
    std::fs::File::open(path).and_then(|f| f.take(SUMMARY_LIMIT).read_to_string(&mut text)).ok()?;
    Some(text)
}

/// the `scene_hash` of the folder's `summary.json`, if it has one that reads.
fn summary_scene_hash(dir: &Path) -> Option<String> {
    let v: serde_json::Value = serde_json::from_str(&summary_text(dir)?).ok()?;
    v.get("scene_hash")?.as_str().map(str::to_string)
}

/// The most of `summary.json` [`finished`] reads (its size is a few kilobytes).
const SUMMARY_LIMIT: u64 = 16 << 20;

/// Continues the run in `dir` from its last checkpoint to the scene's end time, writing into
/// the same directory (`opts.out_dir` and `opts.force` are ignored).
/// A run that has already ended and whose checkpoint is its last state is not run again: its
/// summary is returned and nothing is written. (From an earlier checkpoint, the run is run again
/// from there, to the same bits.)
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<RunSummary, RunError> {
    crate::options::available_threads(opts.threads)?;
    let path = dir.join(checkpoint::FILE_NAME);
    if !path.exists() {
        return Err(RunError::Output(OutputError::Checkpoint {
            path,
            reason: "no checkpoint in this directory (a run writes one on Ctrl-C and every \
                     output.checkpoint_interval)"
                .into(),
        }));
    }
    let _lock = DirLock::acquire(dir)?;
    let c = checkpoint::read(&path)?;
    // the folder's own run, as its summary names it (R3-18: with scene.toml deleted, a 2D
    // checkpoint copied into a 3D run's folder continued there, beside the 3D run's maps)
    if let Some(theirs) = summary_scene_hash(dir) {
        let ours = format!("{:016x}", mpm_scene::fnv1a(c.scene_text.as_bytes()));
        if theirs != ours {
            return Err(RunError::Output(OutputError::Checkpoint {
                path,
                reason: format!(
                    "its scene ({}, hash {ours}) is not the run this folder's summary.json \
                     describes (scene hash {theirs}): a checkpoint copied from another run. \
                     Resume the folder the checkpoint came from, or run the scene again",
                    c.origin
                ),
            }));
        }
    }
    // the folder's own scene: a checkpoint copied in from another run would continue that run
    // here and leave a folder of two runs' files
    let written = dir.join("scene.toml");
    // (line endings and trailing blanks an editor or git may change do not count)
    let same = |a: &str, b: &str| a.lines().map(str::trim_end).eq(b.lines().map(str::trim_end));
    match std::fs::metadata(&written).map(|m| m.file_type().is_file()) {
        Ok(true) => {
            let text = std::fs::read_to_string(&written)
                .map_err(|source| OutputError::Io { path: written.clone(), source })?;
            if !same(&text, &c.scene_text) {
                return Err(RunError::Output(OutputError::Checkpoint {
                    path,
                    reason: format!(
                        "its scene ({}) is not this folder's {}: a checkpoint copied from \
                         another run, or an edited scene.toml. Resume the folder the checkpoint \
                         came from, run the scene again, or, if only scene.toml was edited, \
                         delete it (resume writes it again from the checkpoint)",
                        c.origin,
                        written.display()
                    ),
                }));
            }
        }
        Ok(false) => {
            return Err(RunError::Output(OutputError::Checkpoint {
                path,
                reason: format!("{} is not a regular file", written.display()),
            }));
        }
        // a deleted scene.toml is written again from the checkpoint
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            atomic::write(&written, c.scene_text.as_bytes())?;
        }
        Err(source) => return Err(RunError::Output(OutputError::Io { path: written, source })),
    }
    if let Some(done) = finished(dir, &c) {
        opts.progress.note(&format!(
            "{}: the run has already ended ({:?} at t = {} s after {} steps); nothing to resume, \
             its files are left as they are (run the scene again with --force, or force=True in Python, to redo it)",
            dir.display(),
            done.status,
            done.simulated_time,
            done.steps
        ));
        return Ok(done);
    }
    mpm_output::dir::layout(dir)?;
    if mpm_scene::declared_dimension(&c.scene_text) == 3 {
        return crate::space::resume_space(dir, c, opts);
    }
    if c.state.dimension() != 2 {
        return Err(RunError::Output(OutputError::Checkpoint {
            path,
            reason: "its scene is a 2D scene but its state is a 3D run's".into(),
        }));
    }
    // files the scene names (DEMs, CSV polylines) are relative to the scene file's directory
    let scene = match files_dir(&c) {
        Some(d) => mpm_scene::load_scene_str_in(&c.scene_text, &c.origin, &d)?,
        None => load_scene_str(&c.scene_text, &c.origin)?,
    };
    fits_its_scene(&c, &scene)
        .map_err(|reason| OutputError::Checkpoint { path: path.clone(), reason })?;
    if let Some(reason) = mpm_scene::inputs::changed(&c.inputs, scene.inputs()) {
        return Err(RunError::Output(OutputError::Checkpoint { path, reason }));
    }
    with_pool(opts, scene.resolved().seeds.len(), |threads| {
        dispatch::dispatch(
            &scene,
            RunJob {
                opts,
                resume: Some((c.state, c.history)),
                threads,
                out_dir: Some(dir.to_path_buf()),
            },
        )?
    })
}

/// why a decoded checkpoint cannot continue its scene (its clock, counts and history must be
/// those of a run of it), if it cannot.
fn fits_its_scene(c: &CheckpointFile, scene: &Scene) -> Result<(), String> {
    let r = scene.resolved();
    fits(c, r.end_time, r.max_steps, r.seeds.len(), r.output.probes.len())
}
