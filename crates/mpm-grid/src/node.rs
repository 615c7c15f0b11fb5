//! Integer node coordinates and the boundary planes a node lies on.

use serde::{Deserialize, Serialize};

use crate::math::Vector;

/// Integer node coordinates: column i (along x), row j (upwards; j = 0 is the ground / bottom row).
///
/// The same numbering serves every grid: on a [`TerrainGrid`](crate::TerrainGrid) node (i, j) sits
/// at x = x0 + i·l, y = y_g(x) + j·h; on a [`RegularGrid`](crate::RegularGrid) at
/// origin + (i·dx, j·dy). Stencils of the higher-order shape functions may name nodes one layer
/// outside the grid (i = −1, j = −1, i = nx + 1, …); those are ordinary nodes for the solver.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, Default,
)]
pub struct NodeId {
    /// column, along x.
    pub i: i32,
    /// row, upwards from the ground (j = 0).
    pub j: i32,
}

impl NodeId {
    /// the node in column `i`, row `j`.
    pub const fn new(i: i32, j: i32) -> Self {
        Self { i, j }
    }
}

/// Boundary planes a node lies on, as unit normals pointing from the boundary INTO the material.
///
/// A grid reports a plane for every node on it *or beyond it* (ghost nodes of the B-spline and
/// uGIMP stencils), so that a boundary condition applied to every reported node also holds the
/// ghost layer. Which planes are actually walls is the scene's decision, not the grid's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BoundaryNormals {
    /// ground / floor (row j ≤ 0): the ground's normal at the node; at a kink of a terrain
    /// grid's ground, the normal of the segment on the node's right.
    pub ground: Option<Vector>,
    /// at a kink of the ground only, the normal of the segment on the node's left (a node on
    /// or below the ground at a kink lies on both segments' planes, see
    /// [`TerrainGrid::boundary_normals`](crate::TerrainGrid::boundary_normals)).
    pub ground_kink: Option<Vector>,
    /// left wall (column i ≤ 0): normal +x.
    pub left_wall: Option<Vector>,
    /// right wall (column i ≥ last column): normal −x.
    pub right_wall: Option<Vector>,
}

impl BoundaryNormals {
    /// true when the node lies on no boundary plane.
    pub fn is_empty(&self) -> bool {
        self.ground.is_none()
            && self.ground_kink.is_none()
            && self.left_wall.is_none()
            && self.right_wall.is_none()
    }

    /// the normals present, in the order ground, ground kink, left wall, right wall.
    pub fn iter(&self) -> impl Iterator<Item = Vector> + '_ {
        [self.ground, self.ground_kink, self.left_wall, self.right_wall].into_iter().flatten()
    }
}

/// A point's cell and natural coordinates in it.
///
/// `cell` is the cell's bottom-left node (i, j); the cell spans nodes i..=i+1, j..=j+1.
/// (ξ, η) ∈ [−1, 1]² are the natural coordinates of eqs 19–20.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellCoords {
    /// bottom-left node of the cell.
    pub cell: NodeId,
    /// ξ, along the column (eq 19).
    pub xi: f64,
    /// η, across the rows (eq 20).
    pub eta: f64,
}
