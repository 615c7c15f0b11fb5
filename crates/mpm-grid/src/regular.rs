//! The regular Cartesian grid: the flat special case of the terrain grid, and the grid on which
//! the higher-order shape functions (uGIMP, quadratic B-splines) are defined.
//!
//! # Glossary
//! - origin o: the bottom-left node (0, 0), m; cell sizes dx, dy, m; nx × ny cells.
//! - node (i, j) at o + (i·dx, j·dy); i = 0..=nx, j = 0..=ny inside the grid, ghost nodes outside.
//! - u = ((x − o_x)/dx, (y − o_y)/dy): a point in cell units; cell (⌊u_x⌋, ⌊u_y⌋).
//! - ξ = 2(u_x − i) − 1, η = 2(u_y − j) − 1: eqs 19–20 for a cell with flat bottom and top.
//! - boundaries: floor j = 0 (normal +y), left wall i = 0 (normal +x), right wall i = nx
//!   (normal −x). The top is open.
//! - points up to [`LOCATE_SLACK`] cells beyond an edge belong to the edge cell.
//! - units SI (m).

use crate::error::{GridError, LocateError};
use crate::math::Vector;
use crate::node::{BoundaryNormals, CellCoords, NodeId};
use crate::{LOCATE_SLACK, MAX_CELLS_PER_AXIS};

/// Regular Cartesian grid of nx × ny cells of size dx × dy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegularGrid {
    origin: Vector,
    cell: Vector,
    inv_cell: Vector,
    cells: [usize; 2],
    /// cells + LOCATE_SLACK per axis: upper ends of the accepted range in cell units.
    u_max: Vector,
}

