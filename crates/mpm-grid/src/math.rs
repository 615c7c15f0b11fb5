//! Scalar, vector and matrix aliases used throughout the crate.
//!
//! Everything is `f64` in SI units (metres); plane x–y, with y pointing up (against gravity).

/// Floating-point type of every quantity.
pub type Real = f64;
/// A point or vector in the x–y plane.
pub type Vector = glam::DVec2;
/// A 2×2 matrix (Jacobians of the isoparametric map).
pub type Matrix = glam::DMat2;
