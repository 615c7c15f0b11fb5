//! The `mpm` binary: exit codes and what it prints.

use std::process::Command;

use crate::temp_dir;

fn mpm(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mpm")).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn check_prints_the_plan() {
    let (code, out, _) = mpm(&["check", "flume"]);
    assert_eq!(code, 0);
    assert!(out.contains("particles:        336"), "{out}");
    assert!(out.contains("initial Δt") && out.contains("memory"), "{out}");
}

#[test]
fn a_bad_scene_exits_non_zero_with_its_location() {
    let dir = temp_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    let text =
        mpm_cli::embedded_scene("free_fall").unwrap().replace("courant = 0.1", "courant = 2.0");
    std::fs::write(&file, text).unwrap();
    let (code, _, err) =
        mpm(&["run", file.to_str().unwrap(), "--out", dir.join("o").to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.toml:") && err.contains("`solver.courant` = 2"), "{err}");
    assert!(!dir.join("o").exists(), "nothing may be written for a refused scene");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn scenes_lists_and_writes() {
    let (code, out, _) = mpm(&["scenes"]);
    assert_eq!(code, 0);
    for name in ["flume", "free_fall", "sliding_horizontal", "sliding_inclined"] {
        assert!(out.contains(name), "{out}");
    }
    let dir = temp_dir("write");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("f.toml");
    let (code, _, _) = mpm(&["scenes", "--write", "flume", path.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), mpm_cli::embedded_scene("flume").unwrap());
    // not overwritten without --force
    let (code, _, _) = mpm(&["scenes", "--write", "flume", path.to_str().unwrap()]);
    assert_ne!(code, 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn element_test_writes_csv_and_plot_with_the_papers_numbers() {
    let dir = temp_dir("element");
    let (code, out, err) = mpm(&["element-test", "uniaxial", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // SPEC §4: first yield −28.50 Pa, steady state −36.15 Pa with ψ = 0.
    assert!(out.contains("final σ_yy -36.1"), "{out}");
    assert!(dir.join("element_test.csv").exists() && dir.join("uniaxial.png").exists());
    let (code, _, err) = mpm(&[
        "element-test",
        "simple-shear",
        "--dilatancy",
        "0,20,40",
        "--mixing",
        "1",
        "--out",
        dir.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join("simple_shear_volume.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
