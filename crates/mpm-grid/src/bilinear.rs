//! Bilinear isoparametric shape functions N = ¼(1±ξ)(1±η) (Abe, Johansson & Konagai 2005,
//! eqs 19–20) on the terrain grid and on the regular grid: 4-node stencils.
//!
//! # Glossary
//! - a = (1+ξ)/2, b = (1+η)/2 ∈ [0, 1]: the point's fractions across its cell (eqs 19, 20).
//! - stencil order: nodes (i, j), (i+1, j), (i, j+1), (i+1, j+1) of cell (i, j), i.e. the
//!   paper's corners 1, 2, 3, 4; weights (1−a)(1−b), a(1−b), (1−a)b, ab.
//! - l, h: cell width and (vertical) row spacing; s: ground slope in the column; units SI.
//!
//! Gradients go through the inverse Jacobian, which is constant in each cell of both grids:
//! terrain ∂a/∂x = 1/l, ∂b/∂x = −s/h, ∂b/∂y = 1/h; regular ∂a/∂x = 1/dx, ∂b/∂y = 1/dy.
//! N is C⁰ across cell edges and its gradient jumps there: that jump is the cell-crossing error
//! of the paper's §2(3), which [`Gimp`](crate::Gimp) and
//! [`QuadraticBSpline`](crate::QuadraticBSpline) remove.

use crate::error::LocateError;
#[cfg(feature = "dim3")]
use crate::math::Matrix;
use crate::math::Vector;
use crate::node::{BoundaryNormals, NodeId};
use crate::regular::RegularGrid;
use crate::stencil::ShapeFunctions;
#[cfg(not(feature = "dim3"))]
use crate::terrain::TerrainGrid;

/// Bilinear isoparametric shape functions over grid `G` (a [`TerrainGrid`] or a
/// [`RegularGrid`]): [`ShapeFunctions<4>`].
#[derive(Clone, Debug, PartialEq)]
pub struct Bilinear<G>(pub G);

/// the weights of the four corners at fractions (a, b).
#[cfg(not(feature = "dim3"))]
#[inline(always)]
fn unit_square(a: f64, b: f64) -> [f64; 4] {
    let (am, bm) = (1.0 - a, 1.0 - b);
    [am * bm, a * bm, am * b, a * b]
}

/// (∂N/∂a, ∂N/∂b) of the four corners at fractions (a, b).
#[cfg(not(feature = "dim3"))]
#[inline(always)]
fn unit_square_slopes(a: f64, b: f64) -> ([f64; 4], [f64; 4]) {
    let (am, bm) = (1.0 - a, 1.0 - b);
    ([-bm, bm, -b, b], [-am, -a, am, a])
}

/// A point's fractions (a, b) across its terrain cell and the column's ∂b/∂x.
#[cfg(not(feature = "dim3"))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TerrainFactors {
    a: f64,
    b: f64,
    db_dx: f64,
}

#[cfg(not(feature = "dim3"))]
impl ShapeFunctions<4> for Bilinear<TerrainGrid> {
    type Factors = TerrainFactors;

    const SEPARABLE_NODES: bool = false;

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, TerrainFactors), LocateError> {
        let loc = self.0.locate_parts(x)?;
        let f = TerrainFactors { a: loc.a, b: loc.b, db_dx: loc.db_dx };
        Ok((NodeId::new(loc.i as i32, loc.j as i32), f))
    }

    #[inline(always)]
    fn weights(&self, f: &TerrainFactors) -> [f64; 4] {
        unit_square(f.a, f.b)
    }

    #[inline(always)]
    fn gradients(&self, f: &TerrainFactors) -> [Vector; 4] {
        let (na, nb) = unit_square_slopes(f.a, f.b);
        let (inv_l, inv_h) = self.0.inverse_sizes();
        let grad = |k: usize| Vector::new(na[k] * inv_l + nb[k] * f.db_dx, nb[k] * inv_h);
        // Written out: `[0, 1, 2, 3].map(..)` compiled to an out-of-line call per stencil.
        [grad(0), grad(1), grad(2), grad(3)]
    }

    fn node_position(&self, node: NodeId) -> Vector {
        self.0.node_position(node)
    }

    fn min_cell_size(&self) -> f64 {
        self.0.min_cell_size()
    }

    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        self.0.boundary_normals(node)
    }
}

#[cfg(not(feature = "dim3"))]
impl ShapeFunctions<4> for Bilinear<RegularGrid> {
    /// the point's fractions (a, b) across its cell.
    type Factors = [f64; 2];

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, [f64; 2]), LocateError> {
        let g = &self.0;
        let (i, j, a, b) = g.cell_of_units(g.units_of(x)?);
        Ok((NodeId::new(i, j), [a, b]))
    }

    #[inline(always)]
    fn weights(&self, &[a, b]: &[f64; 2]) -> [f64; 4] {
        unit_square(a, b)
    }

    #[inline(always)]
    fn gradients(&self, &[a, b]: &[f64; 2]) -> [Vector; 4] {
        let (na, nb) = unit_square_slopes(a, b);
        let inv = self.0.inverse_cell_size();
        let grad = |k: usize| Vector::new(na[k] * inv.x, nb[k] * inv.y);
        [grad(0), grad(1), grad(2), grad(3)]
    }

    fn node_position(&self, node: NodeId) -> Vector {
        self.0.node_position(node)
    }

    fn min_cell_size(&self) -> f64 {
        self.0.min_cell_size()
    }

    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        self.0.boundary_normals(node)
    }
}

