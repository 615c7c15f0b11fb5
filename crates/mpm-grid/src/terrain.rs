//! The terrain-following grid of isoparametric skewed rectangles (Abe, Johansson & Konagai 2005,
//! §3(2), eqs 19–20): columns of width l over a piecewise-linear ground, rows at vertical spacing h.
//!
//! # Glossary
//! - profile: the ground polyline y_g(x), points (X_k, Y_k), k = 0..=K, X strictly increasing;
//!   segment k joins points k and k+1.
//! - x0 = X_0: left end of the grid; l: column (cell) width, m; h: row spacing measured
//!   vertically, m; `columns` cells along x, `rows` cells upwards.
//! - node (i, j), i = 0..=columns, j = 0..=rows: at x = x0 + i·l, y = y_g(x) + j·h. Row j = 0
//!   lies exactly on the ground.
//! - cell (i, j): spans columns i..i+1 and rows j..j+1; its corners in the paper's numbering are
//!   1 = node (i, j), 2 = (i+1, j), 3 = (i, j+1), 4 = (i+1, j+1).
//! - ξ, η: natural coordinates (eqs 19–20); a = (1+ξ)/2, b = (1+η)/2 ∈ [0, 1].
//! - s: slope dy/dx of the ground in a column; θ = atan s.
//! - units SI (m); y up.
//!
//! # Kinks fall on column boundaries
//! Each profile point must sit on a column boundary x0 + c·l so that the ground is straight
//! across every column; then a cell's bottom and top edges are straight and parallel (a
//! parallelogram with vertical sides, y3 − y1 = y4 − y2 = h), the general eq 20 map applies, and
//! eq 20 reduces to the affine η = 2(y − y_g(x))/h − (2j + 1). [`KinkPolicy`] says what happens
//! to a point off a boundary: `Snap` moves it horizontally to the nearest boundary (keeping its
//! height), `Reject` is an error. Points within [`KINK_TOLERANCE`]·l of a boundary count as on it
//! under both policies and are placed exactly on it. The grid keeps the snapped profile
//! ([`TerrainGrid::profile`]); that is the ground the solver sees.
//!
//! # Locating a point (O(1), closed form)
//! u = (x − x0)/l, i = ⌊u⌋, a = u − i (eq 19); the ground height y_g(x) = Y_k + r_k·(u − c_k) of
//! the column's segment k (r_k the rise per column); t = (y − y_g(x))/h, j = ⌊t⌋, b = t − j
//! (eq 20). Points up to
//! [`LOCATE_SLACK`](crate::LOCATE_SLACK) cells beyond an edge belong to the edge cell. The profile segment of a column is
//! found by counting the kinks left of it (binary search beyond 4 kinks), so the grid's memory is
//! O(K), not O(columns): a 10 km long grid costs what its profile costs.
//!
//! # Gradients
//! The Jacobian of a parallelogram cell is constant: ∂a/∂x = 1/l, ∂a/∂y = 0, ∂b/∂x = −s/h,
//! ∂b/∂y = 1/h; ∇N = (N_a/l − N_b·s/h, N_b/h) with N_a = ∂N/∂a, N_b = ∂N/∂b. This equals the
//! general inverse-Jacobian route of [`SkewedCell::shape`](crate::SkewedCell::shape) (tested).
//!
//! # Ground normal at a kink
//! A ground node inside a segment takes that segment's unit normal (pointing up, into the
//! material). A node on a kink lies on both adjacent segments' planes, and the boundary
//! conditions hold it on both ([`TerrainGrid::boundary_normals`], where the reason is given);
//! [`TerrainGrid::node_ground_normal`] still describes the ground there by the bisector (for a
//! 30° slope running into a flat runout, 15° from vertical). At a convex kink (a ridge) both
//! planes are stricter than the ground, whose admissible directions are the union of the two
//! half-planes; the node may not follow the downhill segment at once, and the material leaves
//! the ridge along the uphill one, an effect of order Δθ that the convex-hull guarantee needs.

