//! What a study run is: its case, its discretisation and what it measured; shared by the
//! study's sweeps, the flume's runs and the preset selection.

use mpm_tests::{Cost, Discretisation};

/// Which case a run belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Case {
    /// horizontal sliding block, error of the travel against eq 21.
    Horizontal,
    /// inclined (30°) sliding block, error of the travel at 2 s against eq 22.
    Inclined,
    /// vibrating bar, error of the period.
    Bar,
    /// the sand flume, error of the front position against the finest run.
    Flume,
    /// the manufactured solution of Wallstedt & Guilkey (2008), RMS displacement error.
    Manufactured,
}

impl Case {
    /// short name.
    pub fn name(self) -> &'static str {
        match self {
            Case::Horizontal => "sliding-horizontal",
            Case::Inclined => "sliding-inclined",
            Case::Bar => "vibrating-bar",
            Case::Flume => "flume",
            Case::Manufactured => "manufactured",
        }
    }

    /// what the error measures.
    pub fn error_definition(self) -> &'static str {
        match self {
            Case::Horizontal => "|travel − 16.99 m| / 16.99 m (eq 21)",
            Case::Inclined => "|travel(2 s) − 4.712 m| / 4.712 m (eq 22)",
            Case::Bar => "|T − 10 s| / 10 s (exact period)",
            Case::Flume => {
                "|front − front of the finest run| / runout of the finest run (no exact answer)"
            }
            Case::Manufactured => {
                "RMS over the particles of |x − x_exact| / A at t = 1/(2c) (Wallstedt & Guilkey 2008)"
            }
        }
    }
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Run {
    /// case.
    pub case: Case,
    /// the sweep it belongs to (`cell-bilinear`, `ppc`, `scheme`, `courant`, `preset-sweep`, ...).
    pub sweep: String,
    /// its settings.
    pub d: Discretisation,
    /// the raw quantity compared with the reference (m or s).
    pub value: f64,
    /// relative error against the reference (NaN when the run failed).
    pub error: f64,
    /// energy residual relative to the case's energy scale.
    pub energy: f64,
    /// wall time (s).
    pub wall: f64,
    /// steps × particles.
    pub cost: Cost,
    /// error message when the run failed.
    pub failure: Option<String>,
}

impl Run {
    /// particle-steps per second.
    pub fn throughput(&self) -> f64 {
        self.cost.steps as f64 * self.cost.particles as f64 / self.wall
    }

    /// the run finished with a finite error.
    pub fn ok(&self) -> bool {
        self.failure.is_none() && self.error.is_finite()
    }
}

/// Courant numbers of the sweeps.
pub const COURANTS: [f64; 5] = [0.05, 0.1, 0.2, 0.4, 0.8];
