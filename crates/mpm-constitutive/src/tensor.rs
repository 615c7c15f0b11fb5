//! Symmetric second-order tensors (stress, strain) and 6×6 matrices acting on them.
//!
//! # Glossary
//! - `σ`, `ε`: a symmetric 3×3 tensor, stored as six components in the order
//!   `[xx, yy, zz, xy, yz, zx]` ([`SymTensor::to_array`]).
//! - `I`: the identity, `tr A = A_xx + A_yy + A_zz`, `I1 = tr σ`, mean `p = I1 / 3`.
//! - `s = dev A = A − (tr A / 3) I`, the deviator; `J2 = ½ s : s`.
//! - `A : B = Σ_ij A_ij B_ij`, the full double contraction (each off-diagonal pair counts twice).
//!
//! # Conventions
//! - Tension positive, SI units (stress in Pa, strain dimensionless).
//! - Shear components are **tensor** components: `xy` holds `ε_xy = γ_xy / 2` for strains and
//!   `σ_xy` for stresses. Engineering shear strain `γ` appears only in labels of element-test
//!   output.
//! - A [`Tangent`] `T` maps a strain increment to a stress increment as
//!   `dσ[i] = Σ_j T[i][j] dε[j]`, both in the storage order above, where `dε[j]` for a shear slot
//!   is the tensor component (`dε_xy`, which perturbs `ε_xy` and `ε_yx` together). Hence the
//!   isotropic elastic tangent has `T[3][3] = 2G` (not `G`, the engineering-shear convention).

use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use glam::DMat3;
use serde::{Deserialize, Serialize};

/// a 6×6 matrix in the [`SymTensor`] storage order acting on tensor strain components
/// (see the module docs for the shear convention).
pub type Tangent = [[f64; 6]; 6];

/// weight of each storage slot in a full double contraction: off-diagonals count twice.
pub(crate) const DDOT_WEIGHT: [f64; 6] = [1.0, 1.0, 1.0, 2.0, 2.0, 2.0];

/// Component names in storage order, for error messages and CSV headers.
pub const COMPONENT_NAMES: [&str; 6] = ["xx", "yy", "zz", "xy", "yz", "zx"];

/// Symmetric 3×3 tensor, tension positive, stored as `[xx, yy, zz, xy, yz, zx]`
/// (tensor components, not engineering shear).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SymTensor {
    /// normal component `xx`.
    pub xx: f64,
    /// normal component `yy`.
    pub yy: f64,
    /// normal component `zz` (out of plane in plane strain).
    pub zz: f64,
    /// shear component `xy = yx` (tensor component).
    pub xy: f64,
    /// shear component `yz = zy` (tensor component).
    pub yz: f64,
    /// shear component `zx = xz` (tensor component).
    pub zx: f64,
}

