//! The manufactured solution of Wallstedt & Guilkey (2008), "An evaluation of explicit time
//! integration schemes for use with the generalized interpolation material point method"
//! (J. Comput. Phys. 227), for this code's material law: a displacement field is prescribed, the
//! body force that makes it exact is derived, and the particles' displacement error after a
//! fixed time measures the spatial order of convergence of a discretisation.
//!
//! The field is the x half of their axis-aligned one, in a unit bar between fixed walls
//! (X ∈ [0, 1], one cell thick):
//!
//! u_x(X, t) = A sin(2πX) sin(π c t),  u_y = 0,  c = √(E/ρ₀),
//!
//! with ν = 0, so that plane strain has no lateral stress (σ_yy = σ_zz = 0: the top and bottom
//! faces are traction-free, as the bar's are) and the one-dimensional motion is exact in 2D.
//! Along an axis-aligned motion the hypoelastic update σ̇ = E ε̇, ε̇ = ∂v/∂x (eqs 9–11: the
//! strain rate of the current configuration) integrates to the logarithmic strain: with
//! F = 1 + ∂u/∂X, σ_xx = E ln F. The nominal stress is P = J σ F⁻¹ = σ (J = F) and the
//! momentum balance in the reference configuration, ρ₀ ü = ∂P/∂X + ρ₀ b, gives
//!
//! b(X, t) = ü − (E/ρ₀) (∂F/∂X) / F,  ∂F/∂X = −(2π)² A sin(2πX) sin(π c t),
//!
//! exact at any amplitude (W&G derive the same for a neo-Hookean solid; the strains here reach
//! ±2π A = ±12.6 %). The time function sin(π c t) is not the bar's natural frequency (2π c),
//! so the body force does real work. The error is read at t = 1/(2c), where the displacement
//! peaks.

use mpm_constitutive::LinearElastic;
use mpm_contact::Friction;
use mpm_grid::{RegularGrid, ShapeFunctions, ShapeJob, with_regular_shape};
use mpm_solver::generate::Shape;
use mpm_solver::{Boundaries, Solver, SolverConfig, TimeStep, Vector};

use crate::{CaseError, Cost, Discretisation, block, setup};

/// Young's modulus (Pa).
pub const E: f64 = 1e7;
/// Reference density ρ₀ (kg/m³).
pub const RHO: f64 = 1000.0;
/// Displacement amplitude A (m) of [`manufactured`]: strains up to ±2πA = ±12.6 %.
pub const AMPLITUDE: f64 = 0.02;
/// The cell (m) whose Courant number `Discretisation::courant` sets: Δt = C · (1/1024 m) / c on
/// every level (0.98 µs at C = 0.1, 5 120 steps), so that a refinement ladder measures the
/// spatial error at one Δt. The schemes are first order in time here (the error at 64 cells
/// fell from 1.6e-3 to 4e-4 of A when Δt went from C = 0.1 at 1/64 m to 1/256 m, at A = 1e-4),
/// so this Δt leaves a time error of about 1e-4 of A.
pub const REFERENCE_CELL: f64 = 1.0 / 1024.0;

/// the wave speed c = √(E/ρ₀) (m/s): 100 m/s.
pub fn wave_speed() -> f64 {
    (E / RHO).sqrt()
}

/// the time at which the error is read (s): 1/(2c), where sin(π c t) = 1.
pub fn end_time() -> f64 {
    0.5 / wave_speed()
}

/// the wave number k = nπ (1/m) of mode n: u = 0 at both walls. Mode 2 (k = 2π) is W&G's
/// sin(2πX), odd about the middle; an odd mode is even about it (its momentum does not cancel).
pub fn wave_number(mode: u32) -> f64 {
    f64::from(mode) * std::f64::consts::PI
}

/// the exact displacement u_x(X, t) (m) at amplitude `a`, mode 2.
pub fn displacement(a: f64, x: f64, t: f64) -> f64 {
    displacement_mode(a, 2, x, t)
}

