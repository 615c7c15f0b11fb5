//! From a 3D scene's text (`[grid] dimension = 3`) to a [`SpaceScene`]: the grid, the bodies
//! (boxes, cylinders, prisms), the grid's five faces (the top is open) and walls as planes, and the solver settings; the
//! materials and most of `[solver]` are checked by the 2D modules. Every refusal names its
//! field, line and column, as in 2D.

use glam::DVec2;
use mpm_contact3d::{Friction, Wall};
use mpm_grid3d::{MAX_CELLS_PER_AXIS, RegularGrid, TerrainGrid, TerrainGridSpec};
use mpm_solver3d::generate::{self, Shape};
use mpm_solver3d::{Boundaries, Outflow, Periodic, SolverConfig, TimeStep, Vector};

use super::{Ctx, bodies, boundaries, finite_pos, materials, num, plausible, serde_error, solver};
use crate::error::SceneError;
use crate::file::{
    Axis, BoundarySpec, GridKind, ShapeFunctionKind, SpaceBodySpec, SpaceFile, SpaceShapeKind,
    VtkField,
};
use crate::limits::{MAX_BODIES, MAX_PARTICLES, MAX_PARTICLES_PER_CELL, MAX_VERTICES};
use crate::materials::MaterialsBuilt;
use crate::source::SourceMap;
use crate::space::{SpaceGrid, SpaceOutput, SpaceScene, SpaceSeed};

mod body;

mod grid;

fn triple(p: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(p[0]), num(p[1]), num(p[2]))
}

/// Parses and validates a 3D scene; `origin` names the text in messages, and the files it
/// names (a terrain grid's DEM) are relative to the working directory.
pub fn load_space_str(text: &str, origin: &str) -> Result<SpaceScene, SceneError> {
    load_space(text, origin, None)
}

/// [`load_space_str`] for a scene whose named files are relative to `dir` (the directory of
/// the scene file).
pub fn load_space_str_in(
    text: &str,
    origin: &str,
    dir: &std::path::Path,
) -> Result<SpaceScene, SceneError> {
    load_space(text, origin, Some(dir))
}

pub(super) fn load_space(
    text: &str,
    origin: &str,
    dir: Option<&std::path::Path>,
) -> Result<SpaceScene, SceneError> {
    super::bounded(text, origin)?;
    let map = SourceMap::new(text);
    let ctx = Ctx { origin, map: &map, dir, inputs: Default::default() };
    // R3-07: a 3D scene whose dimension was set to anything else (Python's `Scene.set`) would run
    // as 3D under a text that says otherwise, and its run could not be resumed
    let declared = crate::space::declared_dimension(text);
    if declared != 3 {
        return Err(ctx.err(
            "grid.dimension",
            Some(declared.to_string()),
            "a 3D scene's dimension is 3",
            "3 here; a 2D scene is a scene of its own (2D scenes are read by `load_scene_str`)",
            "keep `dimension = 3`, or load the 2D scene as a scene of its own",
        ));
    }
    // The plane-strain tables, refused before their own fields are read (whatever they hold,
    // they are 2D only).
    let table = text.parse::<toml::Table>().unwrap_or_default();
    let boundaries = table.get("boundaries").and_then(toml::Value::as_table);
    if table.contains_key("initial_state") {
        return Err(ctx.err(
            "initial_state",
            None,
            "the implicit initial state (geostatic) is 2D only",
            "no `[initial_state]` in a 3D scene",
            "remove `[initial_state]`; in 3D, let the bodies settle under a ramped gravity \
             (`[solver] gravity_ramp`) before the flow starts",
        ));
    }
    if boundaries.is_some_and(|b| b.contains_key("side_walls")) {
        return Err(ctx.err(
            "boundaries.side_walls",
            None,
            "side walls across the plane are a plane-strain (2D) model",
            "no `side_walls` in a 3D scene",
            "in 3D the channel's walls are faces of the grid: declare `back_wall` and \
             `front_wall` with their friction, e.g. `{ friction_angle_deg = 20.0 }`",
        ));
    }
    let file: SpaceFile = toml::from_str(text).map_err(|e| serde_error(&ctx, &e))?;
    let mut scene = resolve(&ctx, file, text)?;
    scene.dir = dir.map(std::path::Path::to_path_buf);
    scene.inputs = crate::inputs::fingerprints(ctx.inputs.take());
    scene.files_dir = crate::inputs::absolute_dir(origin, dir);
    Ok(scene)
}

fn resolve(ctx: &Ctx<'_>, f: SpaceFile, text: &str) -> Result<SpaceScene, SceneError> {
    let settings = solver::settings(ctx, &f.solver, 3)?;
    let gravity = Vector::from_array(settings.gravity);
    let (grid, surface, crs) = grid::grid(ctx, &f)?;
    let shape_function = f
        .solver
        .shape_function
        .or(settings.preset.map(|p| p.shape_function))
        .unwrap_or(ShapeFunctionKind::Bilinear);
    if matches!(grid, SpaceGrid::Terrain(_)) && shape_function != ShapeFunctionKind::Bilinear {
        return Err(ctx.err(
            "solver.shape_function",
            Some(format!("\"{}\"", shape_function.name())),
            "the terrain grid offers trilinear shape functions only",
            "\"bilinear\" (trilinear in 3D) on `[grid] kind = \"terrain\"`",
            "use `shape_function = \"bilinear\"`, or a regular grid for uGIMP and B-splines",
        ));
    }
    let built = materials::build(ctx, &f.materials)?;
    if f.bodies.is_empty() || f.bodies.len() > MAX_BODIES {
        return Err(ctx.err(
            "bodies",
            Some(f.bodies.len().to_string()),
            "a scene has at least one body",
            format!("1 to {MAX_BODIES} [[bodies]] tables"),
            "add a [[bodies]] table with a material and a shape",
        ));
    }
    let names: Vec<&str> = f.bodies.iter().map(|b| b.material.as_str()).collect();
    let (materials, used) = materials::select(ctx, &f.materials, &names, &built)?;
    let (seeds, gimp_ppc) = body::seeds(ctx, &f, (&grid, surface.as_ref()), &used)?;
    let config = config(ctx, &f, &grid, &settings, gravity, &materials)?;
    fits_in_memory(ctx, &f, &grid, seeds.len(), shape_function, materials.state_bytes())?;
    for (k, w) in config.walls.iter().enumerate() {
        if let Some(s) = seeds.iter().find(|s| w.contains(s.position)) {
            return Err(ctx.err(
                &format!("bodies[{}]", s.body),
                None,
                format!(
                    "this body starts behind boundaries.walls[{k}] (a particle at {} lies on \
                     the solid side of its plane)",
                    s.position
                ),
                "bodies on the side every wall's normal points to",
                "move the body, or reverse the wall's `normal` if it faces the wrong way",
            ));
        }
    }
    let initial_dt = first_dt(ctx, &f, &config, &grid, &materials, &seeds, settings.max_steps)?;
    let output = SpaceOutput { crs, ..output(ctx, &f, &grid, &seeds)? };
    super::output::no_probes_beside_outflow(ctx, config.outflow.any(), &output.probes)?;
    let warnings = plausible::space_warnings(ctx, &f, gravity.length())?;
    let runout_direction = runout_direction(ctx, &f, gravity)?;
    Ok(SpaceScene {
        dir: None,
        inputs: Vec::new(),
        files_dir: None,
        origin: ctx.origin.to_string(),
        text: text.to_string(),
        grid,
        shape_function,
        gimp_ppc,
        materials,
        material_names: used.iter().map(|n| n.to_string()).collect(),
        seeds,
        config,
        end_time: f.solver.end_time,
        initial_dt,
        max_steps: settings.max_steps,
        alarm: settings.alarm,
        stop_at_rest: settings.stop_at_rest,
        output,
        runout_direction,
        warnings,
        file: f,
    })
}

