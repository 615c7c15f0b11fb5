//! uGIMP shape functions (Bardenhagen & Kober 2004, "undeformed" particle domains) on the regular
//! grid: 3 × 3 stencils, C¹ weights that remove the cell-crossing error of bilinear MPM.
//!
//! # Glossary
//! - h: cell size along an axis (dx or dy), m; lp: the particle's half-size along that axis, m,
//!   fixed (undeformed) for the whole run, 0 < lp ≤ h/2 (lp = h/(2·ppc) for ppc particles per
//!   cell along the axis).
//! - r = x − x_i: distance from node i, m. The 1D weight is the average of the hat function over
//!   the particle's domain [x − lp, x + lp]:
//!
//! ```text
//! S(r) = 1 − (r² + lp²)/(2 h lp)         |r| < lp
//!        1 − |r|/h                        lp ≤ |r| ≤ h − lp
//!        (h + lp − |r|)² / (4 h lp)       h − lp < |r| < h + lp
//!        0                                otherwise
//! ```
//!
//!   In 2D, S_i(x) = S(x − x_i)·S(y − y_i), ∇S_i = (S′(x − x_i)S(y − y_i), S(x − x_i)S′(y − y_i)).
//! - stencil: with c the nearest node along each axis, nodes c−1, c, c+1 (support |r| < h + lp
//!   ≤ 1.5h), in order k = 3·b + a for node (c_x − 1 + a, c_y − 1 + b).
//! - boundaries: the point must lie inside the grid; its stencil may reach one ghost layer
//!   outside (i = −1, nx + 1, j = −1, ny + 1). Ghost nodes are ordinary nodes: the weights keep
//!   the partition of unity and linear completeness up to the walls, and the grid's
//!   [`boundary_normals`](crate::RegularGrid::boundary_normals) reports the wall for the ghost
//!   layer too, so boundary conditions hold it.
//! - units SI (m).

use crate::error::{GridError, LocateError};
use crate::math::{DIM, Vector};
use crate::node::{BoundaryNormals, NodeId};
use crate::regular::RegularGrid;
use crate::stencil::ShapeFunctions;

/// uGIMP shape functions on a regular grid: [`ShapeFunctions<9>`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gimp {
    grid: RegularGrid,
    half_particle: Vector,
    /// lp / h and its reciprocals, per axis.
    axes: [GimpAxis; DIM],
}

/// the nodes of a 3-wide tensor-product stencil: 9 in the plane, 27 in space.
pub const WIDE: usize = 3usize.pow(DIM as u32);

impl Gimp {
    /// uGIMP with particle half-size `half_particle` = (lp_x, lp_y[, lp_z]), each in (0, cell/2].
    pub fn new(grid: RegularGrid, half_particle: Vector) -> Result<Self, GridError> {
        let cell = grid.cell_size();
        for (a, axis) in ["x", "y", "z"].into_iter().enumerate().take(DIM) {
            let (value, h) = (half_particle[a], cell[a]);
            if !(value > 0.0 && value <= 0.5 * h) {
                return Err(GridError::InvalidParticleHalfSize { axis, value, max: 0.5 * h });
            }
        }
        let p = half_particle / cell;
        Ok(Self { grid, half_particle, axes: std::array::from_fn(|a| GimpAxis::new(p[a])) })
    }

    /// uGIMP for `ppc` = [n_x, n_y[, n_z]] particles per cell along each axis: lp = cell/(2·n).
    pub fn with_particles_per_cell(
        grid: RegularGrid,
        ppc: [usize; DIM],
    ) -> Result<Self, GridError> {
        for (a, n) in ppc.into_iter().enumerate() {
            if n == 0 || n > crate::MAX_CELLS_PER_AXIS {
                return Err(GridError::CellCountOutOfRange {
                    what: crate::Extent::ParticlesPerCell(a),
                    count: n as f64,
                    max: crate::MAX_CELLS_PER_AXIS,
                });
            }
        }
        let lp = grid.cell_size() / Vector::from_array(ppc.map(|n| 2.0 * n as f64));
        Self::new(grid, lp)
    }

    /// the underlying grid.
    pub fn grid(&self) -> &RegularGrid {
        &self.grid
    }

    /// (lp_x, lp_y[, lp_z]), m.
    pub fn half_particle(&self) -> Vector {
        self.half_particle
    }
}

/// per-axis constants of the 1D uGIMP weight, in cell units (h = 1, p = lp/h).
#[derive(Clone, Copy, Debug, PartialEq)]
struct GimpAxis {
    p: f64,
    /// 1/p, 1/(2p), 1/(4p).
    inv_p: f64,
    inv_2p: f64,
    inv_4p: f64,
}

impl GimpAxis {
    fn new(p: f64) -> Self {
        Self { p, inv_p: 1.0 / p, inv_2p: 0.5 / p, inv_4p: 0.25 / p }
    }