/// [`displacement`] of mode `n`.
pub fn displacement_mode(a: f64, n: u32, x: f64, t: f64) -> f64 {
    let (k, w) = (wave_number(n), std::f64::consts::PI * wave_speed());
    a * (k * x).sin() * (w * t).sin()
}

/// the exact velocity ∂u_x/∂t (m/s) at amplitude `a`, mode `n`.
pub fn velocity(a: f64, n: u32, x: f64, t: f64) -> f64 {
    let (k, w) = (wave_number(n), std::f64::consts::PI * wave_speed());
    a * w * (k * x).sin() * (w * t).cos()
}

/// the body force per unit mass b_x(X, t) (m/s²) that makes the field of amplitude `a`, mode
/// `n`, exact.
pub fn body_force(a: f64, n: u32, x: f64, t: f64) -> f64 {
    let (k, w) = (wave_number(n), std::f64::consts::PI * wave_speed());
    let (sx, st) = ((k * x).sin(), (w * t).sin());
    let f = 1.0 + a * k * (k * x).cos() * st;
    let df = -a * k * k * sx * st;
    -a * w * w * sx * st - E / RHO * df / f
}

/// The discretisation the verification and the study refine: MUSL, 2 × 2 particles per cell,
/// Δt of C = 0.1 on the [`REFERENCE_CELL`], bilinear, lumped, 1/8 m cells.
pub fn baseline() -> Discretisation {
    Discretisation {
        cell: 0.125,
        ppc: 2,
        scheme: mpm_solver::Scheme::Musl,
        shape: crate::ShapeKind::Bilinear,
        courant: 0.1,
        mass: crate::MassMatrix::Lumped,
    }
}

/// What a run measured at [`end_time`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Manufactured {
    /// root mean square over the particles of the displacement error, relative to A
    pub rms_error: f64,
    /// largest displacement error over the particles, relative to A
    pub max_error: f64,
    /// |energy residual| at the end (the body force's work booked as external work) relative to
    /// the initial kinetic energy
    pub energy_residual: f64,
    /// |p(t) − p(0) − body force impulse − boundary impulse| relative to Σ_steps Σ_p m_p |b_p| Δt
    /// (the net impulses nearly cancel, the field being odd about the middle): the momentum
    /// balance (to rounding with either matrix)
    pub momentum_error: f64,
    /// steps and particles
    pub cost: Cost,
}

/// Runs the manufactured solution at amplitude [`AMPLITUDE`] and `d` (cell 1 m / n), with the
/// fixed time step Δt = `d.courant` · [`REFERENCE_CELL`] / c, whatever the cell (rounded down to
/// land on [`end_time`]).
pub fn manufactured(d: &Discretisation) -> Result<Manufactured, CaseError> {
    manufactured_at(d, AMPLITUDE)
}

/// [`manufactured`] at amplitude `a` (m; 0 < a < 1/(2π), so that F > 0): a small one (1e-4)
/// isolates the discretisation from finite strain.
pub fn manufactured_at(d: &Discretisation, a: f64) -> Result<Manufactured, CaseError> {
    manufactured_mode(d, a, 2)
}

