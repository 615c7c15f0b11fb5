//! The energy ledger (SPEC §5): what is stored, what was dissipated, and the residual.
//!
//! Stored: kinetic Σ ½ m_p |v_p|², elastic strain Σ V_p ½ σ_p : C⁻¹ : σ_p, and gravitational potential
//! Σ −m_p g·x_p (zero at the origin). Dissipated (accumulated over the run): plastic work
//! Σ V_p σ_p : Δεᵖ_p, friction work and normal-constraint work at boundary nodes, and the kinetic
//! energy the PIC share of a blended transfer removed (`SolverConfig::pic_fraction`), and the
//! friction work of side walls across the plane (`SolverConfig::side_walls`). External work is the
//! energy put in by loads that change in time: while gravity is ramped up, the potential
//! −m g(t)·x changes with g at fixed x, and that change Σ −m_p Δg·x_p is booked as external work.
//!
//! The residual is (stored + dissipated) − (initial stored + external work): a perfect integrator
//! gives zero; its size is the numerical energy error a user reads to judge a run's accuracy.

use serde::{Deserialize, Serialize};

use crate::math::{Real, Vector};

pub use mpm_core::{EnergyCheck, EnergyLedger};

/// Energy dissipated so far, carried by the solver between steps (and in checkpoints).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Dissipation {
    /// Σ V_p σ_p : Δεᵖ_p over all steps.
    pub plastic: Real,
    /// Boundary friction work over all steps.
    pub friction: Real,
    /// Normal-constraint work over all steps.
    pub constraint: Real,
    /// External work of time-varying loads over all steps (not a dissipation: an input).
    pub external: Real,
    /// Kinetic energy the PIC share of the transfer removed over all steps.
    #[serde(default)]
    pub transfer: Real,
    /// Kinetic energy the side walls' friction took over all steps ([`crate::SideWalls`]).
    #[serde(default)]
    pub side_walls: Real,
    /// Impulse the boundaries gave the material over all steps (N·s per m of thickness): with
    /// gravity's, it is the change of the material's momentum (a check of conservation).
    #[serde(default)]
    pub impulse: Vector,
    /// What left the run through outflow faces ([`crate::Outflow`]).
    #[serde(default)]
    pub outflow: Outflowed,
}

/// What particles took with them when they left the run through outflow faces, summed over
/// the run (in particle order within a step, so the same bits for any thread count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Outflowed {
    /// particles that left.
    pub particles: u64,
    /// their mass (kg; kg per metre of thickness in plane strain).
    pub mass: Real,
    /// their momentum Σ m_p v_p as they left (N·s; per metre in plane strain).
    pub momentum: Vector,
    /// their energy as they left: kinetic, elastic and potential, as the ledger counts them (J;
    /// J/m in plane strain).
    pub energy: Real,
    /// when the first one left (s); `None` while none has.
    pub first_time: Option<Real>,
}