    /// weight S(r) and dS/dr for a node at distance r (cell units). All three pieces are
    /// evaluated and one is selected, so the compiler can avoid unpredictable branches.
    #[inline(always)]
    fn weight(&self, r: f64) -> (f64, f64) {
        let p = self.p;
        let q = r.abs();
        let sign = if r < 0.0 { -1.0 } else { 1.0 };
        // |r| < lp: inside the particle domain.
        let inner = (1.0 - (r * r + p * p) * self.inv_2p, -r * self.inv_p);
        // lp ≤ |r| ≤ h − lp: the hat's linear part.
        let linear = (1.0 - q, -sign);
        // h − lp < |r| < h + lp: the domain straddles the support's rim (0 beyond it).
        let e = (1.0 + p - q).max(0.0);
        let rim = (e * e * self.inv_4p, -sign * e * self.inv_2p);
        if q < p {
            inner
        } else if q <= 1.0 - p {
            linear
        } else {
            rim
        }
    }
}

/// the nearest node c to u and the three 1D (weight, derivative) pairs for c−1, c, c+1.
#[inline(always)]
fn gimp_axis(u: f64, axis: &GimpAxis) -> (i32, [(f64, f64); 3]) {
    // u ≥ −LOCATE_SLACK, so u + 0.5 > 0 and truncation is floor: c is the nearest node.
    let c = (u + 0.5) as i32;
    let d = u - f64::from(c);
    (c, [axis.weight(1.0 + d), axis.weight(d), axis.weight(d - 1.0)])
}

/// The 1D (weight, d/du) pairs of a 3 × 3 (3 × 3 × 3 in 3D) tensor-product stencil along x,
/// along y (and along z), for nodes c − 1, c, c + 1 of each axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AxisFactors {
    x: [(f64, f64); 3],
    y: [(f64, f64); 3],
    #[cfg(feature = "dim3")]
    z: [(f64, f64); 3],
}

impl AxisFactors {
    /// the factors of the stencil centred on node (cx, cy): its first node and the pairs.
    #[cfg(not(feature = "dim3"))]
    #[inline(always)]
    pub(crate) fn centred(
        (cx, x): (i32, [(f64, f64); 3]),
        (cy, y): (i32, [(f64, f64); 3]),
    ) -> (NodeId, Self) {
        (NodeId::new(cx - 1, cy - 1), Self { x, y })
    }

    /// the factors of the stencil centred on node (cx, cy, cz): its first node and the pairs.
    #[cfg(feature = "dim3")]
    #[inline(always)]
    pub(crate) fn centred(
        (cx, x): (i32, [(f64, f64); 3]),
        (cy, y): (i32, [(f64, f64); 3]),
        (cz, z): (i32, [(f64, f64); 3]),
    ) -> (NodeId, Self) {
        (NodeId::new(cx - 1, cy - 1, cz - 1), Self { x, y, z })
    }

    /// the tensor-product weights, slot k = 3 b + a for node (a, b) of the 3 × 3 (in 3D
    /// k = 9 c + 3 b + a for node (a, b, c)).
    #[inline(always)]
    pub(crate) fn weights(&self) -> [f64; WIDE] {
        #[cfg(not(feature = "dim3"))]
        return std::array::from_fn(|k| self.x[k % 3].0 * self.y[k / 3].0);
        #[cfg(feature = "dim3")]
        return {
            // the y–z products first (9), then x (27): slot 9c + 3b + a
            let mut w = [0.0; WIDE];
            for c in 0..3 {
                for b in 0..3 {
                    let yz = self.y[b].0 * self.z[c].0;
                    for a in 0..3 {
                        w[9 * c + 3 * b + a] = self.x[a].0 * yz;
                    }
                }
            }
            w
        };
    }

    /// the tensor-product gradients (1/m) with cell units scaled by `inv_cell`.
    #[inline(always)]
    pub(crate) fn gradients(&self, inv_cell: Vector) -> [Vector; WIDE] {
        #[cfg(not(feature = "dim3"))]
        return std::array::from_fn(|k| {
            let ((sx, dx), (sy, dy)) = (self.x[k % 3], self.y[k / 3]);
            Vector::new(dx * sy * inv_cell.x, sx * dy * inv_cell.y)
        });
        #[cfg(feature = "dim3")]
        return {
            // per axis the scaled derivatives (9 products), per (b, c) the three y–z products
            // (27), per node three more (81): 117 products instead of 243
            let dx = self.x.map(|(_, d)| d * inv_cell.x);
            let mut g = [Vector::ZERO; WIDE];
            for c in 0..3 {
                let (sz, dz) = (self.z[c].0, self.z[c].1 * inv_cell.z);
                for b in 0..3 {
                    let (sy, dy) = (self.y[b].0, self.y[b].1 * inv_cell.y);
                    let (syz, dyz, ydz) = (sy * sz, dy * sz, sy * dz);
                    for a in 0..3 {
                        let sx = self.x[a].0;
                        g[9 * c + 3 * b + a] = Vector::new(dx[a] * syz, sx * dyz, sx * ydz);
                    }
                }
            }
            g
        };
    }
}

