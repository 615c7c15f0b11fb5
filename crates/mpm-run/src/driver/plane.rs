//! What a plane-strain run records beyond the shared series: the runout measures along the
//! ground profile, the hazard envelopes and the deposit along it (`envelope.csv`,
//! `deposit.csv`, with the DEM section's map coordinates), the probes' analytic reference
//! curves, the comparison with an observed deposit, the initial state's report and the plots.

use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

use mpm_grid::ShapeFunctions;
use mpm_output::checkpoint::History;
use mpm_output::csv::{self, ProbeRow};
use mpm_output::report::{self, Deposit};
use mpm_scene::dispatch::SceneModel;
use mpm_scene::edges::{EdgeWatch, Grain};
use mpm_scene::envelope::{self, Envelope};
use mpm_scene::observed;
use mpm_scene::summary::{self, OutflowReport, RunSummary, RunoutMetrics};
use mpm_scene::{InitialState, InitialStateSummary, Resolved, Scene, ground_height};
use mpm_solver::{EnergyCheck, Solver, SolverError, Vector};

use super::{Common, Stepper, View, Wing};
use crate::error::RunError;
use crate::progress::ProgressSink;

/// The plane's wing of the driver: its scene and the initial state found before the run.
pub(crate) struct Plane<'a> {
    scene: &'a Scene,
    common: Common<'a>,
    /// what the initial-state stage did (a new run with `[initial_state]`).
    initial: Option<InitialStateSummary>,
}

impl<'a> Plane<'a> {
    pub(crate) fn new(scene: &'a Scene, initial: Option<InitialStateSummary>) -> Self {
        let r = scene.resolved();
        let o = &r.output;
        let common = Common {
            origin: scene.origin(),
            text: scene.text(),
            files_dir: scene.files_dir(),
            inputs: scene.inputs(),
            hash: scene.hash(),
            end_time: r.end_time,
            max_steps: r.max_steps,
            alarm: r.alarm,
            stop_at_rest: r.stop_at_rest,
            series_interval: o.series_interval,
            interval: o.interval,
            checkpoint_interval: o.checkpoint_interval,
            exact_times: o.exact_times,
            vtk: o.vtk,
            vtk_format: o.vtk_format,
            fields: &o.fields,
            plots: o.plots,
            spacing: r.spacing,
            probes: &o.probes,
            warnings: &r.warnings,
            scheme: r.config.scheme.name(),
            shape_function: r.shape_function.name(),
        };
        Self { scene, common, initial }
    }

    fn r(&self) -> &'a Resolved {
        self.scene.resolved()
    }
}

/// The particles the runout measures, envelopes and deposit see: all of them, or in a scene of
/// flowing and structural materials (sand beside elastic bedrock or an obstacle,
/// `MaterialsBuilt::flow_mask`) the flow's alone, copied at output times.
struct Flow<'a> {
    position: Cow<'a, [Vector]>,
    velocity: Cow<'a, [Vector]>,
    mass: Cow<'a, [f64]>,
    volume: Cow<'a, [f64]>,
    initial_position: Cow<'a, [Vector]>,
}

impl<'a> Flow<'a> {
    /// the flow with the positions it would have had without wrapping through periodic sides:
    /// what the runout measures of an endless slope follow (R3-15: the centre of mass of a mass
    /// thrown across the seam moved backwards).
    fn unwrapped(r: &Resolved, p: &View<'a, Vector>) -> Self {
        Self::with_positions(r, p, p.unwrapped())
    }

    fn of(r: &Resolved, p: &View<'a, Vector>) -> Self {
        Self::with_positions(r, p, Cow::Borrowed(p.position))
    }

    /// the flowing particles' fields, with `position` (one per particle) for their positions.
    fn with_positions(r: &Resolved, p: &View<'a, Vector>, position: Cow<'a, [Vector]>) -> Self {
        let Some(mask) = r.materials.flow_mask() else {
            return Self {
                position,
                velocity: Cow::Borrowed(p.velocity),
                mass: Cow::Borrowed(p.mass),
                volume: Cow::Borrowed(p.volume),
                initial_position: Cow::Borrowed(p.initial_position),
            };
        };
        let keep = |q: &usize| mask.get(usize::from(p.material[*q])).copied().unwrap_or(true);
        fn pick<T: Copy>(v: &[T], idx: &[usize]) -> Cow<'static, [T]> {
            Cow::Owned(idx.iter().map(|&q| v[q]).collect())
        }
        let idx: Vec<usize> = (0..p.len()).filter(keep).collect();
        Self {
            position: pick(&position, &idx),
            velocity: pick(p.velocity, &idx),
            mass: pick(p.mass, &idx),
            volume: pick(p.volume, &idx),
            initial_position: pick(p.initial_position, &idx),
        }
    }
}

