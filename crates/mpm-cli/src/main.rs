//! `mpm`: the command line (clap only; the work is in the `mpm_run` library).
//!
//! Exit codes: 0 success; 1 I/O or other failure (or the output directory is in use); 2 invalid
//! scene, arguments or checkpoint; 3 the solver stopped with an instability (files up to the
//! failure are written); 4 energy alarm (the run ended, or stopped when asked to, with an energy
//! residual above `[solver] energy_alarm`: results suspect); 5 step limit (`[solver] max_steps`);
//! 130 interrupted by SIGINT (Ctrl-C), 143 by SIGTERM (a checkpoint was written; continue with
//! `mpm resume DIR`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

mod out;
mod progress;

use out::{out, outln};

use clap::{Parser, Subcommand, ValueEnum};
use mpm_run::{
    AnyScene, DEFAULT_SCENE, ElementTest, ElementTestOptions, OutputError, RunError, RunOptions,
    RunStatus, RunSummary, SCENES, Scene, SceneError,
};

#[derive(Parser)]
#[command(
    name = "mpm",
    version,
    about = "Explicit MPM for dry granular flows (Abe, Johansson & Konagai 2005)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (default: the embedded dry-sand flume).
    Run {
        /// a scene file, or the name of an embedded scene (`mpm scenes`).
        scene: Option<String>,
        /// output directory [default: out/SCENE_NAME].
        #[arg(long)]
        out: Option<PathBuf>,
        /// worker threads at most [default: one per core]; a small scene uses fewer (one per 1200 particles), with the same results.
        #[arg(long)]
        threads: Option<usize>,
        /// no progress output.
        #[arg(long)]
        quiet: bool,
        /// overwrite an existing output directory.
        #[arg(long)]
        force: bool,
    },
    /// Validate a scene and print what a run would do, without running it.
    Check {
        /// a scene file, or the name of an embedded scene.
        scene: String,
    },
    /// List the embedded scenes, or write one out as an editable file.
    Scenes {
        /// write the embedded scene NAME to PATH (default NAME.toml).
        #[arg(long, value_name = "NAME")]
        write: Option<String>,
        /// where to write it.
        path: Option<PathBuf>,
        /// overwrite an existing file.
        #[arg(long)]
        force: bool,
    },
    /// Run a constitutive element test (plane-strain uniaxial compression or simple shear).
    ElementTest {
        /// which test.
        test: TestKind,
        /// Young's modulus E (Pa).
        #[arg(long, default_value_t = 2.0e6, conflicts_with = "scene")]
        young: f64,
        /// Poisson's ratio ν.
        #[arg(long, default_value_t = 0.3, conflicts_with = "scene")]
        poisson: f64,
        /// cohesion c (Pa).
        #[arg(long, default_value_t = 10.0, conflicts_with = "scene")]
        cohesion: f64,
        /// friction angle φ (degrees).
        #[arg(long, default_value_t = 40.0, conflicts_with = "scene")]
        friction_angle: f64,
        /// dilatancy angle(s) ψ (degrees), comma-separated: one curve each.
        #[arg(long, value_delimiter = ',', default_value = "0", conflicts_with = "scene")]
        dilatancy: Vec<f64>,
        /// plastic modulus H (Pa).
        #[arg(long, default_value_t = 0.0, conflicts_with = "scene")]
        hardening: f64,
        /// mixing parameter(s) M (1 isotropic, 0 kinematic), comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "0.8", conflicts_with = "scene")]
        mixing: Vec<f64>,
        /// final strain: ε_yy for uniaxial [default -1e-3], engineering γ_xy for simple
        /// shear [default 0.02].
        #[arg(long, allow_hyphen_values = true)]
        strain: Option<f64>,
        /// load steps.
        #[arg(long, default_value_t = 400)]
        steps: usize,
        /// simple shear, triaxial and oedometric tests: the initial isotropic stress (Pa,
        /// negative = compression), held vertically in simple shear, laterally in triaxial.
        #[arg(long, default_value_t = -1000.0, allow_hyphen_values = true)]
        confining_stress: f64,
        /// test the materials of this scene (any model) instead of the paper's sand; with
        /// --material, only those.
        #[arg(long, value_name = "SCENE")]
        scene: Option<String>,
        /// with --scene: the materials to test, comma-separated (default: all its bodies').
        #[arg(long, value_delimiter = ',', requires = "scene")]
        material: Vec<String>,
        /// simple shear at this engineering shear rate γ̇ (1/s), for a rate-dependent model
        /// such as μ(I) (default: quasi-static).
        #[arg(long)]
        shear_rate: Option<f64>,
        /// output directory.
        #[arg(long)]
        out: PathBuf,
        /// overwrite existing files.
        #[arg(long)]
        force: bool,
    },
    /// Cut the section of a DEM (ESRI ASCII `.asc` or GeoTIFF `.tif`) along a line: CSV
    /// `station,x,y,z`, station = distance from FROM (a scene's `csv` profile reads it back).
    Section {
        /// the elevation raster.
        dem: PathBuf,
        /// start of the line, map coordinates `X,Y` (m).
        #[arg(long, value_parser = map_point, allow_hyphen_values = true)]
        from: [f64; 2],
        /// end of the line, `X,Y` (m).
        #[arg(long, value_parser = map_point, allow_hyphen_values = true)]
        to: [f64; 2],
        /// station spacing (m) [default: the raster's cell size].
        #[arg(long)]
        spacing: Option<f64>,
        /// write the CSV here instead of to standard output.
        #[arg(long)]
        out: Option<PathBuf>,
        /// overwrite an existing --out file.
        #[arg(long)]
        force: bool,
    },
    /// Continue a run from the last checkpoint in its output directory.
    Resume {
        /// the run's output directory.
        dir: PathBuf,
        /// worker threads at most [default: one per core]; a small scene uses fewer (one per 1200 particles), with the same results.
        #[arg(long)]
        threads: Option<usize>,
        /// no progress output.
        #[arg(long)]
        quiet: bool,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum TestKind {
    /// plane-strain uniaxial compression (σ_xx = 0).
    Uniaxial,
    /// drained simple shear at constant vertical stress.
    SimpleShear,
    /// drained triaxial compression (--strain < 0, default −2e-3) or extension (> 0) from the
    /// isotropic --confining-stress held laterally.
    Triaxial,
    /// one-dimensional (K0) compression from the isotropic --confining-stress.
    Oedometric,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(message) = mpm_run::limits::memory_limit_env() {
        eprintln!("error: {message}");
        return ExitCode::from(2);
    }
    match cli.command {
        Command::Run { scene, out, threads, quiet, force } => {
            let signals = signals();
            let name = scene.unwrap_or_else(|| DEFAULT_SCENE.to_string());
            let scene = match load_any(&name) {
                Ok(s) => s,
                Err(e) => return scene_failure(&e),
            };
            let out = out.unwrap_or_else(|| PathBuf::from("out").join(stem(&name)));
            let opts = RunOptions {
                out_dir: Some(out.clone()),
                threads,
                progress: progress::Terminal::sink(quiet),
                force,
                stop_after: None,
                interrupt: Some(signals.interrupt.clone()),
            };
            let (origin, what, end) = match &scene {
                AnyScene::Plane(s) => (s.origin(), "", s.end_time()),
                AnyScene::Space(s) => (s.origin(), "3D, ", s.end_time),
            };
            if !quiet {
                let particles = match &scene {
                    AnyScene::Plane(s) => s.particle_count(),
                    AnyScene::Space(s) => s.particle_count(),
                };
                eprintln!(
                    "mpm: running {origin} ({what}{particles} particles, end time {end} s) into {}",
                    out.display()
                );
            }
            let result = match &scene {
                AnyScene::Plane(s) => mpm_run::run_scene(s, &opts),
                AnyScene::Space(s) => mpm_run::run_space_scene(s, &opts),
            };
            finish(result, &out, quiet, &signals)
        }
        Command::Resume { dir, threads, quiet } => {
            let signals = signals();
            let opts = RunOptions {
                out_dir: Some(dir.clone()),
                threads,
                progress: progress::Terminal::sink(quiet),
                force: false,
                stop_after: None,
                interrupt: Some(signals.interrupt.clone()),
            };
            finish(mpm_run::resume(&dir, &opts), &dir, quiet, &signals)
        }
        Command::Section { dem, from, to, spacing, out, force } => {
            section(&dem, from, to, spacing, out.as_deref(), force)
        }
        Command::Check { scene } => check(&scene),
        Command::Scenes { write, path, force } => scenes(write, path, force),
        Command::ElementTest {
            test,
            young,
            poisson,
            cohesion,
            friction_angle,
            dilatancy,
            hardening,
            mixing,
            strain,
            steps,
            confining_stress,
            scene,
            material,
            shear_rate,
            out,
            force,
        } => {
            let test = match test {
                TestKind::Uniaxial => ElementTest::Uniaxial,
                TestKind::SimpleShear => ElementTest::SimpleShear,
                TestKind::Triaxial => ElementTest::Triaxial,
                TestKind::Oedometric => ElementTest::Oedometric,
            };
            let materials = match scene.as_deref().map(|s| scene_materials(s, &material)) {
                None => Vec::new(),
                Some(Ok(m)) => m,
                Some(Err(code)) => return code,
            };
            let opts = ElementTestOptions {
                test,
                young,
                poisson,
                cohesion,
                friction_angle_deg: friction_angle,
                dilatancy_deg: dilatancy,
                hardening_modulus: hardening,
                mixing,
                materials,
                shear_rate,
                strain: strain.unwrap_or(match test {
                    ElementTest::Uniaxial | ElementTest::Oedometric => -1e-3,
                    ElementTest::SimpleShear => 0.02,
                    ElementTest::Triaxial => -2e-3,
                }),
                steps,
                confining_stress,
                out_dir: out,
                force,
            };
            element_test(&opts)
        }
    }
}

/// `mpm element-test`: runs the cases and prints each one's end point.
fn element_test(opts: &ElementTestOptions) -> ExitCode {
    match mpm_run::run_element_test(opts) {
        Ok(cases) => {
            for c in cases {
                let first = c.first_yield_syy.map_or("none".into(), |v| format!("{v:.3} Pa"));
                outln!(
                    "{}: first yield σ_yy {first}; final σ_yy {:.3} Pa, σ_xy {:.3} Pa, ε_vol {:.4e}",
                    c.label,
                    c.final_syy,
                    c.final_sxy,
                    c.final_eps_vol
                );
            }
            outln!("wrote {}", opts.out_dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => run_failure(&e),
    }
}

/// The materials `names` (all the bodies' when empty) of the scene `name`, built.
fn scene_materials(
    name: &str,
    names: &[String],
) -> Result<Vec<(String, mpm_run::AnyModel)>, ExitCode> {
    let scene = load(name).map_err(|e| scene_failure(&e))?;
    let all = &scene.resolved().material_names;
    let names = if names.is_empty() { all.as_slice() } else { names };
    names
        .iter()
        .map(|n| {
            scene.material(n).map(|m| (n.clone(), m)).ok_or_else(|| {
                eprintln!(
                    "error: --material {n}: {} has no material of this name used by a body \
                     (its bodies use: {}); give one of those names",
                    scene.origin(),
                    all.join(", ")
                );
                ExitCode::from(2)
            })
        })
        .collect()
}

/// `mpm check SCENE`: validates and prints what a run would do (2D or 3D).
fn check(scene: &str) -> ExitCode {
    let scene = match load_any(scene) {
        Ok(s) => s,
        Err(e) => return scene_failure(&e),
    };
    match mpm_run::check(&scene) {
        Ok(checked) => {
            outln!("{checked}");
            ExitCode::SUCCESS
        }
        Err(e) => run_failure(&e),
    }
}

/// `mpm scenes [--write NAME [PATH]]`: lists the embedded scenes or writes one out.
fn scenes(write: Option<String>, path: Option<PathBuf>, force: bool) -> ExitCode {
    match write {
        None => {
            for (name, text) in SCENES {
                let title = mpm_run::title_of(text).unwrap_or_default();
                let default = if name == DEFAULT_SCENE { " (default)" } else { "" };
                outln!("{name:<20} {title}{default}");
            }
            outln!("(the element tests run with `mpm element-test uniaxial|simple-shear`)");
            ExitCode::SUCCESS
        }
        Some(name) => {
            let Some(text) = mpm_run::embedded_scene(&name) else {
                eprintln!("error: {}", mpm_run::unknown_scene_message(&name));
                return ExitCode::from(2);
            };
            let path = path.unwrap_or_else(|| PathBuf::from(format!("{name}.toml")));
            if path.exists() && !force {
                eprintln!("error: {} exists; choose another path or pass --force", path.display());
                return ExitCode::from(1);
            }
            match std::fs::write(&path, text) {
                Ok(()) => {
                    outln!("wrote {}", path.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {}: {e}", path.display());
                    ExitCode::from(1)
                }
            }
        }
    }
}

/// `X,Y` as two finite numbers.
fn map_point(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<f64> =
        s.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| {
            format!("`{s}`: {e}; give the map point as X,Y (e.g. 500120.5,4100200)")
        })?;
    match v[..] {
        [x, y] if x.is_finite() && y.is_finite() => Ok([x, y]),
        _ => Err(format!("`{s}`: give the map point as two finite numbers X,Y")),
    }
}

/// `mpm section`: the DEM's section along a line, as CSV to `out` or standard output.
fn section(
    dem: &Path,
    from: [f64; 2],
    to: [f64; 2],
    spacing: Option<f64>,
    out: Option<&Path>,
    force: bool,
) -> ExitCode {
    let section = match mpm_run::section(dem, from, to, spacing) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let Some(out) = out else {
        out!("{}", section.csv);
        return ExitCode::SUCCESS;
    };
    if out.exists() && !force {
        eprintln!("error: {} exists; pass --force to overwrite it", out.display());
        return ExitCode::from(2);
    }
    if let Err(e) = mpm_output::atomic::write(out, section.csv.as_bytes()) {
        eprintln!("error: {e}");
        return ExitCode::from(1);
    }
    let (lo, hi) = section.heights;
    outln!(
        "wrote {}: {} stations over {:.3} m, z from {lo:.3} to {hi:.3} m",
        out.display(),
        section.stations,
        section.length
    );
    ExitCode::SUCCESS
}

/// A scene file path (2D or 3D, by its `[grid] dimension`), or an embedded scene's name when no
/// such file exists.
fn load_any(name: &str) -> Result<AnyScene, Box<SceneError>> {
    if Path::new(name).is_file() {
        return mpm_run::load_any_scene_file(Path::new(name)).map_err(Box::new);
    }
    load(name).map(|s| AnyScene::Plane(Box::new(s)))
}

/// A scene file path, or an embedded scene's name when no such file exists.
fn load(name: &str) -> Result<Scene, Box<SceneError>> {
    let path = Path::new(name);
    if !path.is_file() {
        if let Some(text) = mpm_run::embedded_scene(name) {
            return mpm_run::load_scene_str(text, &format!("embedded:{name}")).map_err(Box::new);
        }
    }
    mpm_run::load_scene_file(path).map_err(Box::new)
}

fn stem(name: &str) -> String {
    Path::new(name).file_stem().map_or("run".into(), |s| s.to_string_lossy().into_owned())
}

/// Flags set by SIGINT (Ctrl-C) and SIGTERM (what batch schedulers send before killing a job).
struct Signals {
    /// either signal: the run stops after the current step and writes a checkpoint.
    interrupt: Arc<AtomicBool>,
    /// SIGTERM: the exit code is 143 instead of 130.
    terminated: Arc<AtomicBool>,
}

/// installs the handlers: the first SIGINT or SIGTERM sets the flags (the run stops after the
/// step and writes a checkpoint); a second SIGINT (Ctrl-C pressed again) exits at once with 130,
/// without waiting for the step or the checkpoint. A repeated SIGTERM is ignored: schedulers and
/// GNU `timeout` signal a job's process and its group, so one stop arrives twice, and exiting at
/// the second copy gave 143 (the code that promises a checkpoint) with the checkpoint cut short
/// (R3-01). A job that must die at once gets SIGKILL.
fn signals() -> Signals {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::flag::{register, register_conditional_shutdown};
    let s = Signals {
        interrupt: Arc::new(AtomicBool::new(false)),
        terminated: Arc::new(AtomicBool::new(false)),
    };
    // The shutdown is registered first, so it sees the flag as the previous signal left it.
    let installed = register_conditional_shutdown(SIGINT, 130, s.interrupt.clone())
        .and_then(|_| register(SIGINT, s.interrupt.clone()));
    if let Err(e) = installed {
        eprintln!("mpm: warning: SIGINT will not checkpoint ({e})");
    }
    if let Err(e) = register(SIGTERM, s.interrupt.clone()) {
        eprintln!("mpm: warning: SIGTERM will not checkpoint ({e})");
    }
    if let Err(e) = register(SIGTERM, s.terminated.clone()) {
        eprintln!("mpm: warning: SIGTERM will exit with 130 instead of 143 ({e})");
    }
    s
}

fn scene_failure(e: &SceneError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(2)
}

fn run_failure(e: &RunError) -> ExitCode {
    eprintln!("error: {e}");
    match e {
        RunError::Scene(_)
        | RunError::Output(OutputError::Checkpoint { .. })
        | RunError::Arguments(_) => ExitCode::from(2),
        RunError::Solver { .. } => ExitCode::from(3),
        _ => ExitCode::from(1),
    }
}

fn print_summary(s: &RunSummary, out: &Path) {
    eprintln!(
        "mpm: {:?}: {} particles, {} steps to t = {:.4} s (Δt {:.3e}–{:.3e} s), wall {:.2} s, \
         {:.3e} particle-steps/s on {} thread(s)",
        s.status,
        s.particles,
        s.steps,
        s.simulated_time,
        s.dt.min,
        s.dt.max,
        s.wall_time_s,
        s.particle_steps_per_s,
        s.threads
    );
    // (3D: the front and tail are stations along the runout direction, energies in J)
    let (front, tail, joule) =
        if s.dimension == 3 { ("front", "tail", "J") } else { ("front x", "tail x", "J/m") };
    eprintln!(
        "mpm: {front} = {:.3} m (travel {:.3} m), {tail} = {:.3} m, max thickness {:.3} m, \
         centre of mass travel {:.3} m; energy residual {:.3e} {joule} ({:+.2} % of the energy \
         scale, worst {:+.2} %)",
        s.runout.last.front_x,
        s.runout.last.front_travel,
        s.runout.last.tail_x,
        s.runout.last.max_thickness,
        s.runout.last.com_travel,
        s.energy.residual,
        100.0 * s.energy_check.relative_residual,
        100.0 * s.energy_check.worst_relative_residual
    );
    let i = &s.runout.indicators;
    let deg = |a: Option<f64>| a.map_or("–".to_string(), |a| format!("{a:.1}°"));
    eprintln!(
        "mpm: travel angle {} (centre of mass {}), max front speed {:.3} m/s at t = {:.3} s, {}",
        deg(i.travel_angle_deg),
        deg(i.com_travel_angle_deg),
        i.max_front_speed,
        i.max_front_speed_time,
        i.stop_time.map_or("still moving at the end".to_string(), |t| format!(
            "stopped at t = {t:.3} s (kinetic energy below {:.0} % of its peak)",
            100.0 * i.stop_fraction
        ))
    );
    if let Some(h) = &s.hazard_maps {
        eprintln!(
            "mpm: hazard maps (maps/): affected area {:.4} m², deposit {:.4} m³ over {:.4} m² \
             (deepest {:.3} m), largest flow height {:.3} m, largest impact pressure {:.4e} Pa",
            h.affected_area,
            h.deposit_volume,
            h.deposit_area,
            h.max_deposit_depth,
            h.max_flow_height,
            h.max_pressure
        );
    }
    if let Some(o) = &s.observed {
        eprintln!(
            "mpm: against the observed deposit ({}): front {:+.3} m, tail {:+.3} m, RMS \
             thickness error {:.3} m (observed up to {:.3} m), overlap (IoU) {:.3}",
            o.file,
            o.front_error,
            o.tail_error,
            o.rms_thickness_error,
            o.max_observed_thickness,
            o.iou
        );
        if let (Some(lateral), Some(area)) = (o.lateral_error, o.area_iou) {
            eprintln!(
                "mpm: in plan: lateral spread {lateral:+.3} m, area overlap (IoU) {area:.3} over \
                 {} cells",
                o.stations
            );
        }
    }
    if let Some(o) = &s.outflow {
        eprintln!("mpm: {}", o.line());
    }
    for e in &s.edges {
        eprintln!("mpm: warning: {}", e.warning());
    }
    if let Some(e) = &s.error {
        eprintln!("mpm: {e}");
    }
    eprintln!("mpm: output in {}", out.display());
}

fn finish(
    result: Result<RunSummary, RunError>,
    out: &Path,
    quiet: bool,
    signals: &Signals,
) -> ExitCode {
    match result {
        Ok(s) => {
            if !quiet {
                print_summary(&s, out);
            }
            if s.status == RunStatus::Interrupted {
                eprintln!(
                    "mpm: interrupted at t = {} s; continue with `mpm resume {}`",
                    s.simulated_time,
                    out.display()
                );
                if signals.terminated.load(Ordering::SeqCst) {
                    return ExitCode::from(143);
                }
            } else if !matches!(s.status, RunStatus::Completed | RunStatus::AtRest) && quiet {
                // The status is the answer: say it even when quiet.
                eprintln!("mpm: {:?}: {}", s.status, s.error.as_deref().unwrap_or(""));
            }
            ExitCode::from(s.status.exit_code())
        }
        Err(e) => {
            if let RunError::Solver { summary, message } = &e {
                if !quiet {
                    print_summary(summary, out);
                }
                if summary.status == RunStatus::Interrupted {
                    // a signal during the initial state: nothing to resume (the summary
                    // above said so unless quiet)
                    if quiet {
                        eprintln!("mpm: {message}");
                    }
                    let terminated = signals.terminated.load(Ordering::SeqCst);
                    return ExitCode::from(if terminated { 143 } else { 130 });
                }
            }
            run_failure(&e)
        }
    }
}