/// the sums of [`ShapeFunctions::interpolate`], [`ShapeFunctions::gradient`] and
/// [`ShapeFunctions::nodal_forces`] factorised per axis (`tensor.rs`), for the 3D uGIMP and
/// B-spline stencils alike.
#[cfg(feature = "dim3")]
impl AxisFactors {
    #[inline(always)]
    pub(crate) fn interpolate(
        &self,
        inv_cell: Vector,
        value: impl Fn(usize) -> Vector,
    ) -> (Vector, crate::Matrix) {
        crate::tensor::interpolate(&[self.x, self.y, self.z], inv_cell, value)
    }

    #[inline(always)]
    pub(crate) fn nodal_forces(
        &self,
        inv_cell: Vector,
        mass_body: (f64, Vector),
        volume: f64,
        stress: [Vector; DIM],
    ) -> [Vector; WIDE] {
        crate::tensor::forces(&[self.x, self.y, self.z], inv_cell, mass_body, volume, stress)
    }
}

/// The overrides of the per-axis sums (3D) in the `ShapeFunctions` impls of uGIMP and B-splines.
macro_rules! factorised_sums {
    () => {
        #[cfg(feature = "dim3")]
        #[inline(always)]
        fn interpolate(
            &self,
            f: &AxisFactors,
            value: impl Fn(usize) -> Vector,
        ) -> (Vector, crate::Matrix) {
            f.interpolate(self.grid.inverse_cell_size(), value)
        }

        #[cfg(feature = "dim3")]
        #[inline(always)]
        fn gradient(&self, f: &AxisFactors, value: impl Fn(usize) -> Vector) -> crate::Matrix {
            f.interpolate(self.grid.inverse_cell_size(), value).1
        }

        #[cfg(feature = "dim3")]
        #[inline(always)]
        fn nodal_forces(
            &self,
            f: &AxisFactors,
            _weights: &[f64; WIDE],
            mass_body: (f64, Vector),
            volume: f64,
            stress: [Vector; DIM],
        ) -> [Vector; WIDE] {
            f.nodal_forces(self.grid.inverse_cell_size(), mass_body, volume, stress)
        }
    };
}
pub(crate) use factorised_sums;

impl ShapeFunctions<WIDE> for Gimp {
    type Factors = AxisFactors;

    #[inline(always)]
    fn factors(&self, x: Vector) -> Result<(NodeId, AxisFactors), LocateError> {
        let u = self.grid.units_of(x)?;
        #[cfg(not(feature = "dim3"))]
        return Ok(AxisFactors::centred(
            gimp_axis(u.x, &self.axes[0]),
            gimp_axis(u.y, &self.axes[1]),
        ));
        #[cfg(feature = "dim3")]
        return Ok(AxisFactors::centred(
            gimp_axis(u.x, &self.axes[0]),
            gimp_axis(u.y, &self.axes[1]),
            gimp_axis(u.z, &self.axes[2]),
        ));
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

    /// round-off allowance for O(1) piecewise polynomials.
    const ROUND_OFF: f64 = 1e-14;

    #[test]
    fn one_d_weight_is_continuous_at_the_breakpoints() {
        let p = 0.25;
        let axis = GimpAxis::new(p);
        for q in [p, 1.0 - p, 1.0 + p] {
            let below = axis.weight(q - 1e-12);
            let above = axis.weight(q + 1e-12);
            assert!((below.0 - above.0).abs() < 1e-11, "weight jumps at {q}");
            assert!((below.1 - above.1).abs() < 1e-10, "slope jumps at {q}");
        }
        // average of the hat over [−p, p]: 1 − p/2 at the node itself.
        assert!((axis.weight(0.0).0 - (1.0 - p / 2.0)).abs() < ROUND_OFF);
        assert_eq!(axis.weight(1.3), (0.0, 0.0));
        assert_eq!(axis.weight(-1.25), (0.0, -0.0));
    }

    #[test]
    fn half_size_beyond_half_a_cell_is_rejected() {
        let grid = crate::testing::grid([0.0; 2], [0.1; 2], [4, 4]).unwrap();
        let mut half = Vector::splat(0.05);
        half.y = 0.06;
        let err = Gimp::new(grid, half).unwrap_err();
        assert!(matches!(err, GridError::InvalidParticleHalfSize { axis: "y", .. }));
        let mut per_cell = [2; DIM];
        per_cell[1] = 0;
        assert!(Gimp::with_particles_per_cell(grid, per_cell).is_err());
    }
}
