//! A validated 3D scene ([`SpaceScene`], from a file with `[grid] dimension = 3`) and the one
//! place where its run-time choices become types ([`dispatch_space`]): the model of the
//! materials × the shape functions on the regular 3D grid, or trilinear on the terrain grid
//! over a DEM (`mpm-grid3d`), for the 3D build of the solver (`mpm-solver3d`).

use mpm_grid3d::{
    Bilinear, LocateError, RegularGrid, RegularShape, ShapeFunctions, ShapeJob, TerrainGrid,
    with_regular_shape,
};
use mpm_solver3d::{NewParticle, Particles, SolverConfig, Stress, Vector};

use crate::error::SceneError;
use crate::file::{ShapeFunctionKind, SpaceFile, VtkField, VtkFormat};
use crate::materials::{ModelJob, SceneModel};
use crate::scene::{EnergyAlarm, MaterialsBuilt, StopAtRest, Warning};

/// A validated 3D scene, ready to run.
#[derive(Clone, Debug)]
pub struct SpaceScene {
    /// the directory the scene's named files (a terrain grid's DEM) are relative to.
    pub(crate) dir: Option<std::path::PathBuf>,
    /// the files it read, with their contents' fingerprints.
    pub(crate) inputs: Vec<crate::inputs::InputFile>,
    /// the folder its named files were found in, absolute as the scene was loaded (`None` for
    /// an embedded scene).
    pub(crate) files_dir: Option<String>,
    pub(crate) origin: String,
    pub(crate) text: String,
    pub(crate) file: SpaceFile,
    /// the grid.
    pub grid: SpaceGrid,
    /// the shape functions.
    pub shape_function: ShapeFunctionKind,
    /// particles per cell along each axis that uGIMP's particle size follows (the largest of
    /// the bodies').
    pub gimp_ppc: usize,
    /// the materials the bodies use, in index order.
    pub materials: MaterialsBuilt,
    /// their names, in index order.
    pub material_names: Vec<String>,
    /// the particles, bodies in file order.
    pub seeds: Vec<SpaceSeed>,
    /// the 3D solver's settings.
    pub config: SolverConfig,
    /// simulated end time (s).
    pub end_time: f64,
    /// the time step of the first step (s).
    pub initial_dt: f64,
    /// most steps the run may take.
    pub max_steps: u64,
    /// the energy alarm.
    pub alarm: EnergyAlarm,
    /// when the run ends early because the material has come to rest.
    pub stop_at_rest: Option<StopAtRest>,
    /// what the run writes.
    pub output: SpaceOutput,
    /// the direction the runout measures follow: the horizontal part of gravity, or +x when
    /// gravity is vertical (unit, in the x–z plane).
    pub runout_direction: Vector,
    /// the plausibility warnings, less the silenced ones.
    pub warnings: Vec<Warning>,
}

/// The grid of a 3D scene: regular, or terrain-following over a DEM.
#[derive(Clone, Debug, PartialEq)]
pub enum SpaceGrid {
    /// the regular grid of cubes.
    Regular(RegularGrid),
    /// the terrain-following grid over a DEM (trilinear shape functions only).
    Terrain(TerrainGrid),
}

impl SpaceGrid {
    /// the cell containing `p`, or why there is none.
    pub fn locate(&self, p: Vector) -> Result<(), LocateError> {
        match self {
            SpaceGrid::Regular(g) => g.locate(p).map(|_| ()),
            SpaceGrid::Terrain(g) => g.locate(p).map(|_| ()),
        }
    }

    /// the smallest cell dimension the time step follows (m).
    pub fn min_cell_size(&self) -> f64 {
        match self {
            SpaceGrid::Regular(g) => g.min_cell_size(),
            SpaceGrid::Terrain(g) => g.min_cell_size(),
        }
    }

    /// the side of a cell in plan (m): particles are spaced by it over their particles per
    /// cell, and the hazard maps' cells are it.
    pub fn plan_cell(&self) -> f64 {
        match self {
            SpaceGrid::Regular(g) => g.cell_size().x,
            SpaceGrid::Terrain(g) => g.spacing()[0],
        }
    }

