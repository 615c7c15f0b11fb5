//! The regular Cartesian grid: the flat special case of the terrain grid, and the grid on which
//! the higher-order shape functions (uGIMP, quadratic B-splines) are defined.
//!
//! # Glossary
//! - origin o: the bottom-left node (0, 0), m; cell sizes dx, dy, m; nx × ny cells.
//! - node (i, j) at o + (i·dx, j·dy); i = 0..=nx, j = 0..=ny inside the grid, ghost nodes outside.
//! - u = ((x − o_x)/dx, (y − o_y)/dy): a point in cell units; cell (⌊u_x⌋, ⌊u_y⌋).
//! - ξ = 2(u_x − i) − 1, η = 2(u_y − j) − 1: eqs 19–20 for a cell with flat bottom and top.
//! - boundaries: floor j = 0 (normal +y), left wall i = 0 (normal +x), right wall i = nx
//!   (normal −x); in 3D also the back wall k = 0 (normal +z) and the front wall k = nz
//!   (normal −z). The top is open.
//! - in 3D (the `dim3` build) everything runs along a third axis z the same way: node
//!   (i, j, k), nx × ny × nz cells, cell (⌊u_x⌋, ⌊u_y⌋, ⌊u_z⌋).
//! - points up to [`LOCATE_SLACK`] cells beyond an edge belong to the edge cell.
//! - units SI (m).

use crate::error::{Extent, GridError, LocateError};
use crate::math::{DIM, Vector};
use crate::node::{BoundaryNormals, CellCoords, NodeId};
use crate::{LOCATE_SLACK, MAX_CELLS_PER_AXIS};

/// Regular Cartesian grid of nx × ny cells of size dx × dy (nx × ny × nz of dx × dy × dz in 3D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegularGrid {
    origin: Vector,
    cell: Vector,
    inv_cell: Vector,
    cells: [usize; DIM],
    /// cells + LOCATE_SLACK per axis: upper ends of the accepted range in cell units.
    u_max: Vector,
}

