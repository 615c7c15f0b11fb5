//! The energy ledger (SPEC §5): what is stored, what was dissipated, and the residual.
//!
//! Stored: kinetic Σ ½ m_p |v_p|², elastic strain Σ V_p ½ σ_p : C⁻¹ : σ_p, and gravitational potential
//! Σ −m_p g·x_p (zero at the origin). Dissipated (accumulated over the run): plastic work
//! Σ V_p σ_p : Δεᵖ_p, friction work and normal-constraint work at boundary nodes, and the kinetic
//! energy the PIC share of a blended transfer removed (the settings' `pic_fraction`), and the
//! friction work of side walls across the plane ([`crate::SideWalls`]). External work is the
//! energy put in by loads that change in time: while gravity is ramped up, the potential
//! −m g(t)·x changes with g at fixed x, and that change Σ −m_p Δg·x_p is booked as external work.
//!
//! The residual is (stored + dissipated) − (initial stored + external work): a perfect integrator
//! gives zero; its size is the numerical energy error a user reads to judge a run's accuracy.

use serde::{Deserialize, Serialize};

use crate::settings::Real;

/// Energies of one instant (J; J per metre of thickness in plane strain).
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
    /// Kinetic energy removed by the PIC share of the velocity transfer since the start
    /// (the settings' `pic_fraction`; 0 under pure FLIP).
    #[serde(default)]
    pub transfer_dissipation: Real,
    /// Work done against the friction of side walls across the plane since the start
    /// ([`crate::SideWalls`]; 0 without them).
    #[serde(default)]
    pub side_wall_friction: Real,
    /// Work of non-conservative external loads since the start.
    pub external_work: Real,
    /// Energy (kinetic, elastic and potential, as the stored terms count them) carried out of
    /// the run by particles that left through outflow faces since the start
    /// (the solver's outflow faces; 0 without them). Neither stored nor dissipated: it left.
    #[serde(default)]
    pub outflow: Real,
    /// (stored + dissipated + outflow) − (initial stored + external work).
    pub residual: Real,
}

impl EnergyLedger {
    /// kinetic + strain + potential.
    pub fn stored(&self) -> Real {
        self.kinetic + self.strain + self.potential
    }

    /// plastic + friction + constraint work + transfer dissipation + side-wall friction.
    pub fn dissipated(&self) -> Real {
        self.plastic_dissipation
            + self.friction_work
            + self.constraint_work
            + self.transfer_dissipation
            + self.side_wall_friction
    }

    /// stored + dissipated + what left through outflow faces: constant for a perfect integrator
    /// without external work.
    pub fn total(&self) -> Real {
        self.stored() + self.dissipated() + self.outflow
    }
}