impl SymTensor {
    /// the zero tensor.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    /// the identity `I`.
    pub const IDENTITY: Self = Self::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0);

    /// a tensor from its six components in storage order.
    pub const fn new(xx: f64, yy: f64, zz: f64, xy: f64, yz: f64, zx: f64) -> Self {
        Self { xx, yy, zz, xy, yz, zx }
    }

    /// an in-plane tensor (`zz = yz = zx = 0`), e.g. a plane-strain increment.
    pub const fn plane(xx: f64, yy: f64, xy: f64) -> Self {
        Self::new(xx, yy, 0.0, xy, 0.0, 0.0)
    }

    /// `tr A`.
    #[inline]
    pub fn trace(&self) -> f64 {
        self.xx + self.yy + self.zz
    }

    /// first invariant `I1 = tr A`.
    #[inline]
    pub fn i1(&self) -> f64 {
        self.trace()
    }

    /// mean value `tr A / 3` (the mean stress `p`, tension positive).
    #[inline]
    pub fn mean(&self) -> f64 {
        self.trace() / 3.0
    }

    /// deviator `A − (tr A / 3) I`.
    #[inline]
    pub fn deviator(&self) -> Self {
        let m = self.mean();
        Self::new(self.xx - m, self.yy - m, self.zz - m, self.xy, self.yz, self.zx)
    }

    /// second invariant of the deviator, `J2 = ½ dev A : dev A` (so `J2 ≥ 0`).
    #[inline]
    pub fn j2(&self) -> f64 {
        let d = self.deviator();
        0.5 * d.ddot(&d)
    }

    /// full double contraction `A : B = Σ_ij A_ij B_ij` (off-diagonals count twice).
    #[inline]
    pub fn ddot(&self, other: &Self) -> f64 {
        self.xx * other.xx
            + self.yy * other.yy
            + self.zz * other.zz
            + 2.0 * (self.xy * other.xy + self.yz * other.yz + self.zx * other.zx)
    }

    /// Frobenius norm `√(A : A)`.
    #[inline]
    pub fn norm(&self) -> f64 {
        self.ddot(self).sqrt()
    }

    /// `R A Rᵀ`: the tensor seen in a frame rotated by the orthogonal matrix `r`.
    ///
    /// A rotation about z (the only one plane strain produces) takes the closed form of
    /// [`Self::rotated_z`], a quarter of the work of the general triple product.
    #[inline(always)]
    pub fn rotated(&self, r: &DMat3) -> Self {
        let (x, y) = (r.x_axis, r.y_axis);
        if x.z == 0.0 && y.z == 0.0 && r.z_axis == glam::DVec3::Z && x.x == y.y && x.y == -y.x {
            return self.rotated_z(x.x, x.y);
        }
        let m = self.to_mat3();
        Self::from_mat3_sym(&(*r * m * r.transpose()))
    }

    /// `R A Rᵀ` for the rotation about z with `R = [[c, −s, 0], [s, c, 0], [0, 0, 1]]`, c = cos θ,
    /// s = sin θ: the in-plane block turns by θ, (A_zx, A_yz) turns as a vector and A_zz stays.
    #[inline]
    pub fn rotated_z(&self, c: f64, s: f64) -> Self {
        let p = PlaneTensor::from_sym(self).rotated_z(c, s);
        Self::new(p.xx, p.yy, p.zz, p.xy, s * self.zx + c * self.yz, c * self.zx - s * self.yz)
    }

    /// true when all six components are finite.
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        self.finite_probe() == 0.0
    }

    /// Σ (A_ij − A_ij) over the six components: exactly 0 when all are finite, NaN when one is
    /// infinite or NaN (∞ − ∞ = NaN). Probes of several tensors add up to one test, and the
    /// subtractions vectorise, where six `f64::is_finite` calls were six compares on every
    /// constitutive update's hot path.
    #[inline(always)]
    // x − x is the point: 0 for finite x, NaN otherwise.
    #[allow(clippy::eq_op)]
    pub fn finite_probe(&self) -> f64 {
        ((self.xx - self.xx) + (self.yy - self.yy))
            + ((self.zz - self.zz) + (self.xy - self.xy))
            + ((self.yz - self.yz) + (self.zx - self.zx))
    }

    /// the components in storage order `[xx, yy, zz, xy, yz, zx]`.
    #[inline]
    pub fn to_array(&self) -> [f64; 6] {
        [self.xx, self.yy, self.zz, self.xy, self.yz, self.zx]
    }

    /// a tensor from components in storage order `[xx, yy, zz, xy, yz, zx]`.
    #[inline]
    pub fn from_array(a: [f64; 6]) -> Self {
        Self::new(a[0], a[1], a[2], a[3], a[4], a[5])
    }

    /// the full 3×3 matrix.
    pub fn to_mat3(&self) -> DMat3 {
        // glam is column-major; the matrix is symmetric so columns equal rows.
        DMat3::from_cols_array(&[
            self.xx, self.xy, self.zx, //
            self.xy, self.yy, self.yz, //
            self.zx, self.yz, self.zz,
        ])
    }

    /// the symmetric part `½ (M + Mᵀ)` of a 3×3 matrix.
    pub fn from_mat3_sym(m: &DMat3) -> Self {
        // m.col(j)[i] is M_ij.
        Self::new(
            m.x_axis.x,
            m.y_axis.y,
            m.z_axis.z,
            0.5 * (m.y_axis.x + m.x_axis.y),
            0.5 * (m.z_axis.y + m.y_axis.z),
            0.5 * (m.x_axis.z + m.z_axis.x),
        )
    }

    /// first component that is not finite, with its name, if any.
    pub(crate) fn first_non_finite(&self) -> Option<(&'static str, f64)> {
        self.to_array()
            .into_iter()
            .zip(COMPONENT_NAMES)
            .find(|(v, _)| !v.is_finite())
            .map(|(v, n)| (n, v))
    }
}

