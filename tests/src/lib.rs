//! Shared fixtures and case drivers of the verification tests, also used by `cargo xtask`.
//!
//! Each fixture builds what the paper or the benchmark's source describes, in SI units, so that a
//! test reads as its set-up: "a 1 m × 1 m elastic block, 2 × 2 particles per cell, on a 0.5 m grid".
//! The case drivers ([`sliding_horizontal`], [`sliding_inclined`], [`free_fall`], [`vibrating_bar`])
//! run one verification case at a given [`Discretisation`] and return what was measured; the tests
//! (`tests/verification/`) assert on it, and `cargo xtask verify | study` tabulates it, so both read
//! the same implementation. Drivers never panic: set-up and solver failures come back as
//! [`CaseError`].

use std::ops::ControlFlow;

pub mod geostatic;
pub mod manufactured;
pub mod open_core;
pub mod terrain3d;
pub mod three_d;

use mpm_constitutive::{ConstitutiveModel, LinearElastic, PlaneTensor};
use mpm_contact::Friction;
use mpm_grid::{
    Bilinear, KinkPolicy, RegularGrid, ShapeFunctions, ShapeJob, TerrainGrid, TerrainGridSpec,
    with_regular_shape,
};
use mpm_solver::generate::{Shape, fill};
use mpm_solver::{
    Boundaries, Contact, NewParticle, Observer, Particles, STANDARD_GRAVITY, Scheme, Solver,
    SolverConfig, SolverError, StepReport, TimeStep, Vector,
};

/// Particles filling `shape` at `ppc × ppc` per cell of size `cell`, all of one material.
pub fn block<S: Copy>(
    shape: &Shape,
    cell: f64,
    ppc: usize,
    density: f64,
    velocity: Vector,
    state: S,
) -> Particles<S> {
    let seeds = fill(shape, cell / ppc as f64);
    let mut p = Particles::with_capacity(seeds.len());
    for s in seeds {
        p.push(NewParticle {
            position: s.position,
            velocity,
            volume: s.area,
            density,
            stress: PlaneTensor::ZERO,
            state,
            material: 0,
            body: 0,
        });
    }
    p
}

/// Mass-weighted mean of a per-particle vector (centre of mass, mean velocity).
pub fn mass_mean<S>(p: &Particles<S>, field: &[Vector]) -> Vector {
    let m: f64 = p.mass.iter().sum();
    p.mass.iter().zip(field).map(|(&mi, &f)| mi * f).sum::<Vector>() / m
}

/// Why a case driver could not produce its measurement.
#[derive(Debug)]
pub enum CaseError {
    /// The set-up itself is inadmissible (grid, material, or a combination the case does not offer).
    Setup(String),
    /// The solver refused the scene or stopped during the run.
    Solver(SolverError),
}

impl std::fmt::Display for CaseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CaseError::Setup(s) => write!(f, "set-up: {s}"),
            CaseError::Solver(e) => write!(f, "solver: {e}"),
        }
    }
}

impl std::error::Error for CaseError {}

impl From<SolverError> for CaseError {
    fn from(e: SolverError) -> Self {
        CaseError::Solver(e)
    }
}

fn setup<E: std::fmt::Display>(e: E) -> CaseError {
    CaseError::Setup(e.to_string())
}

/// Shape functions on a regular grid (the terrain grid offers bilinear only); uGIMP takes the
/// particle size of `ppc` particles per cell.
pub use mpm_grid::RegularShape as ShapeKind;

/// The grid's mass matrix: lumped (the paper's) or consistent.
pub use mpm_solver::MassMatrix;

/// The numerical choices of a run: resolution, scheme, shape functions and time step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Discretisation {
    /// Cell size (m): square cells on the regular grid, column width on the terrain grid.
    pub cell: f64,
    /// Particles per cell along each axis (`ppc²` per cell).
    pub ppc: usize,
    /// Update scheme.
    pub scheme: Scheme,
    /// Shape functions.
    pub shape: ShapeKind,
    /// Courant number of the time step.
    pub courant: f64,
    /// Lumped (the paper's) or consistent mass matrix.
    pub mass: MassMatrix,
}