/// `[output] runout_direction`, made horizontal and unit; default the horizontal part of
/// gravity (the way a tilted-gravity slope falls), else +x.
fn runout_direction(ctx: &Ctx<'_>, f: &SpaceFile, gravity: Vector) -> Result<Vector, SceneError> {
    match f.output.runout_direction {
        None => Ok(Vector::new(gravity.x, 0.0, gravity.z).try_normalize().unwrap_or(Vector::X)),
        Some(d) => Vector::new(d[0], 0.0, d[2])
            .try_normalize()
            .filter(|_| d[1].is_finite())
            .ok_or_else(|| {
                ctx.err(
                    "output.runout_direction",
                    Some(triple(d)),
                    "no horizontal direction: x and z are both zero, or a component is not finite",
                    "[dx, dy, dz] with (dx, dz) finite and not both zero (dy is dropped)",
                    "give the way the flow runs in plan, e.g. `runout_direction = [1, 0, 0]`",
                )
            }),
    }
}

/// The memory a 3D run of `n` particles peaks at (bytes): the solver's own accounting
/// (`mpm_solver3d::estimated_bytes`, with every grid node active or `stencil` nodes per particle,
/// whichever is fewer), the scene's seeds, two more copies of the particles' state while a
/// checkpoint or the final state hash is taken (the copy and its encoding), and one frame being
/// written. R3-02: the solver's figure alone was 204 MB where the run peaked at 450 MB.
pub(crate) fn peak_bytes(
    n: usize,
    grid: &SpaceGrid,
    shape_function: ShapeFunctionKind,
    state: usize,
    apic: bool,
    frame: u64,
) -> u64 {
    let stencil = if shape_function == ShapeFunctionKind::Bilinear { 8 } else { 27 };
    let [nx, ny, nz] = grid.cells();
    let nodes = (nx + 3).saturating_mul(ny + 3).saturating_mul(nz + 3);
    let solver = mpm_solver3d::estimated_bytes(
        n,
        nodes.min(n.saturating_mul(stencil)),
        stencil,
        state,
        apic,
    );
    // (a copy of one particle's state, as `bodies::checkpoint_copy` counts it in 2D)
    let copy = 3 * size_of::<Vector>()
        + 2 * size_of::<f64>()
        + size_of::<mpm_solver3d::Stress>()
        + state
        + 2 * size_of::<u16>()
        + if apic { size_of::<mpm_solver3d::Matrix>() } else { 0 };
    solver + (n * (size_of::<SpaceSeed>() + 2 * copy)) as u64 + frame
}

/// refuses a 3D scene whose run would not fit in the memory this process may use, before the
/// solver allocates anything (R3-02: it aborted with SIGABRT under `ulimit -v`, and ran past
/// `MPM_MEMORY_LIMIT`).
fn fits_in_memory(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    grid: &SpaceGrid,
    n: usize,
    shape_function: ShapeFunctionKind,
    state: usize,
) -> Result<(), SceneError> {
    let Some((available, source)) = crate::limits::available_memory() else { return Ok(()) };
    let apic = f.solver.transfer == Some(mpm_solver::Transfer::Apic);
    let frame = if f.output.vtk.unwrap_or(true) {
        let fields = f.output.fields.clone().unwrap_or_else(|| VtkField::ALL.to_vec());
        f.output.vtk_format.unwrap_or_default().frame_bytes(n, &fields)
    } else {
        0
    };
    let need = peak_bytes(n, grid, shape_function, state, apic, frame);
    if need <= available {
        return Ok(());
    }
    Err(ctx.err(
        "bodies",
        None,
        format!(
            "the scene needs about {:.0} MB for {n} particles ({:.0} B each, with the grid, a \
             checkpoint and one frame being written), but only {:.0} MB are available ({source})",
            need as f64 / 1e6,
            need as f64 / n.max(1) as f64,
            available as f64 / 1e6
        ),
        format!("at most about {:.0} MB", available as f64 / 1e6),
        "use a coarser grid, fewer particles per cell or smaller bodies, or run it on a machine \
         with more memory",
    ))
}

/// the friction law of a face, if the scene names one.
fn law(
    ctx: &Ctx<'_>,
    path: &str,
    spec: Option<BoundarySpec>,
) -> Result<Option<Friction>, SceneError> {
    spec.map(|s| boundaries::friction_3d(ctx, path, s)).transpose()
}

