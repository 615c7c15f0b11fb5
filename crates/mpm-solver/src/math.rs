//! Scalar, vector, matrix and stress types used throughout the solver, and the dimension.
//!
//! Everything is `f64` in SI units. This source is compiled twice (see `mpm-grid`'s `math`):
//! - as `mpm-solver`, plane strain in the x–y plane: a particle's "volume" is its area times a
//!   unit thickness (m³ per metre), its mass is per metre of thickness, nodal forces are N/m, and
//!   its stress has the four components of plane strain ([`PlaneTensor`](mpm_constitutive::PlaneTensor));
//! - as `mpm-solver3d` (the `dim3` feature), in space (x, y up, z): volumes in m³, masses in kg,
//!   forces in N, the stress a full symmetric tensor ([`SymTensor`](mpm_constitutive::SymTensor)).

/// Floating-point type of every quantity.
pub type Real = f64;

pub use mpm_grid::DIM;

/// A point or vector in the x–y plane.
#[cfg(not(feature = "dim3"))]
pub type Vector = glam::DVec2;
/// A 2×2 matrix (velocity gradients, spins).
#[cfg(not(feature = "dim3"))]
pub type Matrix = glam::DMat2;
/// A particle's stress: plane strain's σ_xx, σ_yy, σ_zz, σ_xy (Pa, tension positive).
#[cfg(not(feature = "dim3"))]
pub type Stress = mpm_constitutive::PlaneTensor;

/// A point or vector in space (x, y up, z).
#[cfg(feature = "dim3")]
pub type Vector = glam::DVec3;
/// A 3×3 matrix (velocity gradients, spins).
#[cfg(feature = "dim3")]
pub type Matrix = glam::DMat3;
/// A particle's stress: the six components of the symmetric tensor (Pa, tension positive).
#[cfg(feature = "dim3")]
pub type Stress = mpm_constitutive::SymTensor;

/// a point in messages: (x, y) in the plane, (x, y, z) in space, each with its full digits.
pub(crate) struct At(pub(crate) Vector);

impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        #[cfg(not(feature = "dim3"))]
        return write!(f, "({}, {})", self.0.x, self.0.y);
        #[cfg(feature = "dim3")]
        return write!(f, "({}, {}, {})", self.0.x, self.0.y, self.0.z);
    }
}

/// a particle's stress as the full symmetric tensor the constitutive models take.
#[inline(always)]
pub(crate) fn full_stress(s: &Stress) -> mpm_constitutive::SymTensor {
    #[cfg(not(feature = "dim3"))]
    return s.to_sym();
    #[cfg(feature = "dim3")]
    return *s;
}

/// unit vectors that complete the unit vector `n` to an orthonormal basis: its tangent in the
/// plane, a pair spanning its tangent plane in space.
#[inline]
pub(crate) fn tangents(n: Vector) -> [Vector; DIM - 1] {
    #[cfg(not(feature = "dim3"))]
    return [n.perp()];
    #[cfg(feature = "dim3")]
    return n.any_orthonormal_pair().into();
}

/// half the side of a particle of volume `v` (a square of area v in the plane, a cube in
/// space): ½ √v, ½ ∛v (m).
#[inline(always)]
pub(crate) fn half_size(v: Real) -> Real {
    #[cfg(not(feature = "dim3"))]
    return 0.5 * v.sqrt();
    #[cfg(feature = "dim3")]
    return 0.5 * v.cbrt();
}