    /// cells along x, y (a terrain grid's layers) and z.
    pub fn cells(&self) -> [usize; 3] {
        match self {
            SpaceGrid::Regular(g) => g.cells(),
            SpaceGrid::Terrain(g) => {
                let [nx, nz] = g.plan_cells();
                [nx, g.layers().1, nz]
            }
        }
    }

    /// the plan's lowest corner (x₀, z₀) (m).
    pub fn plan_origin(&self) -> [f64; 2] {
        match self {
            SpaceGrid::Regular(g) => [g.origin().x, g.origin().z],
            SpaceGrid::Terrain(g) => g.plan_origin(),
        }
    }

    /// the plan's highest corner (x₁, z₁) (m).
    pub fn plan_end(&self) -> [f64; 2] {
        let [x0, z0] = self.plan_origin();
        let [nx, _, nz] = self.cells();
        let h = self.plan_cell();
        [x0 + nx as f64 * h, z0 + nz as f64 * h]
    }

    /// the ground's height under plan point (x, z) and the vertical component of its upward
    /// unit normal (the cosine of its slope): the floor y₀ and 1 on a regular grid.
    pub fn ground(&self, x: f64, z: f64) -> (f64, f64) {
        match self {
            SpaceGrid::Regular(g) => (g.origin().y, 1.0),
            SpaceGrid::Terrain(g) => (g.ground_height(x, z), g.ground_normal(x, z).y),
        }
    }
}

/// What a 3D run writes.
#[derive(Clone, Debug)]
pub struct SpaceOutput {
    /// simulated time between particle frames (s).
    pub interval: f64,
    /// simulated time between rows of the CSV series (s).
    pub series_interval: f64,
    /// whether steps are shortened to end on every output mark (`exact_times`).
    pub exact_times: bool,
    /// whether frames are written.
    pub vtk: bool,
    /// how frames store their arrays.
    pub vtk_format: VtkFormat,
    /// the point-data arrays of a frame.
    pub fields: Vec<VtkField>,
    /// whether PNG plots are drawn at the end.
    pub plots: bool,
    /// simulated time between checkpoints (s); a checkpoint is also written on an interrupt.
    pub checkpoint_interval: Option<f64>,
    /// whether hazard maps are observed every step and written at the end
    /// ([`crate::plan::PlanEnvelope`]).
    pub hazard_maps: bool,
    /// whether hazard envelopes are observed every step along the runout line, the vertical
    /// section through the source's centre of mass along `runout_direction`, in a strip one
    /// plan cell wide (`envelope.csv`, `deposit.csv`, `section.geojson`).
    pub envelope: bool,
    /// an observed deposit to compare the run's with (`[output] observed = { deposit =
    /// "depth.asc" }`): the file as the scene names it and its raster of vertical depths.
    pub observed: Option<(String, mpm_dem::Raster)>,
    /// the coordinate reference system of a terrain grid's DEM, which the maps are written
    /// with (none on a regular grid, or when the DEM's file states none).
    pub crs: mpm_dem::Crs,
    /// the probed particles (`output.probes`, resolved to indices), whose position,
    /// displacement and velocity `probes.csv` records at every series interval.
    pub probes: Vec<usize>,
}

/// One 3D material point before the constitutive state is attached.
#[derive(Clone, Copy, Debug)]
pub struct SpaceSeed {
    /// position (m).
    pub position: Vector,
    /// initial velocity (m/s).
    pub velocity: Vector,
    /// volume (m³).
    pub volume: f64,
    /// initial density (kg/m³).
    pub density: f64,
    /// material index.
    pub material: u16,
    /// body index (file order).
    pub body: u16,
}

impl SpaceScene {
    /// where the text came from.
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// the memory its run peaks at (bytes) for a constitutive state of `state` bytes a particle:
    /// what a scene is refused for when it does not fit, and what `mpm check` reports.
    pub fn peak_bytes(&self, state: usize) -> u64 {
        let o = &self.output;
        let frame = if o.vtk { o.vtk_format.frame_bytes(self.seeds.len(), &o.fields) } else { 0 };
        let apic = self.config.transfer == mpm_solver3d::Transfer::Apic;
        crate::validate::space::peak_bytes(
            self.seeds.len(),
            &self.grid,
            self.shape_function,
            state,
            apic,
            frame,
        )
    }

