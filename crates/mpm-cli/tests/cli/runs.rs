//! Short runs of the embedded scenes: the files they write, resume bit-identity, refusing an
//! existing output directory, and what an instability leaves behind.

use std::path::Path;

use mpm_cli::{
    CHECKPOINT_FILE, RunError, RunOptions, RunStatus, Scene, embedded_scene, load_scene_str,
    resume, run_scene,
};

use crate::temp_dir;

fn short(name: &str, end_time: f64) -> Scene {
    let scene = load_scene_str(embedded_scene(name).unwrap(), name).unwrap();
    scene
        .modified(|f| {
            f.solver.end_time = end_time;
            f.output.interval = Some(end_time / 4.0);
            f.output.checkpoint_interval = None;
        })
        .unwrap()
}

fn opts(dir: &Path) -> RunOptions {
    RunOptions { out_dir: Some(dir.to_path_buf()), quiet: true, ..Default::default() }
}

#[test]
fn short_runs_write_every_output_file() {
    for (name, end) in [
        ("flume", 0.02),
        ("free_fall", 0.02),
        ("sliding_horizontal", 0.05),
        ("sliding_inclined", 0.02),
    ] {
        let dir = temp_dir(name);
        let summary = run_scene(&short(name, end), &opts(&dir)).unwrap();
        assert_eq!(summary.status, RunStatus::Completed, "{name}");
        assert!((summary.simulated_time - end).abs() < 1e-12, "{name}");
        for file in [
            "scene.toml",
            "summary.json",
            "particles.pvd",
            "frames/particles_000000.vtp",
            "frames/particles_000004.vtp",
            "energy.csv",
            "runout.csv",
            "probes.csv",
            "plots/energy.png",
            "plots/probes.png",
            "plots/runout.png",
            "plots/deposit.png",
        ] {
            let p = dir.join(file);
            let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
            assert!(len > 0, "{name}: {file} missing or empty");
        }
        // no temporary files left behind
        for sub in ["", "frames", "plots"] {
            for e in std::fs::read_dir(dir.join(sub)).unwrap().flatten() {
                let n = e.file_name().to_string_lossy().into_owned();
                assert!(!n.starts_with('.'), "{name}: temporary file {n} left");
            }
        }
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        for key in [
            "code_version",
            "scene_hash",
            "steps",
            "dt",
            "wall_time_s",
            "particle_steps_per_s",
            "energy",
            "runout",
            "state_hash",
        ] {
            assert!(json.get(key).is_some(), "{name}: summary.json lacks {key}");
        }
        assert_eq!(json["steps"].as_u64(), Some(summary.steps));
        let pvd = std::fs::read_to_string(dir.join("particles.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 5, "{name}: {pvd}");
        let vtp = std::fs::read_to_string(dir.join("frames/particles_000004.vtp")).unwrap();
        for field in ["stress", "velocity", "displacement", "plastic_strain", "body", "density"] {
            assert!(vtp.contains(&format!("Name=\"{field}\"")), "{name}: no {field}");
        }
        let energy = std::fs::read_to_string(dir.join("energy.csv")).unwrap();
        assert!(energy.starts_with("time,step,dt,kinetic,strain,potential,plastic_dissipation"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn sliding_block_probe_follows_eq_21() {
    // 0.5 s of the horizontal slide: the block's centre against x0 + v0 t − ½ μ g t².
    let dir = temp_dir("eq21");
    run_scene(&short("sliding_horizontal", 0.5), &opts(&dir)).unwrap();
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    let last: Vec<f64> =
        csv.lines().last().unwrap().split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect();
    let (along, reference) = (last[9], last[10]);
    let expected = 10.0 * 0.5 - 0.5 * 0.3 * 9.81 * 0.25;
    assert!((reference - expected).abs() < 1e-12);
    // The coarse elastic block follows the rigid curve within 1 % (the tolerance).
    assert!((along - reference).abs() < 0.01 * reference, "{along} vs {reference}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn resume_continues_bit_identically() {
    // Drucker-Prager state, objective stress and friction all go through the checkpoint.
    let scene = short("flume", 0.06);
    let straight = run_scene(&scene, &RunOptions { quiet: true, ..Default::default() }).unwrap();

    let dir = temp_dir("resume");
    let stopped = run_scene(&scene, &RunOptions { stop_after: Some(0.025), ..opts(&dir) }).unwrap();
    assert_eq!(stopped.status, RunStatus::Interrupted);
    assert!(stopped.simulated_time < 0.06 && stopped.steps < straight.steps);
    assert!(dir.join(CHECKPOINT_FILE).exists());
    let resumed = resume(&dir, &RunOptions { quiet: true, ..Default::default() }).unwrap();
    assert_eq!(resumed.status, RunStatus::Completed);
    assert_eq!(resumed.steps, straight.steps);
    assert_eq!(resumed.simulated_time.to_bits(), straight.simulated_time.to_bits());
    assert_eq!(resumed.state_hash, straight.state_hash);
    assert_eq!(resumed.energy, straight.energy);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn periodic_checkpoints_resume_bit_identically() {
    let scene =
        short("free_fall", 0.04).modified(|f| f.output.checkpoint_interval = Some(0.015)).unwrap();
    let dir = temp_dir("periodic");
    let full = run_scene(&scene, &opts(&dir)).unwrap();
    // The last periodic checkpoint (t ≈ 0.03 s) resumes to the same end state.
    let resumed = resume(&dir, &RunOptions { quiet: true, ..Default::default() }).unwrap();
    assert_eq!(resumed.state_hash, full.state_hash);
    assert_eq!(resumed.steps, full.steps);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_existing_output_directory_is_refused_and_left_untouched() {
    let dir = temp_dir("exists");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("keep.txt"), "mine").unwrap();
    let err = run_scene(&short("free_fall", 0.01), &opts(&dir)).unwrap_err();
    assert!(matches!(err, RunError::OutputExists(_)), "{err}");
    assert!(err.to_string().contains("--force"));
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name()).collect();
    assert_eq!(names, vec![std::ffi::OsString::from("keep.txt")]);
    assert_eq!(std::fs::read_to_string(dir.join("keep.txt")).unwrap(), "mine");
    // with force it runs
    run_scene(&short("free_fall", 0.01), &RunOptions { force: true, ..opts(&dir) }).unwrap();
    assert!(dir.join("summary.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_instability_writes_what_was_reached_and_names_the_particle() {
    // No floor: the block falls out of the grid.
    let scene = short("free_fall", 0.6).modified(|f| f.boundaries.ground = None).unwrap();
    let dir = temp_dir("unstable");
    let err = run_scene(&scene, &opts(&dir)).unwrap_err();
    let RunError::Solver { message, summary } = &err else { panic!("{err}") };
    assert!(message.contains("particle") && message.contains("outside the grid"), "{message}");
    assert_eq!(summary.status, RunStatus::Failed);
    let json = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(json.contains("\"failed\"") && json.contains("outside the grid"));
    // the frame of the failing state is the last in the collection
    let pvd = std::fs::read_to_string(dir.join("particles.pvd")).unwrap();
    let frames = pvd.matches("<DataSet").count();
    assert!(dir.join(format!("frames/particles_{:06}.vtp", frames - 1)).exists());
    assert!(dir.join("energy.csv").exists() && dir.join("plots/deposit.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
