//! The run driver's own guarantees, through its public API: a checkpoint that cannot belong to
//! its scene is refused, and a run advanced from outside (`Simulation`) is the run itself.

use mpm_output::OutputError;
use mpm_output::checkpoint::{self, CheckpointFile};
use mpm_run::{Limit, RunError, RunOptions, Simulation, load_scene_str, resume, run_scene};
use mpm_scene::SavedState;

/// A checkpoint whose checksum holds but whose content cannot belong to its scene (a time of
/// −1.9e305 s made `resume` run forever; another particle count) is refused before the solver
/// takes it.
#[test]
fn a_checksummed_checkpoint_that_does_not_fit_its_scene_is_refused() {
    let text =
        mpm_run::embedded_scene("free_fall").unwrap().replace("end_time = 1.0", "end_time = 0.02");
    let scene = load_scene_str(&text, "free_fall").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-fits-{}", std::process::id()));
    let opts =
        RunOptions { out_dir: Some(dir.clone()), stop_after: Some(0.01), ..Default::default() };
    run_scene(&scene, &opts).unwrap();
    let path = dir.join(checkpoint::FILE_NAME);
    let good = checkpoint::read(&path).unwrap();
    type Edit = fn(&mut CheckpointFile);
    let edits: [(&str, Edit); 3] = [
        ("time -1.9e305", |c| {
            if let SavedState::Elastic(s) = &mut c.state {
                s.time = -1.9e305;
            }
        }),
        ("particles, but its scene generates", |c| {
            if let SavedState::Elastic(s) = &mut c.state {
                s.particles.position.pop();
            }
        }),
        ("energy rows after", |c| {
            let row = c.history.energy[0];
            c.history.energy.extend(std::iter::repeat_n(row, 10_000));
        }),
    ];
    for (expect, edit) in edits {
        let mut bad = good.clone();
        edit(&mut bad);
        checkpoint::write(&path, &bad).unwrap();
        let e =
            resume(&dir, &RunOptions { threads: opts.threads, ..Default::default() }).unwrap_err();
        assert!(matches!(e, RunError::Output(OutputError::Checkpoint { .. })), "{expect}: {e}");
        assert!(e.to_string().contains(expect), "{expect}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run advanced from outside in pieces (steps, then to its end time) ends with the bits of the same
/// run in one go: the same state hash, step count and energy ledger; its checkpoint resumes to
/// them too.
#[test]
fn a_simulation_advanced_in_pieces_is_the_run_itself() {
    let text = mpm_run::embedded_scene("sliding_inclined")
        .unwrap()
        .replace("end_time = 2.0", "end_time = 0.05");
    let scene = load_scene_str(&text, "sliding_inclined").unwrap();
    assert_eq!(scene.end_time(), 0.05, "the scene's end time was shortened");
    let whole = run_scene(&scene, &RunOptions::default()).unwrap();

    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    let a = sim.advance(Limit::Steps(7), &mut || false).unwrap();
    assert_eq!((a.steps, a.stopped), (7, None));
    // (an advance to a time shortens its last step to land on it: steps keep the run's steps)
    sim.advance(Limit::Steps(30), &mut || false).unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-simulation-{}", std::process::id()));
    sim.checkpoint(&dir).unwrap();
    let a = sim.advance(Limit::Time(0.05), &mut || false).unwrap();
    assert_eq!(a.time, 0.05);
    let stepped = sim.summary().unwrap();
    assert_eq!(stepped.state_hash, whole.state_hash);
    assert_eq!(stepped.steps, whole.steps);
    assert_eq!(stepped.energy, whole.energy);
    let f = sim.fields().unwrap();
    assert_eq!(f.position.len(), scene.particle_count());

    let resumed = resume(&dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, whole.state_hash);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A poll that asks to stop ends an advance after its current step, as Ctrl-C ends a run.
#[test]
fn a_poll_that_asks_to_stop_interrupts_after_a_step() {
    let scene = load_scene_str(mpm_run::embedded_scene("flume").unwrap(), "flume").unwrap();
    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    let a = sim.advance(Limit::Time(scene.end_time()), &mut || true).unwrap();
    assert_eq!(a.stopped, Some(mpm_run::RunStatus::Interrupted));
    assert!(a.steps >= 1 && a.time < scene.end_time(), "{a:?}");
    // and it goes on from there
    let b = sim.advance(Limit::Steps(3), &mut || false).unwrap();
    assert_eq!(b.steps, a.steps + 3);
}
