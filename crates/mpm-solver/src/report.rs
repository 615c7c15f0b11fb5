//! What the solver tells a front end: each step's report, the branch counts of the stress
//! update, why a run ended, and the checkpoint that continues a run exactly (the observer a
//! front end implements is beside the solver it observes).

use serde::{Deserialize, Serialize};

use crate::energy::Dissipation;
use crate::math::Real;
use crate::particles::Particles;

pub use mpm_core::{BranchCounts, RunEnd, StepReport};

/// Everything needed to continue a run exactly: particles, clock and accumulated dissipation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint<St> {
    /// Particle state.
    pub particles: Particles<St>,
    /// Simulated time (s).
    pub time: Real,
    /// Steps completed.
    pub step: u64,
    /// Energy dissipated so far.
    pub dissipation: Dissipation,
    /// What each boundary gave the material so far ([`crate::Solver::boundary_loads`]); empty in
    /// a new run.
    #[serde(default)]
    pub loads: Vec<crate::BoundaryLoad>,
    /// Stored energy at the start of the run (the ledger's reference).
    pub initial_stored: Real,
    /// Lightest initial density of each material (kg/m³): the time step's reference (see
    /// `stages/timestep.rs`); empty in a new run, where the particles' densities set it.
    pub reference_density: Vec<Real>,
    /// The run's small-mass threshold and APIC's cell mass (kg; kg/m in plane strain), as the
    /// particles it started with set them; empty in a new run, where the particles set them.
    /// Kept so that a run some of whose particles have left through outflow faces resumes with
    /// the scales it ran with.
    #[serde(default)]
    pub mass_scales: Vec<Real>,
}
