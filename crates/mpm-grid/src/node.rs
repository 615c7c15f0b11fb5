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
    /// layer, along z (3D builds only).
    #[cfg(feature = "dim3")]
    pub k: i32,
}

impl NodeId {
    /// the node in column `i`, row `j`.
    #[cfg(not(feature = "dim3"))]
    pub const fn new(i: i32, j: i32) -> Self {
        Self { i, j }
    }

    /// the node in column `i`, row `j`, layer `k`.
    #[cfg(feature = "dim3")]
    pub const fn new(i: i32, j: i32, k: i32) -> Self {
        Self { i, j, k }
    }

    /// the node's index along each axis (i, j[, k]).
    #[inline(always)]
    pub const fn axes(self) -> [i32; crate::math::DIM] {
        #[cfg(not(feature = "dim3"))]
        return [self.i, self.j];
        #[cfg(feature = "dim3")]
        return [self.i, self.j, self.k];
    }

    /// the node with indices `a` along the axes.
    #[inline(always)]
    pub const fn from_axes(a: [i32; crate::math::DIM]) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self { i: a[0], j: a[1] };
        #[cfg(feature = "dim3")]
        return Self { i: a[0], j: a[1], k: a[2] };
    }

    /// this node moved by `d` nodes along the axes.
    #[inline(always)]
    pub const fn offset(self, d: [i32; crate::math::DIM]) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self { i: self.i + d[0], j: self.j + d[1] };
        #[cfg(feature = "dim3")]
        return Self { i: self.i + d[0], j: self.j + d[1], k: self.k + d[2] };
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
    /// (3D builds only) the third and fourth distinct ground planes at a node where up to four
    /// terrain cells of different slopes meet (`TerrainGrid::ground_planes` of the 3D build).
    #[cfg(feature = "dim3")]
    pub ground_more: [Option<Vector>; 2],
    /// left wall (column i ≤ 0): normal +x.
    pub left_wall: Option<Vector>,
    /// right wall (column i ≥ last column): normal −x.
    pub right_wall: Option<Vector>,
    /// back wall (layer k ≤ 0, 3D builds only): normal +z.
    #[cfg(feature = "dim3")]
    pub back_wall: Option<Vector>,
    /// front wall (layer k ≥ last layer, 3D builds only): normal −z.
    #[cfg(feature = "dim3")]
    pub front_wall: Option<Vector>,
}

impl BoundaryNormals {
    /// true when the node lies on no boundary plane.
    pub fn is_empty(&self) -> bool {
        self.iter().next().is_none()
    }

    /// the normals present, in the order ground, ground kink (in 3D then the other ground
    /// planes), left wall, right wall (then back and front wall in 3D).
    pub fn iter(&self) -> impl Iterator<Item = Vector> + '_ {
        #[cfg(not(feature = "dim3"))]
        let all = [self.ground, self.ground_kink, self.left_wall, self.right_wall];
        #[cfg(feature = "dim3")]
        let all = [
            self.ground,
            self.ground_kink,
            self.ground_more[0],
            self.ground_more[1],
            self.left_wall,
            self.right_wall,
            self.back_wall,
            self.front_wall,
        ];
        all.into_iter().flatten()
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
    /// ζ, across the layers (3D builds only).
    #[cfg(feature = "dim3")]
    pub zeta: f64,
}