impl Wing for Plane<'_> {
    type Vector = Vector;
    const DIMENSION: usize = 2;
    const PROBES: (&'static str, fn(&mut String, &[ProbeRow])) = (csv::PROBES_HEADER, csv::probes);

    fn common(&self) -> &Common<'_> {
        &self.common
    }

    fn start<Sv: Stepper<Vector = Vector>>(&self, h: &mut History, sv: &Sv) {
        let r = self.r();
        if r.output.envelope {
            let mut e = Envelope::new(&r.ground, r.grid.column_width());
            self.observe_into(&mut e, sv);
            h.envelope = Some(e);
        }
        h.initial = Some(self.metrics(h, sv));
        h.edges = edge_watch(r);
        let p = sv.particles();
        let f = Flow::of(r, &p);
        let top = f.initial_position.iter().copied().max_by(|a, b| a.y.total_cmp(&b.y));
        h.crown = top.map(|c| [c.x, c.y, 0.0]);
        h.energy_check = Some(EnergyCheck::new(
            &sv.energy(),
            p.position,
            p.mass,
            r.config.gravity.length(),
            |x: Vector| x.y - ground_height(&r.ground, x.x),
        ));
    }

    fn observe<Sv: Stepper<Vector = Vector>>(&self, h: &mut History, sv: &Sv) {
        if let Some(e) = &mut h.envelope {
            self.observe_into(e, sv);
        }
    }

    fn metrics<Sv: Stepper<Vector = Vector>>(&self, h: &History, sv: &Sv) -> RunoutMetrics {
        let r = self.r();
        let p = sv.particles();
        let f = Flow::unwrapped(r, &p);
        // every flowing particle has left through outflow sides: the measures stay where they
        // were last taken
        if f.mass.is_empty()
            && let Some(last) = h.runout.last()
        {
            return RunoutMetrics { time: sv.time(), front_speed: 0.0, ..*last };
        }
        summary::runout(
            sv.time(),
            [&f.position, &f.velocity],
            &f.mass,
            &r.ground,
            r.spacing,
            r.grid.column_width(),
            h.initial.as_ref(),
        )
    }

    fn grains<Sv: Stepper<Vector = Vector>>(&self, sv: &Sv) -> Vec<Grain> {
        let r = self.r();
        let p = sv.particles();
        let f = Flow::of(r, &p);
        (f.position.iter().zip(f.mass.iter()))
            .map(|(x, &mass)| Grain {
                position: [x.x, x.y, 0.0],
                ground: ground_height(&r.ground, x.x),
                mass,
            })
            .collect()
    }

    fn flow_mass<Sv: Stepper<Vector = Vector>>(&self, sv: &Sv) -> f64 {
        Flow::of(self.r(), &sv.particles()).mass.iter().sum()
    }

    fn probe_direction(&self) -> Vector {
        self.r().output.reference.map_or(Vector::X, |rf| rf.direction)
    }

    fn reference(&self, t: f64) -> Option<f64> {
        self.r().output.reference.map(|rf| rf.displacement(t))
    }

    fn boundaries(&self) -> Vec<(String, usize)> {
        let c = &self.r().config;
        let b = &c.boundaries;
        let sides = [b.ground, b.left_wall, b.right_wall].map(|s| s.is_some());
        let side_walls = c.side_walls().is_some();
        crate::loads::boundaries(&mpm_solver::SIDE_NAMES, &sides, c.walls.len(), side_walls)
    }

    fn complete<Sv: Stepper<Vector = Vector>>(&self, h: &History, sv: &Sv, s: &mut RunSummary) {
        let r = self.r();
        let p = sv.particles();
        let f = Flow::of(r, &p);
        // the source's top: the highest initial particle's top
        let top = h
            .crown
            .map(|[x, y, _]| Vector::new(x, y))
            .or_else(|| f.initial_position.iter().copied().max_by(|a, b| a.y.total_cmp(&b.y)));
        let crown = top.map_or(Vector::ZERO, |c| c + Vector::new(0.0, 0.5 * r.spacing));
        let kinetic: Vec<(f64, f64)> =
            h.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
        s.runout.indicators = summary::indicators(&h.runout, &kinetic, crown, &r.ground);
        s.observed = r.output.observed.as_ref().and_then(|o| {
            let sim = observed::simulated(&r.ground, r.grid.column_width(), r.spacing, &f.position);
            let last = h.runout.last()?;
            observed::compare(o, &sim, last.front_x, last.tail_x)
        });
        s.initial_state = self.initial.clone();
        let o = r.config.outflow;
        let (particles, mass, momentum, energy, first) = sv.outflowed();
        s.outflow = OutflowReport::new(
            &[("left_wall", o.x_min), ("right_wall", o.x_max)],
            (particles, mass, momentum, energy),
            first,
            p.mass.iter().sum(),
        );
    }

    fn files<Sv: Stepper<Vector = Vector>>(
        &self,
        h: &History,
        sv: &Sv,
        dir: &Path,
        _s: &RunSummary,
    ) -> Result<(), RunError> {
        let r = self.r();
        let p = sv.particles();
        let f = Flow::of(r, &p);
        if let Some(e) = &h.envelope {
            let deposit = envelope::deposit(e, r.spacing, &f.position);
            // the undeclared ends of the grid the flow reached
            let edges: Vec<f64> = h.edges.as_ref().map_or_else(Vec::new, |w| {
                w.faces.iter().filter(|f| f.first_time.is_some()).map(|f| f.at).collect()
            });
            let (section, plots) = (r.section.as_ref(), self.common.plots);
            super::envelope_files(dir, e, &deposit, section, plots, &edges)?;
        }
        if self.common.plots {
            let deposit =
                Deposit { positions: &f.position, initial: &f.initial_position, time: sv.time() };
            report::plots(&dir.join("plots"), self.scene, h, &deposit)?;
        }
        Ok(())
    }
}