use serde::{Deserialize, Serialize};

use crate::error::{Extent, GridError, LocateError};
use crate::math::Vector;
use crate::node::{BoundaryNormals, CellCoords, NodeId};
use crate::skewed_cell::SkewedCell;
use crate::{LOCATE_SLACK, MAX_CELLS_PER_AXIS};

/// relative distance (in units of l) within which a profile point counts as lying on a column
/// boundary: far above the round-off of (X_k − x0)/l for any sane input (~1e-15·K), far below any
/// deliberate offset.
pub const KINK_TOLERANCE: f64 = 1e-9;

/// What to do with a profile point that does not fall on a column boundary x0 + c·l.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum KinkPolicy {
    /// move the point horizontally to the nearest column boundary, keeping its height (error if
    /// two points land on the same boundary).
    #[default]
    Snap,
    /// return [`GridError::KinkOffColumnBoundary`] naming the point.
    Reject,
}

/// Everything that defines a [`TerrainGrid`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TerrainGridSpec {
    /// ground polyline, x strictly increasing, at least two points, m. The first point's x is
    /// the grid's left end; the last point's (snapped) x its right end.
    pub profile: Vec<Vector>,
    /// column width l, m.
    pub cell_width: f64,
    /// row spacing h, measured vertically, m.
    pub row_height: f64,
    /// number of cell rows above the ground (node rows are 0..=rows).
    pub rows: usize,
    /// what to do with profile points off the column boundaries.
    pub kink_policy: KinkPolicy,
}

/// One straight piece of the (snapped) ground profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundSegment {
    /// segment index k: it joins profile points k and k+1.
    pub index: usize,
    /// left end, m.
    pub start: Vector,
    /// right end, m.
    pub end: Vector,
    /// unit normal pointing up, into the material.
    pub normal: Vector,
}

/// The ground segments on either side of a ground node.
///
/// `left` is the segment under column i−1, `right` the one under column i. Inside a segment both
/// are that segment; at a kink they differ; at the grid's ends one is `None`; both are `None` for
/// a column index outside 0..=columns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdjacentSegments {
    /// segment under the column to the node's left.
    pub left: Option<GroundSegment>,
    /// segment under the column to the node's right.
    pub right: Option<GroundSegment>,
}

/// Terrain-following grid of skewed rectangles over a piecewise-linear ground (eqs 19–20).
///
/// Invariants: columns ≥ 1, rows ≥ 1, every profile point on a column boundary, every cell
/// non-degenerate. Memory is O(profile points), independent of the grid's extent.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainGrid {
    x0: f64,
    l: f64,
    h: f64,
    inv_l: f64,
    inv_h: f64,
    columns: usize,
    rows: usize,
    /// snapped profile, K+1 points.
    points: Vec<Vector>,
    /// column boundary index c_k of each profile point; c_0 = 0, c_K = columns.
    point_column: Vec<u32>,
    /// ground rise per column along segment k, (Y_{k+1} − Y_k)/(c_{k+1} − c_k), m; K entries.
    rise: Vec<f64>,
    /// unit normal of segment k; K entries.
    normals: Vec<Vector>,
    /// column boundary index of each interior profile point (c_1 ..= c_{K−1}) as f64: the
    /// segment of a point at u = (x − x0)/l is the number of these ≤ u (the same as the number
    /// ≤ ⌊u⌋, since they are integers).
    kinks: Vec<f64>,
    /// the same, padded with +∞ to a fixed size when there are at most [`FEW_KINKS`] of them
    /// (the common case), so that the count is a fixed, branch-free comparison.
    few_kinks: Option<[f64; FEW_KINKS]>,
    /// columns + LOCATE_SLACK and rows + LOCATE_SLACK: the accepted u and t ranges' upper ends.
    u_max: f64,
    t_max: f64,
    /// per-segment constants of the locate hot path; K entries.
    lines: Vec<GroundLine>,
    min_cell: f64,
}