impl Discretisation {
    /// The paper's set-up at cell size `cell`: 2 × 2 particles per cell, USAVG, bilinear, C = 0.1.
    pub fn paper(cell: f64) -> Self {
        Self {
            cell,
            ppc: 2,
            scheme: Scheme::Usavg,
            shape: ShapeKind::Bilinear,
            courant: 0.1,
            mass: MassMatrix::Lumped,
        }
    }
}

/// Cost of a run: how many steps over how many particles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cost {
    /// Steps taken.
    pub steps: u64,
    /// Particles in the scene.
    pub particles: usize,
}

/// Records a value every `every` steps, through the solver's observer hook.
struct Sampler<F> {
    every: u64,
    f: F,
}

impl<M, S, F, const N: usize> Observer<M, S, N> for Sampler<F>
where
    M: ConstitutiveModel,
    S: ShapeFunctions<N>,
    F: FnMut(&Solver<M, S, N>, &StepReport),
{
    fn after_step(&mut self, solver: &Solver<M, S, N>, report: &StepReport) -> ControlFlow<()> {
        if report.step % self.every == 0 {
            (self.f)(solver, report);
        }
        ControlFlow::Continue(())
    }
}

/// The elastic block of the paper's §4–§5 cases.
pub mod abe2005 {
    /// Young's modulus of the elastic block (Pa).
    pub const E: f64 = 1e6;
    /// Poisson's ratio of the block.
    pub const NU: f64 = 0.3;
    /// Density of the block (kg/m³).
    pub const RHO: f64 = 1000.0;
    /// Coulomb friction coefficient of the sliding cases.
    pub const MU: f64 = 0.3;
    /// Initial speed of the horizontal sliding case (m/s).
    pub const V0: f64 = 10.0;
    /// The block counts as stopped once its mean speed falls below 1 % of v0 = 0.1 m/s, and the
    /// rigid reference is the time the rigid block reaches that same speed, (v0 − 0.1)/(μg) =
    /// 3.364 s. A lower threshold would time the elastic block's shear vibration instead of its
    /// stop: after the base sticks, the E = 1 MPa block keeps rocking with a mean-velocity
    /// amplitude of about 0.05 m/s (measured; its shear period 4H/c_s is 0.2 s), which the strain
    /// energy in the ledger shows.
    pub const STOPPED: f64 = 0.1;
    /// Half the side of a free-fall particle: 0.25 m cells with 2 × 2 particles per cell.
    pub const FREE_FALL_HALF_SIZE: f64 = 0.0625;
    /// Simulated time of the horizontal case: past the rigid stop at 3.398 s.
    pub const HORIZONTAL_END: f64 = 4.0;

    /// eq 21: travel of the rigid block until it stops, v0²/(2μg) = 16.99 m.
    pub fn eq21_distance() -> f64 {
        V0 * V0 / (2.0 * MU * super::STANDARD_GRAVITY)
    }

    /// eq 21: the time the rigid block's speed falls to [`STOPPED`], (v0 − 0.1)/(μg).
    pub fn eq21_stop_time() -> f64 {
        (V0 - STOPPED) / (MU * super::STANDARD_GRAVITY)
    }

    /// the rigid block of eq 21: 10 m/s on the level with μ = 0.3.
    pub fn eq21() -> mpm_contact::RigidSlide {
        mpm_contact::RigidSlide { gravity: super::STANDARD_GRAVITY, mu: MU, slope_rad: 0.0, v0: V0 }
    }

    /// eq 21: rigid displacement at time t (m).
    pub fn eq21_displacement(t: f64) -> f64 {
        eq21().displacement(t)
    }

    /// the rigid block of eq 22: from rest down a slope θ (degrees) with μ = 0.3.
    pub fn eq22(theta_deg: f64) -> mpm_contact::RigidSlide {
        mpm_contact::RigidSlide {
            gravity: super::STANDARD_GRAVITY,
            mu: MU,
            slope_rad: theta_deg.to_radians(),
            v0: 0.0,
        }
    }