/// Trilinear shape functions on the regular 3D grid (the 3D build's [`Bilinear`]): the tensor
/// product of the 1D hats, N = (1±ξ)(1±η)(1±ζ)/8, 8-node stencils in the slot order of
/// [`Stencil`](crate::Stencil) (x fastest, then y, then z).
#[cfg(feature = "dim3")]
impl ShapeFunctions<8> for Bilinear<RegularGrid> {
    /// the point's fractions (a, b, c) across its cell.
    type Factors = [f64; 3];

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, [f64; 3]), LocateError> {
        let g = &self.0;
        Ok(g.cell_fractions(g.units_of(x)?))
    }

    #[inline(always)]
    fn weights(&self, &[a, b, c]: &[f64; 3]) -> [f64; 8] {
        let (x, y, z) = ([1.0 - a, a], [1.0 - b, b], [1.0 - c, c]);
        std::array::from_fn(|k| x[k & 1] * y[(k >> 1) & 1] * z[k >> 2])
    }

    #[inline(always)]
    fn gradients(&self, &[a, b, c]: &[f64; 3]) -> [Vector; 8] {
        let (x, y, z) = ([1.0 - a, a], [1.0 - b, b], [1.0 - c, c]);
        const SLOPE: [f64; 2] = [-1.0, 1.0];
        let inv = self.0.inverse_cell_size();
        std::array::from_fn(|k| {
            let (p, q, r) = (k & 1, (k >> 1) & 1, k >> 2);
            Vector::new(
                SLOPE[p] * y[q] * z[r] * inv.x,
                x[p] * SLOPE[q] * z[r] * inv.y,
                x[p] * y[q] * SLOPE[r] * inv.z,
            )
        })
    }

    #[inline(always)]
    fn interpolate(&self, f: &[f64; 3], value: impl Fn(usize) -> Vector) -> (Vector, Matrix) {
        crate::tensor::interpolate(&hats(f), self.0.inverse_cell_size(), value)
    }

    #[inline(always)]
    fn gradient(&self, f: &[f64; 3], value: impl Fn(usize) -> Vector) -> Matrix {
        crate::tensor::interpolate(&hats(f), self.0.inverse_cell_size(), value).1
    }

    #[inline(always)]
    fn nodal_forces(
        &self,
        f: &[f64; 3],
        _weights: &[f64; 8],
        mass_body: (f64, Vector),
        volume: f64,
        stress: [Vector; 3],
    ) -> [Vector; 8] {
        let inv = self.0.inverse_cell_size();
        crate::tensor::forces(&hats(f), inv, mass_body, volume, stress)
    }

    fn node_position(&self, node: NodeId) -> Vector {
        self.0.node_position(node)
    }

    fn min_cell_size(&self) -> f64 {
        self.0.min_cell_size()
    }

    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        self.0.boundary_normals(node)
    }
}

/// Trilinear shape functions on the terrain-following grid in space (eqs 19–20 over a DEM):
/// the weights of [`Bilinear<RegularGrid>`] in the cell's fractions (a, b, c), the gradients
/// through the cell's inverse Jacobian (`terrain3d.rs`): ∇N = (N_a/hx + N_b ∂b/∂x, N_b/r,
/// N_c/hz + N_b ∂b/∂z).
#[cfg(feature = "dim3")]
impl ShapeFunctions<8> for Bilinear<crate::TerrainGrid> {
    type Factors = crate::TerrainFactors;

    const SEPARABLE_NODES: bool = false;

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, crate::TerrainFactors), LocateError> {
        self.0.locate_parts(x)
    }

    #[inline(always)]
    fn weights(&self, f: &crate::TerrainFactors) -> [f64; 8] {
        let (x, y, z) = ([1.0 - f.a, f.a], [1.0 - f.b, f.b], [1.0 - f.c, f.c]);
        std::array::from_fn(|k| x[k & 1] * y[(k >> 1) & 1] * z[k >> 2])
    }

    #[inline(always)]
    fn gradients(&self, f: &crate::TerrainFactors) -> [Vector; 8] {
        let (x, y, z) = ([1.0 - f.a, f.a], [1.0 - f.b, f.b], [1.0 - f.c, f.c]);
        const SLOPE: [f64; 2] = [-1.0, 1.0];
        let [inv_hx, inv_r, inv_hz] = self.0.inverse_sizes();
        std::array::from_fn(|k| {
            let (p, q, r) = (k & 1, (k >> 1) & 1, k >> 2);
            let (na, nb, nc) =
                (SLOPE[p] * y[q] * z[r], x[p] * SLOPE[q] * z[r], x[p] * y[q] * SLOPE[r]);
            Vector::new(na * inv_hx + nb * f.db_dx, nb * inv_r, nc * inv_hz + nb * f.db_dz)
        })
    }

    fn node_position(&self, node: NodeId) -> Vector {
        self.0.node_position(node)
    }

    fn min_cell_size(&self) -> f64 {
        self.0.min_cell_size()
    }

    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        self.0.boundary_normals(node)
    }
}

/// the 1D hats' (weight, slope per cell unit) pairs along each axis at fractions (a, b, c).
#[cfg(feature = "dim3")]
#[inline(always)]
fn hats(f: &[f64; 3]) -> crate::tensor::Axes<2> {
    f.map(|t| [(1.0 - t, -1.0), (t, 1.0)])
}