/// segment k as the locate hot path needs it: y_g(u) = y0 + rise·(u − c0) with u = (x − x0)/l.
#[derive(Clone, Copy, Debug, PartialEq)]
struct GroundLine {
    /// c_k as f64.
    c0: f64,
    /// Y_k, m.
    y0: f64,
    /// ground rise per column, m.
    rise: f64,
    /// ∂b/∂x = −s/h in the segment's cells, 1/m.
    db_dx: f64,
}

/// up to this many interior kinks, the segment of a point is found by a fixed branch-free count;
/// beyond, by binary search.
const FEW_KINKS: usize = 4;

/// where a point sits: column i, row j, fractions a = (1+ξ)/2, b = (1+η)/2, and ∂b/∂x.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TerrainLocation {
    pub i: i64,
    pub j: i64,
    pub a: f64,
    pub b: f64,
    /// ∂b/∂x = −s/h.
    pub db_dx: f64,
}

impl TerrainGrid {
    /// builds the grid, validating the profile and sizes (see [`GridError`] for every failure,
    /// each naming the offending point or value).
    pub fn new(spec: TerrainGridSpec) -> Result<Self, GridError> {
        let TerrainGridSpec { profile, cell_width: l, row_height: h, rows, kink_policy } = spec;
        if profile.len() < 2 {
            return Err(GridError::TooFewProfilePoints { count: profile.len() });
        }
        for (index, p) in profile.iter().enumerate() {
            if !p.is_finite() {
                return Err(GridError::NonFiniteProfilePoint { index, x: p.x, y: p.y });
            }
        }
        for (index, w) in profile.windows(2).enumerate() {
            if w[1].x <= w[0].x {
                return Err(GridError::NonIncreasingProfile {
                    index: index + 1,
                    x: w[1].x,
                    previous_x: w[0].x,
                });
            }
        }
        let positive = |v: f64| v > 0.0 && v.is_finite();
        if !positive(l) {
            return Err(GridError::NonPositiveSize { what: Extent::CellWidth, value: l });
        }
        if !positive(h) {
            return Err(GridError::NonPositiveSize { what: Extent::RowHeight, value: h });
        }
        if rows == 0 || rows > MAX_CELLS_PER_AXIS {
            return Err(GridError::CellCountOutOfRange {
                what: Extent::Rows,
                count: rows as f64,
                max: MAX_CELLS_PER_AXIS,
            });
        }
        let x0 = profile[0].x;
        let mut points = Vec::with_capacity(profile.len());
        let mut point_column = Vec::with_capacity(profile.len());
        points.push(profile[0]);
        point_column.push(0u32);
        for (index, p) in profile.iter().enumerate().skip(1) {
            let u = (p.x - x0) / l;
            let c = u.round();
            if !(0.0..=MAX_CELLS_PER_AXIS as f64).contains(&c) {
                return Err(GridError::CellCountOutOfRange {
                    what: Extent::Columns,
                    count: c,
                    max: MAX_CELLS_PER_AXIS,
                });
            }
            let boundary_x = x0 + c * l;
            if kink_policy == KinkPolicy::Reject && (u - c).abs() > KINK_TOLERANCE {
                return Err(GridError::KinkOffColumnBoundary {
                    index,
                    x: p.x,
                    nearest_boundary_x: boundary_x,
                });
            }
            let c = c as u32; // 0 ≤ c ≤ MAX_CELLS_PER_AXIS: exact
            if c <= point_column[point_column.len() - 1] {
                return Err(GridError::SnappedPointsCoincide { index, x: p.x, boundary_x });
            }
            points.push(Vector::new(boundary_x, p.y));
            point_column.push(c);
        }
        let columns = point_column[point_column.len() - 1] as usize;
        let y_extent = points.iter().map(|p| p.y.abs()).fold(0.0, f64::max);
        let top = y_extent + h * rows as f64;
        if !top.is_finite() {
            return Err(GridError::NonPositiveSize { what: Extent::GridHeight, value: top });
        }
        let mut rise = Vec::with_capacity(points.len() - 1);
        let mut normals = Vec::with_capacity(points.len() - 1);
        let mut lines = Vec::with_capacity(points.len() - 1);
        let mut min_cell = l;
        for k in 0..points.len() - 1 {
            let n_k = f64::from(point_column[k + 1] - point_column[k]);
            let r = (points[k + 1].y - points[k].y) / n_k;
            let slope = r / l;
            let normal_height = h / (1.0 + slope * slope).sqrt();
            if !(slope.is_finite() && positive(normal_height)) {
                return Err(GridError::DegenerateSegment { index: k, slope, normal_height });
            }
            min_cell = min_cell.min(normal_height);
            rise.push(r);
            normals.push(Vector::new(-r, l).normalize());
            lines.push(GroundLine {
                c0: f64::from(point_column[k]),
                y0: points[k].y,
                rise: r,
                db_dx: -slope / h,
            });
        }
        let kinks: Vec<f64> =
            point_column[1..point_column.len() - 1].iter().map(|&c| f64::from(c)).collect();
        let few_kinks = (kinks.len() <= FEW_KINKS).then(|| {
            let mut padded = [f64::INFINITY; FEW_KINKS];
            padded[..kinks.len()].copy_from_slice(&kinks);
            padded
        });
        Ok(Self {
            x0,
            l,
            h,
            inv_l: 1.0 / l,
            inv_h: 1.0 / h,
            columns,
            rows,
            points,
            point_column,
            rise,
            normals,
            kinks,
            few_kinks,
            lines,
            u_max: columns as f64 + LOCATE_SLACK,
            t_max: rows as f64 + LOCATE_SLACK,
            min_cell,
        })
    }

