//! Typed errors of the solver: bad set-up (before any step) and instabilities (during a run).
//!
//! An instability names the step, the particle (index and position) and the cause, so that a user can
//! find the offending region in the last frame written before the failure.

use crate::math::Vector;
use mpm_constitutive::ConstitutiveError;
use mpm_grid::LocateError;

/// Which particle field went non-finite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// Position x_p.
    Position,
    /// Velocity v_p.
    Velocity,
    /// Volume V_p (and so density).
    Volume,
}

impl std::fmt::Display for Field {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Field::Position => "position",
            Field::Velocity => "velocity",
            Field::Volume => "volume",
        })
    }
}

/// Everything that can stop a solver from being built or from taking a step.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// A configuration value outside its admissible range.
    #[error("invalid solver setting `{name}` = {value}: {expected}")]
    InvalidSetting {
        /// name of the setting
        name: &'static str,
        /// the value given
        value: f64,
        /// what is admissible
        expected: &'static str,
    },
    /// Two settings that each are admissible but not together.
    #[error("solver setting `{setting}` cannot go with `{with}`: {reason}")]
    Incompatible {
        /// the setting refused
        setting: &'static str,
        /// the setting it conflicts with
        with: &'static str,
        /// why, and what to use instead
        reason: &'static str,
    },
    /// A particle given to the solver is inconsistent (non-positive mass, unknown material, ...).
    #[error("particle {particle} at {p}: {reason}", p = crate::math::At(*position))]
    InvalidParticle {
        /// particle index
        particle: usize,
        /// its position
        position: Vector,
        /// what is wrong
        reason: String,
    },
    /// The scene has no particles.
    #[error("the scene has no particles")]
    NoParticles,
    /// A particle is outside the grid (at set-up, or it left the grid during the run).
    #[error("step {step}: particle {particle} at {p} is outside the grid: {cause}", p = crate::math::At(*position))]
    OutsideGrid {
        /// step at which it happened (0 = before the first step)
        step: u64,
        /// particle index
        particle: usize,
        /// its position
        position: Vector,
        /// what the grid reported
        cause: LocateError,
    },
    /// A particle field became NaN or infinite.
    #[error("step {step}: particle {particle} at {p} has a non-finite {field}", p = crate::math::At(*position))]
    NonFinite {
        /// step at which it happened
        step: u64,
        /// particle index
        particle: usize,
        /// its (last finite) position
        position: Vector,
        /// which field
        field: Field,
    },
    /// A particle's volume became zero or negative (the material was turned inside out).
    #[error("step {step}: particle {particle} at {p} inverted: volume ratio 1 + tr Δε = {ratio}", p = crate::math::At(*position))]
    Inverted {
        /// step at which it happened
        step: u64,
        /// particle index
        particle: usize,
        /// its position
        position: Vector,
        /// the volume ratio of the increment
        ratio: f64,
    },
    /// With a fixed time step, the Courant number grew above 1 during the run.
    #[error(
        "step {step}: Courant number {courant:.3} > 1 at particle {particle} (speed {speed:.3} m/s): \
         the fixed time step {dt:e} s is too large; use a Courant-controlled step or a smaller dt"
    )]
    CourantExceeded {
        /// step at which it happened
        step: u64,
        /// particle that set the limit
        particle: usize,
        /// the Courant number reached
        courant: f64,
        /// that particle's speed
        speed: f64,
        /// the fixed time step
        dt: f64,
    },
    /// With a fixed time step, gravity and the fastest particle's speed would carry it more than
    /// one cell in one step (nothing in eq 13 bounds that for a soft or stress-free material).
    #[error(
        "step {step}: particle {particle} at {p} would move {cells:.3} cells in one step \
         (its speed and gravity): the fixed time step {dt:e} s is too large; use a \
         Courant-controlled step or a smaller dt",
        p = crate::math::At(*position)
    )]
    StepTooLong {
        /// step at which it happened
        step: u64,
        /// the fastest particle
        particle: usize,
        /// its position
        position: Vector,
        /// (|v|_max Δt + ½ |g| Δt²) / L
        cells: f64,
        /// the fixed time step
        dt: f64,
    },
    /// A consistent-mass solve (`stages/mass.rs`) did not converge: the matrix is not the
    /// symmetric positive definite one it should be, or its right-hand side is not finite.
    #[error(
        "step {step}: the consistent-mass solve for the {solve} did not converge after \
         {iterations} iterations (relative residual {relative_residual:e}); a non-finite force or \
         velocity, or use mass = \"lumped\""
    )]
    MassSolve {
        /// step at which it happened
        step: u64,
        /// which system
        solve: &'static str,
        /// conjugate-gradient iterations taken
        iterations: usize,
        /// ‖r‖ / ‖b‖ in the lumped matrix's inverse norm
        relative_residual: f64,
    },
    /// The constitutive update refused its input.
    #[error("step {step}: particle {particle} at {p}: {source}", p = crate::math::At(*position))]
    Constitutive {
        /// step at which it happened
        step: u64,
        /// particle index
        particle: usize,
        /// its position
        position: Vector,
        /// the model's error
        source: ConstitutiveError,
    },
    /// The implicit initial state ([`crate::GeostaticSettings`]) found no equilibrium.
    #[error(
        "implicit initial state: no equilibrium at {attempted_pct:.2} % of gravity after {iterations} \
         Newton iterations (residual {residual:.3e} of the gravity load; in equilibrium up to \
         {load_pct:.2} % of gravity): {cause}. The material cannot stand as given: a slope \
         steeper than its friction holds, a base that cannot hold it, or a body no boundary \
         supports",
        attempted_pct = 100.0 * attempted,
        load_pct = 100.0 * load_factor
    )]
    InitialState {
        /// the largest load factor (share of gravity) in equilibrium
        load_factor: f64,
        /// the load factor of the last attempt
        attempted: f64,
        /// Newton iterations taken in all
        iterations: u32,
        /// the last ‖R‖ / ‖f^ext‖
        residual: f64,
        /// why the last attempt failed
        cause: String,
    },
    /// A signal stopped the initial state before it was found (see `Solver::set_interrupt`);
    /// the particles are as they were before it.
    #[error(
        "the initial state ({method}) was interrupted by a signal before it was found; nothing \
         of it was kept and there is nothing to resume: run the scene again"
    )]
    InitialStateInterrupted {
        /// `"implicit"` or `"gravity_ramp"`.
        method: &'static str,
    },
    /// The implicit initial state is in equilibrium only with its base stuck beyond the base's
    /// friction: the body would slide as a whole.
    #[error(
        "implicit initial state: the material is in equilibrium only on a stuck base: the \
         tangential reactions on a friction plane sum to {tangential:.4e} N/m, {ratio:.3} times \
         what its friction holds ({capacity:.4e} N/m); the body would slide as a whole (a \
         retaining wall or gate, or a rougher base, holds it)"
    )]
    SlidingBase {
        /// |Σ tangential| / μ Σ normal reaction on the worst plane
        ratio: f64,
        /// |Σ tangential reaction| on it (N/m)
        tangential: f64,
        /// μ Σ normal reaction on it (N/m)
        capacity: f64,
    },
}
