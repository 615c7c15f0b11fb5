//! A validated scene: the file as written, and everything a run needs derived from it (the
//! grid, the materials, the particle seeds, the solver settings, the output plan).

use mpm_contact::RigidSlide;
use mpm_grid::{RegularGrid, TerrainGrid};
use mpm_solver::{SolverConfig, Vector};

use crate::file::{ReferenceCurve, SceneFile, ShapeFunctionKind, VtkField, VtkFormat};
pub use crate::materials::MaterialsBuilt;

/// A validated scene, ready to run.
#[derive(Clone, Debug)]
pub struct Scene {
    pub(crate) origin: String,
    pub(crate) text: String,
    pub(crate) file: SceneFile,
    pub(crate) r: Resolved,
    /// the directory the scene's named files are relative to.
    pub(crate) dir: Option<std::path::PathBuf>,
    /// the files it read, with their contents' fingerprints.
    pub(crate) inputs: Vec<crate::inputs::InputFile>,
    /// the folder its named files were found in, absolute as the scene was loaded (`None` for
    /// an embedded scene).
    pub(crate) files_dir: Option<String>,
}

/// A value inside its range that is most likely a unit or convention mistake (a friction angle
/// written as a coefficient): printed, listed in `summary.json`, never a refusal. `silence =
/// ["NAME"]` in the scene turns one off.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// the warning's name, for `silence`.
    pub name: String,
    /// the field path it concerns.
    pub field: String,
    /// what is likely wrong and how to write it.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "`{}`: {} (if that is meant: `silence = [\"{}\"]`)",
            self.field, self.message, self.name
        )
    }
}

/// The background grid, built.
#[derive(Clone, Debug)]
pub enum GridBuilt {
    /// the terrain-following grid of skewed rectangles (eqs 19–20).
    Terrain(TerrainGrid),
    /// a regular rectangular grid.
    Regular(RegularGrid),
}

impl GridBuilt {
    /// x of the grid's first and last columns of nodes (its left and right sides, m).
    pub fn x_range(&self) -> (f64, f64) {
        match self {
            GridBuilt::Terrain(t) => t.x_range(),
            GridBuilt::Regular(g) => (g.origin().x, g.upper_corner().x),
        }
    }

    /// the width of a column: the stations of the runout measures, envelopes and DEM sections.
    pub fn column_width(&self) -> f64 {
        match self {
            GridBuilt::Terrain(t) => t.cell_width(),
            GridBuilt::Regular(g) => g.cell_size().x,
        }
    }
}

/// One material point before the constitutive state is attached.
#[derive(Clone, Copy, Debug)]
pub struct Seed {
    /// position (m).
    pub position: Vector,
    /// initial velocity (m/s).
    pub velocity: Vector,
    /// volume (m³ per m of thickness).
    pub volume: f64,
    /// initial density (kg/m³).
    pub density: f64,
    /// material index (the used materials in name order).
    pub material: u16,
    /// body index (file order).
    pub body: u16,
}

/// An analytic reference curve with its parameters taken from the scene.
#[derive(Clone, Copy, Debug)]
pub struct Reference {
    /// the curve the scene names.
    pub curve: ReferenceCurve,
    /// the rigid block it describes (eq 21: on the level with the probe's speed; eq 22: from
    /// rest down the ground under the probe).
    pub slide: RigidSlide,
    /// unit direction the probe displacement is measured along.
    pub direction: Vector,
}

impl Reference {
    /// the reference displacement along `direction` at time t (s).
    pub fn displacement(&self, t: f64) -> f64 {
        self.slide.displacement(t)
    }
}

/// Resolved output settings.
#[derive(Clone, Debug)]
pub struct ResolvedOutput {
    /// simulated time between particle frames (s).
    pub interval: f64,
    /// simulated time between rows of the CSV series (s).
    pub series_interval: f64,
    /// whether steps are shortened to end on every output mark (`exact_times`).
    pub exact_times: bool,
    /// the point-data arrays of a frame.
    pub fields: Vec<VtkField>,
    /// whether frames are written.
    pub vtk: bool,
    /// how frames store their arrays.
    pub vtk_format: VtkFormat,
    /// whether PNG plots are drawn at the end.
    pub plots: bool,
    /// whether hazard envelopes along the path are recorded (every step) and written.
    pub envelope: bool,
    /// the observed deposit the run's is compared with.
    pub observed: Option<crate::observed::ObservedDeposit>,
    /// the probed particles' indices.
    pub probes: Vec<usize>,
    /// the analytic curve the first probe is compared with.
    pub reference: Option<Reference>,
    /// simulated time between checkpoints (s).
    pub checkpoint_interval: Option<f64>,
}