    /// along-slope acceleration g(sin θ − μ cos θ) on a slope θ (degrees); 2.356 m/s² at 30°.
    pub fn eq22_acceleration(theta_deg: f64) -> f64 {
        eq22(theta_deg).acceleration().max(0.0)
    }

    /// eq 22 along the slope: s = ½ a t² (m).
    pub fn eq22_travel(theta_deg: f64, t: f64) -> f64 {
        eq22(theta_deg).displacement(t)
    }

    /// the block's elastic material.
    pub fn material() -> Result<mpm_constitutive::LinearElastic, super::CaseError> {
        mpm_constitutive::LinearElastic::from_young_poisson(E, NU).map_err(super::setup)
    }
}

/// What the horizontal sliding case measured.
#[derive(Clone, Debug, Default)]
pub struct Sliding {
    /// centre-of-mass travel when the block stops (m)
    pub distance: f64,
    /// first time the mean velocity falls below [`abe2005::STOPPED`] (s)
    pub stop_time: f64,
    /// |energy residual| / initial kinetic energy, largest over the run
    pub worst_residual: f64,
    /// strain energy at the end / initial kinetic energy
    pub final_strain: f64,
    /// (t, centre-of-mass displacement) samples
    pub history: Vec<(f64, f64)>,
    /// final particle positions as bits (for determinism checks)
    pub position_bits: Vec<u64>,
    /// steps and particles
    pub cost: Cost,
}

/// The horizontal sliding block of §5(1): 1 m × 1 m, v0 = 10 m/s, μ = 0.3, on a floor at y = 0,
/// run for 4 s in the current rayon pool.
pub fn sliding_horizontal(d: &Discretisation) -> Result<Sliding, CaseError> {
    use abe2005::*;
    let cell = d.cell;
    let cells = [((22.0 / cell) as usize), ((2.0 / cell) as usize)];
    let grid =
        RegularGrid::new(Vector::new(-1.0, 0.0), Vector::splat(cell), cells).map_err(setup)?;
    let particles = block(
        &Shape::Rectangle { min: Vector::ZERO, max: Vector::ONE },
        cell,
        d.ppc,
        RHO,
        Vector::new(V0, 0.0),
        (),
    );
    let config = SolverConfig {
        scheme: d.scheme,
        time_step: TimeStep::Courant(d.courant),
        mass: d.mass,
        boundaries: Boundaries { ground: Some(Friction::Coulomb { mu: MU }), ..Default::default() },
        ..Default::default()
    };
    let elastic = material()?;
    /// the slide as a job over the shape functions.
    struct Slide(LinearElastic, Particles<()>, SolverConfig);
    impl ShapeJob for Slide {
        type Output = Result<Sliding, CaseError>;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
            slide_on(shape, self.0, self.1, self.2)
        }
    }
    with_regular_shape(d.shape, grid, d.ppc, Slide(elastic, particles, config)).map_err(setup)?
}

fn slide_on<S: ShapeFunctions<N>, const N: usize>(
    shape: S,
    elastic: LinearElastic,
    particles: Particles<()>,
    config: SolverConfig,
) -> Result<Sliding, CaseError> {
    use abe2005::{HORIZONTAL_END, STOPPED};
    let mut s = Solver::new(shape, vec![elastic], particles, config)?;
    let x0 = mass_mean(s.particles(), &s.particles().position).x;
    let ke0 = s.energy().kinetic;
    let mut stop_time = f64::NAN;
    let mut worst: f64 = 0.0;
    let mut history = vec![(0.0, 0.0)];
    let mut next_sample = 0.02;
    while s.time() < HORIZONTAL_END {
        s.step()?;
        let v = mass_mean(s.particles(), &s.particles().velocity).x;
        if stop_time.is_nan() && v < STOPPED {
            stop_time = s.time();
        }
        if s.step_count() % 50 == 0 {
            worst = worst.max(s.energy().residual.abs() / ke0);
        }
        if s.time() >= next_sample {
            history.push((s.time(), mass_mean(s.particles(), &s.particles().position).x - x0));
            next_sample += 0.02;
        }
    }
    let e = s.energy();
    let distance = mass_mean(s.particles(), &s.particles().position).x - x0;
    let bits = s.particles().position.iter().flat_map(|p| [p.x.to_bits(), p.y.to_bits()]);
    Ok(Sliding {
        distance,
        stop_time,
        worst_residual: worst.max(e.residual.abs() / ke0),
        final_strain: e.strain / ke0,
        history,
        position_bits: bits.collect(),
        cost: Cost { steps: s.step_count(), particles: s.particles().len() },
    })
}

