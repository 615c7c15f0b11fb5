//! The `mpm` binary: exit codes and what it prints.

use std::path::Path;
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
        mpm_run::embedded_scene("free_fall").unwrap().replace("courant = 0.1", "courant = 2.0");
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
    assert_eq!(std::fs::read_to_string(&path).unwrap(), mpm_run::embedded_scene("flume").unwrap());
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

/// The element tests drive a scene's materials of any kind: the elastic slab of the two-model
/// example answers plane-strain uniaxial compression with σ_yy = E/(1 − ν²) ε_yy
/// (5e7 / 0.96 × −1e-3 = −52 083.333 Pa); a name no body uses is refused, naming those used.
#[test]
fn element_test_drives_the_materials_of_a_scene() {
    let dir = temp_dir("element_scene");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/examples/sand_on_slab.toml");
    let scene = scene.to_str().unwrap();
    let out = dir.to_str().unwrap();
    let (code, text, err) = mpm(&["element-test", "uniaxial", "--scene", scene, "--out", out]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("slab (elastic): first yield σ_yy none; final σ_yy -52083.333"),
        "{text}"
    );
    assert!(text.contains("sand (Drucker-Prager)"), "{text}");
    let args = ["element-test", "uniaxial", "--scene", scene, "--material", "rock", "--out", out];
    let (code, _, err) = mpm(&args);
    assert_eq!(code, 2);
    assert!(err.contains("--material rock") && err.contains("sand, slab"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A Mohr–Coulomb sand of a scene in the triaxial test: its compression and extension peaks are
/// the closed forms k σc − c̄ = −317.321 Pa and (σc + c̄)/k = −27.560 Pa (φ 30°, c 5 Pa,
/// σc = −100 Pa), printed to the millipascal.
#[test]
fn element_test_triaxial_peaks_of_a_mohr_coulomb_scene() {
    let dir = temp_dir("element_triaxial");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("mc.toml");
    std::fs::write(
        &scene,
        "[grid]\nkind = \"regular\"\norigin = [0.0, 0.0]\ncell = [0.1, 0.1]\ncells = [10, 10]\n\
         [materials.sand]\nkind = \"mohr_coulomb\"\nyoung = 2.0e6\npoisson = 0.3\n\
         density = 1600.0\ncohesion = 5.0\nfriction_angle_deg = 30.0\n\
         [[bodies]]\nmaterial = \"sand\"\nshape = \"rectangle\"\nmin = [0.0, 0.0]\n\
         max = [0.5, 0.5]\n[boundaries]\nground = \"rough\"\n[solver]\nend_time = 0.1\n",
    )
    .unwrap();
    let (scene, out) = (scene.to_str().unwrap(), dir.join("out"));
    let out = out.to_str().unwrap();
    // (a negative strain in scientific notation, as a user writes it: clap's negative-number
    // detection refused `-2e-3` before)
    for (strain, peak) in [("-2e-3", "-317.321"), ("2e-3", "-27.560")] {
        let args = [
            "element-test",
            "triaxial",
            "--scene",
            scene,
            "--confining-stress",
            "-100",
            "--strain",
            strain,
            "--steps",
            "1000",
            "--out",
            out,
            "--force",
        ];
        let (code, text, err) = mpm(&args);
        assert_eq!(code, 0, "{err}");
        assert!(text.contains(&format!("final σ_yy {peak} Pa")), "{text}");
    }
    assert!(dir.join("out/triaxial.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// creates `dir` and writes `dir/plane.asc`: z = 50 − 0.5 x, 60 × 10 cells of 1 m, north-west
/// corner (0, 10), cell centres at x = 0.5, 1.5, …
fn plane_dem(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let mut asc = String::from("ncols 60\nnrows 10\nxllcorner 0\nyllcorner 0\ncellsize 1\n");
    for _ in 0..10 {
        let row: Vec<String> =
            (0..60).map(|c| format!("{}", 50.0 - 0.5 * (c as f64 + 0.5))).collect();
        asc.push_str(&row.join(" "));
        asc.push('\n');
    }
    std::fs::write(dir.join("plane.asc"), asc).unwrap();
}

/// A plane DEM: `mpm section` cuts it, a scene takes the same section as its terrain, cuts a
/// rupture surface into it and fills the mass between the two (its top read back from the CSV
/// that `mpm section` wrote).
#[test]
fn a_dem_section_becomes_a_scene_with_a_release_mass_between_two_surfaces() {
    let dir = temp_dir("dem");
    plane_dem(&dir);
    let csv = dir.join("top.csv");
    let (code, out, err) = mpm(&[
        "section",
        dir.join("plane.asc").to_str().unwrap(),
        "--from",
        "0.5,5",
        "--to",
        "59.5,5",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("60 stations over 59.000 m"), "{out}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("station,x,y,z\n0,0.5,5,49.75\n"), "{text}");
    // the same section, the rupture surface 2 m deep at its middle (station 15)
    let scene = r#"
title = "plane DEM"
[grid]
kind = "terrain"
cell_width = 1.0
row_height = 1.0
rows = 10
profile = { dem = "plane.asc", from = [0.5, 5.0], to = [59.5, 5.0] }
rupture_surface = [[10.0, 44.75], [15.0, 40.25], [20.0, 39.75]]
[materials.sand]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "sand"
shape = "between_profiles"
top = { csv = "top.csv" }
bottom = [[10.0, 44.75], [15.0, 40.25], [20.0, 39.75]]
[solver]
end_time = 0.01
"#;
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let (code, out, err) = mpm(&["check", dir.join("scene.toml").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // the mass: the triangle between the plane and the rupture surface, 10 m × 2 m / 2 = 10 m²,
    // at 0.25 m² a particle (2 × 2 per 1 m cell); the lattice gains or loses at most a
    // half-spacing band along the 22.6 m perimeter.
    let n: f64 = out
        .lines()
        .find_map(|l| l.trim().strip_prefix("particles:"))
        .and_then(|v| v.trim().parse().ok())
        .unwrap();
    assert!((n * 0.25 - 10.0).abs() <= 22.6 * 0.25, "{n} particles: {out}");

    // without the rupture surface cut into the ground the mass is below it: refused, with the fix
    std::fs::write(
        dir.join("scene.toml"),
        scene.replace("rupture_surface = [[10.0, 44.75], [15.0, 40.25], [20.0, 39.75]]\n", ""),
    )
    .unwrap();
    let (code, _, err) = mpm(&["check", dir.join("scene.toml").to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("below the ground") && err.contains("rupture_surface"), "{err}");

    // a section whose last interval is shorter than half a column (59.2 m at 1 m) is
    // resampled on the columns, not refused for two points snapping onto one boundary
    std::fs::write(dir.join("scene.toml"), scene.replace("59.5, 5.0]", "59.7, 5.0]")).unwrap();
    let (code, _, err) = mpm(&["check", dir.join("scene.toml").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");

    // a line leaving the raster names the file and the extent
    std::fs::write(dir.join("scene.toml"), scene.replace("59.5, 5.0]", "70.0, 5.0]")).unwrap();
    let (code, _, err) = mpm(&["check", dir.join("scene.toml").to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("plane.asc") && err.contains("outside the raster"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A standard output whose reader has gone (`mpm section … | head`) ends the command quietly,
/// with its own exit code: `println!` panicked there (exit 101). The section's 59 001 stations
/// (1.5 MB of CSV) overfill the 64 KiB pipe, so the writes must meet the closed end.
#[test]
fn a_closed_standard_output_ends_the_command_quietly() {
    let dir = temp_dir("pipe");
    plane_dem(&dir);
    let dem = dir.join("plane.asc");
    let args = [
        "section",
        dem.to_str().unwrap(),
        "--from",
        "0.5,5",
        "--to",
        "59.5,5",
        "--spacing",
        "0.001",
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_mpm"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before reading anything
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
