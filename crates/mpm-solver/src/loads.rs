//! The loads the boundaries take: for each side of the grid and each declared wall, the impulse
//! it gave the material since the start of the run. Divided by a time interval, it is the mean
//! force over that interval; its negative is the load on the boundary (what a check dam's or a
//! barrier's designer sizes it for).
//!
//! Each boundary node's contact impulse (eqs 14–18, [`mpm_contact::apply_all`]) goes to the
//! boundary that carried it (the side walls across the plane of a plane-strain run, when there
//! are some, are the last entry: `stages/side_walls.rs`); a node held by several (a wall's foot on the ground, a corner) is
//! divided by [`mpm_contact::impulse_shares`] (under the consistent mass matrix, whose reactions
//! are formed after its re-solve, such a node's reaction goes whole to its first held plane's
//! boundary). The impulses of the ghost nodes behind a fixed side
//! (wide stencils) go to that side. The loads therefore add up to
//! [`crate::Solver::boundary_impulse`], the total that the momentum balance checks.

use serde::{Deserialize, Serialize};

use crate::math::{Real, Vector};

/// The sides of the grid, in the order of the first entries of [`crate::Solver::boundary_loads`];
/// the declared walls (`SolverConfig::walls`) follow in their order.
#[cfg(not(feature = "dim3"))]
pub const SIDE_NAMES: [&str; 3] = ["ground", "left_wall", "right_wall"];
/// The sides of the grid, in the order of the first entries of [`crate::Solver::boundary_loads`];
/// the declared walls (`SolverConfig::walls`) follow in their order.
#[cfg(feature = "dim3")]
pub const SIDE_NAMES: [&str; 5] = ["ground", "left_wall", "right_wall", "back_wall", "front_wall"];

/// How many entries of [`crate::Solver::boundary_loads`] are grid sides.
pub const SIDES: usize = SIDE_NAMES.len();

/// What one boundary gave the material since the start of the run (N·s; per metre of thickness
/// in 2D). Tension-positive convention of the material: the boundary pushes along its normal n
/// (into the material), so `normal` ≥ 0 for a boundary that only pushes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BoundaryLoad {
    /// Σ J: the impulse vector the boundary gave the material.
    pub impulse: Vector,
    /// Σ J·n: its part along each node's own normal (on a terrain of many facets, each node's
    /// plane), the normal impulse.
    pub normal: Real,
    /// Σ (J − (J·n) n): the rest, the friction impulse, as a vector.
    pub tangential: Vector,
}

impl BoundaryLoad {
    /// adds the impulse `j` given through a plane of unit normal `n`.
    #[inline]
    pub(crate) fn add(&mut self, j: Vector, n: Vector) {
        let jn = j.dot(n);
        self.impulse += j;
        self.normal += jn;
        self.tangential += j - jn * n;
    }

    /// true when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.impulse.is_finite() && self.normal.is_finite() && self.tangential.is_finite()
    }
}