/// What the inclined sliding case measured.
#[derive(Clone, Debug, Default)]
pub struct Inclined {
    /// along-slope travel of the centre of mass at the end time (m)
    pub travel: f64,
    /// along-slope travel of the bottom particle row at the end time (m)
    pub base_travel: f64,
    /// (t, centre-of-mass travel) samples
    pub history: Vec<(f64, f64)>,
    /// largest |energy residual| over the run, relative to the potential energy released by the
    /// rigid reference's travel (or to the block's weight times 1 m when it does not slide)
    pub worst_residual: f64,
    /// steps and particles
    pub cost: Cost,
}

/// A 1 m × 1 m block at rest on a terrain-following grid of slope θ (descending to the right),
/// μ = 0.3, gravity ramped over `gravity_ramp` seconds, run until `t`. Rows are spaced so that
/// `1/cell` of them span the block measured normal to the ground; 2 m of rows in all. The terrain
/// grid has bilinear functions only.
pub fn sliding_inclined(
    theta_deg: f64,
    t: f64,
    gravity_ramp: f64,
    d: &Discretisation,
) -> Result<Inclined, CaseError> {
    use abe2005::*;
    if d.shape != ShapeKind::Bilinear {
        return Err(CaseError::Setup(format!(
            "the terrain grid offers bilinear shape functions only, not {}",
            d.shape.name()
        )));
    }
    let theta = theta_deg.to_radians();
    let l = d.cell;
    let length = 12.0;
    let profile = vec![Vector::new(0.0, 0.0), Vector::new(length, -length * theta.tan())];
    let h = l / theta.cos();
    let grid = TerrainGrid::new(TerrainGridSpec {
        profile,
        cell_width: l,
        row_height: h,
        rows: (2.0 / l).round().max(2.0) as usize,
        kink_policy: KinkPolicy::Reject,
    })
    .map_err(setup)?;
    let down = Vector::new(theta.cos(), -theta.sin());
    let base = Vector::new(1.0, -theta.tan());
    let particles = block(
        &Shape::OnSlope { base_start: base, angle_rad: -theta, length: 1.0, thickness: 1.0 },
        l,
        d.ppc,
        RHO,
        Vector::ZERO,
        (),
    );
    // The first particle row lies half a spacing above the ground, the second one and a half.
    let spacing = l / d.ppc as f64;
    let bottom: Vec<usize> = (0..particles.len())
        .filter(|&i| (particles.position[i] - base).dot(down.perp()) < 0.8 * spacing)
        .collect();
    let config = SolverConfig {
        scheme: d.scheme,
        time_step: TimeStep::Courant(d.courant),
        mass: d.mass,
        boundaries: Boundaries { ground: Some(Friction::Coulomb { mu: MU }), ..Default::default() },
        gravity_ramp,
        ..Default::default()
    };
    let mut s = Solver::new(Bilinear(grid), vec![material()?], particles, config)?;
    let c0 = mass_mean(s.particles(), &s.particles().position);
    let weight = s.particles().total_mass() * STANDARD_GRAVITY;
    let scale = weight * (eq22_travel(theta_deg, t) * theta.sin()).max(1.0);
    let mut history = vec![(0.0, 0.0)];
    let mut worst: f64 = 0.0;
    let every = (t / 100.0 / (d.courant * l / 40.0)).max(1.0) as u64;
    let mut sampler = Sampler {
        every,
        f: |s: &Solver<LinearElastic, Bilinear<TerrainGrid>, 4>, r: &StepReport| {
            let travel = (mass_mean(s.particles(), &s.particles().position) - c0).dot(down);
            history.push((r.time, travel));
            worst = worst.max(s.energy().residual.abs() / scale);
        },
    };
    s.run_until(t, &mut sampler)?;
    let p = s.particles();
    let travel = (mass_mean(p, &p.position) - c0).dot(down);
    let base_travel =
        bottom.iter().map(|&i| (p.position[i] - p.initial_position[i]).dot(down)).sum::<f64>()
            / bottom.len().max(1) as f64;
    let worst_residual = worst.max(s.energy().residual.abs() / scale);
    let cost = Cost { steps: s.step_count(), particles: p.len() };
    history.push((t, travel));
    Ok(Inclined { travel, base_travel, history, worst_residual, cost })
}