/// [`manufactured_at`] with the field of mode `n` (k = nπ, 1 ≤ n ≤ 8).
pub fn manufactured_mode(d: &Discretisation, a: f64, n: u32) -> Result<Manufactured, CaseError> {
    if !(1..=8).contains(&n) {
        return Err(setup(format!("mode {n}: 1 to 8")));
    }
    if !(a > 0.0 && a * wave_number(n) < 1.0) {
        return Err(setup(format!("amplitude {a} m: F = 1 + kA cos … must stay positive")));
    }
    let cells = (1.0 / d.cell).round();
    if !(cells >= 2.0 && (cells * d.cell - 1.0).abs() < 1e-12) {
        return Err(setup(format!("the bar is 1 m long: {} m is not 1 m / n", d.cell)));
    }
    // Five rows with the bar in the middle one: every stencil (B-spline: 3 × 3) stays inside.
    let grid = RegularGrid::new(
        Vector::new(0.0, -2.0 * d.cell),
        Vector::splat(d.cell),
        [cells as usize, 5],
    )
    .map_err(setup)?;
    /// the bar as a job over the shape functions.
    struct OnShape<'a>(&'a Discretisation, f64, u32);
    impl ShapeJob for OnShape<'_> {
        type Output = Result<Manufactured, CaseError>;
        fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> Self::Output {
            run_on(shape, self.0, self.1, self.2)
        }
    }
    with_regular_shape(d.shape, grid, d.ppc, OnShape(d, a, n)).map_err(setup)?
}

fn run_on<S: ShapeFunctions<N>, const N: usize>(
    shape: S,
    d: &Discretisation,
    a: f64,
    n: u32,
) -> Result<Manufactured, CaseError> {
    let material = LinearElastic::from_young_poisson(E, 0.0).map_err(setup)?;
    let mut particles = block(
        &Shape::Rectangle { min: Vector::ZERO, max: Vector::new(1.0, d.cell) },
        d.cell,
        d.ppc,
        RHO,
        Vector::ZERO,
        (),
    );
    for i in 0..particles.len() {
        particles.velocity[i] = Vector::new(velocity(a, n, particles.position[i].x, 0.0), 0.0);
    }
    let end = end_time();
    let steps = (end / (d.courant * REFERENCE_CELL / wave_speed())).ceil().max(1.0);
    let dt = end / steps;
    let config = SolverConfig {
        scheme: d.scheme,
        // every step's Courant number is still checked against 1 (the stretched bar is faster)
        time_step: TimeStep::Fixed(dt),
        mass: d.mass,
        gravity: Vector::ZERO,
        // the small-mass rule (§2(3)) drops the force at light nodes, and with it Newton's third
        // law there: off, so that the momentum balance checks the walls' impulse alone
        small_mass_ratio: 0.0,
        boundaries: Boundaries {
            left_wall: Some(Friction::Fixed),
            right_wall: Some(Friction::Fixed),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut s = Solver::new(shape, vec![material], particles, config)?;
    let kinetic = s.energy().kinetic;
    let p0 = s.particles().momentum();
    let (mut body_impulse, mut body_scale) = (Vector::ZERO, 0.0);
    for step in 0..steps as u64 {
        let mid = (step as f64 + 0.5) * dt;
        s.set_body_force(|p, all| {
            Vector::new(body_force(a, n, all.initial_position[p].x, mid), 0.0)
        })?;
        let p = s.particles();
        let pushes =
            (0..p.len()).map(|i| p.mass[i] * body_force(a, n, p.initial_position[i].x, mid));
        let (pushed, size) = pushes.fold((0.0, 0.0), |(s, z), f| (s + f, z + f.abs()));
        s.step()?;
        body_impulse.x += pushed * s.last_report().dt;
        body_scale += size * s.last_report().dt;
    }
    let walls = s.boundary_impulse();
    let change = s.particles().momentum() - p0;
    let momentum_error = (change - body_impulse - walls).length() / body_scale;
    let t = s.time();
    let p = s.particles();
    let (mut sum, mut max) = (0.0_f64, 0.0_f64);
    for (x, x0) in p.position.iter().zip(&p.initial_position) {
        let exact = Vector::new(x0.x + displacement_mode(a, n, x0.x, t), x0.y);
        let e = (*x - exact).length();
        sum += e * e;
        max = max.max(e);
    }
    Ok(Manufactured {
        rms_error: (sum / p.len() as f64).sqrt() / a,
        max_error: max / a,
        energy_residual: s.energy().residual.abs() / kinetic,
        momentum_error,
        cost: Cost { steps: s.step_count(), particles: p.len() },
    })
}
