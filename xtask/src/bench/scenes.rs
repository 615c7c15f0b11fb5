//! Whole scenes through the run driver, as `mpm run` runs them: the flume end to end (its output
//! included), granular columns of growing size on one and two threads (what the thread policy of
//! small scenes gives), and one 100 k-particle frame in each VTK format (its size and the time to
//! write it). Written below the step driver's tables by `cargo xtask bench`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};
use mpm_run::{RunOptions, RunSummary, run_scene};
use mpm_scene::{embedded_scene, load_scene_str};

use crate::table::{Status, Table};

/// Columns of Drucker-Prager sand, cells across the column (2 × 2 particles a cell): about
/// 800, 3 200 and 12 800 particles.
const COLUMN_CELLS: [u32; 3] = [14, 28, 56];
/// Simulated time of a column run (s): the first half of the collapse, while all of it flows.
const COLUMN_TIME: f64 = 0.1;

/// one run of `text` on at most `threads` threads, into `out` (or writing nothing).
fn run_once(text: &str, label: &str, threads: usize, out: Option<&Path>) -> Result<RunSummary> {
    let scene = load_scene_str(text, label).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
    let options = RunOptions {
        out_dir: out.map(Path::to_path_buf),
        threads: Some(threads),
        force: true,
        ..Default::default()
    };
    let s = run_scene(&scene, &options).with_context(|| label.to_string())?;
    if s.status.exit_code() != 0 {
        bail!("{label}: {:?} {}", s.status, s.error.unwrap_or_default());
    }
    Ok(s)
}

/// the run with the median wall time of `repeats`.
fn median_run(
    text: &str,
    label: &str,
    threads: usize,
    out: Option<&Path>,
    repeats: usize,
) -> Result<RunSummary> {
    let mut runs =
        (0..repeats).map(|_| run_once(text, label, threads, out)).collect::<Result<Vec<_>>>()?;
    runs.sort_by(|a, b| a.wall_time_s.total_cmp(&b.wall_time_s));
    Ok(runs.swap_remove(runs.len() / 2))
}

/// a column of `cells` × `cells` cells of sand released on a rough floor.
fn column_text(cells: u32) -> String {
    let width = 0.2;
    let dx = width / f64::from(cells);
    format!(
        "title = \"column\"\n\
         [grid]\nkind = \"regular\"\norigin = [0.0, 0.0]\ncell = [{dx}, {dx}]\n\
         cells = [{nx}, {ny}]\n\
         [materials.sand]\nkind = \"drucker_prager\"\nyoung = 2.0e6\npoisson = 0.3\n\
         density = 1600.0\ncohesion = 0.0\nfriction_angle_deg = 30.0\n\
         dilatancy_angle_deg = 0.0\nhardening_modulus = 0.0\nmixing = 0.8\n\
         [[bodies]]\nname = \"column\"\nmaterial = \"sand\"\nshape = \"rectangle\"\n\
         min = [0.0, 0.0]\nmax = [{width}, {width}]\nparticles_per_cell = 2\n\
         [boundaries]\nground = \"rough\"\nleft_wall = \"frictionless\"\n\
         [solver]\nend_time = {COLUMN_TIME}\n",
        nx = 3 * cells + 2,
        ny = cells + cells / 2 + 2,
    )
}

/// a 100 k-particle elastic block at rest on the floor, two frames in `format`.
fn frame_text(format: &str) -> String {
    // 158 × 158 cells of 2 × 2 particles: 99 856 particles.
    "title = \"frames\"\n\
     [grid]\nkind = \"regular\"\norigin = [0.0, 0.0]\ncell = [0.01, 0.01]\ncells = [160, 161]\n\
     [materials.block]\nkind = \"elastic\"\nyoung = 1.0e6\npoisson = 0.3\ndensity = 2000.0\n\
     [[bodies]]\nname = \"block\"\nmaterial = \"block\"\nshape = \"rectangle\"\n\
     min = [0.01, 0.0]\nmax = [1.59, 1.58]\nparticles_per_cell = 2\n\
     [boundaries]\nground = \"rough\"\n\
     [solver]\nend_time = 1.0e-4\n\
     [output]\ninterval = 1.0e-4\nplots = false\n"
        .to_string()
        + &format!("vtk_format = \"{format}\"\n")
}

