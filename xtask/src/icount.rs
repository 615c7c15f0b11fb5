//! `cargo xtask icount [--bless]`: the instructions a few fixed small runs execute, counted by
//! valgrind's callgrind, against the committed baseline `benches/icount.toml`.
//!
//! Wall time on a shared 2-core machine moves by 10–20 % from one run to the next; an
//! instruction count does not move at all (the same binary, scene and environment give the same
//! total whatever else the machine does). So CI guards the step's cost with counts: a run that
//! executes more than [`TOLERANCE`] more instructions than its baseline fails the command, and
//! so does a run the baseline does not know (a renamed run, a missing profile: no silent pass). A
//! count that fell by more than that is reported, so that the baseline can be tightened.
//!
//! The runs: the side-by-side block (a sand square collapsing on the floor of a box) in each 2D
//! scheme family (USL/APIC/B-spline, MUSL/FLIP/bilinear, USAVG/FLIP/bilinear), the paper's flume
//! (the embedded default, its first 0.1 s, without its plots: the step's cost, not the PNG
//! encoder's), and a sand cube in 3D (MUSL/FLIP/trilinear and
//! USL/APIC/B-spline). Each runs `mpm run SCENE --threads 1` (one thread: the count of a thread
//! pool's idle spinning is not repeatable), in an environment of its own, so that nothing of the
//! caller's changes the count.
//!
//! The counts are those of the binary beside this one (`target/<profile>/mpm`), and a baseline
//! is kept per profile: CI measures its test build (`debug`: the workspace's crates at opt-level
//! 1, their dependencies at 3), which it has built anyway; `cargo xtask icount` measures the
//! release build (`[release]`). `--bless` rewrites the profile's table of the baseline with the
//! counts just measured: commit it with a message that says why the counts moved. CI's table is
//! blessed with CI's build: `cargo build --workspace --bins --tests` in `.ci/run`'s environment,
//! then `target/debug/xtask icount --bless`.
//!
//! The counts also depend on how the binary was built and on the C library's routines
//! valgrind's CPU selects: clippy's driver as `RUSTC_WORKSPACE_WRAPPER` (as CI builds) leaves
//! the MIR unoptimised, 8–13 % more instructions than rustc's build of the same source. The
//! baseline records, per profile, the compiler, wrapper and `RUSTFLAGS` it was counted with, and
//! a failure says when this build's differ (then re-bless if the build, not the code, moved).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::table::{Status, Table};

/// The growth over the baseline that fails the guard (2 %): far above the counts' own
/// variation (none between two runs of one binary; a few hundred instructions in 10⁸ from the
/// length of the output path), well below what one extra pass over the particles costs (5–15 %).
const TOLERANCE: f64 = 0.02;

/// the committed baseline, relative to the workspace root.
const BASELINE: &str = "benches/icount.toml";

/// the runs: (name, scene text).
fn runs() -> Result<Vec<(&'static str, String)>> {
    let flume = mpm_scene::embedded_scene("flume").context("the embedded flume")?;
    let flume = shortened(flume, "end_time = 3.0", "end_time = 0.1")?;
    let flume = shortened(&flume, "[output]\n", "[output]\nplots = false\n")?;
    Ok(vec![
        ("2d usl/apic/bspline", block(2, "usl", "apic", "bspline")),
        ("2d musl/flip/bilinear", block(2, "musl", "flip", "bilinear")),
        ("2d usavg/flip/bilinear", block(2, "usavg", "flip", "bilinear")),
        ("2d flume (0.1 s)", flume),
        ("3d musl/flip/trilinear", block(3, "musl", "flip", "bilinear")),
        ("3d usl/apic/bspline", block(3, "usl", "apic", "bspline")),
    ])
}

/// `text` with its one `from` replaced by `to` (an error if the scene no longer has it once).
fn shortened(text: &str, from: &str, to: &str) -> Result<String> {
    if text.matches(from).count() != 1 {
        bail!("the embedded flume no longer has `{}` once: update icount.rs", from.trim());
    }
    Ok(text.replace(from, to))
}

