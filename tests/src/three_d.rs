//! The 3D cases: the same solver source built for space (`mpm-solver3d` over `mpm-grid3d` and
//! `mpm-contact3d`), checked against the rigid block's laws written for a vector and against
//! conservation. y is up in both builds and z is the third axis, so a 2D case is the section
//! z = const of its 3D sibling.
//!
//! - [`slope`]: a block sliding down a 30° plane whose fall line is oblique to the grid's axes
//!   (the floor is the grid's y = 0 face and gravity is tilted, so the fall line runs 30° from
//!   x towards z): eq 22 along the fall line, nothing across it.
//! - [`thrown`]: the same block thrown across the slope, against the rigid block's ODE
//!   (Coulomb friction opposing the sliding velocity in the plane), integrated here.
//! - [`diagonal`]: eq 21 along the grid's diagonal (x = z) on the level: isotropy.
//! - [`free_fall`]: momentum m g t to round-off.
//! - [`collapse_bits`]: a Drucker-Prager column collapsing on a rough floor, its state's bits
//!   for a given number of threads.
//! - [`vibrating_bar`]: the fixed–free bar along z, its period against 2π/ω.
//! - [`bagnold`]: steady μ(I) flow on a periodic 3D strip against Bagnold's profile.
//! - [`oblique_wall`]: a block thrown into a wall plane oblique to every grid axis: momentum
//!   balanced by the wall's impulse, the impulse within Coulomb's cone, no particle behind it.

use mpm_constitutive::{
    ConeMatch, ConstitutiveError, ConstitutiveModel, DruckerPrager, DruckerPragerParams,
    LinearElastic,
};
use mpm_contact3d::Friction;
use mpm_grid3d::{RegularGrid, RegularShape, ShapeFunctions, ShapeJob, with_regular_shape};
use mpm_solver3d::generate::{Shape, fill};
use mpm_solver3d::{
    Boundaries, NewParticle, Particles, STANDARD_GRAVITY, Scheme, Solver, SolverConfig,
    SolverError, Stress, TimeStep, Transfer, Vector,
};

use crate::CaseError;
use crate::abe2005::{E, MU, NU, RHO, V0};

fn setup<E: std::fmt::Display>(e: E) -> CaseError {
    CaseError::Setup(e.to_string())
}

impl From<mpm_solver3d::SolverError> for CaseError {
    fn from(e: mpm_solver3d::SolverError) -> Self {
        CaseError::Setup(format!("3D solver: {e}"))
    }
}

/// The numerical choices of a 3D run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Numerics {
    /// cube cells of this side (m)
    pub cell: f64,
    /// particles per cell along each axis (ppc³ per cell)
    pub ppc: usize,
    /// update scheme
    pub scheme: Scheme,
    /// FLIP or APIC
    pub transfer: Transfer,
    /// shape functions
    pub shape: RegularShape,
    /// Courant number
    pub courant: f64,
}

impl Numerics {
    /// the paper's choices at cell size `cell`: 2 × 2 × 2 particles per cell, USAVG, FLIP,
    /// (tri)linear, C = 0.1.
    pub fn paper(cell: f64) -> Self {
        Self {
            cell,
            ppc: 2,
            scheme: Scheme::Usavg,
            transfer: Transfer::Flip,
            shape: RegularShape::Bilinear,
            courant: 0.1,
        }
    }

    /// a short name for tables: "USAVG FLIP TRILINEAR".
    pub fn name(&self) -> String {
        let shape = match self.shape {
            RegularShape::Bilinear => "trilinear",
            other => other.name(),
        };
        format!("{:?} {:?} {shape}", self.scheme, self.transfer).to_uppercase()
    }
}

/// Particles of one material filling `shape` at `ppc³` per cell of side `cell`.
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
            volume: s.volume,
            density,
            stress: Stress::ZERO,
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

/// A run: a solver built on the shape functions the job is given, stopped at each of `times`
/// for `sample` to look at the particles.
struct Run<'a, M: ConstitutiveModel> {
    material: M,
    particles: Particles<M::State>,
    config: SolverConfig,
    times: &'a [f64],
    sample: &'a mut dyn FnMut(f64, &Particles<M::State>),
}

impl<M: ConstitutiveModel> ShapeJob for Run<'_, M> {
    type Output = Result<u64, SolverError>;
    fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
        let mut s = Solver::new(shape, vec![self.material], self.particles, self.config)?;
        for &t in self.times {
            s.run_until(t, &mut ())?;
            (self.sample)(t, s.particles());
        }
        Ok(s.step_count())
    }
}

