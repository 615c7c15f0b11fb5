//! What the solver tells a front end, whatever its dimension: each step's report, the branch
//! counts of the stress update and why a run ended.

use mpm_constitutive::MAX_BRANCHES;

use crate::settings::Real;

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
/// ([`mpm_constitutive::ConstitutiveModel::BRANCHES`]): the solver knows no model's vocabulary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BranchCounts {
    names: &'static [&'static str],
    counts: [usize; MAX_BRANCHES],
}

impl BranchCounts {
    /// counts of the branches `names` from a tally by index; with `counted` false (an elastic
    /// model, whose updates the solver does not tally), all `particles` are on the elastic branch.
    pub fn new(
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
    pub fn none(names: &'static [&'static str]) -> Self {
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

/// Why a run of the solver (its `run_until`) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// The end time was reached.
    EndTime,
    /// The observer asked to stop.
    Stopped,
}
