//! Principal values and directions of a symmetric 3×3 tensor, for models written in principal
//! stresses (Mohr–Coulomb).
//!
//! A tensor with no out-of-plane shear (`yz = zx = 0`, every plane-strain state) is split in
//! closed form: `z` is a principal direction and the in-plane pair follows from one `atan2`, so
//! the in-plane directions have exactly zero `z` components and a stress rebuilt from them keeps
//! `yz = zx = 0` to the bit. Any other tensor goes through cyclic Jacobi rotations, which
//! converge quadratically (three to five sweeps) and return orthonormal directions to rounding
//! whatever the multiplicity of the values.
// (3 × 3 index arithmetic reads as the formulas it implements)
#![allow(clippy::needless_range_loop)]

use glam::DVec3;

use crate::tensor::SymTensor;

/// Principal values in descending order (`values[0] ≥ values[1] ≥ values[2]`, tension
/// positive: `values[0]` is the major, least compressive one) and their unit directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principal {
    /// the principal values, descending.
    pub values: [f64; 3],
    /// the unit direction of each value (orthonormal, right-handed not guaranteed).
    pub directions: [DVec3; 3],
}

impl Principal {
    /// the principal decomposition of `t` (finite components assumed).
    pub fn of(t: &SymTensor) -> Self {
        let (values, directions) = if t.yz == 0.0 && t.zx == 0.0 { in_plane(t) } else { jacobi(t) };
        sort_descending(values, directions)
    }

    /// `Σ_a v_a n_a ⊗ n_a` for the given values along these directions.
    pub fn compose(&self, v: [f64; 3]) -> SymTensor {
        let mut out = SymTensor::ZERO;
        for (value, n) in v.iter().zip(&self.directions) {
            out += outer(*n) * *value;
        }
        out
    }

    /// the components of `x` in the principal frame, `N_aᵀ X N_b` (a 3×3 symmetric array).
    pub fn to_frame(&self, x: &SymTensor) -> [[f64; 3]; 3] {
        let m = x.to_mat3();
        let mut out = [[0.0; 3]; 3];
        for a in 0..3 {
            let xa = m * self.directions[a];
            for b in 0..3 {
                out[a][b] = self.directions[b].dot(xa);
            }
        }
        out
    }

    /// the tensor whose components in the principal frame are `y` (the inverse of
    /// [`to_frame`](Self::to_frame)).
    pub fn from_frame(&self, y: &[[f64; 3]; 3]) -> SymTensor {
        let mut out = SymTensor::ZERO;
        for a in 0..3 {
            out += outer(self.directions[a]) * y[a][a];
            for b in (a + 1)..3 {
                out += sym_outer(self.directions[a], self.directions[b]) * y[a][b];
            }
        }
        out
    }
}

/// `n ⊗ n`.
fn outer(n: DVec3) -> SymTensor {
    SymTensor::new(n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.y * n.z, n.z * n.x)
}

/// `a ⊗ b + b ⊗ a`.
fn sym_outer(a: DVec3, b: DVec3) -> SymTensor {
    SymTensor::new(
        2.0 * a.x * b.x,
        2.0 * a.y * b.y,
        2.0 * a.z * b.z,
        a.x * b.y + a.y * b.x,
        a.y * b.z + a.z * b.y,
        a.z * b.x + a.x * b.z,
    )
}

/// closed form for `yz = zx = 0`: the in-plane pair from the Mohr circle, `z` principal.
fn in_plane(t: &SymTensor) -> ([f64; 3], [DVec3; 3]) {
    if t.xy == 0.0 {
        // the axes themselves: no rounding at all.
        return ([t.xx, t.yy, t.zz], [DVec3::X, DVec3::Y, DVec3::Z]);
    }
    let centre = 0.5 * (t.xx + t.yy);
    let half = 0.5 * (t.xx - t.yy);
    let radius = half.hypot(t.xy);
    // the major direction at θ = ½ atan2(2σxy, σxx − σyy) from x, from the half-angle
    // formulas (no trigonometric call): cos 2θ = half/R, sin 2θ = σxy/R, the larger of cos θ
    // and sin θ from its square root and the other from sin θ cos θ = σxy/(2R), without
    // cancellation
    let cos2 = half / radius;
    let (c, s) = if cos2 >= 0.0 {
        let c = (0.5 * (1.0 + cos2)).sqrt();
        (c, t.xy / (2.0 * radius * c))
    } else {
        let s = (0.5 * (1.0 - cos2)).sqrt().copysign(t.xy);
        (t.xy / (2.0 * radius * s), s)
    };
    (
        [centre + radius, centre - radius, t.zz],
        [DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z],
    )
}