/// runs `particles` of `material` on `grid` with the shape functions of `n`, sampling at `times`;
/// the steps taken.
fn run<M: ConstitutiveModel>(
    grid: RegularGrid,
    n: &Numerics,
    material: M,
    particles: Particles<M::State>,
    config: SolverConfig,
    times: &[f64],
    sample: &mut dyn FnMut(f64, &Particles<M::State>),
) -> Result<u64, CaseError> {
    let job = Run { material, particles, config, times, sample };
    Ok(with_regular_shape(n.shape, grid, n.ppc, job).map_err(setup)??)
}

/// the elastic block of the paper's cases (E = 1 MPa, ν = 0.3).
fn elastic() -> Result<LinearElastic, CaseError> {
    LinearElastic::from_young_poisson(E, NU).map_err(setup)
}

/// the settings of the sliding cases: the floor with Coulomb friction μ, gravity `gravity`.
fn sliding_config(n: &Numerics, gravity: Vector, mu: f64) -> SolverConfig {
    SolverConfig {
        scheme: n.scheme,
        transfer: n.transfer,
        time_step: TimeStep::Courant(n.courant),
        gravity,
        boundaries: Boundaries { ground: Some(Friction::Coulomb { mu }), ..Default::default() },
        ..Default::default()
    }
}

/// The inclination of [`slope`] and [`thrown`] (deg) and the azimuth of their fall line, from x
/// towards z (deg): oblique to every grid axis.
pub const SLOPE_DEG: f64 = 30.0;
/// the fall line's azimuth (deg).
pub const AZIMUTH_DEG: f64 = 30.0;

/// The slope's frame: gravity, the fall line (unit, in the floor) and the direction across it.
pub fn slope_frame() -> (Vector, Vector, Vector) {
    let (theta, alpha) = (SLOPE_DEG.to_radians(), AZIMUTH_DEG.to_radians());
    let g = STANDARD_GRAVITY;
    let gravity =
        Vector::new(g * theta.sin() * alpha.cos(), -g * theta.cos(), g * theta.sin() * alpha.sin());
    let down = Vector::new(alpha.cos(), 0.0, alpha.sin());
    let across = Vector::new(-alpha.sin(), 0.0, alpha.cos());
    (gravity, down, across)
}

/// What a sliding run measured: at each sample time, the centre of mass's travel along the fall
/// line and across it (m), and the rigid block's (m, m).
#[derive(Clone, Debug, Default)]
pub struct Path {
    /// (t, simulated (along, across), rigid block's (along, across)).
    pub samples: Vec<(f64, [f64; 2], [f64; 2])>,
    /// steps and particles.
    pub steps: u64,
    /// particles in the scene.
    pub particles: usize,
}

impl Path {
    /// the largest error of the travel (the length of the difference of the in-plane
    /// displacements) relative to the rigid block's travel.
    pub fn worst_relative(&self) -> f64 {
        self.samples
            .iter()
            .map(|(_, s, r)| {
                let d = glam::DVec2::from(*s) - glam::DVec2::from(*r);
                d.length() / glam::DVec2::from(*r).length()
            })
            .fold(0.0, f64::max)
    }
}

/// A 1 × 0.5 × 1 m elastic block on a 30° slope whose fall line runs 30° from x towards z
/// (μ = 0.3), released at rest (`across_speed` = 0) or thrown across the fall line at
/// `across_speed` m/s, sampled at `times`; the rigid block's path beside it.
fn on_slope(n: &Numerics, across_speed: f64, times: &[f64]) -> Result<Path, CaseError> {
    let (gravity, down, across) = slope_frame();
    let grid =
        RegularGrid::new(Vector::ZERO, Vector::splat(n.cell), cells([10.0, 1.5, 10.0], n.cell))
            .map_err(setup)?;
    let min = Vector::new(2.0, 0.0, 1.0);
    let shape = Shape::Box { min, max: min + Vector::new(1.0, 0.5, 1.0) };
    let particles = block(&shape, n.cell, n.ppc, RHO, across_speed * across, ());
    let count = particles.len();
    let c0 = mass_mean(&particles, &particles.position);
    let config = sliding_config(n, gravity, MU);
    let mut samples = Vec::new();
    let mut sample = |t: f64, p: &Particles<()>| {
        let d = mass_mean(p, &p.position) - c0;
        let rigid = rigid_path(across_speed, t);
        samples.push((t, [d.dot(down), d.dot(across)], rigid));
    };
    let steps = run(grid, n, elastic()?, particles, config, times, &mut sample)?;
    Ok(Path { samples, steps, particles: count })
}