impl Plane<'_> {
    /// takes the flow's state now into the envelopes.
    fn observe_into<Sv: Stepper<Vector = Vector>>(&self, e: &mut Envelope, sv: &Sv) {
        let r = self.r();
        let p = sv.particles();
        let f = Flow::of(r, &p);
        e.observe(sv.time(), r.spacing, (&f.position, &f.velocity), [&f.mass, &f.volume]);
    }
}

/// the watch over the grid's sides that the scene left undeclared (no wall law, not outflow,
/// not periodic); `None` when every side is declared.
fn edge_watch(r: &Resolved) -> Option<EdgeWatch> {
    let c = &r.config;
    let (x0, x1) = r.grid.x_range();
    let open = c.periodic.is_none();
    let mut faces = Vec::new();
    if open && c.boundaries.left_wall.is_none() && c.outflow.x_min.is_none() {
        faces.push(("left_wall", 0, x0, -1.0));
    }
    if open && c.boundaries.right_wall.is_none() && c.outflow.x_max.is_none() {
        faces.push(("right_wall", 0, x1, 1.0));
    }
    EdgeWatch::new(faces, r.grid.column_width())
}

/// finds a new run's initial stresses as the scene asks (`[initial_state]`), timed and reported
/// to `progress`; `Ok(None)` for a stress-free start.
pub(crate) fn initial_state<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    solver: &mut Solver<M, S, N>,
    how: &InitialState,
    progress: &ProgressSink,
) -> Result<Option<InitialStateSummary>, SolverError> {
    let start = Instant::now();
    let summary = match *how {
        InitialState::None => return Ok(None),
        InitialState::Implicit(settings) => {
            let g = solver.solve_geostatic(&settings)?;
            InitialStateSummary {
                method: "implicit".into(),
                load_steps: Some(g.load_steps),
                iterations: Some(g.iterations),
                residual: Some(g.residual),
                residual_history: g.history.iter().map(|h| h.residual).collect(),
                plastic_particles: Some(g.plastic_particles),
                tied_nodes: Some(g.tied_nodes),
                released_planes: Some(g.released_planes),
                max_displacement: Some(g.max_displacement),
                base_friction_ratio: Some(g.base_friction_ratio),
                ..InitialStateSummary::default()
            }
        }
        InitialState::GravityRamp { ramp, hold } => {
            let r = solver.settle(ramp, hold)?;
            InitialStateSummary {
                method: "gravity_ramp".into(),
                steps: Some(r.steps),
                kinetic_energy: Some(r.kinetic_energy),
                ..InitialStateSummary::default()
            }
        }
    };
    let s = InitialStateSummary { wall_time_s: start.elapsed().as_secs_f64(), ..summary };
    progress.note(&match s.method.as_str() {
        "implicit" => format!(
            "initial state (implicit): {} load step(s), {} Newton iterations, residual {:.2e}, \
             {} particles plastic, {} surface nodes tied, largest displacement {:.3e} m, {:.2} s",
            s.load_steps.unwrap_or(0),
            s.iterations.unwrap_or(0),
            s.residual.unwrap_or(0.0),
            s.plastic_particles.unwrap_or(0),
            s.tied_nodes.unwrap_or(0),
            s.max_displacement.unwrap_or(0.0),
            s.wall_time_s
        ),
        _ => format!(
            "initial state (gravity ramp): {} steps, kinetic energy left {:.3e} J/m (dropped), \
             {:.2} s",
            s.steps.unwrap_or(0),
            s.kinetic_energy.unwrap_or(0.0),
            s.wall_time_s
        ),
    });
    Ok(Some(s))
}
