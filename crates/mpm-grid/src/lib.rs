//! Background grids for MPM: the terrain-following grid of isoparametric skewed rectangles
//! (Abe, Johansson & Konagai 2005, eqs 19–20), a regular grid, their shape functions and the
//! sparse set of active nodes.
//!
//! # Layers
//! - grids: [`TerrainGrid`] (columns of width l over a piecewise-linear ground, rows at vertical
//!   spacing h, the bottom row on the ground) and [`RegularGrid`]. Both locate a point in O(1),
//!   closed form, and report boundary normals of their nodes.
//! - one cell: [`SkewedCell`], the general eq 19–20 map with vertical sides.
//! - shape functions, all behind [`ShapeFunctions<N>`] (fixed-size [`Stencil<N>`], no allocation,
//!   no dyn): [`Bilinear`] on either grid (N = 4), [`Gimp`] (uGIMP) and [`QuadraticBSpline`] on
//!   the regular grid (N = 9).
//! - [`ActiveNodes`]: the nodes touched by material, numbered deterministically.
//!
//! # Node numbering
//! [`NodeId`] (i, j): column i along x, row j upwards, j = 0 on the ground/floor. Stencils of
//! the 9-node shape functions may include one ghost layer outside the grid.
//!
//! # Architecture invariant
//! This crate knows nothing of materials, particle state, time stepping or contact laws: it maps
//! points to nodes, weights and gradients, and says where the boundaries are.
//!
//! Units SI (m), f64, y up.
//!
//! # Example
//! ```
//! use mpm_grid::{
//!     ActiveNodes, Bilinear, KinkPolicy, ShapeFunctions, TerrainGrid, TerrainGridSpec, Vector,
//! };
//!
//! // a 30° slope running into a flat runout at x = 2 m, 0.1 m cells, 10 rows.
//! let t = 30f64.to_radians().tan();
//! let grid = TerrainGrid::new(TerrainGridSpec {
//!     profile: vec![Vector::new(0.0, 2.0 * t), Vector::new(2.0, 0.0), Vector::new(4.0, 0.0)],
//!     cell_width: 0.1,
//!     row_height: 0.1,
//!     rows: 10,
//!     kink_policy: KinkPolicy::Reject,
//! })?;
//! let sf = Bilinear(grid);
//! let s = sf.stencil(Vector::new(1.05, 0.6))?;
//! assert!((s.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
//!
//! let mut active = ActiveNodes::new();
//! active.rebuild(s.nodes);
//! assert_eq!(active.len(), 4);
//! let k = active.index_of(s.nodes[0]).expect("active");
//! assert_eq!(active.nodes()[k], s.nodes[0]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod active;
mod bilinear;
mod bspline;
mod dispatch;
mod error;
mod gimp;
pub mod math;
mod node;
mod regular;
#[cfg(not(feature = "dim3"))]
mod skewed_cell;
mod stencil;
#[cfg(feature = "dim3")]
mod tensor;
#[cfg(not(feature = "dim3"))]
mod terrain;
#[cfg(feature = "dim3")]
mod terrain3d;
#[doc(hidden)]
pub mod testing;

pub use active::{ActiveNodes, BLOCK_SIDE};
pub use bilinear::Bilinear;
#[cfg(not(feature = "dim3"))]
pub use bilinear::TerrainFactors;
pub use bspline::QuadraticBSpline;
pub use dispatch::{RegularShape, ShapeJob, with_regular_shape};
pub use error::{Extent, GridError, LocateError};
pub use gimp::{AxisFactors, Gimp, WIDE};
pub use math::{DIM, Matrix, Real, Vector};
pub use node::{BoundaryNormals, CellCoords, NodeId};
pub use regular::RegularGrid;
#[cfg(not(feature = "dim3"))]
pub use skewed_cell::SkewedCell;
pub use stencil::{ShapeFunctions, Stencil, slot_offset, stencil_nodes, stencil_side};
#[cfg(not(feature = "dim3"))]
pub use terrain::{
    AdjacentSegments, GroundSegment, KINK_TOLERANCE, KinkPolicy, TerrainGrid, TerrainGridSpec,
};
#[cfg(feature = "dim3")]
pub use terrain3d::{TerrainFactors, TerrainGrid, TerrainGridSpec};

/// most cells (or rows, or columns) along one axis: 2³⁰, so that node indices, ghost layers and
/// i + 1 stay far from i32 overflow.
#[cfg(not(feature = "dim3"))]
pub const MAX_CELLS_PER_AXIS: usize = 1 << 30;
/// most cells along one axis in 3D: 2²¹, so that the three block indices of a node pack into
/// one 64-bit key of the active-node set (and 2²¹ cells along each of three axes is far more
/// than any memory holds).
#[cfg(feature = "dim3")]
pub const MAX_CELLS_PER_AXIS: usize = 1 << 21;

/// how far beyond the grid's edges (and below the ground), in cells, a point is still located
/// in the edge cell rather than rejected: 1e-9 of a cell, far above the round-off of positions
/// computed to lie on a boundary (~1e-15 relative) and far below anything physical. Such a point
/// is not clamped: its cell map extrapolates by at most this much, so the weights still sum to
/// one and reproduce linear fields exactly (a weight may be negative by ~1e-9).
pub const LOCATE_SLACK: f64 = 1e-9;