    /// the files the scene read (the DEM, rasters), with their fingerprints.
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
    pub fn file(&self) -> &SpaceFile {
        &self.file
    }

    /// the scene's title, if it has one.
    pub fn title(&self) -> Option<&str> {
        self.file.title.as_deref()
    }

    /// the DEM a terrain grid follows, as the scene names it (`None` on a regular grid).
    pub fn dem(&self) -> Option<&str> {
        self.file.grid.dem.as_deref()
    }

    /// number of particles.
    pub fn particle_count(&self) -> usize {
        self.seeds.len()
    }
}

/// Work generic over the model and the 3D shape functions.
pub trait SpaceJob {
    /// what the job returns.
    type Output;
    /// runs with concrete types.
    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &SpaceScene,
        shape: S,
        materials: Vec<M>,
    ) -> Self::Output;
}

/// Builds the scene's shape functions and materials and runs `job` with them.
pub fn dispatch_space<J: SpaceJob>(scene: &SpaceScene, job: J) -> Result<J::Output, SceneError> {
    struct WithModel<'a, J, M> {
        job: J,
        scene: &'a SpaceScene,
        materials: Vec<M>,
    }
    impl<J: SpaceJob, M: SceneModel> ShapeJob for WithModel<'_, J, M> {
        type Output = J::Output;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> J::Output {
            self.job.run(self.scene, shape, self.materials)
        }
    }
    struct WithScene<'a, J> {
        job: J,
        scene: &'a SpaceScene,
    }
    impl<J: SpaceJob> ModelJob for WithScene<'_, J> {
        type Output = Result<J::Output, SceneError>;
        fn run<M: SceneModel>(self, materials: Vec<M>) -> Self::Output {
            let scene = self.scene;
            let kind = match scene.shape_function {
                ShapeFunctionKind::Bilinear => RegularShape::Bilinear,
                ShapeFunctionKind::Gimp => RegularShape::Gimp,
                ShapeFunctionKind::Bspline => RegularShape::BSpline,
            };
            let grid = match &scene.grid {
                SpaceGrid::Regular(g) => *g,
                // (validation refused other shape functions on a terrain grid)
                SpaceGrid::Terrain(t) => {
                    return Ok(self.job.run(scene, Bilinear(t.clone()), materials));
                }
            };
            let job = WithModel { job: self.job, scene, materials };
            with_regular_shape(kind, grid, scene.gimp_ppc, job).map_err(|e| SceneError {
                origin: scene.origin.clone(),
                line: None,
                column: None,
                path: "solver.shape_function".into(),
                value: Some(format!("\"{}\"", scene.shape_function.name())),
                problem: e.to_string(),
                admissible: "particles_per_cell ≥ 1".into(),
                fix: "check particles_per_cell".into(),
            })
        }
    }
    scene.materials.run(WithScene { job, scene })
}

/// The scene's particles with each material's initial state.
pub fn space_particles<M: SceneModel>(seeds: &[SpaceSeed], materials: &[M]) -> Particles<M::State> {
    let mut p = Particles::with_capacity(seeds.len());
    for s in seeds {
        let state =
            materials.get(usize::from(s.material)).map(|m| m.initial_state()).unwrap_or_default();
        p.push(NewParticle {
            position: s.position,
            velocity: s.velocity,
            volume: s.volume,
            density: s.density,
            stress: Stress::ZERO,
            state,
            material: s.material,
            body: s.body,
        });
    }
    p
}

/// The dimension a scene text declares (`[grid] dimension`, default 2), read without validating
/// anything else: front ends route a file to [`crate::load_scene_str`] or
/// [`crate::load_space_str`] by it. A text that is not TOML, or whose dimension is not an
/// integer, reads as 2 (the 2D loader then reports what is wrong, located).
pub fn declared_dimension(text: &str) -> i64 {
    let Ok(table) = text.parse::<toml::Table>() else { return 2 };
    table
        .get("grid")
        .and_then(|g| g.get("dimension"))
        .and_then(toml::Value::as_integer)
        .unwrap_or(2)
}
