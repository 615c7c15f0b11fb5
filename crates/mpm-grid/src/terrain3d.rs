//! The terrain-following grid in space (3D builds): the paper's skewed grid (Abe, Johansson &
//! Konagai 2005, §3(2), eqs 19–20) over a digital elevation model. Vertical columns stand on a
//! regular plan lattice; node layers follow the terrain; each cell is a hexahedron whose bottom
//! face is the DEM's bilinear surface over its plan cell.
//!
//! # Glossary
//! - plan lattice: nodes (i, k), i = 0..=nx along x, k = 0..=nz along z, at x = x0 + i·hx,
//!   z = z0 + k·hz; the DEM gives the ground height G(i, k) at each (y up).
//! - g(x, z): the ground, bilinear over each plan cell (the DEM's bilinear surface).
//! - r: the layer height, measured vertically; `layers` cells upwards.
//! - node (i, j, k) at (x0 + i·hx, G(i, k) + j·r, z0 + k·hz); layer j = 0 lies on the ground.
//! - cell (i, j, k): plan cell (i, k), layers j..j+1; fractions a (along x), b (up), c (along z)
//!   in [0, 1], the natural coordinates ξ = 2a − 1, η = 2b − 1, ζ = 2c − 1.
//! - units SI (m).
//!
//! # Locating a point (O(1), closed form)
//! u = (x − x0)/hx, i = ⌊u⌋, a = u − i; w = (z − z0)/hz, k = ⌊w⌋, c = w − k (eq 19 along both
//! plan axes); g = the bilinear ground at (a, c); t = (y − g)/r, j = ⌊t⌋, b = t − j (eq 20).
//! That is the inverse of the cell's trilinear isoparametric map exactly: the map's height is
//! Σ N y_node = g̃(a, c) + (j + b)·r, with g̃ the bilinear ground, so no iteration is needed.
//! Points up to [`LOCATE_SLACK`] cells beyond an edge belong to the edge cell.
//!
//! # Gradients
//! ∂a/∂x = 1/hx, ∂c/∂z = 1/hz, ∂b/∂y = 1/r, and from b = (y − g(a, c))/r − j,
//! ∂b/∂x = −(∂g/∂x)/r and ∂b/∂z = −(∂g/∂z)/r, with ∂g/∂x bilinear's slope along x at the
//! point's c and ∂g/∂z its slope along z at the point's a. So
//! ∇N = (N_a/hx + N_b ∂b/∂x, N_b/r, N_c/hz + N_b ∂b/∂z): the inverse Jacobian of the
//! isoparametric map, in closed form (tested against finite differences of the map).
//!
//! # The ground at a node
//! A ground node is a corner of up to four plan cells. Each cell's bilinear ground has, at that
//! corner, the tangent plane spanned by the two lattice edges leaving the node in that cell; the
//! node is held by every distinct one of those planes (the 2D grid's kink nodes are held by
//! both segments' lines the same way). On a DEM whose cells are planar (a tilted plane, or any
//! g = f(x) + p(z) of piecewise-linear f and p) every ground face is its own plane and, with the
//! nodes held by all their cells' planes, a particle in a bottom cell stays above it: the
//! interpolated normal velocity of the face is a positive combination of non-negative ones.
//! Sides: x = x0 and x = x0 + nx·hx (normals ±x), z = z0 and z = z0 + nz·hz (±z); the top is
//! open.

use crate::error::{Extent, GridError, LocateError};
use crate::math::Vector;
use crate::node::{BoundaryNormals, CellCoords, NodeId};
use crate::{LOCATE_SLACK, MAX_CELLS_PER_AXIS};

/// Everything that defines a [`TerrainGrid`] in space.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainGridSpec {
    /// plan position (x0, z0) of lattice node (0, 0), m.
    pub origin: [f64; 2],
    /// plan cell sizes (hx, hz), m.
    pub spacing: [f64; 2],
    /// plan cells (nx, nz).
    pub cells: [usize; 2],
    /// ground height G(i, k) at every lattice node, m: row k after row k − 1, i fastest
    /// ((nx + 1)(nz + 1) values).
    pub heights: Vec<f64>,
    /// layer height r, measured vertically, m.
    pub layer_height: f64,
    /// cell layers above the ground (node layers are 0..=layers).
    pub layers: usize,
}