/// the side-by-side block of `benches/peers/` at a small size: a sand square (cube) of 0.4
/// resting on the floor of the unit box, 2 particles per cell and axis, Δt = 0.1 dx / c_p;
/// 10 000 particles and 20 steps in 2D, 8 000 and 10 steps in 3D (and the half step that lands
/// on the end time).
fn block(dim: usize, scheme: &str, transfer: &str, shape: &str) -> String {
    let (per_side, steps) = if dim == 2 { (50, 20) } else { (10, 10) };
    let cells = (per_side as f64 / 0.4).ceil() as usize;
    let dx = 1.0 / cells as f64;
    let (young, poisson, density): (f64, f64, f64) = (3.537e5, 0.3, 2200.0);
    let modulus = young * (1.0 - poisson) / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
    let dt = 0.1 * dx / (modulus / density).sqrt();
    let t_end = dt * (steps as f64 + 0.5);
    let (lo, hi) = (0.3, 0.3 + per_side as f64 * dx);
    let (floor, top) = (3.0 * dx, 3.0 * dx + per_side as f64 * dx);
    let axes = |v: [f64; 3]| {
        let v: Vec<String> = v[..dim].iter().map(|x| format!("{x:?}")).collect();
        format!("[{}]", v.join(", "))
    };
    let counts: Vec<String> = (0..dim).map(|_| cells.to_string()).collect();
    let sides =
        if dim == 3 { "back_wall = \"frictionless\"\nfront_wall = \"frictionless\"\n" } else { "" };
    format!(
        "title = \"icount block\"\n[grid]\ndimension = {dim}\nkind = \"regular\"\n\
         origin = {origin}\ncell = {cell}\ncells = [{counts}]\n\n\
         [materials.sand]\nkind = \"drucker_prager\"\nyoung = {young:?}\npoisson = {poisson:?}\n\
         density = {density:?}\ncohesion = 0.0\nfriction_angle_deg = 30.0\n\n\
         [[bodies]]\nmaterial = \"sand\"\nshape = \"{body}\"\nmin = {min}\nmax = {max}\n\
         particles_per_cell = 2\n\n\
         [boundaries]\nground = \"frictionless\"\nleft_wall = \"frictionless\"\n\
         right_wall = \"frictionless\"\n{sides}\n\
         [solver]\nscheme = \"{scheme}\"\ntransfer = \"{transfer}\"\nshape_function = \"{shape}\"\n\
         dt = {dt:?}\nend_time = {t_end:?}\n\n\
         [output]\nvtk = false\nplots = false\ninterval = {t_end:?}\nseries_interval = {t_end:?}\n",
        origin = axes([0.0; 3]),
        cell = axes([dx; 3]),
        counts = counts.join(", "),
        body = if dim == 2 { "rectangle" } else { "box" },
        min = axes([lo, floor, lo]),
        max = axes([hi, top, hi]),
    )
}

/// counts the runs with the `mpm` binary beside this one, compares them with the baseline (or
/// rewrites it with `bless`); false if one grew by more than [`TOLERANCE`].
pub fn run(bless: bool) -> Result<bool> {
    let exe = std::env::current_exe().context("the path of xtask")?;
    let dir = exe.parent().context("the directory of xtask")?;
    // `target/<profile>/xtask`, or `target/<profile>/deps/xtask-…` under `cargo run`
    let dir = if dir.ends_with("deps") { dir.parent().unwrap_or(dir) } else { dir };
    let profile = dir
        .file_name()
        .and_then(|p| p.to_str())
        .context("the profile directory's name")?
        .to_string();
    // the binary measured is built first, as its profile's other commands build it (CI's
    // `cargo build --workspace --bins --tests`, after which this is a no-op; `bench`'s release
    // `mpm`): another selection could resolve other features and build another binary
    let build: &[&str] = match profile.as_str() {
        "release" => &["build", "--release", "-p", "mpm-cli"],
        "debug" => &["build", "--workspace", "--bins", "--tests"],
        other => bail!("`icount` measures the debug or the release build, not `{other}`"),
    };
    let status = Command::new(env!("CARGO"))
        .current_dir(crate::workspace_root())
        .args(build)
        .status()
        .context("cargo build of mpm")?;
    if !status.success() {
        bail!("mpm did not build");
    }
    let mpm = dir.join(format!("mpm{}", std::env::consts::EXE_SUFFIX));
    if !mpm.is_file() {
        bail!("no `mpm` binary beside xtask ({}) after the build", mpm.display());
    }
    let valgrind = Command::new("valgrind").arg("--version").output();
    if !valgrind.is_ok_and(|o| o.status.success()) {
        bail!("valgrind is not installed: `apt-get install valgrind` (its callgrind counts)");
    }
    let work = crate::out_dir("icount")?;
    let root = crate::workspace_root();
    let baseline_path = root.join(BASELINE);
    let mut baseline = read_baseline(&baseline_path)?;
    let known = baseline.counts.get(&profile).cloned().unwrap_or_default();
    let settings = build_settings();
    println!("counting the `{profile}` build of {}: {settings}", mpm.display());
    let mut measured = BTreeMap::new();
    let mut table = Table::new(&["run", "instructions", "baseline", "change", "verdict"]);
    for (name, scene) in runs()? {
        let count = count(&mpm, &work, name, &scene)?;
        println!("{name}: {count} instructions");
        let (base, change, status) = match known.get(name) {
            Some(&base) => {
                let change = count as f64 / base as f64 - 1.0;
                let status = if change > TOLERANCE { Status::Fail } else { Status::Pass };
                (base.to_string(), format!("{:+.2} %", 100.0 * change), status)
            }
            None if bless => ("none".into(), String::new(), Status::Info),
            None => ("none".into(), String::new(), Status::Fail),
        };
        let fewer = known.get(name).is_some_and(|&b| (count as f64) < (1.0 - TOLERANCE) * b as f64);
        let verdict = match (known.contains_key(name), status) {
            (false, _) => format!("not in the `{profile}` baseline"),
            (true, Status::Fail) => format!("more than {} % over the baseline", 100.0 * TOLERANCE),
            (true, _) if fewer => "fewer: `--bless` to tighten the baseline".into(),
            _ => String::new(),
        };
        table.push(vec![name.into(), count.to_string(), base, change, verdict], status);
        measured.insert(name.to_string(), count);
    }
    println!("\n{}", table.text());
    if bless {
        baseline.counts.insert(profile.clone(), measured);
        baseline.built_with.insert(profile.clone(), settings);
        write_baseline(&baseline_path, &baseline)?;
        println!("baseline `{profile}` rewritten: {}", baseline_path.display());
        return Ok(true);
    }
    let failed = table.failures();
    if failed > 0 {
        // the command that rewrites this profile's table (the alias runs the release build)
        let again = if profile == "release" {
            "cargo xtask icount --bless".to_string()
        } else {
            format!("{} icount --bless", exe.display())
        };
        println!(
            "{failed} run(s) grew by more than {} % or are not in the baseline (callgrind's \
             profiles are in {}): find the cost, or run `{again}` and commit the baseline with \
             a message that says why it is worth it",
            100.0 * TOLERANCE,
            work.display()
        );
        match baseline.built_with.get(&profile) {
            Some(then) if *then != settings => println!(
                "note: the baseline was counted with a build of other settings ({then}), this \
                 is {settings}: build as the baseline's was, or re-bless if the build, not the \
                 code, is what moved the counts"
            ),
            _ => {}
        }
    }
    Ok(failed == 0)
}

