//! Typed errors: why a grid could not be built and why a point could not be located.

/// Why a point could not be located in a grid. Every variant carries the offending point.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum LocateError {
    /// a coordinate is NaN or infinite.
    #[cfg_attr(not(feature = "dim3"), error("point ({x}, {y}) has a non-finite coordinate"))]
    #[cfg_attr(feature = "dim3", error("point ({x}, {y}, {z}) has a non-finite coordinate"))]
    NonFinite {
        /// x of the point, m.
        x: f64,
        /// y of the point, m.
        y: f64,
        /// z of the point, m (3D builds only).
        #[cfg(feature = "dim3")]
        z: f64,
    },
    /// the point lies left or right of the grid's x range, or above its top row.
    #[cfg_attr(
        not(feature = "dim3"),
        error("point ({x}, {y}) lies outside the grid (left, right or above it)")
    )]
    #[cfg_attr(
        feature = "dim3",
        error("point ({x}, {y}, {z}) lies outside the grid (beside or above it)")
    )]
    Outside {
        /// x of the point, m.
        x: f64,
        /// y of the point, m.
        y: f64,
        /// z of the point, m (3D builds only).
        #[cfg(feature = "dim3")]
        z: f64,
    },
    /// the point lies within the grid's x range but below the ground (or floor).
    #[cfg_attr(
        not(feature = "dim3"),
        error("point ({x}, {y}) lies below the ground, whose height there is {ground_y}")
    )]
    #[cfg_attr(
        feature = "dim3",
        error("point ({x}, {y}, {z}) lies below the ground, whose height there is {ground_y}")
    )]
    BelowGround {
        /// x of the point, m.
        x: f64,
        /// y of the point, m.
        y: f64,
        /// z of the point, m (3D builds only).
        #[cfg(feature = "dim3")]
        z: f64,
        /// height of the ground at x, m.
        ground_y: f64,
    },
}

/// Why a grid, a cell or a shape-function set could not be built.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    /// a ground profile needs at least two points.
    #[error("the ground profile has {count} point(s); at least 2 are needed")]
    TooFewProfilePoints {
        /// number of points given.
        count: usize,
    },
    /// a profile point has a NaN or infinite coordinate.
    #[error("ground profile point {index} = ({x}, {y}) is not finite")]
    NonFiniteProfilePoint {
        /// index of the point in the profile.
        index: usize,
        /// its x, m.
        x: f64,
        /// its y, m.
        y: f64,
    },
    /// profile x must increase strictly from one point to the next.
    #[error(
        "ground profile point {index} has x = {x}, not greater than the previous point's {previous_x}"
    )]
    NonIncreasingProfile {
        /// index of the offending point.
        index: usize,
        /// its x, m.
        x: f64,
        /// x of point `index - 1`, m.
        previous_x: f64,
    },
    /// with [`KinkPolicy::Reject`](crate::KinkPolicy::Reject), every profile point must lie on a
    /// column boundary x0 + k·l.
    #[error(
        "ground profile point {index} at x = {x} is not on a column boundary (nearest is {nearest_boundary_x}); move it or use KinkPolicy::Snap"
    )]
    KinkOffColumnBoundary {
        /// index of the offending point.
        index: usize,
        /// its x, m.
        x: f64,
        /// the nearest column boundary, m.
        nearest_boundary_x: f64,
    },
    /// after snapping to column boundaries, a point landed on the same boundary as its predecessor
    /// (or on the first point): the profile has detail finer than one column.
    #[error(
        "ground profile point {index} at x = {x} snaps to the column boundary {boundary_x}, as the previous point does; use a smaller cell width or drop the point"
    )]
    SnappedPointsCoincide {
        /// index of the offending point.
        index: usize,
        /// its x before snapping, m.
        x: f64,
        /// the column boundary both points snap to, m.
        boundary_x: f64,
    },
    /// a length that must be positive and finite is not.
    #[error("{what} = {value} must be positive and finite")]
    NonPositiveSize {
        /// which length.
        what: Extent,
        /// the value given.
        value: f64,
    },
    /// a coordinate that must be finite is not.
    #[cfg_attr(not(feature = "dim3"), error("{what} = ({x}, {y}) is not finite"))]
    #[cfg_attr(feature = "dim3", error("{what} = ({x}, {y}, {z}) is not finite"))]
    NonFinitePoint {
        /// which point ("grid origin", "cell corner", …).
        what: &'static str,
        /// its x.
        x: f64,
        /// its y.
        y: f64,
        /// its z (3D builds only).
        #[cfg(feature = "dim3")]
        z: f64,
    },
    /// a grid needs at least one cell along each axis and at most [`MAX_CELLS_PER_AXIS`](crate::MAX_CELLS_PER_AXIS).
    #[error("{what} = {count} is out of range (1 ..= {max})")]
    CellCountOutOfRange {
        /// which count.
        what: Extent,
        /// the count asked for (as f64, because it may come from a ratio of lengths).
        count: f64,
        /// the largest count allowed.
        max: usize,
    },
    /// a skewed cell whose isoparametric Jacobian is not positive everywhere in it.
    #[error(
        "cell of width {width} with left side height {left_height} and right side height {right_height} is degenerate: its Jacobian is not positive everywhere"
    )]
    DegenerateCell {
        /// x2 − x1, m.
        width: f64,
        /// y3 − y1, m.
        left_height: f64,
        /// y4 − y2, m.
        right_height: f64,
    },
    /// a profile segment so steep that its cells' height normal to the ground (h·cos θ) is not a
    /// positive finite number.
    #[error(
        "ground profile segment from point {index} has slope {slope}: its cells would be degenerate (height normal to the ground {normal_height})"
    )]
    DegenerateSegment {
        /// index of the segment's first point.
        index: usize,
        /// dy/dx of the segment.
        slope: f64,
        /// h / √(1 + slope²), m.
        normal_height: f64,
    },
    /// a terrain lattice whose heights do not number (columns + 1) × (layers + 1) of the plan.
    #[error(
        "the terrain lattice has {count} heights; a plan of {nx} × {nz} cells needs (nx + 1)(nz + 1) = {expected}"
    )]
    HeightCount {
        /// heights given.
        count: usize,
        /// cells along x.
        nx: usize,
        /// cells along z.
        nz: usize,
        /// heights needed.
        expected: usize,
    },
    /// a terrain height that is NaN or infinite.
    #[error("the terrain height at lattice node (i {i}, k {k}) = {value} is not finite")]
    NonFiniteHeight {
        /// lattice index along x.
        i: usize,
        /// lattice index along z.
        k: usize,
        /// the value.
        value: f64,
    },
    /// uGIMP needs a particle half-size lp with 0 < lp ≤ cell/2 along each axis.
    #[error("uGIMP particle half-size along {axis} = {value} must lie in (0, {max}] (half a cell)")]
    InvalidParticleHalfSize {
        /// "x" or "y".
        axis: &'static str,
        /// the value given, m.
        value: f64,
        /// half the cell size along that axis, m.
        max: f64,
    },
}