impl Add for SymTensor {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(
            self.xx + o.xx,
            self.yy + o.yy,
            self.zz + o.zz,
            self.xy + o.xy,
            self.yz + o.yz,
            self.zx + o.zx,
        )
    }
}

impl Sub for SymTensor {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(
            self.xx - o.xx,
            self.yy - o.yy,
            self.zz - o.zz,
            self.xy - o.xy,
            self.yz - o.yz,
            self.zx - o.zx,
        )
    }
}

impl Mul<f64> for SymTensor {
    type Output = Self;
    #[inline]
    fn mul(self, a: f64) -> Self {
        Self::new(self.xx * a, self.yy * a, self.zz * a, self.xy * a, self.yz * a, self.zx * a)
    }
}

impl Mul<SymTensor> for f64 {
    type Output = SymTensor;
    #[inline]
    fn mul(self, t: SymTensor) -> SymTensor {
        t * self
    }
}

impl Neg for SymTensor {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self * -1.0
    }
}

impl AddAssign for SymTensor {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl SubAssign for SymTensor {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

/// A symmetric tensor without out-of-plane shear (`yz = zx = 0`): the stress and strain of plane
/// strain, stored as `[xx, yy, zz, xy]` (tensor components, tension positive).
///
/// Under plane strain (`Δε_zz = Δε_yz = Δε_zx = 0`) an isotropic model never creates `σ_yz` or
/// `σ_zx`, so a 2D solver carries four components and each operation costs two thirds of its
/// [`SymTensor`] counterpart. Every operation is the [`SymTensor`] one with the two zero
/// components left out, and gives the same bits up to the sign of a zero result (a sum gains
/// nothing from an exact `0`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlaneTensor {
    /// normal component `xx`.
    pub xx: f64,
    /// normal component `yy`.
    pub yy: f64,
    /// normal component `zz` (out of plane).
    pub zz: f64,
    /// shear component `xy = yx` (tensor component).
    pub xy: f64,
}

impl PlaneTensor {
    /// the zero tensor.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0, 0.0);

    /// a tensor from its four components.
    pub const fn new(xx: f64, yy: f64, zz: f64, xy: f64) -> Self {
        Self { xx, yy, zz, xy }
    }

    /// the in-plane part of `t` (its `yz` and `zx` are dropped).
    #[inline(always)]
    pub const fn from_sym(t: &SymTensor) -> Self {
        Self::new(t.xx, t.yy, t.zz, t.xy)
    }

    /// the full tensor (`yz = zx = 0`).
    #[inline(always)]
    pub const fn to_sym(&self) -> SymTensor {
        SymTensor::new(self.xx, self.yy, self.zz, self.xy, 0.0, 0.0)
    }

    /// `tr A`.
    #[inline(always)]
    pub fn trace(&self) -> f64 {
        self.xx + self.yy + self.zz
    }

    /// mean value `tr A / 3` (the mean stress `p`, tension positive).
    #[inline]
    pub fn mean(&self) -> f64 {
        self.trace() / 3.0
    }

    /// full double contraction `A : B` (the off-diagonal pair counts twice).
    #[inline(always)]
    pub fn ddot(&self, o: &Self) -> f64 {
        self.xx * o.xx + self.yy * o.yy + self.zz * o.zz + 2.0 * (self.xy * o.xy)
    }

    /// Frobenius norm `√(A : A)`.
    #[inline]
    pub fn norm(&self) -> f64 {
        self.ddot(self).sqrt()
    }

    /// true when all four components are finite.
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        Symmetric::finite_probe(self) == 0.0
    }

    /// `R A Rᵀ` for the rotation about z by θ (c = cos θ, s = sin θ): [`SymTensor::rotated_z`].
    #[inline(always)]
    pub fn rotated_z(&self, c: f64, s: f64) -> Self {
        let (cc, ss, cs) = (c * c, s * s, c * s);
        Self {
            xx: cc * self.xx - 2.0 * cs * self.xy + ss * self.yy,
            yy: ss * self.xx + 2.0 * cs * self.xy + cc * self.yy,
            zz: self.zz,
            xy: cs * (self.xx - self.yy) + (cc - ss) * self.xy,
        }
    }
}

