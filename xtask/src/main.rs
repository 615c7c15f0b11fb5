//! `cargo xtask`: the workspace's numerical checks, run in release mode.
//!
//! - `verify [--quick]`: every verification case of the paper (and beyond it) against its reference, one table,
//!   `target/verify/report.md` and PNG plots; exits non-zero if any row fails.
//! - `study [--quick]`: the speed/accuracy trade (cell size, particles per cell, scheme, shape
//!   functions, Courant number) on the sliding blocks, the vibrating bar and the flume; CSV,
//!   convergence orders, Pareto fronts and the three presets, in `target/study/`.
//! - `runout [--quick]`: column collapses against the quasi-2D and axisymmetric experiments,
//!   Mohr–Coulomb and Drucker-Prager, with and without side walls, at several resolutions;
//!   `target/runout/` and `docs/runout.md` (`RUNOUT_ONLY=TEXT` runs the cases whose label has it).
//! - `dem`: the worked example's synthetic valley-side DEM (ASCII grid and GeoTIFF) and its
//!   rupture surface, in `docs/examples/valley/`.
//! - `icount [--bless]`: the instructions a few fixed small runs execute (valgrind's callgrind)
//!   against `benches/icount.toml`; exits non-zero if one grew by more than 2 %.
//! - `extremes`: scenes at the edges of the admissible settings, each with its expected outcome
//!   (completes within the energy bound, or stops with a named error); `target/extremes/`.

mod bench;
mod column;
mod dem;
mod extremes;
mod flume;
mod icount;
mod plot;
mod presets;
mod runout;
mod runs;
mod study;
mod table;
mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "\
usage: cargo xtask <command> [options]

commands:
  verify [--quick]   run the verification cases (--quick: the CI subset, < 3 min)
  study [--quick]    measure the speed/accuracy trade and derive the presets (--quick: fewer runs)
  bench [--quick]    measure throughput and thread scaling into docs/performance.md
                     (--quick: no 1 M-particle bodies; MPM_PEERS_DIR=benches/peers adds the
                     side-by-side against Taichi, which needs `pip install taichi`)
  runout [--quick]   column collapses against the experiments, model by model, into
                     docs/runout.md (RUNOUT_ONLY=TEXT: only the cases whose label has TEXT)
  icount [--bless]   count the instructions of a few fixed small runs (valgrind's callgrind)
                     against benches/icount.toml: fails on 2 % growth (--bless: rewrite it)
  extremes           run scenes at the edges of the settings and tabulate their outcomes
  dem                write the worked example's synthetic valley-side DEM (docs/examples/valley/)
  help               this text";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(command) = args.first() else {
        eprintln!("{USAGE}");
        return ExitCode::FAILURE;
    };
    let options = &args[1..];
    let quick = options.iter().any(|a| a == "--quick");
    let bless = options.iter().any(|a| a == "--bless");
    let allowed = if command == "icount" { "--bless" } else { "--quick" };
    if let Some(bad) = options.iter().find(|a| *a != allowed) {
        eprintln!("unknown option `{bad}`\n\n{USAGE}");
        return ExitCode::FAILURE;
    }
    if quick && (command == "extremes" || command == "dem") {
        eprintln!("`{command}` has no --quick option\n\n{USAGE}");
        return ExitCode::FAILURE;
    }
    let result = match command.as_str() {
        "verify" => verify::run(quick),
        "study" => study::run(quick),
        "bench" => bench::run(quick),
        "runout" => runout::run(quick),
        "icount" => icount::run(bless),
        "extremes" => extremes::run(),
        "dem" => dem::run(),
        "help" | "--help" | "-h" => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        other => {
            eprintln!("unknown command `{other}`\n\n{USAGE}");
            return ExitCode::FAILURE;
        }
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// `target/<name>` of the workspace (created), whatever the current directory.
fn out_dir(name: &str) -> anyhow::Result<PathBuf> {
    let root = workspace_root();
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or(root.join("target"));
    let dir = target.join(name);
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// the workspace root (for editing files such as the CLI's preset table).
fn workspace_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let root = manifest.parent().map(PathBuf::from).unwrap_or(manifest);
    root.canonicalize().unwrap_or(root)
}