impl LocateError {
    /// a point with a non-finite coordinate.
    pub fn non_finite(p: crate::Vector) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self::NonFinite { x: p.x, y: p.y };
        #[cfg(feature = "dim3")]
        return Self::NonFinite { x: p.x, y: p.y, z: p.z };
    }

    /// a point beside or above the grid.
    pub fn outside(p: crate::Vector) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self::Outside { x: p.x, y: p.y };
        #[cfg(feature = "dim3")]
        return Self::Outside { x: p.x, y: p.y, z: p.z };
    }

    /// a point below the ground, whose height there is `ground_y`.
    pub fn below_ground(p: crate::Vector, ground_y: f64) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self::BelowGround { x: p.x, y: p.y, ground_y };
        #[cfg(feature = "dim3")]
        return Self::BelowGround { x: p.x, y: p.y, z: p.z, ground_y };
    }
}

/// Which length or count of a grid a [`GridError`] names: a front end maps it to the field that
/// set it by its variant (the text is for messages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extent {
    /// a terrain grid's column width.
    CellWidth,
    /// a terrain grid's row height.
    RowHeight,
    /// a terrain grid's height over its deepest ground point, row height × rows.
    GridHeight,
    /// a terrain grid's rows.
    Rows,
    /// a terrain grid's columns, from its profile's extent over the column width.
    Columns,
    /// a skewed cell's width x2 − x1.
    SkewedCellWidth,
    /// a regular grid's cell size along an axis (0 x, 1 y, 2 z).
    CellSize(usize),
    /// a regular grid's cells along an axis.
    Cells(usize),
    /// particles per cell along an axis (uGIMP's particle size).
    ParticlesPerCell(usize),
    /// a 3D terrain grid's plan cell size along x (0) or z (1).
    PlanCellSize(usize),
    /// a 3D terrain grid's plan cells along x (0) or z (1).
    PlanCells(usize),
    /// a 3D terrain grid's layer height.
    LayerHeight,
    /// a 3D terrain grid's layers.
    Layers,
    /// a 3D terrain cell's height normal to the ground.
    NormalHeight,
}

impl std::fmt::Display for Extent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const AXES: [&str; 3] = ["x", "y", "z"];
        const PLAN: [&str; 2] = ["x", "z"];
        let axis = |a: usize, names: &[&'static str]| names.get(a).copied().unwrap_or("?");
        match *self {
            Extent::CellWidth => f.write_str("cell width"),
            Extent::RowHeight => f.write_str("row height"),
            Extent::GridHeight => f.write_str("row height × rows"),
            Extent::Rows => f.write_str("rows"),
            Extent::Columns => f.write_str("columns"),
            Extent::SkewedCellWidth => f.write_str("cell width x2 - x1"),
            Extent::CellSize(a) => write!(f, "cell size d{}", axis(a, &AXES)),
            Extent::Cells(a) => write!(f, "cells along {}", axis(a, &AXES)),
            Extent::ParticlesPerCell(a) => write!(f, "particles per cell along {}", axis(a, &AXES)),
            Extent::PlanCellSize(a) => write!(f, "plan cell size h{}", axis(a, &PLAN)),
            Extent::PlanCells(a) => write!(f, "plan cells along {}", axis(a, &PLAN)),
            Extent::LayerHeight => f.write_str("layer height"),
            Extent::Layers => f.write_str("layers"),
            Extent::NormalHeight => f.write_str("cell height normal to the ground"),
        }
    }
}

impl GridError {
    /// `what` (a point) has a non-finite coordinate.
    pub fn non_finite_point(what: &'static str, p: crate::Vector) -> Self {
        #[cfg(not(feature = "dim3"))]
        return Self::NonFinitePoint { what, x: p.x, y: p.y };
        #[cfg(feature = "dim3")]
        return Self::NonFinitePoint { what, x: p.x, y: p.y, z: p.z };
    }
}