    /// the snapped ground profile: the ground the grid follows, m.
    pub fn profile(&self) -> &[Vector] {
        &self.points
    }

    /// column width l, m.
    pub fn cell_width(&self) -> f64 {
        self.l
    }

    /// row spacing h (vertical), m.
    pub fn row_height(&self) -> f64 {
        self.h
    }

    /// (1/l, 1/h), 1/m.
    #[inline]
    pub(crate) fn inverse_sizes(&self) -> (f64, f64) {
        (self.inv_l, self.inv_h)
    }

    /// number of cell columns (node columns are 0..=columns).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// number of cell rows (node rows are 0..=rows).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// x range [x0, x0 + columns·l] covered by the grid, m.
    pub fn x_range(&self) -> (f64, f64) {
        (self.x0, self.x0 + self.columns as f64 * self.l)
    }

    /// smallest distance between opposite cell edges, m: min(l, h·cos θ_max).
    pub fn min_cell_size(&self) -> f64 {
        self.min_cell
    }

    /// index k of the last profile point at or left of column boundary `i` (0 ≤ i ≤ columns).
    #[inline]
    fn point_at_or_before(&self, i: usize) -> usize {
        // c_0 = 0 ≤ i, so the partition point is ≥ 1.
        self.point_column.partition_point(|&c| c as usize <= i) - 1
    }

    /// ground height of node column `i`, 0 ≤ i ≤ columns, from profile point k ≤ i.
    #[inline]
    fn ground_of_column_in(&self, k: usize, i: usize) -> f64 {
        let offset = i - self.point_column[k] as usize;
        if offset == 0 { self.points[k].y } else { self.points[k].y + self.rise[k] * offset as f64 }
    }

    /// ground height of node column `i`, m. Outside 0..=columns the end segments are extended.
    pub fn node_ground_height(&self, i: i32) -> f64 {
        let last = self.points.len() - 1;
        if i < 0 {
            self.points[0].y + self.rise[0] * f64::from(i)
        } else if i as usize > self.columns {
            self.points[last].y + self.rise[last - 1] * (i as usize - self.columns) as f64
        } else {
            let i = i as usize;
            self.ground_of_column_in(self.point_at_or_before(i), i)
        }
    }

