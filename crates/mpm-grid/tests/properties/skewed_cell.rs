//! A general eq 19–20 cell (vertical sides, any straight bottom and top): the closed-form inverse
//! map and the bilinear isoparametric shape functions on random cells.

use mpm_grid::{SkewedCell, Vector};
use proptest::prelude::*;

use crate::common::{IDENTITY_TOL, PARTITION_TOL, RELATIVE_TOL, config};

/// central differences with step 1e-5·L: truncation ~(1e-5)²·|∂³N|·L² ≈ 1e-10, round-off
/// ~ε/1e-5 ≈ 1e-11, both in units of 1/L; 1e-7 leaves room for strongly tapered cells.
const DIFFERENCE_TOL: f64 = 1e-7;

/// a random cell: x1 ∈ [−20, 20], width l ∈ [0.05, 5], bottom slope within ±60°, left height
/// ∈ [0.1, 4]·l, right height ∈ [0.25, 4]× left height (a real trapezoid, not only the
/// terrain grid's parallelograms).
fn cell() -> impl Strategy<Value = SkewedCell> {
    (-20.0f64..20.0, 0.05f64..5.0, -20.0f64..20.0, -60.0f64..60.0, 0.1f64..4.0, 0.25f64..4.0)
        .prop_map(|(x1, l, y1, deg, left, ratio)| {
            let y2 = y1 + l * deg.to_radians().tan();
            let hl = left * l;
            SkewedCell::new(x1, x1 + l, [y1, y2, y1 + hl, y2 + hl * ratio]).unwrap()
        })
}

fn min_size(c: &SkewedCell) -> f64 {
    let k = c.corners();
    c.width().min(k[2].y - k[0].y).min(k[3].y - k[1].y)
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn inverse_map_round_trips(c in cell(), xi in -1.0f64..=1.0, eta in -1.0f64..=1.0) {
        let p = c.to_global(xi, eta);
        let (a, b) = c.to_local(p);
        prop_assert!((a - xi).abs() <= IDENTITY_TOL && (b - eta).abs() <= IDENTITY_TOL,
            "({xi}, {eta}) -> {p} -> ({a}, {b})");
        let q = c.to_global(a, b);
        prop_assert!((q - p).length() <= RELATIVE_TOL * p.length().max(min_size(&c)),
            "x(ξ(x)) = {q}, x = {p}");
    }

    #[test]
    fn jacobian_is_positive_and_matches_l_d_over_8(c in cell(), xi in -1.0f64..=1.0, eta in -1.0f64..=1.0) {
        let k = c.corners();
        let d = (1.0 - xi) * (k[2].y - k[0].y) + (1.0 + xi) * (k[3].y - k[1].y);
        let det = c.jacobian(xi, eta).determinant();
        prop_assert!(det > 0.0);
        prop_assert!((det - c.width() * d / 8.0).abs() <= IDENTITY_TOL * det);
    }

    #[test]
    fn shape_functions_satisfy_the_identities(c in cell(), xi in -1.0f64..=1.0, eta in -1.0f64..=1.0) {
        let p = c.to_global(xi, eta);
        let (n, g) = c.shape(p);
        let size = min_size(&c);
        prop_assert!((n.iter().sum::<f64>() - 1.0).abs() <= PARTITION_TOL);
        prop_assert!(n.iter().all(|&w| w >= -PARTITION_TOL));
        let gs: Vector = g.iter().copied().sum();
        prop_assert!(gs.length() * size <= IDENTITY_TOL, "Σ∇N = {gs}");
        let corners = c.corners();
        let x: Vector = (0..4).map(|a| n[a] * corners[a]).sum();
        prop_assert!((x - p).length() <= RELATIVE_TOL * p.length().max(size));
        let mut m = [0.0; 4];
        for a in 0..4 {
            let d = corners[a] - p;
            m[0] += d.x * g[a].x; m[1] += d.x * g[a].y; m[2] += d.y * g[a].x; m[3] += d.y * g[a].y;
        }
        prop_assert!((m[0] - 1.0).abs() + m[1].abs() + m[2].abs() + (m[3] - 1.0).abs() <= IDENTITY_TOL,
            "Σ x ⊗ ∇N = {m:?}");
    }

    #[test]
    fn gradients_match_central_differences(c in cell(), xi in -0.99f64..0.99, eta in -0.99f64..0.99) {
        let p = c.to_global(xi, eta);
        let size = min_size(&c);
        let delta = 1e-5 * size;
        let (_, g) = c.shape(p);
        for e in [Vector::X, Vector::Y] {
            let (np, _) = c.shape(p + delta * e);
            let (nm, _) = c.shape(p - delta * e);
            for a in 0..4 {
                let fd = (np[a] - nm[a]) / (2.0 * delta);
                prop_assert!((fd - g[a].dot(e)).abs() * size <= DIFFERENCE_TOL,
                    "corner {a}: {} vs difference quotient {fd}", g[a].dot(e));
            }
        }
    }

    /// two cells sharing a vertical side, and two sharing a horizontal edge: on the shared edge
    /// the shared nodes' weights agree and the other nodes' weights vanish.
    #[test]
    fn weights_are_continuous_across_shared_edges(
        c in cell(), l2 in 0.05f64..5.0, deg in -60.0f64..60.0, h_top in 0.1f64..4.0,
        s in 0.0f64..=1.0,
    ) {
        let k = c.corners();
        // right neighbour: its left side is c's right side.
        let y2 = k[1].y + l2 * deg.to_radians().tan();
        let right = SkewedCell::new(k[1].x, k[1].x + l2, [k[1].y, y2, k[3].y, y2 + (k[3].y - k[1].y)]).unwrap();
        let p = k[1] + s * (k[3] - k[1]);
        let (nl, _) = c.shape(p);
        let (nr, _) = right.shape(p);
        // shared: c's corners 2, 4 are right's corners 1, 3.
        prop_assert!((nl[1] - nr[0]).abs() <= PARTITION_TOL && (nl[3] - nr[2]).abs() <= PARTITION_TOL);
        prop_assert!(nl[0].abs() <= PARTITION_TOL && nl[2].abs() <= PARTITION_TOL);
        prop_assert!(nr[1].abs() <= PARTITION_TOL && nr[3].abs() <= PARTITION_TOL);
        // upper neighbour: its bottom edge is c's top edge.
        let hl = h_top * c.width();
        let up = SkewedCell::new(k[2].x, k[3].x, [k[2].y, k[3].y, k[2].y + hl, k[3].y + hl]).unwrap();
        let q = k[2] + s * (k[3] - k[2]);
        let (nb, _) = c.shape(q);
        let (nt, _) = up.shape(q);
        prop_assert!((nb[2] - nt[0]).abs() <= PARTITION_TOL && (nb[3] - nt[1]).abs() <= PARTITION_TOL);
        prop_assert!(nb[0].abs() <= PARTITION_TOL && nb[1].abs() <= PARTITION_TOL);
        prop_assert!(nt[2].abs() <= PARTITION_TOL && nt[3].abs() <= PARTITION_TOL);
    }
}