/// The terrain-following grid of hexahedra over a DEM (eqs 19–20 in space).
///
/// Invariants: nx, nz, layers ≥ 1; every height finite; every cell non-degenerate (its height
/// normal to the ground positive).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainGrid {
    x0: f64,
    z0: f64,
    hx: f64,
    hz: f64,
    r: f64,
    inv_hx: f64,
    inv_hz: f64,
    inv_r: f64,
    nx: usize,
    nz: usize,
    layers: usize,
    /// G(i, k), (nx + 1)(nz + 1), i fastest.
    heights: Vec<f64>,
    /// u, w and t's accepted upper ends: cells + LOCATE_SLACK.
    u_max: f64,
    w_max: f64,
    t_max: f64,
    min_cell: f64,
}

/// A point's fractions (a, b, c) across its terrain cell and ∂b/∂x, ∂b/∂z there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TerrainFactors {
    pub(crate) a: f64,
    pub(crate) b: f64,
    pub(crate) c: f64,
    pub(crate) db_dx: f64,
    pub(crate) db_dz: f64,
}

impl TerrainGrid {
    /// builds the grid, validating sizes and heights (each failure a [`GridError`] naming the
    /// value).
    pub fn new(spec: TerrainGridSpec) -> Result<Self, GridError> {
        let TerrainGridSpec { origin, spacing, cells, heights, layer_height: r, layers } = spec;
        let origin3 = Vector::new(origin[0], 0.0, origin[1]);
        if !origin3.is_finite() {
            return Err(GridError::non_finite_point("terrain grid origin", origin3));
        }
        for (what, value) in [
            (Extent::PlanCellSize(0), spacing[0]),
            (Extent::PlanCellSize(1), spacing[1]),
            (Extent::LayerHeight, r),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(GridError::NonPositiveSize { what, value });
            }
        }
        for (what, count) in [
            (Extent::PlanCells(0), cells[0]),
            (Extent::PlanCells(1), cells[1]),
            (Extent::Layers, layers),
        ] {
            if count == 0 || count > MAX_CELLS_PER_AXIS {
                return Err(GridError::CellCountOutOfRange {
                    what,
                    count: count as f64,
                    max: MAX_CELLS_PER_AXIS,
                });
            }
        }
        let [nx, nz] = cells;
        let expected = (nx + 1).saturating_mul(nz + 1);
        if heights.len() != expected {
            return Err(GridError::HeightCount { count: heights.len(), nx, nz, expected });
        }
        if let Some(at) = heights.iter().position(|h| !h.is_finite()) {
            return Err(GridError::NonFiniteHeight {
                i: at % (nx + 1),
                k: at / (nx + 1),
                value: heights[at],
            });
        }
        let far =
            origin3 + Vector::new(spacing[0] * (nx + 1) as f64, 0.0, spacing[1] * (nz + 1) as f64);
        if !far.is_finite() {
            return Err(GridError::non_finite_point("terrain grid's far corner", far));
        }
        let mut grid = Self {
            x0: origin[0],
            z0: origin[1],
            hx: spacing[0],
            hz: spacing[1],
            r,
            inv_hx: 1.0 / spacing[0],
            inv_hz: 1.0 / spacing[1],
            inv_r: 1.0 / r,
            nx,
            nz,
            layers,
            heights,
            u_max: nx as f64 + LOCATE_SLACK,
            w_max: nz as f64 + LOCATE_SLACK,
            t_max: layers as f64 + LOCATE_SLACK,
            min_cell: 0.0,
        };
        // The cells' height normal to the ground is r / √(1 + |∇g|²), smallest where the ground
        // is steepest: at a corner of some cell (|∇g|² is bilinear's, largest at a corner).
        let mut steepest: f64 = 0.0;
        for k in 0..nz {
            for i in 0..nx {
                for (a, c) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                    let (gx, gz) = grid.ground_slopes(i, k, a, c);
                    steepest = steepest.max(gx * gx + gz * gz);
                }
            }
        }
        let normal_height = r / (1.0 + steepest).sqrt();
        if !(normal_height > 0.0 && normal_height.is_finite()) {
            return Err(GridError::NonPositiveSize {
                what: Extent::NormalHeight,
                value: normal_height,
            });
        }
        grid.min_cell = grid.hx.min(grid.hz).min(normal_height);
        Ok(grid)
    }

    /// plan cells (nx, nz).
    pub fn plan_cells(&self) -> [usize; 2] {
        [self.nx, self.nz]
    }

    /// plan cell sizes (hx, hz), m.
    pub fn spacing(&self) -> [f64; 2] {
        [self.hx, self.hz]
    }

    /// plan position (x0, z0) of lattice node (0, 0), m.
    pub fn plan_origin(&self) -> [f64; 2] {
        [self.x0, self.z0]
    }

    /// the layer height r, m, and the number of cell layers.
    pub fn layers(&self) -> (f64, usize) {
        (self.r, self.layers)
    }

    /// 1/hx, 1/r, 1/hz (1/m).
    #[inline(always)]
    pub(crate) fn inverse_sizes(&self) -> [f64; 3] {
        [self.inv_hx, self.inv_r, self.inv_hz]
    }

    /// the lattice height G(i, k), m, the lattice clamped to its edges (so that every node id
    /// has a position).
    #[inline(always)]
    fn height(&self, i: i64, k: i64) -> f64 {
        let i = i.clamp(0, self.nx as i64) as usize;
        let k = k.clamp(0, self.nz as i64) as usize;
        self.heights[k * (self.nx + 1) + i]
    }

    /// the ground's slopes (∂g/∂x, ∂g/∂z) in plan cell (i, k) at fractions (a, c).
    #[inline(always)]
    fn ground_slopes(&self, i: usize, k: usize, a: f64, c: f64) -> (f64, f64) {
        let (i, k) = (i as i64, k as i64);
        let (g00, g10) = (self.height(i, k), self.height(i + 1, k));
        let (g01, g11) = (self.height(i, k + 1), self.height(i + 1, k + 1));
        (
            ((g10 - g00) * (1.0 - c) + (g11 - g01) * c) * self.inv_hx,
            ((g01 - g00) * (1.0 - a) + (g11 - g10) * a) * self.inv_hz,
        )
    }

    /// the ground height g(x, z), m, of the DEM's bilinear surface (clamped to the lattice's
    /// edges beyond them).
    pub fn ground_height(&self, x: f64, z: f64) -> f64 {
        let u = ((x - self.x0) * self.inv_hx).clamp(0.0, self.nx as f64);
        let w = ((z - self.z0) * self.inv_hz).clamp(0.0, self.nz as f64);
        let (i, k) = ((u as i64).min(self.nx as i64 - 1), (w as i64).min(self.nz as i64 - 1));
        self.bilinear(i, k, u - i as f64, w - k as f64)
    }

    #[inline(always)]
    fn bilinear(&self, i: i64, k: i64, a: f64, c: f64) -> f64 {
        let (g00, g10) = (self.height(i, k), self.height(i + 1, k));
        let (g01, g11) = (self.height(i, k + 1), self.height(i + 1, k + 1));
        (g00 * (1.0 - a) + g10 * a) * (1.0 - c) + (g01 * (1.0 - a) + g11 * a) * c
    }

    /// the upward unit normal of the ground at plan point (x, z).
    pub fn ground_normal(&self, x: f64, z: f64) -> Vector {
        let u = ((x - self.x0) * self.inv_hx).clamp(0.0, self.nx as f64);
        let w = ((z - self.z0) * self.inv_hz).clamp(0.0, self.nz as f64);
        let (i, k) = ((u as usize).min(self.nx - 1), (w as usize).min(self.nz - 1));
        let (gx, gz) = self.ground_slopes(i, k, u - i as f64, w - k as f64);
        Vector::new(-gx, 1.0, -gz).normalize()
    }

    /// smallest cell dimension for the time-step limit, m: the plan sizes and the layers'
    /// height normal to the steepest ground, r / √(1 + |∇g|²).
    pub fn min_cell_size(&self) -> f64 {
        self.min_cell
    }

    /// position of a node, m (defined for every id: the lattice clamped to its edges).
    pub fn node_position(&self, node: NodeId) -> Vector {
        let g = self.height(i64::from(node.i), i64::from(node.k));
        Vector::new(
            self.x0 + f64::from(node.i) * self.hx,
            g + f64::from(node.j) * self.r,
            self.z0 + f64::from(node.k) * self.hz,
        )
    }

    /// the cell of `p` and its factors (fractions and ∂b/∂x, ∂b/∂z); a typed error for a
    /// point off the grid.
    #[inline(always)]
    pub(crate) fn locate_parts(&self, p: Vector) -> Result<(NodeId, TerrainFactors), LocateError> {
        let u = (p.x - self.x0) * self.inv_hx;
        let w = (p.z - self.z0) * self.inv_hz;
        let plan =
            (-LOCATE_SLACK..=self.u_max).contains(&u) && (-LOCATE_SLACK..=self.w_max).contains(&w);
        if !plan {
            return Err(self.locate_error(p, None));
        }
        // truncation is floor within the slack; the far edges belong to the last cell
        let i = (u as i64).min(self.nx as i64 - 1);
        let k = (w as i64).min(self.nz as i64 - 1);
        let (a, c) = (u - i as f64, w - k as f64);
        let (g00, g10) = (self.height(i, k), self.height(i + 1, k));
        let (g01, g11) = (self.height(i, k + 1), self.height(i + 1, k + 1));
        let g = (g00 * (1.0 - a) + g10 * a) * (1.0 - c) + (g01 * (1.0 - a) + g11 * a) * c;
        let t = (p.y - g) * self.inv_r;
        if !(-LOCATE_SLACK..=self.t_max).contains(&t) {
            return Err(self.locate_error(p, Some(g)));
        }
        let j = (t as i64).min(self.layers as i64 - 1);
        let gx = ((g10 - g00) * (1.0 - c) + (g11 - g01) * c) * self.inv_hx;
        let gz = ((g01 - g00) * (1.0 - a) + (g11 - g10) * a) * self.inv_hz;
        let f = TerrainFactors {
            a,
            b: t - j as f64,
            c,
            db_dx: -gx * self.inv_r,
            db_dz: -gz * self.inv_r,
        };
        Ok((NodeId::new(i as i32, j as i32, k as i32), f))
    }

    #[cold]
    #[inline(never)]
    fn locate_error(&self, p: Vector, ground: Option<f64>) -> LocateError {
        if !p.is_finite() {
            LocateError::non_finite(p)
        } else if let Some(g) = ground.filter(|&g| p.y < g) {
            LocateError::below_ground(p, g)
        } else {
            LocateError::outside(p)
        }
    }

    /// the cell and natural coordinates (ξ, η, ζ) of `p`.
    pub fn locate(&self, p: Vector) -> Result<CellCoords, LocateError> {
        let (cell, f) = self.locate_parts(p)?;
        Ok(CellCoords { cell, xi: 2.0 * f.a - 1.0, eta: 2.0 * f.b - 1.0, zeta: 2.0 * f.c - 1.0 })
    }

    /// the point at natural coordinates `c` of its cell: the trilinear isoparametric map.
    pub fn position(&self, c: CellCoords) -> Vector {
        let (a, b, cc) = (0.5 * (1.0 + c.xi), 0.5 * (1.0 + c.eta), 0.5 * (1.0 + c.zeta));
        let (i, j, k) = (i64::from(c.cell.i), i64::from(c.cell.j), i64::from(c.cell.k));
        Vector::new(
            self.x0 + (i as f64 + a) * self.hx,
            self.bilinear(i, k, a, cc) + (j as f64 + b) * self.r,
            self.z0 + (k as f64 + cc) * self.hz,
        )
    }

    /// the upward unit normals of the ground's tangent planes at lattice node (i, k), one per
    /// plan cell the node is a corner of, distinct ones only (normals within 1e-12 of one
    /// another are one plane: the same slope computed from different pairs of heights), at
    /// most four: each spanned by the
    /// two lattice edges that leave the node in that cell.
    pub fn ground_planes(&self, i: i64, k: i64) -> [Option<Vector>; 4] {
        let (i, k) = (i.clamp(0, self.nx as i64), k.clamp(0, self.nz as i64));
        let g = self.height(i, k);
        // slopes of the lattice edges leaving the node: towards −x, +x, −z, +z
        let sx = [
            (i > 0).then(|| (g - self.height(i - 1, k)) * self.inv_hx),
            (i < self.nx as i64).then(|| (self.height(i + 1, k) - g) * self.inv_hx),
        ];
        let sz = [
            (k > 0).then(|| (g - self.height(i, k - 1)) * self.inv_hz),
            (k < self.nz as i64).then(|| (self.height(i, k + 1) - g) * self.inv_hz),
        ];
        let mut out: [Option<Vector>; 4] = [None; 4];
        let mut n = 0;
        for gz in sz.into_iter().flatten() {
            for gx in sx.into_iter().flatten() {
                let normal = Vector::new(-gx, 1.0, -gz).normalize();
                // (planes within round-off of one already held are that plane)
                let held = out[..n].iter().flatten().any(|m| (*m - normal).length() < 1e-12);
                if !held {
                    out[n] = Some(normal);
                    n += 1;
                }
            }
        }
        out
    }

    /// boundary planes a node lies on or beyond: the ground's planes at its plan node (layer
    /// j ≤ 0, [`TerrainGrid::ground_planes`]: `ground`, `ground_kink` and `ground_more`), and
    /// the four vertical sides.
    pub fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        let [g0, g1, g2, g3] = if node.j <= 0 {
            self.ground_planes(i64::from(node.i), i64::from(node.k))
        } else {
            [None; 4]
        };
        BoundaryNormals {
            ground: g0,
            ground_kink: g1,
            ground_more: [g2, g3],
            left_wall: (node.i <= 0).then_some(Vector::X),
            right_wall: (i64::from(node.i) >= self.nx as i64).then_some(Vector::NEG_X),
            back_wall: (node.k <= 0).then_some(Vector::Z),
            front_wall: (i64::from(node.k) >= self.nz as i64).then_some(Vector::NEG_Z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Bilinear, RegularGrid, ShapeFunctions};

    /// a DEM with planar cells of many slopes and orientations: g = f(x) + p(z), f and p
    /// piecewise linear with kinks on the lattice, plus a tilt.
    fn kinked(nx: usize, nz: usize) -> TerrainGrid {
        let f = |i: usize| [0.0, 0.3, 0.1, 0.7, 0.2, 0.5, 0.55, 0.0][i % 8];
        let p = |k: usize| [0.0, -0.2, 0.35, 0.1, 0.6, 0.2][k % 6];
        let heights = (0..=nz)
            .flat_map(|k| (0..=nx).map(move |i| f(i) + p(k) + 0.05 * i as f64 - 0.03 * k as f64))
            .collect();
        TerrainGrid::new(TerrainGridSpec {
            origin: [-1.0, 2.0],
            spacing: [0.5, 0.4],
            cells: [nx, nz],
            heights,
            layer_height: 0.25,
            layers: 6,
        })
        .unwrap()
    }

    /// a twisted DEM (non-planar bilinear cells).
    fn twisted() -> TerrainGrid {
        let heights = (0..=3)
            .flat_map(|k| {
                (0..=4).map(move |i| 0.3 * ((i * 7 + k * 3) % 5) as f64 - 0.1 * (i * k) as f64)
            })
            .collect();
        TerrainGrid::new(TerrainGridSpec {
            origin: [0.0, 0.0],
            spacing: [0.5, 0.5],
            cells: [4, 3],
            heights,
            layer_height: 0.3,
            layers: 5,
        })
        .unwrap()
    }

    /// points spread through the grid's cells, a fixed sequence.
    fn samples(g: &TerrainGrid) -> Vec<Vector> {
        let [nx, nz] = g.plan_cells();
        let (_, layers) = g.layers();
        let mut out = Vec::new();
        let mut s = 0.123_f64;
        for _ in 0..500 {
            s = (s * 7.31 + 0.417).fract();
            let a = s;
            s = (s * 5.77 + 0.291).fract();
            let b = s;
            s = (s * 3.93 + 0.613).fract();
            let c = s;
            let cell = NodeId::new(
                ((a * 97.0) as usize % nx) as i32,
                ((b * 89.0) as usize % layers) as i32,
                ((c * 83.0) as usize % nz) as i32,
            );
            out.push(g.position(CellCoords {
                cell,
                xi: 2.0 * a - 1.0,
                eta: 2.0 * b - 1.0,
                zeta: 2.0 * c - 1.0,
            }));
        }
        out
    }

    /// locate inverts the isoparametric map, the weights reproduce linear fields (Σ N = 1,
    /// Σ N x_i = x, Σ x_i ⊗ ∇N_i = I), and the gradients are the map's inverse Jacobian
    /// (central differences of the weights, step 1e-6 m: error O(1e-10) for these curvatures).
    #[test]
    fn locate_weights_and_gradients_are_the_isoparametric_maps() {
        for g in [kinked(7, 5), twisted()] {
            let shape = Bilinear(g.clone());
            for x in samples(&g) {
                let (first, f) = shape.factors(x).unwrap();
                let back = g.position(g.locate(x).unwrap());
                assert!((back - x).length() < 1e-12, "{x} → {back}");
                let (w, grad) = (shape.weights(&f), shape.gradients(&f));
                let nodes = crate::stencil_nodes::<8>(first);
                let mut sum = 0.0;
                let mut at = Vector::ZERO;
                let mut ident = crate::Matrix::ZERO;
                for k in 0..8 {
                    let xi = shape.node_position(nodes[k]);
                    sum += w[k];
                    at += w[k] * xi;
                    ident +=
                        crate::Matrix::from_cols(xi * grad[k].x, xi * grad[k].y, xi * grad[k].z);
                }
                assert!((sum - 1.0).abs() < 1e-13);
                assert!((at - x).length() < 1e-12, "{at} vs {x}");
                assert!(ident.abs_diff_eq(crate::Matrix::IDENTITY, 1e-11), "{ident}");
                let d = 1e-6;
                for (axis, unit) in Vector::AXES.iter().enumerate() {
                    let step = *unit * d;
                    let (fp, fm) = (shape.factors(x + step), shape.factors(x - step));
                    let (Ok((np, fp)), Ok((nm, fm))) = (fp, fm) else { continue };
                    if np != first || nm != first {
                        continue; // across a cell edge
                    }
                    let (wp, wm) = (shape.weights(&fp), shape.weights(&fm));
                    for k in 0..8 {
                        let fd = (wp[k] - wm[k]) / (2.0 * d);
                        assert!(
                            (fd - grad[k][axis]).abs() < 1e-6,
                            "axis {axis} slot {k}: {fd} vs {}",
                            grad[k][axis]
                        );
                    }
                }
            }
        }
    }

    /// A flat DEM is the regular grid: the same nodes, weights and gradients.
    #[test]
    fn a_flat_dem_is_the_regular_grid() {
        let t = TerrainGrid::new(TerrainGridSpec {
            origin: [0.5, -1.0],
            spacing: [0.25, 0.5],
            cells: [6, 4],
            heights: vec![0.2; 35],
            layer_height: 0.125,
            layers: 8,
        })
        .unwrap();
        let r =
            RegularGrid::new(Vector::new(0.5, 0.2, -1.0), Vector::new(0.25, 0.125, 0.5), [6, 8, 4])
                .unwrap();
        let (st, sr) = (Bilinear(t.clone()), Bilinear(r));
        for x in samples(&t) {
            let (nt, ft) = st.factors(x).unwrap();
            let (nr, fr) = sr.factors(x).unwrap();
            assert_eq!(nt, nr);
            let (wt, wr) = (st.weights(&ft), sr.weights(&fr));
            let (gt, gr) = (st.gradients(&ft), sr.gradients(&fr));
            for k in 0..8 {
                assert!((wt[k] - wr[k]).abs() < 1e-14);
                assert!((gt[k] - gr[k]).length() < 1e-12);
            }
        }
        assert_eq!(st.min_cell_size(), sr.min_cell_size());
        for node in [NodeId::new(0, 0, 0), NodeId::new(3, 0, 2), NodeId::new(6, 2, 4)] {
            assert_eq!(t.boundary_normals(node), r.boundary_normals(node));
        }
    }

    /// Ground nodes carry every distinct tangent plane of their cells, and each passes through
    /// the lattice edges leaving the node; a node inside a tilted plane has one.
    #[test]
    fn ground_nodes_carry_the_tangent_planes_of_their_cells() {
        let g = kinked(7, 5);
        let n = g.ground_planes(3, 2);
        let planes: Vec<Vector> = n.iter().flatten().copied().collect();
        assert_eq!(planes.len(), 4, "a node where four planar cells of different slopes meet");
        let here = g.node_position(NodeId::new(3, 0, 2));
        for (di, dk) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
            let there = g.node_position(NodeId::new(3 + di, 0, 2 + dk));
            // the edge lies in two of the planes (the cells on either side of it)
            let on = planes.iter().filter(|p| (there - here).dot(**p).abs() < 1e-12).count();
            assert_eq!(on, 2, "edge ({di}, {dk})");
        }
        let tilted = TerrainGrid::new(TerrainGridSpec {
            origin: [0.0, 0.0],
            spacing: [1.0, 1.0],
            cells: [3, 3],
            heights: (0..16).map(|n| 0.4 * (n % 4) as f64 - 0.2 * (n / 4) as f64).collect(),
            layer_height: 0.5,
            layers: 2,
        })
        .unwrap();
        let n = tilted.ground_planes(1, 2);
        assert!(n[0].is_some() && n[1..].iter().all(Option::is_none));
        assert!((n[0].unwrap() - Vector::new(-0.4, 1.0, 0.2).normalize()).length() < 1e-15);
        assert_eq!(tilted.boundary_normals(NodeId::new(1, 1, 2)).ground, None);
        // corners: the sides too
        let c = tilted.boundary_normals(NodeId::new(0, 0, 3));
        assert_eq!((c.left_wall, c.front_wall), (Some(Vector::X), Some(Vector::NEG_Z)));
    }

    /// Bad specifications are refused with the value named.
    #[test]
    fn bad_specifications_are_refused() {
        let spec = TerrainGridSpec {
            origin: [0.0, 0.0],
            spacing: [1.0, 1.0],
            cells: [2, 2],
            heights: vec![0.0; 9],
            layer_height: 0.5,
            layers: 2,
        };
        assert!(TerrainGrid::new(spec.clone()).is_ok());
        let e = TerrainGrid::new(TerrainGridSpec { heights: vec![0.0; 8], ..spec.clone() });
        assert!(matches!(e, Err(GridError::HeightCount { count: 8, expected: 9, .. })));
        let mut h = vec![0.0; 9];
        h[5] = f64::NAN;
        let e = TerrainGrid::new(TerrainGridSpec { heights: h, ..spec.clone() });
        assert!(matches!(e, Err(GridError::NonFiniteHeight { i: 2, k: 1, .. })));
        let e = TerrainGrid::new(TerrainGridSpec { layer_height: 0.0, ..spec.clone() });
        assert!(matches!(e, Err(GridError::NonPositiveSize { .. })));
        let e = TerrainGrid::new(TerrainGridSpec { cells: [0, 2], ..spec.clone() });
        assert!(matches!(e, Err(GridError::CellCountOutOfRange { .. })));
        let g = TerrainGrid::new(spec).unwrap();
        assert!(matches!(
            g.locate(Vector::new(1.0, -0.1, 1.0)),
            Err(LocateError::BelowGround { .. })
        ));
        assert!(matches!(g.locate(Vector::new(2.5, 0.1, 1.0)), Err(LocateError::Outside { .. })));
        assert!(matches!(
            g.locate(Vector::new(1.0, f64::NAN, 1.0)),
            Err(LocateError::NonFinite { .. })
        ));
    }
}