    /// u = (x − x0)/l and the column i = ⌊u⌋ of an x in range (up to the slack); `None` outside
    /// or non-finite.
    #[inline(always)]
    fn column_of(&self, x: f64) -> Option<(f64, i64)> {
        let u = (x - self.x0) * self.inv_l;
        if !(-LOCATE_SLACK..=self.u_max).contains(&u) {
            return None;
        }
        // truncation is floor for u ≥ 0 and gives 0 for the slack below 0; the right edge (and
        // the slack beyond it) belongs to the last column. i64 (not usize) keeps the int ↔ float
        // conversions single instructions.
        Some((u, (u as i64).min(self.columns as i64 - 1)))
    }

    /// the ground line under the point at u = (x − x0)/l, u in range; a point on a kink
    /// belongs to the segment on its right, like its column.
    #[inline(always)]
    fn line_at(&self, u: f64) -> &GroundLine {
        let k = match &self.few_kinks {
            // branch-free and independent of the column computation, so both run in parallel.
            Some(few) => few.iter().map(|&c| usize::from(c <= u)).sum(),
            None => self.kinks.partition_point(|&c| c <= u),
        };
        &self.lines[k]
    }

    /// height of the ground at `x`, m; `None` for a non-finite x or one outside the grid's
    /// x range. This is the function [`Self::locate`] compares against for
    /// [`LocateError::BelowGround`]; at node columns it equals [`Self::node_ground_height`] up
    /// to round-off (exactly at profile points).
    pub fn ground_height(&self, x: f64) -> Option<f64> {
        let (u, _) = self.column_of(x)?;
        let s = self.line_at(u);
        Some(s.y0 + s.rise * (u - s.c0))
    }

    #[inline(always)]
    pub(crate) fn locate_parts(&self, p: Vector) -> Result<TerrainLocation, LocateError> {
        let Some((u, i)) = self.column_of(p.x) else {
            return Err(column_error(p));
        };
        let s = self.line_at(u);
        let ground_y = s.y0 + s.rise * (u - s.c0);
        let t = (p.y - ground_y) * self.inv_h;
        if !(-LOCATE_SLACK..=self.t_max).contains(&t) {
            return Err(row_error(p, t, ground_y));
        }
        let j = (t as i64).min(self.rows as i64 - 1);
        Ok(TerrainLocation { i, j, a: u - i as f64, b: t - j as f64, db_dx: s.db_dx })
    }

    /// the cell holding `p` and its natural coordinates (eqs 19–20), O(1).
    pub fn locate(&self, p: Vector) -> Result<CellCoords, LocateError> {
        let loc = self.locate_parts(p)?;
        Ok(CellCoords {
            cell: NodeId::new(loc.i as i32, loc.j as i32),
            xi: 2.0 * loc.a - 1.0,
            eta: 2.0 * loc.b - 1.0,
        })
    }

    /// the forward isoparametric map: the point at natural coordinates (ξ, η) of a cell, Σ N_a x_a
    /// over the cell's four nodes.
    pub fn position(&self, c: CellCoords) -> Vector {
        let n = crate::skewed_cell::weights(c.xi, c.eta);
        let NodeId { i, j } = c.cell;
        let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
        corners
            .iter()
            .zip(n)
            .map(|(&(i, j), w)| w * self.node_position(NodeId::new(i, j)))
            .fold(Vector::ZERO, |acc, v| acc + v)
    }

    /// position of node (i, j): x0 + i·l, ground + j·h, m. Ghost nodes beyond the ends extend the
    /// first/last segment; rows below 0 or above `rows` continue the vertical spacing.
    pub fn node_position(&self, node: NodeId) -> Vector {
        Vector::new(
            self.x0 + f64::from(node.i) * self.l,
            self.node_ground_height(node.i) + f64::from(node.j) * self.h,
        )
    }