/// the cells of a grid of `size` m along each axis at cell size `cell`.
fn cells(size: [f64; 3], cell: f64) -> [usize; 3] {
    size.map(|s| (s / cell).round().max(1.0) as usize)
}

/// eq 22 along the slope's fall line: released at rest, the block slides from t = 0 at
/// g (sin θ − μ cos θ) and (on the fall line) never sideways; [`slope`] measures that at 1 s
/// and 2 s.
pub fn slope(n: &Numerics) -> Result<Path, CaseError> {
    on_slope(n, 0.0, &[1.0, 2.0])
}

/// The speed [`thrown`] throws the block across the fall line with (m/s).
pub const THROW_SPEED: f64 = 2.0;

/// the block thrown across the slope at [`THROW_SPEED`], sampled at 1 s and 2 s against the
/// rigid block's ODE.
pub fn thrown(n: &Numerics) -> Result<Path, CaseError> {
    on_slope(n, THROW_SPEED, &[1.0, 2.0])
}

/// The rigid block on the slope, in the slope's plane: (along, across) travel at `t` of a block
/// starting with speed `across_speed` across the fall line, under the in-plane gravity
/// g sin θ along the fall line and Coulomb friction μ g cos θ opposing its sliding velocity.
/// Integrated by the classical Runge-Kutta method, the step halved until two answers agree
/// to 1e-12 m (the block never stops: tan θ > μ).
pub fn rigid_path(across_speed: f64, t: f64) -> [f64; 2] {
    let theta = SLOPE_DEG.to_radians();
    let (gt, gn) = (STANDARD_GRAVITY * theta.sin(), STANDARD_GRAVITY * theta.cos());
    let pull = glam::DVec2::new(gt, 0.0);
    let accel = |v: glam::DVec2| {
        // at rest the block starts along the pull (g sin θ > μ g cos θ), friction against it
        let speed = v.length();
        let direction = if speed > 0.0 { v / speed } else { pull.normalize() };
        pull - MU * gn * direction
    };
    let integrate = |steps: usize| {
        let h = t / steps as f64;
        let (mut x, mut v) = (glam::DVec2::ZERO, glam::DVec2::new(0.0, across_speed));
        for _ in 0..steps {
            // (x, v)' = (v, a(v))
            let (k1x, k1v) = (v, accel(v));
            let (k2x, k2v) = (v + 0.5 * h * k1v, accel(v + 0.5 * h * k1v));
            let (k3x, k3v) = (v + 0.5 * h * k2v, accel(v + 0.5 * h * k2v));
            let (k4x, k4v) = (v + h * k3v, accel(v + h * k3v));
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        x
    };
    if t <= 0.0 {
        return [0.0, 0.0];
    }
    let mut steps = 64;
    let mut last = integrate(steps);
    loop {
        steps *= 2;
        let next = integrate(steps);
        if (next - last).length() < 1e-12 || steps > 1 << 22 {
            return next.to_array();
        }
        last = next;
    }
}

/// What the diagonal case measured.
#[derive(Clone, Debug, Default)]
pub struct Diagonal {
    /// the centre of mass's travel along the diagonal at the end (m)
    pub travel: f64,
    /// eq 21's v0²/(2 μ g) (m)
    pub expected: f64,
    /// its travel across the diagonal (m)
    pub across: f64,
    /// steps
    pub steps: u64,
    /// particles
    pub particles: usize,
}

/// eq 21 along the grid's diagonal: a 1 m elastic cube sliding at 10 m/s along x = z on a level
/// floor with μ = 0.3 stops after v0²/(2 μ g) = 16.99 m, as it does along x (isotropy of the
/// tangential law and of the grid). Run to 4 s, past the rigid stop at 3.40 s.
pub fn diagonal(n: &Numerics) -> Result<Diagonal, CaseError> {
    let grid =
        RegularGrid::new(Vector::ZERO, Vector::splat(n.cell), cells([15.0, 2.0, 15.0], n.cell))
            .map_err(setup)?;
    let dir = Vector::new(1.0, 0.0, 1.0).normalize();
    let across = Vector::new(-1.0, 0.0, 1.0).normalize();
    let min = Vector::new(0.5, 0.0, 0.5);
    let shape = Shape::Box { min, max: min + Vector::ONE };
    let particles = block(&shape, n.cell, n.ppc, RHO, V0 * dir, ());
    let count = particles.len();
    let c0 = mass_mean(&particles, &particles.position);
    let config = sliding_config(n, Vector::NEG_Y * STANDARD_GRAVITY, MU);
    let mut end = Vector::ZERO;
    let mut sample = |_t: f64, p: &Particles<()>| end = mass_mean(p, &p.position) - c0;
    let steps = run(grid, n, elastic()?, particles, config, &[4.0], &mut sample)?;
    Ok(Diagonal {
        travel: end.dot(dir),
        expected: crate::abe2005::eq21_distance(),
        across: end.dot(across),
        steps,
        particles: count,
    })
}

/// What the free-fall case measured.
#[derive(Clone, Debug, Default)]
pub struct FreeFall {
    /// |P − m g t| / |m g t| at the end, P the particles' momentum
    pub momentum_error: f64,
    /// steps
    pub steps: u64,
}

/// A 1 m elastic cube falling freely for 0.3 s (no boundary reached): the momentum is m g t.
pub fn free_fall(n: &Numerics) -> Result<FreeFall, CaseError> {
    let grid =
        RegularGrid::new(Vector::ZERO, Vector::splat(n.cell), cells([3.0, 3.0, 3.0], n.cell))
            .map_err(setup)?;
    let min = Vector::new(1.0, 1.5, 1.0);
    let particles =
        block(&Shape::Box { min, max: min + Vector::ONE }, n.cell, n.ppc, RHO, Vector::ZERO, ());
    let config = SolverConfig {
        scheme: n.scheme,
        transfer: n.transfer,
        time_step: TimeStep::Courant(n.courant),
        ..Default::default()
    };
    let t = 0.3;
    let mut error = f64::NAN;
    let mut sample = |t: f64, p: &Particles<()>| {
        let expected = Vector::NEG_Y * STANDARD_GRAVITY * p.total_mass() * t;
        error = (p.momentum() - expected).length() / expected.length();
    };
    let steps = run(grid, n, elastic()?, particles, config, &[t], &mut sample)?;
    Ok(FreeFall { momentum_error: error, steps })
}

/// the Drucker-Prager sand of the 3D column (E = 2 MPa, ν = 0.3, c = 10 Pa, φ = 35°, ψ = 0,
/// the cone through the triaxial-compression corners).
pub fn sand() -> Result<DruckerPrager, ConstitutiveError> {
    DruckerPrager::new(DruckerPragerParams {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 35.0,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        mixing: 1.0,
        cone_match: ConeMatch::Outer,
    })
}

/// The bits of a collapsing sand column's state after `steps` steps: a 1.2 × 1 × 1.2 m column
/// of Drucker-Prager sand at 0.1 m cells, 2³ particles per cell (11 520 particles, many
/// chunks and node blocks), quadratic B-splines and APIC, on a floor with μ = 0.5 between
/// frictionless walls, run on the current rayon pool. Bit-identical results for any thread
/// count are what is asserted of it.
pub fn collapse_bits(steps: u64) -> Result<(usize, Vec<u64>), CaseError> {
    let n = Numerics {
        cell: 0.1,
        ppc: 2,
        scheme: Scheme::Musl,
        transfer: Transfer::Apic,
        shape: RegularShape::BSpline,
        courant: 0.3,
    };
    let grid =
        RegularGrid::new(Vector::ZERO, Vector::splat(n.cell), cells([3.0, 1.5, 3.0], n.cell))
            .map_err(setup)?;
    let min = Vector::new(0.9, 0.0, 0.9);
    let shape = Shape::Box { min, max: min + Vector::new(1.2, 1.0, 1.2) };
    let material = sand().map_err(setup)?;
    let particles = block(&shape, n.cell, n.ppc, 1600.0, Vector::ZERO, material.initial_state());
    let count = particles.len();
    let free = Friction::Coulomb { mu: 0.0 };
    let config = SolverConfig {
        scheme: n.scheme,
        transfer: n.transfer,
        time_step: TimeStep::Courant(n.courant),
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.5 }),
            ..Boundaries::all(free)
        },
        ..Default::default()
    };
    let mut solver =
        Solver::new(mpm_grid3d::QuadraticBSpline::new(grid), vec![material], particles, config)?;
    for _ in 0..steps {
        solver.step()?;
    }
    let p = solver.particles();
    let mut bits = Vec::with_capacity(p.len() * 12);
    for i in 0..p.len() {
        bits.extend(p.position[i].to_array().map(f64::to_bits));
        bits.extend(p.velocity[i].to_array().map(f64::to_bits));
        bits.extend(p.stress[i].to_array().map(f64::to_bits));
    }
    Ok((count, bits))
}