/// Everything the run needs, derived from the file.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// the background grid.
    pub grid: GridBuilt,
    /// the shape functions.
    pub shape_function: ShapeFunctionKind,
    /// particles per cell used by uGIMP (the largest of the bodies').
    pub gimp_ppc: usize,
    /// the materials the bodies use, in index order.
    pub materials: MaterialsBuilt,
    /// the materials' names, in index order (`[materials.NAME]` keys the bodies use).
    pub material_names: Vec<String>,
    /// the plausibility warnings of the scene, less the silenced ones.
    pub warnings: Vec<Warning>,
    /// the particles, bodies in file order.
    pub seeds: Vec<Seed>,
    /// the solver settings (after presets and defaults).
    pub config: SolverConfig,
    /// simulated end time (s).
    pub end_time: f64,
    /// what the run writes.
    pub output: ResolvedOutput,
    /// the ground polyline (terrain profile, or the floor of a regular grid).
    pub ground: Vec<Vector>,
    /// smallest particle spacing (m).
    pub spacing: f64,
    /// the time step the first step will take (s).
    pub initial_dt: f64,
    /// when the energy residual stops or flags a run.
    pub alarm: EnergyAlarm,
    /// most steps the run may take.
    pub max_steps: u64,
    /// when a run ends early because the material has come to rest.
    pub stop_at_rest: Option<StopAtRest>,
    /// how the initial stresses are found.
    pub initial_state: InitialState,
    /// the map line of a terrain grid whose profile is a DEM section; `None` otherwise.
    pub section: Option<SectionLine>,
}

/// The map line a DEM section runs along (`grid.profile = { dem, from, to }`): the scene's x
/// is the distance along it from `from` (the station), so x stands at
/// `from + x (to − from) / |to − from|` on the map, as `mpm_dem::Raster::section` places its
/// stations.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionLine {
    /// the DEM file as the scene names it.
    pub dem: String,
    /// the section's start, map (x, y) (m).
    pub from: [f64; 2],
    /// its end, map (x, y) (m).
    pub to: [f64; 2],
}

impl SectionLine {
    /// the map (x, y) of station `x` (m along the line from `from`).
    pub fn map(&self, x: f64) -> [f64; 2] {
        let (dx, dy) = (self.to[0] - self.from[0], self.to[1] - self.from[1]);
        let t = x / dx.hypot(dy);
        [self.from[0] + t * dx, self.from[1] + t * dy]
    }
}

/// How a new run finds its initial stresses (`[initial_state]`); a resumed run has them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum InitialState {
    /// stress-free.
    #[default]
    None,
    /// `mpm_solver::Solver::solve_geostatic` with these settings.
    Implicit(mpm_solver::GeostaticSettings),
    /// `mpm_solver::Solver::settle`: gravity ramped over `ramp` seconds, held `hold` more.
    GravityRamp {
        /// ramp time (s)
        ramp: f64,
        /// hold time (s)
        hold: f64,
    },
}

/// Default `[solver] energy_alarm`: the largest |residual| / energy scale a run may reach
/// before it is flagged (see `mpm_solver::EnergyCheck` for the scale). Measured: the embedded
/// scenes and collapsing columns of every scheme stay within 4 %, the paper's node contact on the
/// free fall reaches 7–10 %; an elastic block of E = 1 kPa crushed flat on the floor reaches
/// −40 %, a sand block dropped 100 m between walls −22 % (it bounces 8 m high).
pub const DEFAULT_ENERGY_ALARM: f64 = 0.2;