    /// cell (i, j) as a general eq 19–20 cell, `None` if (i, j) is not a cell of this grid.
    pub fn cell(&self, cell: NodeId) -> Option<SkewedCell> {
        let (i, j) = (cell.i, cell.j);
        if i < 0 || j < 0 || i as usize >= self.columns || j as usize >= self.rows {
            return None;
        }
        let p1 = self.node_position(NodeId::new(i, j));
        let p2 = self.node_position(NodeId::new(i + 1, j));
        let p3 = self.node_position(NodeId::new(i, j + 1));
        let p4 = self.node_position(NodeId::new(i + 1, j + 1));
        SkewedCell::new(p1.x, p2.x, [p1.y, p2.y, p3.y, p4.y]).ok()
    }

    /// number of ground segments K (profile points − 1).
    pub fn segment_count(&self) -> usize {
        self.rise.len()
    }

    /// ground segment k, `None` if k ≥ K.
    pub fn ground_segment(&self, k: usize) -> Option<GroundSegment> {
        (k < self.rise.len()).then(|| GroundSegment {
            index: k,
            start: self.points[k],
            end: self.points[k + 1],
            normal: self.normals[k],
        })
    }

    /// segment under column `c` (0 ≤ c < columns).
    fn segment_of_column(&self, c: i64) -> Option<GroundSegment> {
        if c < 0 || c as usize >= self.columns {
            return None;
        }
        self.ground_segment(self.point_at_or_before(c as usize))
    }

    /// the ground segments on either side of ground node column `i`.
    pub fn ground_segments(&self, i: i32) -> AdjacentSegments {
        AdjacentSegments {
            left: self.segment_of_column(i64::from(i) - 1),
            right: self.segment_of_column(i64::from(i)),
        }
    }

    /// unit normal of the ground at node column `i`, pointing into the material: the segment's
    /// normal inside a segment, the normalised average of both segments' normals at a kink, the
    /// end segment's normal beyond the grid's ends. (A description of the ground; the boundary
    /// conditions hold a kink node on both segments, see [`Self::boundary_normals`].)
    pub fn node_ground_normal(&self, i: i32) -> Vector {
        match self.ground_segments(i) {
            AdjacentSegments { left: Some(l), right: Some(r) } if l.index != r.index => {
                // both normals have a positive y component, so the sum is never zero.
                (l.normal + r.normal).normalize()
            }
            AdjacentSegments { left: Some(s), .. } | AdjacentSegments { right: Some(s), .. } => {
                s.normal
            }
            AdjacentSegments { left: None, right: None } => {
                if i < 0 {
                    self.normals[0]
                } else {
                    self.normals[self.normals.len() - 1]
                }
            }
        }
    }

    /// boundary planes of a node: ground for j ≤ 0, left wall (+x) for i ≤ 0, right wall (−x)
    /// for i ≥ columns.
    ///
    /// At a kink the node carries both segments' planes (`ground`, the right one, and
    /// `ground_kink`, the left one), not their bisector: a ground node's velocity is interpolated
    /// into the cells on both sides, so it must be admissible for both segments. Then, with
    /// bilinear weights (non-negative, a particle's new position is the convex combination of its
    /// cell's four nodes moved by Δt v_i), a particle above the ground stays above it whenever a
    /// node moves less than a cell in a step: every moved node of a column lies above that
    /// column's segment line and above the neighbouring one across a kink. A node held to the
    /// bisector instead moves below the next segment's line by Δt |v| sin(Δθ/2) along it, and a
    /// flow sliding over a curved ground of many kinks sinks through it step by step.
    pub fn boundary_normals(&self, node: NodeId) -> BoundaryNormals {
        let on_ground = node.j <= 0;
        let kink = match self.ground_segments(node.i) {
            AdjacentSegments { left: Some(l), right: Some(r) }
                if on_ground && l.index != r.index && l.normal != r.normal =>
            {
                Some((l.normal, r.normal))
            }
            _ => None,
        };
        BoundaryNormals {
            ground: match kink {
                Some((_, right)) => Some(right),
                None => on_ground.then(|| self.node_ground_normal(node.i)),
            },
            ground_kink: kink.map(|(left, _)| left),
            left_wall: (node.i <= 0).then_some(Vector::X),
            right_wall: (node.i as i64 >= self.columns as i64).then_some(Vector::NEG_X),
        }
    }

