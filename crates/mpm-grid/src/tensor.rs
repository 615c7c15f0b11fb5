//! Sums over a tensor-product stencil in space, factorised per axis (the 3D build only).
//!
//! # Glossary
//! - w: nodes per axis of the stencil (2 trilinear, 3 uGIMP and B-spline); slot
//!   k = a + w b + w² c for node (a, b, c) from the first node, as in [`crate::Stencil`].
//! - (s_a, s′_a), (t_b, t′_b), (u_c, u′_c): the 1D weight and its derivative per cell unit along
//!   x, y and z; S_k = s_a t_b u_c and ∇S_k = (s′_a t_b u_c / h_x, s_a t′_b u_c / h_y,
//!   s_a t_b u′_c / h_z).
//!
//! A sum over the w³ nodes of a value times a weight or a gradient component splits into a sum
//! over a of a sum over (b, c): the products that do not depend on a are formed once per (b, c)
//! instead of once per node. For 27 nodes that is a half to two thirds of the multiplications of forming
//! the 27 weights and gradients and then the sums. The terms are the same, added in another
//! order, so results differ from the node-by-node sums by round-off only (checked for every 3D
//! shape function in `tests/tests/verification/three_d.rs`).

use crate::math::{Matrix, Vector};

/// the 1D (weight, derivative per cell unit) pairs along x, y and z.
pub(crate) type Axes<const W: usize> = [[(f64, f64); W]; 3];

/// Σ_k S_k v_k and Σ_k v_k ⊗ ∇S_k, v_k = `value(k)`; `inv` holds 1/h per axis.
#[inline(always)]
pub(crate) fn interpolate<const W: usize>(
    [x, y, z]: &Axes<W>,
    inv: Vector,
    value: impl Fn(usize) -> Vector,
) -> (Vector, Matrix) {
    let (mut v, mut gx, mut gy, mut gz) = (Vector::ZERO, Vector::ZERO, Vector::ZERO, Vector::ZERO);
    for (c, &(sz, dz)) in z.iter().enumerate() {
        for (b, &(sy, dy)) in y.iter().enumerate() {
            // the sums along x of the w values of this (b, c) row, weighted and differentiated
            let (mut s, mut d) = (Vector::ZERO, Vector::ZERO);
            for (a, &(sx, dx)) in x.iter().enumerate() {
                let value = value(W * W * c + W * b + a);
                s += sx * value;
                d += dx * value;
            }
            let syz = sy * sz;
            v += syz * s;
            gx += syz * d;
            gy += (dy * sz) * s;
            gz += (sy * dz) * s;
        }
    }
    (v, Matrix::from_cols(gx * inv.x, gy * inv.y, gz * inv.z))
}

/// m S_k b − V σ·∇S_k for every slot k (eqs 2–3 of one particle), the stress given by its
/// columns σ e_a and `inv` holding 1/h per axis. With p_a = −V σ e_a / h_a the node's share is
/// s_a (t_b u_c m b + t′_b u_c p_y + t_b u′_c p_z) + s′_a (t_b u_c p_x).
#[inline(always)]
pub(crate) fn forces<const W: usize, const N: usize>(
    [x, y, z]: &Axes<W>,
    inv: Vector,
    (mass, body): (f64, Vector),
    volume: f64,
    stress: [Vector; 3],
) -> [Vector; N] {
    const { assert!(W * W * W == N, "a stencil of w × w × w nodes") };
    let mb = mass * body;
    let [px, py, pz]: [Vector; 3] = std::array::from_fn(|a| (-volume * inv[a]) * stress[a]);
    let mut out = [Vector::ZERO; N];
    for (c, &(sz, dz)) in z.iter().enumerate() {
        for (b, &(sy, dy)) in y.iter().enumerate() {
            let syz = sy * sz;
            let along = syz * mb + (dy * sz) * py + (sy * dz) * pz;
            let across = syz * px;
            for (a, &(sx, dx)) in x.iter().enumerate() {
                out[W * W * c + W * b + a] = sx * along + dx * across;
            }
        }
    }
    out
}
