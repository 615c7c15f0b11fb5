//! What the consistent mass matrix keeps between steps (`stages/mass.rs` assembles and solves
//! it): the banded matrix, the solver's vectors, and the name of each system it solves. Apart
//! from the stage so that the solver's scratch memory can hold it without depending on the
//! stage.

// the 3D build has the lumped matrix only (`stages/mass.rs`)
#![cfg_attr(feature = "dim3", allow(dead_code))]

use crate::math::{Real, Vector};

/// Which system a consistent solve is for (named in errors).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Solve {
    /// M v = Σ m_p S_ip v_p after particle-to-grid.
    Velocity,
    /// M a = f, the grid solve.
    Acceleration,
    /// M v = Σ m_p S_ip v_p of the MUSL/USAVG remap (eq 8).
    Remap,
}

impl Solve {
    /// what the system is, for messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Solve::Velocity => "particle-to-grid velocity",
            Solve::Acceleration => "nodal acceleration",
            Solve::Remap => "remapped velocity",
        }
    }
}

/// The consistent matrix and the solver's vectors, reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct ConsistentScratch {
    /// The active set's generation the neighbour table was built for (`u64::MAX`: never).
    pub(crate) generation: u64,
    /// Entries per row, (2w − 1)².
    pub(crate) band: usize,
    /// Dense index of each row's neighbour at each band place (the row's own index where that
    /// node is inactive, whose entry then stays zero).
    pub(crate) neighbours: Vec<u32>,
    /// The matrix, row by row in the band layout.
    pub(crate) values: Vec<Real>,
    /// Nodes solved for (module docs: above the small-mass threshold, not held by a Coulomb or
    /// rough plane).
    pub(crate) free: Vec<bool>,
    /// The nodes a re-solve prescribes that were solved for (freed again after it).
    pub(crate) prescribed: Vec<u32>,
    /// The nodes whose reactions the ledger books (`Solver::book_reactions`).
    pub(crate) reacting: Vec<u32>,
    /// (node, boundary, normal) of each reacting node, sorted by node: where its reaction is
    /// booked among the loads (`loads.rs`).
    pub(crate) sources: Vec<(u32, u16, Vector)>,
    /// Right-hand side, residual, search direction, its product with M.
    pub(crate) rhs: Vec<Vector>,
    pub(crate) residual: Vec<Vector>,
    pub(crate) direction: Vec<Vector>,
    pub(crate) product: Vec<Vector>,
    /// Boundary nodes a plane held in this step's grid solve.
    pub(crate) constrained: Vec<u32>,
    /// (ghost, image) of the held ghosts behind fixed planes (`Scratch::fixed_ghosts`) that the
    /// current solve ties, a_ghost = −a_image (both solved for): empty outside the re-solve.
    pub(crate) slaves: Vec<(u32, u32)>,
    /// Conjugate-gradient iterations over the run (all solves).
    pub(crate) iterations: u64,
}

impl ConsistentScratch {
    /// an empty scratch that builds its tables on first use.
    pub(crate) fn new() -> Self {
        Self { generation: u64::MAX, ..Default::default() }
    }

    /// heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.neighbours.capacity() * size_of::<u32>()
            + self.values.capacity() * size_of::<Real>()
            + self.free.capacity()
            + (self.prescribed.capacity() + self.reacting.capacity() + 2 * self.slaves.capacity())
                * size_of::<u32>()
            + self.sources.capacity() * size_of::<(u32, u16, Vector)>()
            + (self.rhs.capacity()
                + self.residual.capacity()
                + self.direction.capacity()
                + self.product.capacity())
                * size_of::<Vector>()
    }
}