/// What the free-fall case measured.
#[derive(Clone, Debug, Default)]
pub struct FreeFall {
    /// largest relative growth of the total energy in free flight (t < [`FREE_FLIGHT_END`])
    pub flight_growth: f64,
    /// largest relative growth of the total energy over the whole run
    pub overall_growth: f64,
    /// stored energy (kinetic + strain + potential) at the end, relative to E0, minus one
    pub stored_change: f64,
    /// energy the floor's normal constraint took, booked in the ledger, relative to E0
    pub constraint_work: f64,
    /// the ledger's residual at the end, relative to E0 (negative: numerical dissipation)
    pub residual: f64,
    /// lowest particle centre seen over the run (m above the floor)
    pub lowest: f64,
    /// largest |p_y − (−m g t)| / |m g t| in free flight
    pub momentum_error: f64,
    /// largest |Σ m_i − Σ m_p| / Σ m_p over the run
    pub grid_mass_error: f64,
    /// steps checked in free flight
    pub flight_steps: usize,
    /// (t, (E(t) − E0)/E0) after every step
    pub history: Vec<(f64, f64)>,
    /// steps and particles
    pub cost: Cost,
}

/// Free flight lasts until the lowest particle row nears the floor's nodes: the block's base
/// falls 1 m in √(2/g) = 0.45 s; momentum is checked up to 0.35 s, when the base is still 0.4 m
/// up and no node of the block's stencils touches the floor.
pub const FREE_FLIGHT_END: f64 = 0.35;

/// The free fall of §4(2): a 1 m × 1 m elastic block released from rest 1 m above a frictionless
/// floor, 0.25 m cells, 2 × 2 particles per cell (particle half-size [`abe2005::FREE_FALL_HALF_SIZE`]),
/// bilinear, run for 1 s (it lands at 0.45 s and bounces), with the given contact rule.
pub fn free_fall(scheme: Scheme, courant: f64, contact: Contact) -> Result<FreeFall, CaseError> {
    use abe2005::*;
    let cell = 0.25;
    let grid =
        RegularGrid::new(Vector::new(-1.0, 0.0), Vector::splat(cell), [12, 16]).map_err(setup)?;
    let particles = block(
        &Shape::Rectangle { min: Vector::new(0.0, 1.0), max: Vector::new(1.0, 2.0) },
        cell,
        2,
        RHO,
        Vector::ZERO,
        (),
    );
    let config = SolverConfig {
        scheme,
        time_step: TimeStep::Courant(courant),
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.0 }),
            ..Default::default()
        },
        contact,
        ..Default::default()
    };
    let mut s = Solver::new(Bilinear(grid), vec![material()?], particles, config)?;
    let mass = s.particles().total_mass();
    let e0 = s.energy().total();
    let mut r = FreeFall { lowest: f64::INFINITY, ..Default::default() };
    r.history.push((0.0, 0.0));
    while s.time() < 1.0 {
        s.step()?;
        let t = s.time();
        r.lowest = s.particles().position.iter().fold(r.lowest, |m, x| m.min(x.y));
        let growth = (s.energy().total() - e0) / e0;
        r.history.push((t, growth));
        r.overall_growth = r.overall_growth.max(growth);
        if t < FREE_FLIGHT_END {
            let expected = -mass * STANDARD_GRAVITY * t;
            let got = s.particles().momentum().y;
            r.momentum_error = r.momentum_error.max((got - expected).abs() / expected.abs());
            r.flight_growth = r.flight_growth.max(growth);
            r.flight_steps += 1;
        }
        r.grid_mass_error = r.grid_mass_error.max((s.grid_mass() - mass).abs() / mass);
    }
    let e = s.energy();
    r.stored_change = e.stored() / e0 - 1.0;
    r.constraint_work = e.constraint_work / e0;
    r.residual = e.residual / e0;
    r.cost = Cost { steps: s.step_count(), particles: s.particles().len() };
    Ok(r)
}