/// bytes of the files in `dir`.
fn dir_bytes(dir: &Path) -> Result<u64> {
    let mut total = 0;
    for entry in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
        total += entry?.metadata()?.len();
    }
    Ok(total)
}

/// appends the whole-scene tables to `text`.
pub fn whole_scenes(text: &mut String, repeats: usize) -> Result<()> {
    let scratch = std::env::temp_dir().join(format!("mpm-bench-{}", std::process::id()));
    let flume_text = embedded_scene("flume").context("the embedded flume")?;
    let mut scenes =
        Table::new(&["scene", "particles", "threads", "wall (s)", "output", "M particle-steps/s"]);
    let mut row = |name: &str, s: &RunSummary| {
        scenes.push(
            vec![
                name.into(),
                s.particles.to_string(),
                s.threads.to_string(),
                format!("{:.2}", s.wall_time_s),
                format!("{:.0} %", 100.0 * s.output_time_s / s.wall_time_s),
                format!("{:.2}", s.particle_steps_per_s / 1e6),
            ],
            Status::Info,
        );
    };
    let mut ratios = Vec::new();
    for threads in [1, 2] {
        let s = median_run(flume_text, "flume", threads, Some(&scratch.join("flume")), repeats)?;
        println!("flume, {threads} thread(s) at most: {:.2} s", s.wall_time_s);
        row("flume (with its output)", &s);
    }
    for cells in COLUMN_CELLS {
        let text_c = column_text(cells);
        let one = median_run(&text_c, "column", 1, None, repeats)?;
        let two = median_run(&text_c, "column", 2, None, repeats)?;
        println!("column {}: {:.2} s → {:.2} s", one.particles, one.wall_time_s, two.wall_time_s);
        ratios.push((one.particles, one.wall_time_s / two.wall_time_s, two.threads));
        row("column", &one);
        row("column", &two);
    }
    let _ = writeln!(
        text,
        "\n## Whole scenes (written by `cargo xtask bench`)\n\n`mpm run` as a user runs it, \
         the median of {repeats} runs: the embedded flume end to end (frames, series, plots and \
         checkpoints included; \"output\" is the share of the wall time spent writing them), and \
         a square column of the paper's sand collapsing on a rough floor for {COLUMN_TIME} s \
         (USAVG, bilinear, 2 × 2 particles a cell, no output). \"threads\" is what the run used: \
         `--threads 2` is an upper bound, and a scene gets one thread per 1 200 particles at \
         most (the results are the same bits for any count).\n\n{}",
        scenes.markdown()
    );
    let speedups: Vec<String> = ratios
        .iter()
        .map(|(n, r, t)| {
            format!("{n} particles {r:.2}× ({t} {})", if *t == 1 { "thread" } else { "threads" })
        })
        .collect();
    let _ = writeln!(text, "Two threads against one on the columns: {}.\n", speedups.join(", "));

    let mut frames = Table::new(&["vtk_format", "one frame (MB)", "written in (s)"]);
    for format in ["binary", "compressed", "ascii"] {
        let dir = scratch.join(format);
        let s = median_run(&frame_text(format), "frames", 2, Some(&dir), repeats)?;
        let count = std::fs::read_dir(dir.join("frames"))?.count().max(1);
        let bytes = dir_bytes(&dir.join("frames"))?;
        println!("{format}: {bytes} bytes in {count} frames, {:.3} s", s.output_time_s);
        frames.push(
            vec![
                format!("`{format}`"),
                format!("{:.1}", bytes as f64 / count as f64 / 1e6),
                format!("{:.3}", s.output_time_s / count as f64),
            ],
            Status::Info,
        );
    }
    let _ = writeln!(
        text,
        "One frame of a 100 k-particle elastic block at rest (positions, velocities, stresses and \
         the state's fields), in each format (the run's output time, series included, shared \
         over its frames; median of {repeats} runs):\n\n{}",
        frames.markdown()
    );
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(())
}