/// The 3D solver's settings; where the scene is silent the materials' model decides, as in 2D.
fn config(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    grid: &SpaceGrid,
    settings: &solver::Settings,
    gravity: Vector,
    materials: &MaterialsBuilt,
) -> Result<SolverConfig, SceneError> {
    let b = &f.boundaries;
    // a side declared `"outflow"` has no law; it lets material leave through its plane
    let side = |path: &str, spec: Option<BoundarySpec>| match spec {
        Some(BoundarySpec::Outflow) => Ok(None),
        other => law(ctx, path, other),
    };
    let boundaries = Boundaries {
        ground: law(ctx, "boundaries.ground", b.ground)?,
        left_wall: side("boundaries.left_wall", b.left_wall)?,
        right_wall: side("boundaries.right_wall", b.right_wall)?,
        back_wall: side("boundaries.back_wall", b.back_wall)?,
        front_wall: side("boundaries.front_wall", b.front_wall)?,
    };
    let ([x0, z0], [x1, z1]) = (grid.plan_origin(), grid.plan_end());
    let at =
        |spec: Option<BoundarySpec>, c: f64| (spec == Some(BoundarySpec::Outflow)).then_some(c);
    let outflow = Outflow {
        x_min: at(b.left_wall, x0),
        x_max: at(b.right_wall, x1),
        z_min: at(b.back_wall, z0),
        z_max: at(b.front_wall, z1),
    };
    let periodic = if b.periodic {
        if b.left_wall.is_some() || b.right_wall.is_some() {
            return Err(ctx.err(
                "boundaries.periodic",
                Some("true".into()),
                "periodic sides cannot also be walls",
                "periodic = true without left_wall and right_wall",
                "remove `left_wall` and `right_wall`, or `periodic`",
            ));
        }
        let SpaceGrid::Regular(g) = grid else {
            return Err(ctx.err(
                "boundaries.periodic",
                Some("true".into()),
                "periodic sides need a regular grid (a terrain's two sides differ)",
                "periodic = true with `[grid] kind = \"regular\"`",
                "remove `periodic`, or use a regular grid",
            ));
        };
        let nx = g.cells()[0];
        Some(Periodic {
            x_min: g.origin().x,
            length: nx as f64 * g.cell_size().x,
            columns: nx as u32,
        })
    } else {
        None
    };
    let mut walls = Vec::new();
    for (k, w) in b.walls.iter().enumerate() {
        let path = format!("boundaries.walls[{k}]");
        let friction = boundaries::friction_3d(ctx, &format!("{path}.law"), w.law)?;
        let normal = Vector::from_array(w.normal);
        let wall = normal
            .try_normalize()
            .and_then(|n| Wall::plane(Vector::from_array(w.point), n, friction).ok())
            .ok_or_else(|| {
                ctx.err(
                    &path,
                    Some(format!("point {}, normal {}", triple(w.point), triple(w.normal))),
                    "a wall is a plane through a finite point with a non-zero normal",
                    "finite `point`, non-zero finite `normal` (into the material)",
                    "give the plane's point and the direction its material lies in",
                )
            })?;
        // R3-16: a plane on a face of a regular grid whose own law differs is two laws on one
        // plane (the floor's nodes took both, and its friction all but vanished)
        if let (SpaceGrid::Regular(g), Some(n)) = (grid, normal.try_normalize()) {
            let (lo, hi) = (g.origin(), g.upper_corner());
            let faces = [
                ("boundaries.ground", boundaries.ground, lo, Vector::Y),
                ("boundaries.left_wall", boundaries.left_wall, lo, Vector::X),
                ("boundaries.right_wall", boundaries.right_wall, hi, Vector::NEG_X),
                ("boundaries.back_wall", boundaries.back_wall, lo, Vector::Z),
                ("boundaries.front_wall", boundaries.front_wall, hi, Vector::NEG_Z),
            ];
            let slack = 1e-6 * g.min_cell_size();
            let point = Vector::from_array(w.point);
            let on = faces.iter().find(|(_, law, at, e)| {
                law.is_some_and(|l| l != friction)
                    && n.dot(*e).abs() > 1.0 - 1e-9
                    && (point - *at).dot(*e).abs() <= slack
            });
            if let Some((face, ..)) = on {
                return Err(ctx.err(
                    &path,
                    Some(format!("point {}, normal {}", triple(w.point), triple(w.normal))),
                    format!(
                        "the plane is the grid's face that `{face}` gives another law: two laws \
                         on one plane"
                    ),
                    "a wall off the grid's faces, or on a face with that face's own law",
                    format!("give the law as `{face}` and remove this wall"),
                ));
            }
        }
        walls.push(wall);
    }
    let c = solver::choices(ctx, &f.solver, materials)?;
    let config = SolverConfig {
        scheme: settings.scheme,
        time_step: settings.time_step,
        gravity,
        boundaries,
        periodic,
        outflow,
        walls,
        small_mass_ratio: settings.small_mass_ratio,
        objective_stress: c.objective_stress,
        gravity_ramp: settings.gravity_ramp,
        transfer: c.transfer,
        pic_fraction: c.pic_fraction,
        pic_relaxation: c.pic_relaxation,
        pic_weighting: c.pic_weighting,
        separation_density: c.separation_density,
        contact: c.contact,
        mass: c.mass,
    };
    config.validate().map_err(|e| {
        let (path, fix) = match &e {
            mpm_solver3d::SolverError::Incompatible { setting, .. } => {
                (format!("solver.{setting}"), "use an admissible combination")
            }
            mpm_solver3d::SolverError::InvalidSetting { name, .. } if *name == "walls" => (
                "boundaries.walls".to_string(),
                "remove the walls or `periodic = true` (walls beside periodic sides are not \
                 supported yet)",
            ),
            mpm_solver3d::SolverError::InvalidSetting { name, .. } => {
                (format!("solver.{name}"), "use an admissible value")
            }
            _ => ("solver".to_string(), "check the [solver] table"),
        };
        ctx.err(&path, None, e.to_string(), String::new(), fix)
    })?;
    Ok(config)
}

/// The Δt of the first step by the solver's rule, and the refusal of a scene that cannot end
/// within `max_steps`.
fn first_dt(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    config: &SolverConfig,
    grid: &SpaceGrid,
    materials: &MaterialsBuilt,
    seeds: &[SpaceSeed],
    max_steps: u64,
) -> Result<f64, SceneError> {
    let moduli = materials.p_wave_moduli();
    let signal = seeds
        .iter()
        .map(|s| (moduli[usize::from(s.material)] / s.density).sqrt() + s.velocity.length())
        .fold(0.0, f64::max);
    let v_max = seeds.iter().map(|s| s.velocity.length()).fold(0.0, f64::max);
    let min_cell = grid.min_cell_size();
    let dt =
        mpm_solver3d::stable_dt(config.time_step, min_cell, config.gravity.length(), signal, v_max)
            .map_err(|e| {
                let path = if matches!(config.time_step, TimeStep::Fixed(_)) {
                    "solver.dt"
                } else {
                    "solver"
                };
                ctx.err(
                    path,
                    None,
                    format!("the first time step is not stable: {e:?}"),
                    "a Courant number ≤ 1 at t = 0",
                    "replace `dt` by `courant = 0.1`",
                )
            })?;
    let steps = (f.solver.end_time / dt).ceil();
    if steps.is_nan() || steps > max_steps as f64 {
        return Err(ctx.err(
            "solver.end_time",
            Some(num(f.solver.end_time)),
            format!(
                "the run would take {steps:.0} steps or more (initial Δt {} s), above max_steps \
                 = {max_steps}",
                num(dt)
            ),
            format!("end_time / Δt ≤ max_steps = {max_steps}"),
            "shorten end_time, coarsen the grid, or raise `[solver] max_steps`",
        ));
    }
    Ok(dt)
}