impl RegularGrid {
    /// the grid with bottom-left node at `origin`, cells of size `cell` = (dx, dy) and
    /// `cells` = [nx, ny] cells. Errors name the offending value.
    pub fn new(origin: Vector, cell: Vector, cells: [usize; DIM]) -> Result<Self, GridError> {
        if !origin.is_finite() {
            return Err(GridError::non_finite_point("grid origin", origin));
        }
        for a in 0..DIM {
            let value = cell[a];
            if !(value > 0.0 && value.is_finite()) {
                return Err(GridError::NonPositiveSize { what: Extent::CellSize(a), value });
            }
        }
        for (a, &count) in cells.iter().enumerate() {
            if count == 0 || count > MAX_CELLS_PER_AXIS {
                return Err(GridError::CellCountOutOfRange {
                    what: Extent::Cells(a),
                    count: count as f64,
                    max: MAX_CELLS_PER_AXIS,
                });
            }
        }
        let counts = Vector::from_array(cells.map(|n| n as f64));
        let far = origin + cell * (counts + 1.0);
        if !far.is_finite() {
            return Err(GridError::non_finite_point("grid's far corner", far));
        }
        let u_max = counts + LOCATE_SLACK;
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

    /// [nx, ny] ([nx, ny, nz] in 3D).
    pub fn cells(&self) -> [usize; DIM] {
        self.cells
    }

    /// node (nx, ny) ((nx, ny, nz) in 3D), m.
    pub fn upper_corner(&self) -> Vector {
        self.node_position(NodeId::from_axes(self.cells.map(|n| n as i32)))
    }

    /// min(dx, dy) (min(dx, dy, dz) in 3D), m.
    pub fn min_cell_size(&self) -> f64 {
        self.cell.min_element()
    }

    /// position of node (i, j[, k]), m (any node: ghost nodes continue the spacing).
    pub fn node_position(&self, node: NodeId) -> Vector {
        self.origin + self.cell * Vector::from_array(node.axes().map(f64::from))
    }

    /// the point in cell units u = (x − o)/(dx, dy), checked to lie in [0, nx] × [0, ny] up to
    /// [`LOCATE_SLACK`].
    #[inline]
    pub(crate) fn units_of(&self, p: Vector) -> Result<Vector, LocateError> {
        let u = (p - self.origin) * self.inv_cell;
        let x_range = -LOCATE_SLACK..=self.u_max.x;
        let y_range = -LOCATE_SLACK..=self.u_max.y;
        #[cfg(not(feature = "dim3"))]
        let inside = x_range.contains(&u.x) && y_range.contains(&u.y);
        #[cfg(feature = "dim3")]
        let inside = x_range.contains(&u.x)
            && y_range.contains(&u.y)
            && (-LOCATE_SLACK..=self.u_max.z).contains(&u.z);
        if inside {
            return Ok(u);
        }
        Err(self.locate_error(p, u))
    }

    /// why a point out of range was rejected; kept out of line, the hot path only branches here.
    #[cold]
    #[inline(never)]
    fn locate_error(&self, p: Vector, u: Vector) -> LocateError {
        let beside = (0..DIM).any(|a| a != 1 && !(-LOCATE_SLACK..=self.u_max[a]).contains(&u[a]));
        if !p.is_finite() {
            LocateError::non_finite(p)
        } else if !beside && u.y < 0.0 {
            LocateError::below_ground(p, self.origin.y)
        } else {
            LocateError::outside(p)
        }
    }

    /// cell index and fractions (a, b) ∈ [0, 1]² of a point already in cell units.
    #[cfg(not(feature = "dim3"))]
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

    /// the cell holding a point already in cell units and its fractions across the cell, each in
    /// [0, 1] (the 3D build's `cell_of_units`).
    #[cfg(feature = "dim3")]
    #[inline]
    pub(crate) fn cell_fractions(&self, u: Vector) -> (NodeId, [f64; DIM]) {
        // as `cell_of_units`: truncation is floor within the slack, far edges in the last cell
        let c: [i64; DIM] = std::array::from_fn(|a| (u[a] as i64).min(self.cells[a] as i64 - 1));
        (NodeId::from_axes(c.map(|c| c as i32)), std::array::from_fn(|a| u[a] - c[a] as f64))
    }

    /// the cell holding `p` and its natural coordinates, O(1).
    pub fn locate(&self, p: Vector) -> Result<CellCoords, LocateError> {
        #[cfg(not(feature = "dim3"))]
        {
            let (i, j, a, b) = self.cell_of_units(self.units_of(p)?);
            Ok(CellCoords { cell: NodeId::new(i, j), xi: 2.0 * a - 1.0, eta: 2.0 * b - 1.0 })
        }
        #[cfg(feature = "dim3")]
        {
            let (cell, [a, b, c]) = self.cell_fractions(self.units_of(p)?);
            Ok(CellCoords { cell, xi: 2.0 * a - 1.0, eta: 2.0 * b - 1.0, zeta: 2.0 * c - 1.0 })
        }
    }

    /// the forward map of a cell's natural coordinates, m.
    pub fn position(&self, c: CellCoords) -> Vector {
        #[cfg(not(feature = "dim3"))]
        let a = Vector::new(0.5 * (1.0 + c.xi), 0.5 * (1.0 + c.eta));
        #[cfg(feature = "dim3")]
        let a = Vector::new(0.5 * (1.0 + c.xi), 0.5 * (1.0 + c.eta), 0.5 * (1.0 + c.zeta));
        self.node_position(c.cell) + a * self.cell
    }

    /// the mirror image of a ghost node across the floor (j < 0), the left wall (i < 0) or the
    /// right wall (i > nx) (in 3D then the back wall, k < 0, or the front wall, k > nz), with
    /// that plane's normal; `None` inside the grid. The floor is checked first, so a corner ghost
    /// mirrors across the floor.
    pub fn mirror(&self, node: NodeId) -> Option<(NodeId, Vector)> {
        let nx = i64::try_from(self.cells[0]).unwrap_or(i64::MAX);
        if node.j < 0 {
            let mut a = node.axes();
            a[1] = -a[1];
            Some((NodeId::from_axes(a), Vector::Y))
        } else if node.i < 0 {
            let mut a = node.axes();
            a[0] = -a[0];
            Some((NodeId::from_axes(a), Vector::X))
        } else if i64::from(node.i) > nx {
            // 2 nx − i stays in range: i ≤ nx + 2 for the stencils that reach ghosts.
            let mut a = node.axes();
            a[0] = (2 * nx - i64::from(node.i)) as i32;
            Some((NodeId::from_axes(a), Vector::NEG_X))
        } else {
            self.mirror_z(node)
        }
    }

    /// [`Self::mirror`] across the back (k < 0) and front (k > nz) walls.
    #[cfg(feature = "dim3")]
    fn mirror_z(&self, node: NodeId) -> Option<(NodeId, Vector)> {
        let nz = i64::try_from(self.cells[2]).unwrap_or(i64::MAX);
        if node.k < 0 {
            Some((NodeId::new(node.i, node.j, -node.k), Vector::Z))
        } else if i64::from(node.k) > nz {
            Some((NodeId::new(node.i, node.j, (2 * nz - i64::from(node.k)) as i32), Vector::NEG_Z))
        } else {
            None
        }
    }

    /// [`Self::mirror`] in the plane: no third axis.
    #[cfg(not(feature = "dim3"))]
    fn mirror_z(&self, _node: NodeId) -> Option<(NodeId, Vector)> {
        None
    }

    /// boundary planes a node lies on: floor (j ≤ 0), left wall (i ≤ 0), right wall (i ≥ nx),
    /// in 3D back wall (k ≤ 0) and front wall (k ≥ nz); ghost nodes beyond them included.
    pub fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        BoundaryNormals {
            ground: (node.j <= 0).then_some(Vector::Y),
            ground_kink: None,
            #[cfg(feature = "dim3")]
            ground_more: [None; 2],
            left_wall: (node.i <= 0).then_some(Vector::X),
            right_wall: (i64::from(node.i) >= self.cells[0] as i64).then_some(Vector::NEG_X),
            #[cfg(feature = "dim3")]
            back_wall: (node.k <= 0).then_some(Vector::Z),
            #[cfg(feature = "dim3")]
            front_wall: (i64::from(node.k) >= self.cells[2] as i64).then_some(Vector::NEG_Z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{at, cells, grid, node};

    #[test]
    fn locate_classifies_points() {
        let g = grid([-1.0, 0.0], [0.5, 0.25], [4, 8]).unwrap();
        let c = g.locate(at(0.0, 0.125)).unwrap();
        assert_eq!(c.cell, node(2, 0));
        assert_eq!((c.xi, c.eta), (-1.0, 0.0));
        assert_eq!(g.locate(at(1.0, 2.0)).unwrap().cell, node(3, 7));
        assert!(matches!(
            g.locate(at(0.0, -0.1)),
            Err(LocateError::BelowGround { ground_y, .. }) if ground_y == 0.0
        ));
        assert!(matches!(g.locate(at(1.1, 0.1)), Err(LocateError::Outside { .. })));
        assert!(matches!(g.locate(at(0.0, 2.1)), Err(LocateError::Outside { .. })));
        assert!(matches!(g.locate(at(f64::NAN, 0.1)), Err(LocateError::NonFinite { .. })));
    }

    #[test]
    fn bad_sizes_are_named() {
        let mut flat = Vector::splat(0.1);
        flat.y = 0.0;
        let err = RegularGrid::new(Vector::ZERO, flat, cells([1, 1])).unwrap_err();
        assert_eq!(err, GridError::NonPositiveSize { what: Extent::CellSize(1), value: 0.0 });
        let err = RegularGrid::new(Vector::ZERO, Vector::ONE, cells([3, 0])).unwrap_err();
        assert!(matches!(err, GridError::CellCountOutOfRange { what: Extent::Cells(1), .. }));
    }
}