/// The 1D vibrating bar (fixed–free), a standard MPM benchmark used by Bardenhagen (2002) and by
/// most MPM codes since: v(x, 0) = v0 sin(βx), β = π/(2L), ω = β √(E/ρ), period T = 2π/ω.
/// With L = 25, E = 100, ρ = 1: c = 10 and T = 4L/c = 10 s.
pub mod bar {
    /// Bar length (m).
    pub const L: f64 = 25.0;
    /// Young's modulus (Pa).
    pub const E: f64 = 100.0;
    /// Density (kg/m³).
    pub const RHO: f64 = 1.0;
    /// Velocity amplitude (m/s).
    pub const V0: f64 = 0.1;

    /// the exact period 2π/ω of the first mode (s): 10 s.
    pub fn period() -> f64 {
        let beta = std::f64::consts::PI / (2.0 * L);
        2.0 * std::f64::consts::PI / (beta * (E / RHO).sqrt())
    }
}

/// What the vibrating bar measured over five periods.
#[derive(Clone, Debug, Default)]
pub struct Bar {
    /// measured period / exact period (NaN with fewer than two zero crossings)
    pub period_ratio: f64,
    /// largest |E(t) − E0| / E0
    pub worst_energy: f64,
    /// zero crossings of the mean velocity seen (ten expected in five periods)
    pub crossings: usize,
    /// (t, mean velocity) after every step
    pub history: Vec<(f64, f64)>,
    /// steps and particles
    pub cost: Cost,
}

/// The vibrating bar on a regular grid of cell `d.cell`, one cell thick, for five periods.
pub fn vibrating_bar(d: &Discretisation) -> Result<Bar, CaseError> {
    let cell = d.cell;
    let grid = RegularGrid::new(
        Vector::new(0.0, -1.0),
        Vector::splat(cell),
        [(28.0 / cell) as usize, (3.0 / cell) as usize],
    )
    .map_err(setup)?;
    /// the bar as a job over the shape functions.
    struct OnShape<'a>(&'a Discretisation);
    impl ShapeJob for OnShape<'_> {
        type Output = Result<Bar, CaseError>;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
            bar_on(shape, self.0)
        }
    }
    with_regular_shape(d.shape, grid, d.ppc, OnShape(d)).map_err(setup)?
}