/// What the 3D vibrating bar measured over five periods.
#[derive(Clone, Debug, Default)]
pub struct Bar {
    /// measured period / exact period (NaN with fewer than two zero crossings)
    pub period_ratio: f64,
    /// largest |E(t) − E0| / E0
    pub worst_energy: f64,
    /// zero crossings of the mean velocity seen (ten expected in five periods)
    pub crossings: usize,
    /// steps and particles
    pub steps: u64,
    /// particles
    pub particles: usize,
}

/// The vibrating bar of [`crate::bar`] (fixed–free, L = 25 m, c = 10 m/s, T = 10 s) along the
/// grid's z axis, the axis the plane-strain solver does not have: one cell square in x and y,
/// fixed to the back wall (z = 0), ν = 0 so that it is one-dimensional, run for five periods
/// with the numerics `n` (its cell, scheme, transfer, shape functions and Courant number).
pub fn vibrating_bar(n: &Numerics) -> Result<Bar, CaseError> {
    use crate::bar::{E, L, RHO, V0, period};
    let cell = n.cell;
    // one cell of material between two empty ones in x and y (the stencils' reach), 28 m in z
    let grid = RegularGrid::new(
        Vector::new(-cell, -cell, 0.0),
        Vector::splat(cell),
        [3, 3, (28.0 / cell).round() as usize],
    )
    .map_err(setup)?;
    let material = LinearElastic::from_young_poisson(E, 0.0).map_err(setup)?;
    let beta = std::f64::consts::PI / (2.0 * L);
    let mut particles = block(
        &Shape::Box { min: Vector::ZERO, max: Vector::new(cell, cell, L) },
        cell,
        n.ppc,
        RHO,
        Vector::ZERO,
        (),
    );
    for (v, x) in particles.velocity.iter_mut().zip(&particles.position) {
        *v = Vector::new(0.0, 0.0, V0 * (beta * x.z).sin());
    }
    let config = SolverConfig {
        scheme: n.scheme,
        transfer: n.transfer,
        time_step: TimeStep::Courant(n.courant),
        gravity: Vector::ZERO,
        boundaries: Boundaries { back_wall: Some(Friction::Fixed), ..Default::default() },
        ..Default::default()
    };
    /// the bar as a job over the shape functions.
    struct OnShape(LinearElastic, Particles<()>, SolverConfig, f64);
    impl ShapeJob for OnShape {
        type Output = Result<Bar, SolverError>;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
            let OnShape(material, particles, config, period) = self;
            let mut s = Solver::new(shape, vec![material], particles, config)?;
            let e0 = s.energy().total();
            let mut worst: f64 = 0.0;
            let mut crossings = Vec::new();
            let mut last = (0.0, mass_mean(s.particles(), &s.particles().velocity).z);
            while s.time() < 5.0 * period {
                s.step()?;
                let v = mass_mean(s.particles(), &s.particles().velocity).z;
                if (v > 0.0) != (last.1 > 0.0) {
                    // the zero of the mean velocity within the step, linearly interpolated
                    crossings.push(last.0 + (s.time() - last.0) * last.1 / (last.1 - v));
                }
                last = (s.time(), v);
                worst = worst.max((s.energy().total() - e0).abs() / e0);
            }
            // successive zero crossings of cos ωt are half a period apart
            let k = crossings.len();
            let period_ratio = if k >= 2 {
                2.0 * (crossings[k - 1] - crossings[0]) / (k - 1) as f64 / period
            } else {
                f64::NAN
            };
            Ok(Bar {
                period_ratio,
                worst_energy: worst,
                crossings: k,
                steps: s.step_count(),
                particles: s.particles().len(),
            })
        }
    }
    let job = OnShape(material, particles, config, period());
    Ok(with_regular_shape(n.shape, grid, n.ppc, job).map_err(setup)??)
}