    /// heap bytes held by the grid (O(profile points), independent of the extent).
    pub fn heap_bytes(&self) -> usize {
        self.points.capacity() * size_of::<Vector>()
            + self.point_column.capacity() * size_of::<u32>()
            + self.rise.capacity() * size_of::<f64>()
            + self.normals.capacity() * size_of::<Vector>()
            + self.kinks.capacity() * size_of::<f64>()
            + self.lines.capacity() * size_of::<GroundLine>()
    }
}

/// why a point whose x is out of range (or non-finite) was rejected. Kept out of line: the
/// locate hot path only branches to it.
#[cold]
#[inline(never)]
fn column_error(p: Vector) -> LocateError {
    if p.is_finite() {
        LocateError::Outside { x: p.x, y: p.y }
    } else {
        LocateError::NonFinite { x: p.x, y: p.y }
    }
}

/// why a point in the x range whose height t (in rows above the ground) is out of range was
/// rejected.
#[cold]
#[inline(never)]
fn row_error(p: Vector, t: f64, ground_y: f64) -> LocateError {
    if !p.y.is_finite() {
        LocateError::NonFinite { x: p.x, y: p.y }
    } else if t < 0.0 {
        LocateError::BelowGround { x: p.x, y: p.y, ground_y }
    } else {
        LocateError::Outside { x: p.x, y: p.y }
    }
}

#[cfg(all(test, not(feature = "dim3")))]
mod tests {
    use super::*;

    /// round-off allowance for coordinates of order 1–10 m after a few operations.
    const ROUND_OFF: f64 = 1e-12;

    fn slope_runout() -> TerrainGrid {
        // 30° slope from x = 0 to 2 (5 columns of 0.4 m… the kink at x = 2 falls on a boundary),
        // then a flat runout to x = 4.
        let t = 30f64.to_radians().tan();
        TerrainGrid::new(TerrainGridSpec {
            profile: vec![Vector::new(0.0, 2.0 * t), Vector::new(2.0, 0.0), Vector::new(4.0, 0.0)],
            cell_width: 0.4,
            row_height: 0.25,
            rows: 4,
            kink_policy: KinkPolicy::Reject,
        })
        .unwrap()
    }

    #[test]
    fn node_columns_and_rows_follow_the_ground() {
        let g = slope_runout();
        assert_eq!(g.columns(), 10);
        let t = 30f64.to_radians().tan();
        let p = g.node_position(NodeId::new(2, 3));
        assert!((p.x - 0.8).abs() < ROUND_OFF);
        assert!((p.y - ((2.0 - 0.8) * t + 0.75)).abs() < ROUND_OFF);
        assert_eq!(g.node_position(NodeId::new(5, 0)).y, 0.0);
    }

    #[test]
    fn locate_reports_cell_and_natural_coordinates() {
        let g = slope_runout();
        // centre of cell (6, 1): flat ground, x = 2.6, y = 0.375.
        let c = g.locate(Vector::new(2.6, 0.375)).unwrap();
        assert_eq!(c.cell, NodeId::new(6, 1));
        assert!(c.xi.abs() < ROUND_OFF && c.eta.abs() < ROUND_OFF);
    }

    #[test]
    fn min_cell_size_is_h_cos_theta_on_a_slope() {
        let g = slope_runout();
        assert!((g.min_cell_size() - 0.25 * 30f64.to_radians().cos()).abs() < ROUND_OFF);
    }
}