/// `[output]` of a 3D scene: frames and series; the 2D-only outputs are refused.
fn output(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    grid: &SpaceGrid,
    seeds: &[SpaceSeed],
) -> Result<SpaceOutput, SceneError> {
    let o = &f.output;
    let refused = [("output.reference", o.reference.is_some())];
    if let Some((path, _)) = refused.iter().find(|(_, here)| *here) {
        return Err(ctx.err(
            path,
            None,
            "this output is not available in 3D scenes yet",
            "interval, series_interval, exact_times, checkpoint_interval, fields, vtk, \
             vtk_format, plots, probes, runout_direction, hazard_maps, envelope, observed",
            "remove it (3D runs write frames, energy.csv, runout.csv, probes.csv, checkpoints \
             and summary.json)",
        ));
    }
    let c = super::output::cadence(ctx, o, f.solver.end_time)?;
    let hazard_maps = o.hazard_maps.unwrap_or(false);
    let [nx, _, nz] = grid.cells();
    // per plan cell: its maxima (56 B) and one observation's sums (64 B)
    let plan_bytes = (nx as f64) * (nz as f64) * 120.0;
    let budget = crate::limits::available_memory().map_or(f64::INFINITY, |(b, _)| b as f64 / 4.0);
    if hazard_maps && ((nx * nz) as f64 > mpm_dem::MAX_CELLS as f64 || plan_bytes > budget) {
        return Err(ctx.err(
            "output.hazard_maps",
            Some("true".into()),
            format!(
                "the plan has {nx} × {nz} cells: its maps would take {:.1} GB (a raster has at \
                 most {} cells)",
                plan_bytes / 1e9,
                mpm_dem::MAX_CELLS
            ),
            "a plan whose maps fit in a quarter of the memory and in one raster",
            "coarsen the grid in plan or shrink it to the area the flow can reach",
        ));
    }
    // an observed deposit: a raster of vertical depths (m) in map coordinates
    let observed = match &o.observed {
        None => None,
        Some(spec) => {
            let raster = mpm_dem::Raster::read_within(
                &super::polyline::file_path(ctx, &spec.deposit),
                crate::limits::available_memory(),
            )
            .map_err(|e| super::polyline::dem_error(ctx, "output.observed.deposit", e))?;
            // R3-09: a comparison with nothing on the plan (all zero, holes, or another place:
            // a wrong CRS or offset) would be left out of the summary without a word. Sampled
            // as the comparison samples it: at each plan cell's centre, bilinearly.
            let ([x0, z0], [x1, z1]) = (grid.plan_origin(), grid.plan_end());
            let ([nx, _, nz], h) = (grid.cells(), grid.plan_cell());
            let on_plan = (0..nz).any(|k| {
                let z = z0 + (k as f64 + 0.5) * h;
                (0..nx).any(|i| {
                    let x = x0 + (i as f64 + 0.5) * h;
                    raster.height(x, -z).is_ok_and(|d| d > 0.0)
                })
            });
            if !on_plan {
                return Err(ctx.err(
                    "output.observed.deposit",
                    Some(format!("\"{}\"", spec.deposit)),
                    format!(
                        "the raster holds no positive depth at any plan cell's centre (x {} to \
                         {}, map y {} to {})",
                        num(x0),
                        num(x1),
                        num(-z1),
                        num(-z0)
                    ),
                    "a raster of the deposit's vertical depths (m), positive where it lies, in \
                     the DEM's map coordinates",
                    "check the raster's coordinates against the plan, and that it holds depths \
                     (a DEM difference), not elevations",
                ));
            }
            Some((spec.deposit.clone(), raster))
        }
    };
    let probes = super::output::probes(ctx, o, seeds.len(), 3, |at| {
        let at = Vector::new(at[0], at[1], at[2]);
        super::output::nearest(seeds.iter().map(|s| s.position.distance_squared(at)))
    })?;
    Ok(SpaceOutput {
        observed,
        probes,
        interval: c.interval,
        series_interval: c.series_interval,
        exact_times: c.exact_times,
        vtk: c.vtk,
        vtk_format: c.vtk_format,
        fields: c.fields,
        plots: c.plots,
        checkpoint_interval: c.checkpoint_interval,
        hazard_maps,
        envelope: c.envelope,
        crs: mpm_dem::Crs::default(),
    })
}

/// A polygon's vertices `[[u, v], ...]` at `path`: 3 to [`MAX_VERTICES`] finite corners, a closing
/// vertex that repeats the first dropped, refused (at the vertex) unless simple: a bow-tie, a
/// slip of the corners' order, would have only part of the inside the outline means.
fn simple_polygon(
    ctx: &Ctx<'_>,
    path: &str,
    vertices: &[[f64; 2]],
    what: &str,
    fix: &str,
) -> Result<Vec<DVec2>, SceneError> {
    if !(3..=MAX_VERTICES).contains(&vertices.len())
        || !vertices.iter().flatten().all(|x| x.is_finite())
    {
        return Err(ctx.err(
            path,
            Some(format!("{} vertices", vertices.len())),
            format!("{what} has 3 to {MAX_VERTICES} finite vertices"),
            format!("3 to {MAX_VERTICES} vertices (m)"),
            fix,
        ));
    }
    let mut polygon: Vec<DVec2> = vertices.iter().map(|v| DVec2::from_array(*v)).collect();
    // a closing vertex that repeats the first one is a common way to write an outline
    if polygon.len() > 3 && polygon.first() == polygon.last() {
        polygon.pop();
    }
    if let Some((a, c)) = bodies::self_intersection(&polygon) {
        return Err(ctx.err(
            &format!("{path}[{a}]"),
            Some(format!("[{}, {}]", num(vertices[a][0]), num(vertices[a][1]))),
            format!(
                "the polygon is not simple: its edge from vertex {a} crosses the edge from vertex \
                 {c} (a bow-tie has no inside)"
            ),
            "a simple polygon: edges meet only at their shared corners",
            fix,
        ));
    }
    Ok(polygon)
}

#[cfg(test)]
mod tests {
    use super::{load_space_str, load_space_str_in};
    use crate::limits::MAX_VERTICES;
    use crate::space::SpaceGrid;

    /// A 3D scene with a box, a cylinder and a prism over a rough floor; `extra` is appended
    /// (after the last table) and `swap` replaces one text for another.
    fn scene(swap: (&str, &str), extra: &str) -> String {
        let base = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [20, 10, 10]

[materials.sand]
kind = "drucker_prager"
young = 1.0e6
poisson = 0.3
density = 1600.0
cohesion = 0.0
friction_angle_deg = 30.0
cone_match = "outer"

[[bodies]]
material = "sand"
shape = "box"
min = [0.2, 0.0, 0.2]
max = [0.6, 0.4, 0.6]

[[bodies]]
material = "sand"
shape = "cylinder"
base = [1.0, 0.0, 0.5]
radius = 0.2
height = 0.3

[[bodies]]
material = "sand"
shape = "prism"
vertices = [[1.4, 0.0], [1.8, 0.0], [1.4, 0.4]]
axis = "z"
from = 0.1
to = 0.5

[boundaries]
ground = "rough"

[solver]
end_time = 0.1
"#;
        assert!(base.contains(swap.0), "the base scene has no `{}`", swap.0);
        base.replacen(swap.0, swap.1, 1) + extra
    }

    fn error(text: &str) -> String {
        match load_space_str(text, "test.toml") {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e.to_string(),
        }
    }