/// What the 3D Bagnold flow measured at the end of the run (as [`crate::open_core::Bagnold`]).
pub type Bagnold = crate::open_core::Bagnold;

/// Steady flow of a μ(I) layer down a rough 24° plane, in 3D: the case of
/// [`crate::open_core::bagnold`] (glass beads, depth 8 mm over `cells` cells, a periodic strip
/// 4 cells long in x, gravity turned by θ in the x–y plane, a no-slip base, APIC, MUSL, a
/// gravity ramp of 0.05 s) two cells wide in z between frictionless back and front walls,
/// 2 × 2 × 2 particles per cell, run from rest for `end` seconds: each layer's mean speed
/// against Bagnold's profile u(z) = (2 I_θ / 3d) √(φ g cos θ) (h^{3/2} − (h − z)^{3/2}).
pub fn bagnold(kind: RegularShape, cells: usize, end: f64) -> Result<Bagnold, CaseError> {
    use crate::open_core::{SOLID_FRACTION, bagnold_velocity, glass_beads};
    let (depth, theta, columns, width) = (8e-3, 24.0f64, 4u32, 2u32);
    let cell = depth / cells as f64;
    let grid = RegularGrid::new(
        Vector::ZERO,
        Vector::splat(cell),
        [columns as usize, cells + 4, width as usize],
    )
    .map_err(setup)?;
    let m = glass_beads()?;
    let density = SOLID_FRACTION * m.params().grain_density;
    let length = f64::from(columns) * cell;
    let body =
        Shape::Box { min: Vector::ZERO, max: Vector::new(length, depth, f64::from(width) * cell) };
    let particles = block(&body, cell, 2, density, Vector::ZERO, m.initial_state());
    let t = theta.to_radians();
    let config = SolverConfig {
        scheme: Scheme::Musl,
        transfer: Transfer::Apic,
        time_step: TimeStep::Courant(0.5),
        gravity: STANDARD_GRAVITY * Vector::new(t.sin(), -t.cos(), 0.0),
        boundaries: Boundaries {
            ground: Some(Friction::Rough),
            back_wall: Some(Friction::Coulomb { mu: 0.0 }),
            front_wall: Some(Friction::Coulomb { mu: 0.0 }),
            ..Default::default()
        },
        periodic: Some(mpm_solver3d::Periodic { x_min: 0.0, columns, length }),
        gravity_ramp: 0.05,
        ..Default::default()
    };
    // each particle's layer: 2 per cell, counted from the base
    let layers = 2 * cells;
    let layer: Vec<usize> = particles
        .position
        .iter()
        .map(|x| ((x.y / (0.5 * cell)).floor() as usize).min(layers - 1))
        .collect();
    let count = particles.len();
    // (mean height, mean x velocity) of each layer at 3/4 of the run and at its end
    let mut means: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut sample = |_t: f64, p: &Particles<mpm_constitutive::MuIState>| {
        let mut sum = vec![(0.0, 0.0, 0usize); layers];
        for ((x, v), &k) in p.position.iter().zip(&p.velocity).zip(&layer) {
            sum[k].0 += x.y;
            sum[k].1 += v.x;
            sum[k].2 += 1;
        }
        means.push(
            sum.into_iter().map(|(z, u, n)| (z / n.max(1) as f64, u / n.max(1) as f64)).collect(),
        );
    };
    let n = Numerics {
        cell,
        ppc: 2,
        scheme: Scheme::Musl,
        transfer: Transfer::Apic,
        shape: kind,
        courant: 0.5,
    };
    let steps = run(grid, &n, m, particles, config, &[0.75 * end, end], &mut sample)?;
    let surface = bagnold_velocity(&m, theta, depth, depth);
    let (mut worst, mut change) = (0.0f64, 0.0f64);
    let mut profile = Vec::new();
    for (&(z, u), &(_, u_late)) in means[1].iter().zip(&means[0]) {
        let exact = bagnold_velocity(&m, theta, depth, z);
        worst = worst.max((u - exact).abs() / surface);
        change = change.max((u - u_late).abs() / surface);
        profile.push((z, u, exact));
    }
    Ok(Bagnold { profile, worst, change, cells, steps, particles: count })
}

