//! The energy ledger (SPEC §5): what is stored, what was dissipated, and the residual.
//!
//! Stored: kinetic Σ ½ m_p |v_p|², elastic strain Σ V_p ½ σ_p : C⁻¹ : σ_p, and gravitational potential
//! Σ −m_p g·x_p (zero at the origin). Dissipated (accumulated over the run): plastic work
//! Σ V_p σ_p : Δεᵖ_p, friction work and normal-constraint work at boundary nodes. External work is the
//! energy put in by loads that change in time: while gravity is ramped up, the potential
//! −m g(t)·x changes with g at fixed x, and that change Σ −m_p Δg·x_p is booked as external work.
//!
//! The residual is (stored + dissipated) − (initial stored + external work): a perfect integrator
//! gives zero; its size is the numerical energy error a user reads to judge a run's accuracy.

use serde::{Deserialize, Serialize};

use crate::math::Real;

/// Energies of one instant (J per metre of thickness).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyLedger {
    /// Σ ½ m_p |v_p|².
    pub kinetic: Real,
    /// Σ V_p ½ σ_p : C⁻¹ : σ_p (recoverable elastic energy).
    pub strain: Real,
    /// Σ −m_p g·x_p.
    pub potential: Real,
    /// Plastic dissipation accumulated since the start.
    pub plastic_dissipation: Real,
    /// Work done against boundary friction since the start.
    pub friction_work: Real,
    /// Kinetic energy removed by normal boundary constraints since the start.
    pub constraint_work: Real,
    /// Work of non-conservative external loads since the start.
    pub external_work: Real,
    /// (stored + dissipated) − (initial stored + external work).
    pub residual: Real,
}

impl EnergyLedger {
    /// kinetic + strain + potential.
    pub fn stored(&self) -> Real {
        self.kinetic + self.strain + self.potential
    }

    /// plastic + friction + constraint work.
    pub fn dissipated(&self) -> Real {
        self.plastic_dissipation + self.friction_work + self.constraint_work
    }

    /// stored + dissipated: constant for a perfect integrator without external work.
    pub fn total(&self) -> Real {
        self.stored() + self.dissipated()
    }
}

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
}