/// the instructions one run of `scene` executes, under callgrind (its profile kept in `work`).
fn count(mpm: &Path, work: &Path, name: &str, scene: &str) -> Result<u64> {
    let slug: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    let scene_path = work.join(format!("{slug}.toml"));
    std::fs::write(&scene_path, scene).with_context(|| scene_path.display().to_string())?;
    let profile = work.join(format!("{slug}.callgrind"));
    let out: PathBuf = work.join(&slug);
    let mut command = Command::new("valgrind");
    command
        .env_clear()
        .env("PATH", std::env::var_os("PATH").unwrap_or_default())
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", profile.display()))
        .arg(mpm)
        .arg("run")
        .arg(&scene_path)
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--force", "--threads", "1"]);
    let output = command.output().context("valgrind")?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        bail!("`{name}` failed under callgrind:\n{stderr}");
    }
    // "==1234== Collected : 123456789"
    stderr
        .lines()
        .find_map(|l| l.split_once("Collected :").and_then(|(_, n)| n.trim().parse().ok()))
        .with_context(|| format!("`{name}`: no instruction count in callgrind's output:\n{stderr}"))
}

/// The committed counts: the compiler they were counted with, and profile → run → count.
#[derive(Default, serde::Serialize, serde::Deserialize)]
struct Baseline {
    /// per profile, the settings of the build its counts were taken from ([`build_settings`])
    #[serde(default)]
    built_with: BTreeMap<String, String>,
    #[serde(flatten)]
    counts: BTreeMap<String, BTreeMap<String, u64>>,
}

/// what shapes the build's code besides its source: `rustc --version` of the compiler on PATH
/// (the one cargo builds with), the workspace wrapper's file name and `RUSTFLAGS`.
fn build_settings() -> String {
    let rustc = Command::new("rustc")
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let wrapper = std::env::var_os("RUSTC_WORKSPACE_WRAPPER")
        .filter(|w| !w.is_empty())
        .map(|w| Path::new(&w).file_name().unwrap_or(&w).to_string_lossy().into_owned())
        .unwrap_or_else(|| "none".into());
    let flags = std::env::var("RUSTFLAGS").unwrap_or_default();
    format!("{rustc}, RUSTC_WORKSPACE_WRAPPER={wrapper}, RUSTFLAGS=\"{}\"", flags.trim())
}

/// the baseline file (empty if there is none yet).
fn read_baseline(path: &Path) -> Result<Baseline> {
    if !path.exists() {
        return Ok(Baseline::default());
    }
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    toml::from_str(&text).with_context(|| format!("{}: not a baseline of counts", path.display()))
}

/// writes the baseline with its header.
fn write_baseline(path: &Path, counts: &Baseline) -> Result<()> {
    let header = "# Instructions executed by the fixed runs of `cargo xtask icount` (valgrind's callgrind,\n\
                  # one thread), per build profile: CI fails a run that executes more than 2 % more\n\
                  # than its count here. Rewritten by `icount --bless` (xtask/src/icount.rs says how),\n\
                  # in a commit that says why the counts moved.\n\n";
    let body = toml::to_string(counts).context("the baseline as TOML")?;
    std::fs::write(path, format!("{header}{body}")).with_context(|| path.display().to_string())
}