/// What [`oblique_wall`] measured.
#[derive(Clone, Debug, Default)]
pub struct ObliqueWall {
    /// largest |p(t) − p(0) − J(t)| / |p(0)| over the run (J: the wall's impulse; nothing else
    /// acts).
    pub balance: f64,
    /// the wall's impulse over the run: normal component J·n (> 0: a push) (kg m/s).
    pub normal_impulse: f64,
    /// its tangential part |J − (J·n) n| (kg m/s).
    pub tangential_impulse: f64,
    /// J_t · v_t(0) / (|J_t| |v_t(0)|): −1 when friction opposes the tangential approach.
    pub tangential_alignment: f64,
    /// the centre of mass's velocity along n at the end (m/s; the approach is negative).
    pub normal_velocity_end: f64,
    /// smallest (d_p − r_p) / r_p over the run and the particles, d_p the distance of a
    /// particle's centre from the plane and r_p its half-size: below −1, a centre behind it.
    pub closest_edge: f64,
    /// steps and particles.
    pub steps: u64,
    /// particles.
    pub particles: usize,
}

/// The normal of [`oblique_wall`]'s plane (into the material): oblique to all three axes.
pub fn oblique_normal() -> Vector {
    Vector::new(-1.0, 0.35, -0.45).normalize()
}