/// The arithmetic of a return mapping, on a full [`SymTensor`] or on a [`PlaneTensor`]: a model
/// written once against it runs in 3D and, at two thirds of the cost, in plane strain.
pub trait Symmetric:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self>
{
    /// the identity `I`.
    const IDENTITY: Self;
    /// `tr A`.
    fn trace(&self) -> f64;
    /// `A − (tr A / 3) I`.
    fn deviator(&self) -> Self;
    /// `A : B` (off-diagonals count twice).
    fn ddot(&self, other: &Self) -> f64;
    /// `0` when every component is finite, NaN otherwise ([`SymTensor::finite_probe`]).
    fn finite_probe(&self) -> f64;
    /// eq 10's elastic trial `σ + λ tr(Δε) I + 2G Δε` given `lt = λ tr Δε` and `tg = 2G`,
    /// summed as `(σ + λ tr Δε) + 2G Δε` (Drucker-Prager's order).
    fn elastic_trial(&self, lt: f64, tg: f64, d_eps: &Self) -> Self;
    /// eq 10's increment `λ tr(Δε) I + 2G Δε` of the strain increment `self`, given
    /// `lt = λ tr Δε` and `g2 = 2G` (linear elasticity adds it to σ).
    fn elastic_increment(&self, lt: f64, g2: f64) -> Self;
    /// the in-plane part of a full tensor (the identity for [`SymTensor`]).
    fn from_sym(t: &SymTensor) -> Self;
    /// the full tensor.
    fn to_sym(&self) -> SymTensor;
}

impl Symmetric for SymTensor {
    const IDENTITY: Self = SymTensor::IDENTITY;
    #[inline(always)]
    fn trace(&self) -> f64 {
        SymTensor::trace(self)
    }
    #[inline(always)]
    fn deviator(&self) -> Self {
        SymTensor::deviator(self)
    }
    #[inline(always)]
    fn ddot(&self, other: &Self) -> f64 {
        SymTensor::ddot(self, other)
    }
    #[inline(always)]
    fn finite_probe(&self) -> f64 {
        SymTensor::finite_probe(self)
    }
    #[inline(always)]
    fn elastic_trial(&self, lt: f64, tg: f64, d: &Self) -> Self {
        Self::new(
            self.xx + lt + tg * d.xx,
            self.yy + lt + tg * d.yy,
            self.zz + lt + tg * d.zz,
            self.xy + tg * d.xy,
            self.yz + tg * d.yz,
            self.zx + tg * d.zx,
        )
    }
    #[inline(always)]
    fn elastic_increment(&self, lt: f64, g2: f64) -> Self {
        Self::new(
            lt + g2 * self.xx,
            lt + g2 * self.yy,
            lt + g2 * self.zz,
            g2 * self.xy,
            g2 * self.yz,
            g2 * self.zx,
        )
    }
    #[inline(always)]
    fn from_sym(t: &SymTensor) -> Self {
        *t
    }
    #[inline(always)]
    fn to_sym(&self) -> SymTensor {
        *self
    }
}

impl Symmetric for PlaneTensor {
    const IDENTITY: Self = Self::new(1.0, 1.0, 1.0, 0.0);
    #[inline(always)]
    fn trace(&self) -> f64 {
        PlaneTensor::trace(self)
    }
    #[inline(always)]
    fn deviator(&self) -> Self {
        let m = self.mean();
        Self::new(self.xx - m, self.yy - m, self.zz - m, self.xy)
    }
    #[inline(always)]
    fn ddot(&self, o: &Self) -> f64 {
        PlaneTensor::ddot(self, o)
    }
    #[inline(always)]
    // x − x is the point: 0 for finite x, NaN otherwise.
    #[allow(clippy::eq_op)]
    fn finite_probe(&self) -> f64 {
        ((self.xx - self.xx) + (self.yy - self.yy)) + ((self.zz - self.zz) + (self.xy - self.xy))
    }
    #[inline(always)]
    fn elastic_trial(&self, lt: f64, tg: f64, d: &Self) -> Self {
        Self::new(
            self.xx + lt + tg * d.xx,
            self.yy + lt + tg * d.yy,
            self.zz + lt + tg * d.zz,
            self.xy + tg * d.xy,
        )
    }
    #[inline(always)]
    fn elastic_increment(&self, lt: f64, g2: f64) -> Self {
        Self::new(lt + g2 * self.xx, lt + g2 * self.yy, lt + g2 * self.zz, g2 * self.xy)
    }
    #[inline(always)]
    fn from_sym(t: &SymTensor) -> Self {
        PlaneTensor::from_sym(t)
    }
    #[inline(always)]
    fn to_sym(&self) -> SymTensor {
        PlaneTensor::to_sym(self)
    }
}