fn bar_on<S: ShapeFunctions<N>, const N: usize>(
    shape: S,
    d: &Discretisation,
) -> Result<Bar, CaseError> {
    use bar::*;
    let beta = std::f64::consts::PI / (2.0 * L);
    let period = period();
    // ν = 0: plane strain then has no lateral coupling and the bar is one-dimensional.
    let material = LinearElastic::from_young_poisson(E, 0.0).map_err(setup)?;
    let mut particles = block(
        &Shape::Rectangle { min: Vector::ZERO, max: Vector::new(L, d.cell) },
        d.cell,
        d.ppc,
        RHO,
        Vector::ZERO,
        (),
    );
    for i in 0..particles.len() {
        particles.velocity[i] = Vector::new(V0 * (beta * particles.position[i].x).sin(), 0.0);
    }
    let config = SolverConfig {
        scheme: d.scheme,
        time_step: TimeStep::Courant(d.courant),
        mass: d.mass,
        gravity: Vector::ZERO,
        boundaries: Boundaries { left_wall: Some(Friction::Fixed), ..Default::default() },
        ..Default::default()
    };
    let mut s = Solver::new(shape, vec![material], particles, config)?;
    let e0 = s.energy().total();
    let mut worst: f64 = 0.0;
    let mut crossings = Vec::new();
    let mut last = (0.0, mass_mean(s.particles(), &s.particles().velocity).x);
    let mut history = vec![last];
    while s.time() < 5.0 * period {
        s.step()?;
        let v = mass_mean(s.particles(), &s.particles().velocity).x;
        if (v > 0.0) != (last.1 > 0.0) {
            // Linear interpolation of the zero of the mean velocity within the step.
            crossings.push(last.0 + (s.time() - last.0) * last.1 / (last.1 - v));
        }
        last = (s.time(), v);
        history.push(last);
        worst = worst.max((s.energy().total() - e0).abs() / e0);
    }
    // Successive zero crossings of cos(ωt) are half a period apart.
    let n = crossings.len();
    let period_ratio = if n >= 2 {
        2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64 / period
    } else {
        f64::NAN
    };
    Ok(Bar {
        period_ratio,
        worst_energy: worst,
        crossings: n,
        history,
        cost: Cost { steps: s.step_count(), particles: s.particles().len() },
    })
}

/// A 1 m × 0.75 m elastic block (E = 1 MPa, ν = 0.3, ρ ≈ 1.6 t/m³ varying with x) in free flight
/// for 40 steps on a 0.25 m grid, 2 × 2 particles per cell, with a swirling velocity
/// v = (sin 3y, cos 2x) m/s and a non-uniform stress, so that every node's force and velocity
/// differ: returns |p(t) − p(0) − M g t| / (|p(0)| + M g t), the momentum balance's relative
/// error. With no boundary, the lumped and the consistent mass matrices (whose rows sum to the
/// lumped masses) both conserve momentum to rounding.
pub fn swirl_momentum_error(d: &Discretisation) -> Result<f64, CaseError> {
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.25), [16, 16]).map_err(setup)?;
    /// the block as a job over the shape functions.
    struct Swirl(Discretisation);
    impl ShapeJob for Swirl {
        type Output = Result<f64, CaseError>;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
            let mut particles = Particles::default();
            for j in 0..6 {
                for i in 0..8 {
                    let x =
                        Vector::new(1.0625 + 0.125 * f64::from(i), 1.0625 + 0.125 * f64::from(j));
                    let v = Vector::new((3.0 * x.y).sin(), (2.0 * x.x).cos());
                    let density = 1500.0 + 100.0 * x.x;
                    let mut p = NewParticle::unstressed(x, v, 0.125 * 0.125, density, ());
                    p.stress = PlaneTensor::new(-1e3 * x.x, -2e3 * x.y, -5e2, 3e2 * x.x * x.y);
                    particles.push(p);
                }
            }
            let config = SolverConfig {
                scheme: self.0.scheme,
                mass: self.0.mass,
                time_step: TimeStep::Courant(self.0.courant),
                small_mass_ratio: 0.0,
                ..Default::default()
            };
            let material = LinearElastic::from_young_poisson(1e6, 0.3).map_err(setup)?;
            let mut s = Solver::new(shape, vec![material], particles, config)?;
            let p0 = s.particles().momentum();
            let total = s.particles().total_mass();
            for _ in 0..40 {
                s.step()?;
            }
            let gained = total * s.config().gravity * s.time();
            let error = (s.particles().momentum() - p0 - gained).length();
            Ok(error / (p0.length() + gained.length()))
        }
    }
    with_regular_shape(d.shape, grid, 2, Swirl(*d)).map_err(setup)?
}
