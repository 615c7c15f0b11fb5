//! Scalar, vector and matrix aliases used throughout the crate, and the dimension.
//!
//! Everything is `f64` in SI units (metres), with y pointing up (against gravity). This source is
//! compiled twice: as `mpm-grid` for the plane (x–y, the paper's plane strain) and, with the
//! `dim3` feature, as `mpm-grid3d` for space (x–y–z, z across the plane of the 2D build, so a 2D
//! scene is a 3D scene's section at constant z).

/// Floating-point type of every quantity.
pub type Real = f64;

/// A point or vector in the x–y plane.
#[cfg(not(feature = "dim3"))]
pub type Vector = glam::DVec2;
/// A 2×2 matrix (Jacobians of the isoparametric map).
#[cfg(not(feature = "dim3"))]
pub type Matrix = glam::DMat2;
/// The number of space dimensions of this build.
#[cfg(not(feature = "dim3"))]
pub const DIM: usize = 2;

/// A point or vector in space (x, y up, z).
#[cfg(feature = "dim3")]
pub type Vector = glam::DVec3;
/// A 3×3 matrix.
#[cfg(feature = "dim3")]
pub type Matrix = glam::DMat3;
/// The number of space dimensions of this build.
#[cfg(feature = "dim3")]
pub const DIM: usize = 3;

#[cfg(all(feature = "dim2", feature = "dim3"))]
compile_error!("a build of mpm-grid is for one dimension: `dim2` and `dim3` are both enabled");