impl Add for PlaneTensor {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.xx + o.xx, self.yy + o.yy, self.zz + o.zz, self.xy + o.xy)
    }
}

impl Sub for PlaneTensor {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.xx - o.xx, self.yy - o.yy, self.zz - o.zz, self.xy - o.xy)
    }
}

impl Mul<f64> for PlaneTensor {
    type Output = Self;
    #[inline(always)]
    fn mul(self, a: f64) -> Self {
        Self::new(self.xx * a, self.yy * a, self.zz * a, self.xy * a)
    }
}

/// `T · dε` for a [`Tangent`] and a tensor strain increment (storage order, tensor shear).
pub fn tangent_apply(t: &Tangent, d_eps: &SymTensor) -> SymTensor {
    let e = d_eps.to_array();
    let mut out = [0.0; 6];
    for (o, row) in out.iter_mut().zip(t) {
        *o = row.iter().zip(e).map(|(a, b)| a * b).sum();
    }
    SymTensor::from_array(out)
}

/// the [`Tangent`] of the map `dε ↦ a (b : dε)`, i.e. the dyad `a ⊗ b`.
pub(crate) fn dyad(a: &SymTensor, b: &SymTensor) -> Tangent {
    let (a, b) = (a.to_array(), b.to_array());
    let mut t = [[0.0; 6]; 6];
    for (row, ai) in t.iter_mut().zip(a) {
        for ((tij, bj), wj) in row.iter_mut().zip(b).zip(DDOT_WEIGHT) {
            *tij = ai * bj * wj;
        }
    }
    t
}

/// the [`Tangent`] of `dε ↦ dev dε`.
pub(crate) fn deviatoric_projector() -> Tangent {
    let third = 1.0 / 3.0;
    let mut t = [[0.0; 6]; 6];
    for (i, row) in t.iter_mut().enumerate() {
        for (j, tij) in row.iter_mut().enumerate() {
            *tij = match (i < 3, j < 3) {
                (true, true) => f64::from(u8::from(i == j)) - third,
                _ => f64::from(u8::from(i == j)),
            };
        }
    }
    t
}