    /// The three shapes fill their volumes: the particles' summed volume against the box
    /// (0.4³), the cylinder (π 0.2² 0.3) and the prism (½ 0.4² · 0.4) within the lattice's
    /// staircase: one layer of 0.05 m particles over each curved or slanted surface, bounded by
    /// 0.05 m × that surface's area.
    #[test]
    fn the_three_shapes_fill_their_volumes() {
        let s = load_space_str(&scene(("", ""), ""), "test.toml").unwrap();
        let volume = |b: u16| s.seeds.iter().filter(|p| p.body == b).map(|p| p.volume).sum::<f64>();
        assert!((volume(0) - 0.064).abs() < 1e-12, "box {}", volume(0));
        let cyl = std::f64::consts::PI * 0.04 * 0.3;
        let side = 2.0 * std::f64::consts::PI * 0.2 * 0.3;
        assert!((volume(1) - cyl).abs() < 0.05 * side, "cylinder {} against {cyl}", volume(1));
        let slant = 0.4 * std::f64::consts::SQRT_2 * 0.4;
        assert!((volume(2) - 0.032).abs() < 0.05 * slant, "prism {}", volume(2));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// A cylinder's axis may have any non-zero length (R3-14): [0, 1e308, 1e308], whose length
    /// overflows, and [0, 1e-320, 0], whose length underflows, give the cylinders of [0, 1, 1]
    /// and [0, 1, 0] particle for particle; a zero vector is refused at `direction`.
    #[test]
    fn a_cylinder_axis_of_any_magnitude_gives_the_same_cylinder() {
        let cylinder = "base = [1.0, 0.0, 0.5]\nradius = 0.2\nheight = 0.3";
        let seeds = |d: &str| {
            let raised =
                format!("base = [1.0, 0.3, 0.5]\nradius = 0.15\nheight = 0.3\ndirection = {d}");
            let text = scene((cylinder, &raised), "");
            let s = load_space_str(&text, "test.toml").unwrap();
            s.seeds.iter().filter(|p| p.body == 1).map(|p| p.position).collect::<Vec<_>>()
        };
        let tilted = seeds("[0.0, 1.0, 1.0]");
        assert!(!tilted.is_empty());
        assert_eq!(seeds("[0.0, 1e308, 1e308]"), tilted);
        assert_eq!(seeds("[0.0, 1e-320, 0.0]"), seeds("[0.0, 1.0, 0.0]"));
        let e = error(&scene((cylinder, &format!("{cylinder}\ndirection = [0.0, 0.0, 0.0]")), ""));
        assert!(e.contains("bodies[1].direction") && e.contains("no direction"), "{e}");
    }

    #[test]
    fn a_body_behind_a_wall_plane_is_refused() {
        let wall = "\n[[boundaries.walls]]\npoint = [0.4, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n\
                    law = \"frictionless\"\n";
        let text = scene(("[boundaries]\nground = \"rough\"\n", ""), "")
            + "[boundaries]\nground = \"rough\"\n"
            + wall;
        let e = error(&text);
        assert!(e.contains("`bodies[0]`") && e.contains("boundaries.walls[0]"), "{e}");
        // facing −x from x = 0.7 the plane clears the box and cuts the cylinder
        let flipped = text
            .replace("normal = [1.0, 0.0, 0.0]", "normal = [-1.0, 0.0, 0.0]")
            .replace("point = [0.4, 0.0, 0.0]", "point = [0.7, 0.0, 0.0]");
        let e = error(&flipped);
        assert!(e.contains("`bodies[1]`"), "{e}");
        let clear = text.replace("point = [0.4, 0.0, 0.0]", "point = [0.1, 0.0, 0.0]");
        load_space_str(&clear, "test.toml").unwrap();
    }

    #[test]
    fn a_bow_tie_prism_is_refused_at_its_vertex() {
        let e = error(&scene(
            (
                "[[1.4, 0.0], [1.8, 0.0], [1.4, 0.4]]",
                "[[1.4, 0.0], [1.8, 0.4], [1.8, 0.0], [1.4, 0.4]]",
            ),
            "",
        ));
        assert!(e.contains("bodies[2].vertices[") && e.contains("not simple"), "{e}");
        // a closing vertex that repeats the first is an outline, not a crossing
        let closed = scene(
            (
                "[[1.4, 0.0], [1.8, 0.0], [1.4, 0.4]]",
                "[[1.4, 0.0], [1.8, 0.0], [1.4, 0.4], [1.4, 0.0]]",
            ),
            "",
        );
        load_space_str(&closed, "test.toml").unwrap();
    }

    /// `[output]` is one table in both dimensions, checked by one function: a field listed
    /// twice (a .vtp with two arrays of one name) and more than 1e6 frames are refused in 3D as
    /// in 2D, at their paths.
    #[test]
    fn the_output_table_is_checked_as_in_2d() {
        let twice = error(&scene(("", ""), "\n[output]\nfields = [\"velocity\", \"velocity\"]\n"));
        assert!(twice.contains("`output.fields[1]`") && twice.contains("listed twice"), "{twice}");
        let frames = error(&scene(("", ""), "\n[output]\ninterval = 1e-9\n"));
        assert!(frames.contains("`output.interval`") && frames.contains("1e6 frames"), "{frames}");
    }

    /// A plan too large for one raster (2²⁸ cells) is refused when the scene loads, not after
    /// the run; the same grid without hazard maps loads (the grid stores only nodes near
    /// material).
    #[test]
    fn hazard_maps_of_a_plan_too_large_are_refused_at_load() {
        let huge = scene(("cells = [20, 10, 10]", "cells = [20000, 10, 20000]"), "");
        load_space_str(&huge, "test.toml").unwrap();
        let e = error(&format!("{huge}\n[output]\nhazard_maps = true\n"));
        assert!(e.contains("`output.hazard_maps`") && e.contains("20000 × 20000"), "{e}");
        load_space_str(&scene(("", ""), "\n[output]\nhazard_maps = true\n"), "test.toml").unwrap();
    }

    #[test]
    fn the_geostatic_state_is_refused_as_2d_only() {
        for table in ["method = \"implicit\"", "kind = \"geostatic\""] {
            let e = error(&scene(("", ""), &format!("\n[initial_state]\n{table}\n")));
            assert!(e.contains("`initial_state`") && e.contains("2D only"), "{table}: {e}");
            assert!(e.contains(":45:1:"), "located at the table's header: {e}");
        }
    }

    /// Side walls across the plane are a plane-strain model: refused in 3D at their line,
    /// with the faces to use instead.
    #[test]
    fn side_walls_are_refused_as_2d_only() {
        let e = error(&scene(
            (
                "ground = \"rough\"\n",
                "ground = \"rough\"\nside_walls = { width = 0.2, friction = 0.4 }\n",
            ),
            "",
        ));
        assert!(e.contains("`boundaries.side_walls`") && e.contains("back_wall"), "{e}");
    }

    /// A Mohr–Coulomb sand loads in 3D and draws no cone warning (it has no cone to choose).
    #[test]
    fn mohr_coulomb_needs_no_cone_in_3d() {
        let text = scene(("kind = \"drucker_prager\"", "kind = \"mohr_coulomb\""), "")
            .replace("cone_match = \"outer\"\n", "");
        let s = load_space_str(&text, "test.toml").unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    /// R3-13: a grid at coordinates where doubles are coarser than a millionth of a cell (x = z
    /// = 1e15 m: 0.125 m apart, against 0.1 m cells) is refused at `grid.origin`, as is a
    /// terrain whose layers reach infinity (layer_height 1e308); map coordinates of a UTM size
    /// (5e6 m) are taken.
    #[test]
    fn coordinates_beyond_the_precision_of_doubles_are_refused() {
        let far = scene(("origin = [0.0, 0.0, 0.0]", "origin = [1.0e15, 0.0, 1.0e15]"), "");
        let e = error(&far);
        assert!(e.contains("`grid.origin`") && e.contains("doubles are"), "{e}");
        let utm = scene(("origin = [0.0, 0.0, 0.0]", "origin = [5.0e6, 0.0, -5.0e6]"), "")
            .replace("min = [0.2, 0.0, 0.2]", "min = [5000000.2, 0.0, -4999999.8]")
            .replace("max = [0.6, 0.4, 0.6]", "max = [5000000.6, 0.4, -4999999.4]");
        let dir = std::env::temp_dir().join(format!("mpm-precision-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let terrain = terrain_scene(&dir, "", 9.0)
            .replace("layer_height = 0.1\n", "layer_height = 1.0e308\n");
        let e = load_space_str_in(&terrain, "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("`grid.layer_height`") && e.contains("infinite"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
        // the UTM-sized box alone (the other bodies stay near the origin, off this grid): all
        // of its 8 × 8 × 8 particles (the fill's count allows for the rounding of its size there)
        let utm = utm.split("\n[[bodies]]").take(2).collect::<Vec<_>>().join("\n[[bodies]]")
            + "\n[boundaries]\nground = \"rough\"\n\n[solver]\nend_time = 0.1\n";
        let s = load_space_str(&utm, "t.toml").unwrap();
        assert_eq!(s.seeds.len(), 8 * 8 * 8);
    }

    /// R3-07: a 3D scene's dimension set to 2 (as Python's `Scene.set` does) is refused at
    /// `grid.dimension`: the scene would run as 3D under a text that says 2D.
    #[test]
    fn a_3d_scene_set_to_another_dimension_is_refused() {
        let s = load_space_str(&scene(("", ""), ""), "test.toml").unwrap();
        let e = s.with_value("grid.dimension", "2").unwrap_err().to_string();
        assert!(e.contains("`grid.dimension`") && e.contains("dimension is 3"), "{e}");
    }

    /// R3-16: a wall on a face of the grid whose law differs from the face's own (the rough
    /// floor and a frictionless plane on it; the left side) is refused at the wall, naming the
    /// face; the face's own law on it, and a plane off the faces, are taken.
    #[test]
    fn a_wall_on_a_face_with_another_law_is_refused() {
        let wall = |point: &str, normal: &str, law: &str| {
            scene(
                ("ground = \"rough\"\n", "ground = \"rough\"\nleft_wall = \"frictionless\"\n"),
                &format!(
                    "\n[[boundaries.walls]]\npoint = {point}\nnormal = {normal}\nlaw = \"{law}\"\n"
                ),
            )
        };
        let e = error(&wall("[0.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]", "frictionless"));
        assert!(e.contains("`boundaries.walls[0]`") && e.contains("`boundaries.ground`"), "{e}");
        let e = error(&wall("[0.0, 0.5, 0.5]", "[2.0, 0.0, 0.0]", "rough"));
        assert!(e.contains("`boundaries.left_wall`"), "{e}");
        for (point, normal, law) in [
            ("[0.5, 0.0, 0.5]", "[0.0, 1.0, 0.0]", "rough"),
            ("[1.95, 0.0, 0.0]", "[-1.0, 0.0, 0.0]", "frictionless"),
        ] {
            assert!(load_space_str(&wall(point, normal, law), "t.toml").is_ok(), "{point}");
        }
    }

    #[test]
    fn walls_beside_periodic_sides_are_refused_at_the_walls() {
        let e = error(&scene(
            ("ground = \"rough\"\n", "ground = \"rough\"\nperiodic = true\n"),
            "\n[[boundaries.walls]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
             law = \"rough\"\n",
        ));
        assert!(e.contains("`boundaries.walls`"), "{e}");
    }

    /// The warnings are the 2D ones over the five faces and the materials, with the 3D one of
    /// a plane-strain cone; `silence` removes them by name and refuses an unknown name.
    #[test]
    fn plausibility_warnings_and_silence_work_in_3d() {
        let warned = |text: &str| -> Vec<String> {
            let s = load_space_str(text, "test.toml").unwrap();
            s.warnings.iter().map(|w| w.name.clone()).collect()
        };
        let slip = scene(("ground = \"rough\"", "ground = { friction = 30.0 }"), "");
        assert_eq!(warned(&slip), ["friction_as_degrees"]);
        let cone = scene(("cone_match = \"outer\"\n", ""), "");
        assert_eq!(warned(&cone), ["plane_strain_cone_in_3d"]);
        let quiet = format!("silence = [\"plane_strain_cone_in_3d\"]\n{cone}");
        assert!(warned(&quiet).is_empty());
        let e = error(&format!("silence = [\"friction\"]\n{cone}"));
        assert!(e.contains("silence[0]"), "{e}");
    }

    #[test]
    fn the_runout_direction_is_made_horizontal_and_checked() {
        let s = load_space_str(&scene(("", ""), ""), "test.toml").unwrap();
        assert_eq!(s.runout_direction, mpm_solver3d::Vector::X);
        let text = scene(("", ""), "\n[output]\nrunout_direction = [0.0, 5.0, -2.0]\n");
        let s = load_space_str(&text, "test.toml").unwrap();
        assert_eq!(s.runout_direction, mpm_solver3d::Vector::NEG_Z);
        let e = error(&scene(("", ""), "\n[output]\nrunout_direction = [0.0, 1.0, 0.0]\n"));
        assert!(e.contains("`output.runout_direction`"), "{e}");
        // a 2D section runs along x: the field is refused there
        let flume = crate::validate::load_scene_str(
            crate::scenes::embedded_scene("flume").unwrap(),
            "flume",
        )
        .unwrap();
        let e = flume.modified(|f| f.output.runout_direction = Some([1.0, 0.0, 0.0])).unwrap_err();
        assert!(e.to_string().contains("`output.runout_direction`"), "{e}");
    }

    /// a terrain scene over `dem.asc` in `dir`: a plane falling 0.5 m per metre towards map
    /// east (30 × 20 cells of 0.1 m, south-west corner (100, 200)), a box released on it.
    fn terrain_scene(dir: &std::path::Path, grid_extra: &str, body_min_y: f64) -> String {
        let mut dem =
            String::from("ncols 30\nnrows 20\nxllcorner 100\nyllcorner 200\ncellsize 0.1\n");
        for _row in 0..20 {
            let line: Vec<String> =
                (0..30).map(|c| format!("{}", 10.0 - 0.5 * 0.1 * (c as f64 + 0.5))).collect();
            dem += &(line.join(" ") + "\n");
        }
        std::fs::write(dir.join("dem.asc"), dem).unwrap();
        format!(
            r#"
[grid]
dimension = 3
kind = "terrain"
dem = "dem.asc"
from = [100.05, 200.05]
to = [102.95, 201.95]
plan_cell = 0.1
layer_height = 0.1
layers = 12
{grid_extra}
[materials.sand]
kind = "drucker_prager"
young = 1.0e6
poisson = 0.3
density = 1600.0
cohesion = 0.0
friction_angle_deg = 30.0
cone_match = "outer"

[[bodies]]
material = "sand"
shape = "box"
min = [100.5, {body_min_y}, -201.5]
max = [101.0, 10.5, -200.5]

[boundaries]
ground = "rough"

[solver]
end_time = 0.1
"#
        )
    }

    /// A terrain grid over a DEM: the plan from `from` to `to` at `plan_cell` (map y = −z),
    /// the ground the DEM's plane at every lattice node, a box body kept above the ground
    /// only; the terrain's fields refused on a regular grid and the regular ones on a terrain,
    /// the plan not a whole number of cells refused with the fix, B-splines refused.
    #[test]
    fn a_terrain_grid_over_a_dem_is_read_and_checked() {
        let dir = std::env::temp_dir().join(format!("mpm-terrain3d-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = terrain_scene(&dir, "", 9.0);
        let s = load_space_str_in(&text, "t.toml", &dir).unwrap();
        let SpaceGrid::Terrain(t) = &s.grid else { panic!("{:?}", s.grid) };
        assert_eq!(t.plan_cells(), [29, 19]);
        assert_eq!(t.plan_origin(), [100.05, -201.95]);
        // the plane z = 10 − 0.5 (x − 100), exact under bilinear interpolation
        for (x, z) in [(100.05, -201.95), (101.3, -200.7), (102.95, -200.05)] {
            let g = t.ground_height(x, z);
            assert!((g - (10.0 - 0.5 * (x - 100.0))).abs() < 1e-12, "{x} {z}: {g}");
        }
        assert!(!s.seeds.is_empty());
        for seed in &s.seeds {
            let p = seed.position;
            assert!(p.y > t.ground_height(p.x, p.z), "{p}");
        }
        // the box from y = 9 m: its part above the plane (9.75 to 9.5 m under it), cut
        let lowest = s.seeds.iter().map(|q| q.position.y).fold(f64::INFINITY, f64::min);
        assert!(lowest > 9.5 && lowest < 9.6, "{lowest}");
        // without a directory the DEM is not found: the error names the field
        assert!(error(&text).contains("grid.dem"), "{}", error(&text));
        let e = load_space_str_in(&terrain_scene(&dir, "cells = [1, 1, 1]", 9.0), "t.toml", &dir)
            .unwrap_err()
            .to_string();
        assert!(e.contains("grid.cells"), "{e}");
        let e = load_space_str_in(&text.replace("to = [102.95", "to = [102.97"), "t.toml", &dir)
            .unwrap_err()
            .to_string();
        assert!(e.contains("grid.to") && e.contains("102.95"), "{e}");
        let spline = text.replace("[solver]\n", "[solver]\nshape_function = \"bspline\"\n");
        let e = load_space_str_in(&spline, "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("solver.shape_function") && e.contains("trilinear"), "{e}");
        let e = error(&scene(("cells = [20, 10, 10]", "cells = [20, 10, 10]\nlayers = 3"), ""));
        assert!(e.contains("grid.layers"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A release area cut 0.3 m into the DEM's plane: the release body's particles fill
    /// exactly the cut, 0.3 m × (the lattice nodes inside the polygon) × plan_cell² (each
    /// node's bilinear hat holds plan_cell² of plan; the columns' midpoint rule is exact on a
    /// bilinear depth), between the ground and the DEM's surface; a rupture raster 0.2 m below
    /// the DEM over its own extent cuts the same way; a release body without a cut, or with a
    /// box's fields, is refused.
    #[test]
    fn a_release_volume_fills_exactly_what_is_cut_into_the_dem() {
        let dir = std::env::temp_dir().join(format!("mpm-release3d-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = terrain_scene(&dir, "", 9.0);
        let body = "shape = \"box\"\nmin = [100.5, 9, -201.5]\nmax = [101.0, 10.5, -200.5]";
        assert!(text.contains(body));
        let release = text.replace(body, "shape = \"release\"");
        // a polygon holding lattice nodes x = 100.55 … 101.45 (10), y = 200.55 … 201.25 (8)
        let cut = "release_polygon = [[100.5, 200.5], [101.5, 200.5], [101.5, 201.3], [100.5, 201.3]]\n\
                   release_depth = 0.3";
        let s = load_space_str_in(
            &release.replace("layers = 12\n", &format!("layers = 12\n{cut}\n")),
            "t.toml",
            &dir,
        )
        .unwrap();
        let volume: f64 = s.seeds.iter().map(|q| q.volume).sum();
        let expected = 0.3 * 80.0 * 0.01;
        assert!((volume - expected).abs() < 1e-9 * expected, "{volume} vs {expected}");
        let SpaceGrid::Terrain(t) = &s.grid else { panic!() };
        for q in &s.seeds {
            let p = q.position;
            let g = t.ground_height(p.x, p.z);
            let top = 10.0 - 0.5 * (p.x - 100.0);
            assert!(p.y > g && p.y < top + 1e-12, "{p}: ground {g}, surface {top}");
        }
        // a rupture raster 0.2 m below the DEM over x ∈ [100.5, 101.5], y ∈ [200.5, 201.5]
        let mut r =
            String::from("ncols 10\nnrows 10\nxllcorner 100.5\nyllcorner 200.5\ncellsize 0.1\n");
        for _ in 0..10 {
            let line: Vec<String> = (0..10)
                .map(|c| format!("{}", 9.8 - 0.5 * (0.5 + 0.1 * (c as f64 + 0.5))))
                .collect();
            r += &(line.join(" ") + "\n");
        }
        std::fs::write(dir.join("rupture.asc"), r).unwrap();
        let with_rupture =
            release.replace("layers = 12\n", "layers = 12\nrupture = \"rupture.asc\"\n");
        let s = load_space_str_in(&with_rupture, "t.toml", &dir).unwrap();
        let volume: f64 = s.seeds.iter().map(|q| q.volume).sum();
        // lattice nodes within the raster's reach: x 100.55 … 101.45, y 200.55 … 201.45
        let expected = 0.2 * 100.0 * 0.01;
        assert!((volume - expected).abs() < 1e-9 * expected, "{volume} vs {expected}");
        let e = load_space_str_in(&release, "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("bodies[0].shape") && e.contains("no cut"), "{e}");
        let e = load_space_str_in(
            &release.replace("shape = \"release\"", "shape = \"release\"\nradius = 1.0"),
            "t.toml",
            &dir,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("bodies[0].radius"), "{e}");
        // the polygon and the rupture together: the polygon's 0.3 m is below the DEM, not below
        // the rupture (whose 0.2 m it contains): 0.3 m over its 80 nodes, 0.2 m over the
        // rupture's 20 others
        let both = with_rupture.replace("layers = 12\n", &format!("layers = 12\n{cut}\n"));
        let s = load_space_str_in(&both, "t.toml", &dir).unwrap();
        let volume: f64 = s.seeds.iter().map(|q| q.volume).sum();
        let expected = (0.3 * 80.0 + 0.2 * 20.0) * 0.01;
        assert!((volume - expected).abs() < 1e-9 * expected, "{volume} vs {expected}");
        // a second release body, and a box in the release volume after it, are refused
        let twice = format!("{both}\n[[bodies]]\nmaterial = \"sand\"\nshape = \"release\"\n");
        let e = load_space_str_in(&twice, "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("bodies[1].shape") && e.contains("already"), "{e}");
        let boxed = format!(
            "{both}\n[[bodies]]\nmaterial = \"sand\"\nshape = \"box\"\n\
             min = [100.9, 9.0, -201.2]\nmax = [101.1, 9.9, -201.0]\n"
        );
        let e = load_space_str_in(&boxed, "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("bodies[1]") && e.contains("release volume"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// R3-09: an observed deposit raster with no positive depth over the plan (all zero, or a
    /// good one offset off the plan by a wrong CRS) is refused at its field; the same raster
    /// over the plan is taken.
    #[test]
    fn an_observed_deposit_off_the_plan_or_empty_is_refused() {
        let dir = std::env::temp_dir().join(format!("mpm-observed3d-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = terrain_scene(&dir, "", 9.0)
            + "\n[output]\nhazard_maps = true\nobserved = { deposit = \"obs.asc\" }\n";
        let raster = |xll: f64, depth: f64| {
            let mut r =
                format!("ncols 30\nnrows 20\nxllcorner {xll}\nyllcorner 200\ncellsize 0.1\n");
            for _ in 0..20 {
                r += &(vec![format!("{depth}"); 30].join(" ") + "\n");
            }
            std::fs::write(dir.join("obs.asc"), r).unwrap();
        };
        raster(100.0, 0.2);
        assert!(load_space_str_in(&text, "t.toml", &dir).is_ok());
        for (xll, depth) in [(100.0, 0.0), (5000.0, 0.2)] {
            raster(xll, depth);
            let e = load_space_str_in(&text, "t.toml", &dir).unwrap_err().to_string();
            assert!(e.contains("`output.observed.deposit`") && e.contains("positive depth"), "{e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// R3-17: a release that must take more particles than a scene may have, whatever the
    /// heights (here 16 per cell along each axis over the whole 5.5 m² plan, 6 m deep: at least
    /// 3.4e7), is refused at `grid.plan_cell` before any lattice height is computed, not at the
    /// body after all of them; a polygon far wider than the plan counts only its part over the
    /// plan (a 1 km square around it, 0.3 m deep, 2 per cell: taken).
    #[test]
    fn a_release_too_fine_for_the_particle_limit_is_refused_before_the_heights() {
        let dir = std::env::temp_dir().join(format!("mpm-release-bound-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let release = |polygon: &str, depth: f64, ppc: u32| {
            terrain_scene(&dir, "", 9.0)
                .replace(
                    "shape = \"box\"\nmin = [100.5, 9, -201.5]\nmax = [101.0, 10.5, -200.5]",
                    &format!("shape = \"release\"\nparticles_per_cell = {ppc}"),
                )
                .replace(
                    "layers = 12\n",
                    &format!("layers = 12\nrelease_polygon = {polygon}\nrelease_depth = {depth}\n"),
                )
        };
        let plan = "[[100.05, 200.05], [102.95, 200.05], [102.95, 201.95], [100.05, 201.95]]";
        let e = load_space_str_in(&release(plan, 6.0, 16), "t.toml", &dir).unwrap_err().to_string();
        assert!(
            e.contains("`grid.plan_cell`")
                && e.contains("5.510 m²")
                && e.contains("at least 3.39e7"),
            "{e}"
        );
        let wide = "[[-400.0, -300.0], [600.0, -300.0], [600.0, 700.0], [-400.0, 700.0]]";
        assert!(load_space_str_in(&release(wide, 0.3, 2), "t.toml", &dir).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// R3-03: a release under cell layers finer than the particle spacing (layers of 0.02 m,
    /// particles 0.05 m apart in plan) gets a particle in every layer it spans: 15 per column
    /// of its 0.3 m depth, where the plan's spacing alone gave 6 and left most layers empty.
    /// The volume is the cut's, as before.
    #[test]
    fn a_release_fills_every_cell_layer_it_spans() {
        let dir = std::env::temp_dir().join(format!("mpm-release-layers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = terrain_scene(&dir, "", 9.0)
            .replace(
                "shape = \"box\"\nmin = [100.5, 9, -201.5]\nmax = [101.0, 10.5, -200.5]",
                "shape = \"release\"",
            )
            .replace(
                "layer_height = 0.1\nlayers = 12\n",
                "layer_height = 0.02\nlayers = 60\nrelease_polygon = [[100.5, 200.5], \
                 [101.5, 200.5], [101.5, 201.3], [100.5, 201.3]]\nrelease_depth = 0.3\n",
            );
        let s = load_space_str_in(&text, "t.toml", &dir).unwrap();
        let volume: f64 = s.seeds.iter().map(|q| q.volume).sum();
        assert!((volume - 0.3 * 80.0 * 0.01).abs() < 1e-9, "{volume}");
        // particles per column (the columns under the polygon's inside are 0.3 m deep)
        let mut columns = std::collections::BTreeMap::new();
        for q in &s.seeds {
            *columns.entry((q.position.x.to_bits(), q.position.z.to_bits())).or_insert(0) += 1;
        }
        assert_eq!(columns.values().max(), Some(&15), "{columns:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// R3-06, R3-10: a release polygon is checked as a prism's is. Its corners in a crossing
    /// order (a bow-tie, half the release) are refused at the first crossing edge's vertex; a
    /// closing vertex that repeats the first is the same polygon; more than `MAX_VERTICES`
    /// corners are refused; a round outline of 4 000 corners over the plan cuts the nodes
    /// inside its circle (row by row, the same test as point by point).
    #[test]
    fn a_release_polygon_is_simple_bounded_and_cut_row_by_row() {
        let dir = std::env::temp_dir().join(format!("mpm-release-poly-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let release = terrain_scene(&dir, "", 9.0).replace(
            "shape = \"box\"\nmin = [100.5, 9, -201.5]\nmax = [101.0, 10.5, -200.5]",
            "shape = \"release\"",
        );
        let with = |polygon: &str| {
            release.replace(
                "layers = 12\n",
                &format!("layers = 12\nrelease_polygon = {polygon}\nrelease_depth = 0.3\n"),
            )
        };
        let volume = |text: &str| -> f64 {
            let s = load_space_str_in(text, "t.toml", &dir).unwrap();
            s.seeds.iter().map(|q| q.volume).sum()
        };
        let square = "[[100.5, 200.5], [101.5, 200.5], [101.5, 201.3], [100.5, 201.3]";
        let v = volume(&with(&format!("{square}]")));
        assert!((v - 0.3 * 80.0 * 0.01).abs() < 1e-9, "{v}");
        assert_eq!(volume(&with(&format!("{square}, [100.5, 200.5]]"))), v);
        let bowtie = "[[100.5, 200.5], [101.5, 201.3], [101.5, 200.5], [100.5, 201.3]]";
        let e = load_space_str_in(&with(bowtie), "t.toml", &dir).unwrap_err().to_string();
        assert!(e.contains("`grid.release_polygon[0]`") && e.contains("not simple"), "{e}");
        let corners = |n: usize| {
            let c: Vec<String> = (0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    format!("[{}, {}]", 101.5 + 0.52 * t.cos(), 201.0 + 0.52 * t.sin())
                })
                .collect();
            format!("[{}]", c.join(", "))
        };
        let e = load_space_str_in(&with(&corners(MAX_VERTICES + 1)), "t.toml", &dir)
            .unwrap_err()
            .to_string();
        assert!(e.contains("`grid.release_polygon`") && e.contains("10000"), "{e}");
        // lattice nodes (100.05 + 0.1 i, 200.05 + 0.1 k) within 0.52 m of (101.5, 201.0): the
        // polygon's corners lie on that circle, its edges within 0.52 (1 − cos(π/4000)) < 1e-7 m
        // of it, and no node lies that close to it
        let nodes = (0..30)
            .flat_map(|i| (0..20).map(move |k| (0.1 * i as f64 - 1.45, 0.1 * k as f64 - 0.95)))
            .filter(|(x, y)| x * x + y * y < 0.52 * 0.52)
            .count();
        let v = volume(&with(&corners(4000)));
        assert!((v - 0.3 * nodes as f64 * 0.01).abs() < 1e-9, "{v} vs {nodes} nodes");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
