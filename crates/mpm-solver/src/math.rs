//! Scalar and vector aliases used throughout the solver.
//!
//! Everything is `f64` in SI units. Plane strain in the x–y plane: a particle's "volume" is its area
//! times a unit thickness (m³ per metre), its mass is per metre of thickness, and nodal forces are N/m.

/// Floating-point type of every quantity.
pub type Real = f64;
/// A point or vector in the x–y plane.
pub type Vector = glam::DVec2;
/// A 2×2 matrix (velocity gradients, spins).
pub type Matrix = glam::DMat2;