/// `a·A + b·B` for two [`Tangent`]s.
pub(crate) fn tangent_axpby(a: f64, ta: &Tangent, b: f64, tb: &Tangent) -> Tangent {
    let mut t = [[0.0; 6]; 6];
    for ((row, ra), rb) in t.iter_mut().zip(ta).zip(tb) {
        for ((tij, x), y) in row.iter_mut().zip(ra).zip(rb) {
            *tij = a * x + b * y;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// exact arithmetic on small integers and halves: no rounding at all.
    const EXACT: f64 = 0.0;
    /// a few roundings of O(1) numbers.
    const ROUNDING: f64 = 1e-14;

    fn sample() -> SymTensor {
        SymTensor::new(3.0, -1.0, 2.0, 0.5, -1.5, 1.0)
    }

    /// The closed-form z rotation (taken by `rotated` whenever `r` is one) equals the general
    /// triple product R A Rᵀ to rounding, and keeps the invariants.
    #[test]
    fn z_rotation_closed_form_equals_the_triple_product() {
        let a = sample();
        for k in 0..64 {
            let theta = -3.2 + 0.1 * k as f64;
            let r = DMat3::from_rotation_z(theta);
            let fast = a.rotated(&r);
            let general = SymTensor::from_mat3_sym(&(r * a.to_mat3() * r.transpose()));
            assert!((fast - general).norm() <= 10.0 * ROUNDING * a.norm(), "θ = {theta}");
            assert!((fast.j2() - a.j2()).abs() <= 10.0 * ROUNDING * a.j2());
            assert_eq!(fast.zz, a.zz);
        }
        // Not a z rotation: the general path, still R A Rᵀ.
        let r = DMat3::from_rotation_x(0.3);
        let general = SymTensor::from_mat3_sym(&(r * a.to_mat3() * r.transpose()));
        assert_eq!(a.rotated(&r), general);
    }

    #[test]
    fn invariants_match_hand_computation() {
        let a = sample();
        assert_eq!(a.trace(), 4.0);
        assert_eq!(a.i1(), 4.0);
        assert!((a.mean() - 4.0 / 3.0).abs() <= ROUNDING);
        let d = a.deviator();
        assert!(d.trace().abs() <= ROUNDING);
        // J2 = ((s1-s2)² + (s2-s3)² + (s3-s1)²)/6 + xy² + yz² + zx² on the normal parts.
        let j2 = ((3.0f64 - -1.0).powi(2) + (-1.0f64 - 2.0).powi(2) + (2.0f64 - 3.0).powi(2)) / 6.0
            + 0.25
            + 2.25
            + 1.0;
        assert!((a.j2() - j2).abs() <= ROUNDING * j2);
        // A : A = 9 + 1 + 4 + 2 (0.25 + 2.25 + 1).
        assert!((a.ddot(&a) - 21.0).abs() <= EXACT);
        assert!((a.norm() - 21f64.sqrt()).abs() <= ROUNDING);
    }

    #[test]
    fn matrix_round_trip_and_rotation_by_quarter_turn() {
        let a = sample();
        assert_eq!(SymTensor::from_mat3_sym(&a.to_mat3()), a);
        // a quarter turn about z maps x → y: (R A Rᵀ)_yy = A_xx, _xx = A_yy, _xy = −A_xy.
        let r = DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let b = a.rotated(&r);
        assert!((b.yy - a.xx).abs() <= ROUNDING);
        assert!((b.xx - a.yy).abs() <= ROUNDING);
        assert!((b.xy + a.xy).abs() <= ROUNDING);
        assert!((b.zz - a.zz).abs() <= ROUNDING);
        // invariants survive rotation.
        assert!((b.j2() - a.j2()).abs() <= ROUNDING * a.j2());
        assert!((b.trace() - a.trace()).abs() <= ROUNDING);
    }

    #[test]
    fn operators_and_arrays() {
        let a = sample();
        let b = SymTensor::plane(1.0, 2.0, 3.0);
        assert_eq!((a + b - b), a);
        assert_eq!(-a * 2.0, a * -2.0);
        assert_eq!(2.0 * a, a * 2.0);
        let mut c = a;
        c += b;
        c -= a;
        assert_eq!(c, b);
        assert_eq!(SymTensor::from_array(a.to_array()), a);
        assert!(a.is_finite());
        assert!(!SymTensor::new(0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0).is_finite());
        // Every component, every kind of non-finite value; the largest finite values pass.
        for k in 0..6 {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut v = [f64::MAX, -f64::MAX, 1.0, f64::MIN_POSITIVE, -0.0, 5e-324];
                assert!(SymTensor::from_array(v).is_finite());
                v[k] = bad;
                assert!(!SymTensor::from_array(v).is_finite(), "component {k} = {bad}");
            }
        }
        assert_eq!(
            SymTensor::new(0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0).first_non_finite(),
            Some(("yz", f64::INFINITY))
        );
    }

    #[test]
    fn dyad_and_projector_act_like_their_definitions() {
        let a = sample();
        let b = SymTensor::new(0.3, -0.2, 0.7, 0.1, 0.4, -0.6);
        let e = SymTensor::new(1.0, 2.0, -3.0, 0.25, -0.5, 0.75);
        let lhs = tangent_apply(&dyad(&a, &b), &e);
        let rhs = a * b.ddot(&e);
        assert!((lhs - rhs).norm() <= ROUNDING * rhs.norm());
        let p = tangent_apply(&deviatoric_projector(), &e);
        assert!((p - e.deviator()).norm() <= ROUNDING);
    }
}