impl RegularGrid {
    /// the grid with bottom-left node at `origin`, cells of size `cell` = (dx, dy) and
    /// `cells` = [nx, ny] cells. Errors name the offending value.
    pub fn new(origin: Vector, cell: Vector, cells: [usize; 2]) -> Result<Self, GridError> {
        if !origin.is_finite() {
            return Err(GridError::NonFinitePoint {
                what: "grid origin",
                x: origin.x,
                y: origin.y,
            });
        }
        for (what, value) in [("cell size dx", cell.x), ("cell size dy", cell.y)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(GridError::NonPositiveSize { what, value });
            }
        }
        for (what, count) in [("cells along x", cells[0]), ("cells along y", cells[1])] {
            if count == 0 || count > MAX_CELLS_PER_AXIS {
                return Err(GridError::CellCountOutOfRange {
                    what,
                    count: count as f64,
                    max: MAX_CELLS_PER_AXIS,
                });
            }
        }
        let far = origin + cell * Vector::new(cells[0] as f64 + 1.0, cells[1] as f64 + 1.0);
        if !far.is_finite() {
            return Err(GridError::NonFinitePoint {
                what: "grid's far corner",
                x: far.x,
                y: far.y,
            });
        }
        let u_max = Vector::new(cells[0] as f64, cells[1] as f64) + LOCATE_SLACK;
        Ok(Self { origin, cell, inv_cell: cell.recip(), cells, u_max })
    }

    /// node (0, 0), m.
    pub fn origin(&self) -> Vector {
        self.origin
    }

    /// (dx, dy), m.
    pub fn cell_size(&self) -> Vector {
        self.cell
    }

    /// (1/dx, 1/dy), 1/m.
    #[inline]
    pub(crate) fn inverse_cell_size(&self) -> Vector {
        self.inv_cell
    }

    /// [nx, ny].
    pub fn cells(&self) -> [usize; 2] {
        self.cells
    }

    /// node (nx, ny), m.
    pub fn upper_corner(&self) -> Vector {
        self.node_position(NodeId::new(self.cells[0] as i32, self.cells[1] as i32))
    }

    /// min(dx, dy), m.
    pub fn min_cell_size(&self) -> f64 {
        self.cell.x.min(self.cell.y)
    }

    /// position of node (i, j), m (any i, j: ghost nodes continue the spacing).
    pub fn node_position(&self, node: NodeId) -> Vector {
        self.origin + self.cell * Vector::new(f64::from(node.i), f64::from(node.j))
    }

    /// the point in cell units u = (x − o)/(dx, dy), checked to lie in [0, nx] × [0, ny] up to
    /// [`LOCATE_SLACK`].
    #[inline]
    pub(crate) fn units_of(&self, p: Vector) -> Result<Vector, LocateError> {
        let u = (p - self.origin) * self.inv_cell;
        let x_range = -LOCATE_SLACK..=self.u_max.x;
        let y_range = -LOCATE_SLACK..=self.u_max.y;
        if x_range.contains(&u.x) && y_range.contains(&u.y) {
            return Ok(u);
        }
        Err(self.locate_error(p, u))
    }

    /// why a point out of range was rejected; kept out of line, the hot path only branches here.
    #[cold]
    #[inline(never)]
    fn locate_error(&self, p: Vector, u: Vector) -> LocateError {
        if !p.is_finite() {
            LocateError::NonFinite { x: p.x, y: p.y }
        } else if (-LOCATE_SLACK..=self.u_max.x).contains(&u.x) && u.y < 0.0 {
            LocateError::BelowGround { x: p.x, y: p.y, ground_y: self.origin.y }
        } else {
            LocateError::Outside { x: p.x, y: p.y }
        }
    }

    /// cell index and fractions (a, b) ∈ [0, 1]² of a point already in cell units.
    #[inline]
    pub(crate) fn cell_of_units(&self, u: Vector) -> (i32, i32, f64, f64) {
        // truncation is floor for u ≥ 0 and gives 0 within the slack below 0; the far edges
        // belong to the last cell.
        // i64 (not usize) keeps the int ↔ float conversions single instructions; cells ≤ 2³⁰
        // so the i32 node indices are exact.
        let i = (u.x as i64).min(self.cells[0] as i64 - 1);
        let j = (u.y as i64).min(self.cells[1] as i64 - 1);
        (i as i32, j as i32, u.x - i as f64, u.y - j as f64)
    }

    /// the cell holding `p` and its natural coordinates, O(1).
    pub fn locate(&self, p: Vector) -> Result<CellCoords, LocateError> {
        let (i, j, a, b) = self.cell_of_units(self.units_of(p)?);
        Ok(CellCoords { cell: NodeId::new(i, j), xi: 2.0 * a - 1.0, eta: 2.0 * b - 1.0 })
    }

    /// the forward map of a cell's natural coordinates, m.
    pub fn position(&self, c: CellCoords) -> Vector {
        let a = Vector::new(0.5 * (1.0 + c.xi), 0.5 * (1.0 + c.eta));
        self.node_position(c.cell) + a * self.cell
    }

    /// the mirror image of a ghost node across the floor (j < 0), the left wall (i < 0) or the
    /// right wall (i > nx), with that plane's normal; `None` inside the grid. The floor is checked
    /// first, so a corner ghost mirrors across the floor.
    pub fn mirror(&self, node: NodeId) -> Option<(NodeId, Vector)> {
        let nx = i64::try_from(self.cells[0]).unwrap_or(i64::MAX);
        if node.j < 0 {
            Some((NodeId::new(node.i, -node.j), Vector::Y))
        } else if node.i < 0 {
            Some((NodeId::new(-node.i, node.j), Vector::X))
        } else if i64::from(node.i) > nx {
            // 2 nx − i stays in range: i ≤ nx + 2 for the stencils that reach ghosts.
            Some((NodeId::new((2 * nx - i64::from(node.i)) as i32, node.j), Vector::NEG_X))
        } else {
            None
        }
    }

    /// boundary planes a node lies on: floor (j ≤ 0), left wall (i ≤ 0), right wall (i ≥ nx);
    /// ghost nodes beyond them included.
    pub fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        BoundaryNormals {
            ground: (node.j <= 0).then_some(Vector::Y),
            ground_kink: None,
            left_wall: (node.i <= 0).then_some(Vector::X),
            right_wall: (i64::from(node.i) >= self.cells[0] as i64).then_some(Vector::NEG_X),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_classifies_points() {
        let g = RegularGrid::new(Vector::new(-1.0, 0.0), Vector::new(0.5, 0.25), [4, 8]).unwrap();
        let c = g.locate(Vector::new(0.0, 0.125)).unwrap();
        assert_eq!(c.cell, NodeId::new(2, 0));
        assert_eq!((c.xi, c.eta), (-1.0, 0.0));
        assert_eq!(g.locate(Vector::new(1.0, 2.0)).unwrap().cell, NodeId::new(3, 7));
        assert!(matches!(
            g.locate(Vector::new(0.0, -0.1)),
            Err(LocateError::BelowGround { ground_y, .. }) if ground_y == 0.0
        ));
        assert!(matches!(g.locate(Vector::new(1.1, 0.1)), Err(LocateError::Outside { .. })));
        assert!(matches!(g.locate(Vector::new(0.0, 2.1)), Err(LocateError::Outside { .. })));
        assert!(matches!(g.locate(Vector::new(f64::NAN, 0.1)), Err(LocateError::NonFinite { .. })));
    }

    #[test]
    fn bad_sizes_are_named() {
        let err = RegularGrid::new(Vector::ZERO, Vector::new(0.1, 0.0), [1, 1]).unwrap_err();
        assert_eq!(err, GridError::NonPositiveSize { what: "cell size dy", value: 0.0 });
        let err = RegularGrid::new(Vector::ZERO, Vector::ONE, [3, 0]).unwrap_err();
        assert!(matches!(err, GridError::CellCountOutOfRange { what: "cells along y", .. }));
    }
}