/// cyclic Jacobi rotations until the off-diagonal entries vanish to rounding.
fn jacobi(t: &SymTensor) -> ([f64; 3], [DVec3; 3]) {
    let mut a = [[t.xx, t.xy, t.zx], [t.xy, t.yy, t.yz], [t.zx, t.yz, t.zz]];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    // Quadratic convergence: 5 sweeps are typical; 64 is a bound that is never reached by a
    // finite tensor (each sweep at least squares the relative off-diagonal size).
    for _ in 0..64 {
        let mut rotated = false;
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            // negligible against both diagonal entries: set to zero (Rutishauser's test).
            let small = 100.0 * apq.abs();
            if a[p][p].abs() + small == a[p][p].abs() && a[q][q].abs() + small == a[q][q].abs() {
                a[p][q] = 0.0;
                a[q][p] = 0.0;
                continue;
            }
            rotated = true;
            // the rotation that zeroes a_pq: t = tan φ, the smaller root of t² + 2θt − 1 = 0.
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let tan = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let cos = 1.0 / (tan * tan + 1.0).sqrt();
            let sin = tan * cos;
            // A ← Jᵀ A J with J the rotation in the (p, q) plane.
            for row in a.iter_mut() {
                let (x, y) = (row[p], row[q]);
                row[p] = cos * x - sin * y;
                row[q] = sin * x + cos * y;
            }
            for k in 0..3 {
                let (x, y) = (a[p][k], a[q][k]);
                a[p][k] = cos * x - sin * y;
                a[q][k] = sin * x + cos * y;
            }
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            for row in v.iter_mut() {
                let (x, y) = (row[p], row[q]);
                row[p] = cos * x - sin * y;
                row[q] = sin * x + cos * y;
            }
        }
        if !rotated {
            break;
        }
    }
    let col = |j: usize| DVec3::new(v[0][j], v[1][j], v[2][j]);
    ([a[0][0], a[1][1], a[2][2]], [col(0), col(1), col(2)])
}

/// sorts the values descending, their directions with them (a fixed network of three
/// compare-and-swaps).
fn sort_descending(mut v: [f64; 3], mut d: [DVec3; 3]) -> Principal {
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if v[j] > v[i] {
            v.swap(i, j);
            d.swap(i, j);
        }
    }
    Principal { values: v, directions: d }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// a few roundings of O(1) numbers (Jacobi: a handful of rotations per entry).
    const TOL: f64 = 1e-13;

    fn check(t: SymTensor) {
        let p = Principal::of(&t);
        let scale = t.norm().max(1.0);
        assert!(p.values[0] >= p.values[1] && p.values[1] >= p.values[2], "{p:?}");
        // orthonormal directions
        for a in 0..3 {
            for b in 0..3 {
                let expected = if a == b { 1.0 } else { 0.0 };
                let d = p.directions[a].dot(p.directions[b]);
                assert!((d - expected).abs() <= TOL, "n{a}·n{b} = {d}");
            }
        }
        // the decomposition rebuilds the tensor, and each direction is an eigenvector
        assert!((p.compose(p.values) - t).norm() <= TOL * scale, "{t:?}");
        let m = t.to_mat3();
        for a in 0..3 {
            let r = m * p.directions[a] - p.directions[a] * p.values[a];
            assert!(r.length() <= TOL * scale);
        }
        // invariants
        assert!((p.values.iter().sum::<f64>() - t.trace()).abs() <= TOL * scale);
        // the frame round trip
        let frame = p.to_frame(&t);
        assert!((p.from_frame(&frame) - t).norm() <= TOL * scale);
    }

    /// Distinct, repeated and triple values, in-plane and fully 3D tensors.
    #[test]
    fn decomposition_rebuilds_the_tensor_with_orthonormal_directions() {
        check(SymTensor::new(3.0, -1.0, 2.0, 0.5, -1.5, 1.0));
        check(SymTensor::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0));
        check(SymTensor::new(2.0, 2.0, -1.0, 0.0, 0.0, 0.0));
        check(SymTensor::new(-5.0, 3.0, 0.7, 2.0, 0.0, 0.0));
        check(SymTensor::new(1.0, 1.0, 1.0, 1.0, 1.0, 1.0));
        check(SymTensor::new(1e6, -3e5, 2e5, 4e-9, 1e-12, 3e4));
        check(SymTensor::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0));
        for k in 0..200 {
            let x = k as f64;
            check(SymTensor::new(
                (0.37 * x).sin(),
                (1.3 * x).cos(),
                (0.71 * x).sin() * 2.0,
                (0.11 * x).cos(),
                (2.3 * x).sin() * 0.3,
                (0.53 * x).cos() * 0.7,
            ));
        }
    }

    /// A plane-strain tensor keeps exactly zero out-of-plane components when rebuilt.
    #[test]
    fn in_plane_tensors_stay_in_plane_to_the_bit() {
        let t = SymTensor::new(-3.0, -1.0, -2.0, 0.4, 0.0, 0.0);
        let p = Principal::of(&t);
        let r = p.compose([p.values[0] - 0.1, p.values[1], p.values[2] + 0.2]);
        assert_eq!((r.yz, r.zx), (0.0, 0.0));
        assert!((p.compose(p.values) - t).norm() <= TOL * t.norm());
    }
}
