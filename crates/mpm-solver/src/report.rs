//! What the solver tells a front end: each step's report, the branch counts of the stress
//! update, why a run ended, and the checkpoint that continues a run exactly (the observer a
//! front end implements is beside the solver it observes).

use mpm_constitutive::MAX_BRANCHES;
use serde::{Deserialize, Serialize};

use crate::energy::Dissipation;
use crate::math::Real;
use crate::particles::Particles;

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Steps completed, including this one.
    pub step: u64,
    /// Simulated time at the end of the step (s).
    pub time: Real,
    /// The step's Δt (s).
    pub dt: Real,
    /// The Courant number Δt·max(c + |v|)/L of the step.
    pub courant: Real,
    /// Number of active grid nodes.
    pub active_nodes: usize,
    /// How many particles took each branch of their model in the step's last stress update.
    pub branches: BranchCounts,
}

/// How many particles took each branch of their material's model in one stress update, counted by
/// the index the model reports ([`mpm_constitutive::Branch`]) and named by the model
/// ([`ConstitutiveModel::BRANCHES`]): the solver knows no model's vocabulary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BranchCounts {
    names: &'static [&'static str],
    counts: [usize; MAX_BRANCHES],
}

impl BranchCounts {
    /// counts of the branches `names` from a tally by index; with `counted` false (an elastic
    /// model, whose updates the solver does not tally), all `particles` are on the elastic branch.
    pub(crate) fn new(
        names: &'static [&'static str],
        mut counts: [usize; MAX_BRANCHES],
        particles: usize,
        counted: bool,
    ) -> Self {
        if !counted {
            counts = [0; MAX_BRANCHES];
            counts[0] = particles;
        }
        Self { names, counts }
    }

    /// no particle counted yet (before the first step).
    pub(crate) fn none(names: &'static [&'static str]) -> Self {
        Self { names, counts: [0; MAX_BRANCHES] }
    }

    /// the number of particles on the branch called `name`; `None` for a name the model does not
    /// use.
    pub fn get(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| *n == name).map(|i| self.counts[i])
    }

    /// (name, count) of every branch of the model, in its order (the elastic branch first).
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, usize)> + '_ {
        self.names.iter().copied().zip(self.counts)
    }

    /// the particles on any branch but the elastic one.
    pub fn plastic(&self) -> usize {
        self.counts.iter().skip(1).sum()
    }
}

/// Why [`Solver::run_until`](crate::Solver::run_until) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// The end time was reached.
    EndTime,
    /// The observer asked to stop.
    Stopped,
}

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
