//! Quadratic B-spline shape functions on the regular grid: 3 × 3 stencils, C¹ weights (the
//! cell-crossing error of bilinear MPM disappears; Steffen, Kirby & Berzins 2008).
//!
//! # Glossary
//! - h: cell size along an axis, m; u = (x − o)/h: a point in cell units.
//! - the uniform quadratic B-spline centred on node k, with q = |u − k|:
//!
//! ```text
//! N(q) = 3/4 − q²          q < 1/2
//!        (3/2 − q)² / 2     1/2 ≤ q < 3/2
//!        0                  otherwise
//! ```
//!
//!   With c the nearest node and d = u − c ∈ [−½, ½], the three weights are
//!   ½(½ − d)², ¾ − d², ½(½ + d)² for nodes c−1, c, c+1, with derivatives (d − ½)/h, −2d/h,
//!   (½ + d)/h. 2D weights are tensor products; stencil order k = 3·b + a for node
//!   (c_x − 1 + a, c_y − 1 + b).
//! - boundaries: the knot vector is uniform and unbounded, i.e. every node including one ghost
//!   layer outside the grid (i = −1, nx + 1, j = −1, ny + 1) carries the same unclipped spline.
//!   So partition of unity and linear completeness hold up to the walls, a point on a wall gives
//!   weight 1/8 to the ghost node behind it, and the grid's
//!   [`boundary_normals`](crate::RegularGrid::boundary_normals) reports the wall for ghost
//!   nodes too (they get the same boundary condition). No boundary-modified (open-knot) splines.
//! - units SI (m).

use crate::error::LocateError;
use crate::gimp::{AxisFactors, WIDE, factorised_sums};
#[cfg(feature = "dim3")]
use crate::math::DIM;
use crate::math::Vector;
use crate::node::{BoundaryNormals, NodeId};
use crate::regular::RegularGrid;
use crate::stencil::ShapeFunctions;

/// Quadratic B-spline shape functions on a regular grid: [`ShapeFunctions<9>`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadraticBSpline {
    grid: RegularGrid,
}

impl QuadraticBSpline {
    /// quadratic B-splines on `grid` (any regular grid is valid).
    pub fn new(grid: RegularGrid) -> Self {
        Self { grid }
    }

    /// the underlying grid.
    pub fn grid(&self) -> &RegularGrid {
        &self.grid
    }
}

/// nearest node c to u ≥ 0 and the (weight, d/du) pairs for c−1, c, c+1.
#[inline(always)]
fn bspline_axis(u: f64) -> (i32, [(f64, f64); 3]) {
    // u ≥ −LOCATE_SLACK, so u + 0.5 > 0 and truncation is floor: c is the nearest node.
    let c = (u + 0.5) as i32;
    let d = u - f64::from(c);
    let (m, p) = (0.5 - d, 0.5 + d);
    (c, [(0.5 * m * m, -m), (0.75 - d * d, -2.0 * d), (0.5 * p * p, p)])
}

impl ShapeFunctions<WIDE> for QuadraticBSpline {
    type Factors = AxisFactors;

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, AxisFactors), LocateError> {
        let u = self.grid.units_of(x)?;
        #[cfg(not(feature = "dim3"))]
        return Ok(AxisFactors::centred(bspline_axis(u.x), bspline_axis(u.y)));
        #[cfg(feature = "dim3")]
        return Ok(AxisFactors::centred(bspline_axis(u.x), bspline_axis(u.y), bspline_axis(u.z)));
    }

    #[inline(always)]
    fn weights(&self, f: &AxisFactors) -> [f64; WIDE] {
        f.weights()
    }

    #[inline(always)]
    fn gradients(&self, f: &AxisFactors) -> [Vector; WIDE] {
        f.gradients(self.grid.inverse_cell_size())
    }

    factorised_sums!();

    fn node_position(&self, node: NodeId) -> Vector {
        self.grid.node_position(node)
    }

    fn min_cell_size(&self) -> f64 {
        self.grid.min_cell_size()
    }

    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        self.grid.boundary_normals(node)
    }

    fn mirror(&self, node: NodeId) -> Option<(NodeId, Vector)> {
        self.grid.mirror(node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// round-off allowance for O(1) quadratics.
    const ROUND_OFF: f64 = 1e-15;

    #[test]
    fn weights_on_a_node_are_one_eighth_three_quarters_one_eighth() {
        let (c, w) = bspline_axis(3.0);
        assert_eq!(c, 3);
        let expect = [0.125, 0.75, 0.125];
        for k in 0..3 {
            assert!((w[k].0 - expect[k]).abs() < ROUND_OFF);
        }
    }
}