/// Default `[solver] pic_fraction` of scenes of granular materials (Drucker-Prager, Mohr–Coulomb,
/// μ(I)); elastic scenes keep the paper's pure FLIP. The smallest share per step measured to
/// bring every deposit to rest: the flume run to 60 s keeps at most 3.9e-7 of its peak kinetic
/// energy after 5 s (pure FLIP: 6 J/m for ever, and a grain thrown out at 22.65 s; 1e-4 per step:
/// 1.5e-4, and a grain 0.6 m beyond the front), and the column collapses of
/// `cargo xtask verify --quick` come to rest. A share per step damps at the rate β/Δt, so the
/// answer follows Δt (the stiffness, the Courant number): a 3D column ran (R∞ − R0)/R0 = 0.865
/// at Courant 0.1 and 1.004 at 0.3, and 0.838 against 1.242 with 1e-4 per step
/// (`docs/runout.md`). `[solver] pic_relaxation` gives the share as a relaxation time instead,
/// the same damping per second whatever Δt; as τ = 2 √(L/g) it left an a = 0.5 column of
/// `cargo xtask verify --quick` at 8.9e-6 of its peak kinetic energy and threw a grain of another,
/// which is why it is not the default. Ten times more (0.01 per step) shortens a = 0.5 to 2
/// collapses by a third.
pub const GRANULAR_PIC_FRACTION: f64 = 0.001;

/// Default `[solver] separation_density` of Drucker-Prager scenes (μ(I) tracks its own opening):
/// a particle below half its material's reference density is a separated grain and carries no
/// stress (`mpm_solver::SolverConfig::separation_density` says why half).
pub const GRANULAR_SEPARATION_DENSITY: f64 = 0.5;

/// Default `[solver] max_steps`.
pub const DEFAULT_MAX_STEPS: u64 = 100_000_000;

/// The energy alarm of a run.
#[derive(Clone, Copy, Debug)]
pub struct EnergyAlarm {
    /// largest admissible |residual| / scale.
    pub threshold: f64,
    /// stop the run when it trips.
    pub stop: bool,
}

/// `[solver] stop_at_rest`, checked: the run ends with status `at_rest` once the kinetic energy
/// has stayed below `kinetic_fraction` of its peak for `duration` seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopAtRest {
    /// fraction of the run's peak kinetic energy.
    pub kinetic_fraction: f64,
    /// time (s) the kinetic energy must stay below it.
    pub duration: f64,
}

impl Scene {
    /// where the text came from (a path or `embedded:NAME`).
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// the files the scene read (DEMs, rasters, CSV polylines), with their fingerprints.
    pub fn inputs(&self) -> &[crate::inputs::InputFile] {
        &self.inputs
    }

    /// the folder its named files were found in, absolute as the scene was loaded (`None` for
    /// an embedded scene): what a checkpoint records for `mpm resume`.
    pub fn files_dir(&self) -> Option<&str> {
        self.files_dir.as_deref()
    }

    /// where an edited copy of the scene finds its named files: the folder they were found in
    /// as it was loaded (a later change of working directory does not move them).
    pub(crate) fn files_base(&self) -> Option<&std::path::Path> {
        self.files_dir.as_deref().map(std::path::Path::new).or(self.dir.as_deref())
    }

    /// the scene's text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// the parsed file.
    pub fn file(&self) -> &SceneFile {
        &self.file
    }

    /// a stable hash of the scene text (FNV-1a 64, hex).
    pub fn hash(&self) -> String {
        format!("{:016x}", fnv1a(self.text.as_bytes()))
    }

    /// number of particles the scene generates.
    pub fn particle_count(&self) -> usize {
        self.r.seeds.len()
    }

    /// simulated end time (s).
    pub fn end_time(&self) -> f64 {
        self.r.end_time
    }

    /// the Δt of the first step (s).
    pub fn initial_dt(&self) -> f64 {
        self.r.initial_dt
    }

    /// the solver settings the run will use (after presets and defaults).
    pub fn solver_config(&self) -> &SolverConfig {
        &self.r.config
    }

    /// everything the run needs, derived from the file.
    pub fn resolved(&self) -> &Resolved {
        &self.r
    }

    /// the material `[materials.NAME]` a body uses, built (`None` for a name no body uses).
    pub fn material(&self, name: &str) -> Option<crate::materials::AnyModel> {
        let i = self.r.material_names.iter().position(|n| n == name)?;
        self.r.materials.get(i)
    }

    /// the shape functions the run will use.
    pub fn shape_function(&self) -> ShapeFunctionKind {
        self.r.shape_function
    }
}

/// FNV-1a 64-bit hash: stable across platforms and versions.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