/// A 0.2 m elastic cube (E = 1 MPa, ν = 0.3, ρ = 1000 kg/m³, 2³ particles per 0.05 m cell)
/// thrown at 2 m/s along +x, without gravity, into the plane through (1.3, 0.6, 0.6) with
/// [`oblique_normal`] and Coulomb friction `mu` (0: frictionless), as the 2D check dam
/// (`open_core::obstacle`) but with a plane no grid axis lies in. It approaches the plane at
/// 1.74 m/s and hits it at about 0.3 s; the run ends at 0.5 s, after the rebound. The small-mass rule is off so that the balance isolates the wall's impulse.
pub fn oblique_wall(kind: RegularShape, mu: f64) -> Result<ObliqueWall, CaseError> {
    let cell = 0.05;
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(cell), [36, 24, 24]).map_err(setup)?;
    with_regular_shape(kind, grid, 2, ObliqueWallJob { cell, mu }).map_err(setup)?
}

struct ObliqueWallJob {
    cell: f64,
    mu: f64,
}

impl ShapeJob for ObliqueWallJob {
    type Output = Result<ObliqueWall, CaseError>;

    fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
        let n = oblique_normal();
        let law = Friction::Coulomb { mu: self.mu };
        let wall = mpm_contact3d::Wall::plane(Vector::new(1.3, 0.6, 0.6), n, law).map_err(setup)?;
        let min = Vector::new(0.5, 0.5, 0.5);
        let body = Shape::Box { min, max: min + Vector::splat(0.2) };
        let v0 = Vector::new(2.0, 0.0, 0.0);
        let particles = block(&body, self.cell, 2, 1000.0, v0, ());
        let count = particles.len();
        let config = SolverConfig {
            gravity: Vector::ZERO,
            walls: vec![wall],
            small_mass_ratio: 0.0,
            ..Default::default()
        };
        let elastic = LinearElastic::from_young_poisson(1e6, 0.3).map_err(setup)?;
        let mut s = Solver::new(shape, vec![elastic], particles, config)?;
        let p0 = s.particles().momentum();
        let mut r =
            ObliqueWall { closest_edge: f64::INFINITY, particles: count, ..Default::default() };
        let end = 0.5;
        while s.time() < end * (1.0 - 1e-12) {
            s.step_capped(end - s.time())?;
            let p = s.particles();
            let imbalance = p.momentum() - p0 - s.boundary_impulse();
            r.balance = r.balance.max(imbalance.length() / p0.length());
            for (x, v) in p.position.iter().zip(&p.volume) {
                let half = 0.5 * v.cbrt();
                r.closest_edge = r.closest_edge.min((wall.distance(*x) - half) / half);
            }
        }
        let j = s.boundary_impulse();
        r.normal_impulse = j.dot(n);
        let jt = j - r.normal_impulse * n;
        r.tangential_impulse = jt.length();
        let vt0 = v0 - v0.dot(n) * n;
        r.tangential_alignment = if r.tangential_impulse > 0.0 {
            jt.dot(vt0) / (r.tangential_impulse * vt0.length())
        } else {
            0.0
        };
        let p = s.particles();
        r.normal_velocity_end = p.momentum().dot(n) / p.total_mass();
        r.steps = s.step_count();
        Ok(r)
    }
}
