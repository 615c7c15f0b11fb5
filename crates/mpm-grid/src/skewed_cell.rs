//! One isoparametric skewed rectangle with vertical sides: the closed-form inverse map of
//! Abe, Johansson & Konagai (2005), eqs 19–20, and its bilinear shape functions.
//!
//! # Glossary
//! - (x, y): global coordinates, m; y up.
//! - (ξ, η) ∈ [−1, 1]²: natural coordinates of the cell (the reference square).
//! - corners, numbered as in the paper: 1 = (x1, y1) bottom-left, 2 = (x2, y2) bottom-right,
//!   3 = (x1, y3) top-left, 4 = (x2, y4) top-right. The left and right sides are vertical.
//! - l = x2 − x1: the cell (column) width, m.
//! - N_a = ¼(1 ± ξ)(1 ± η): bilinear shape function of corner a; in stencils the corners are
//!   the nodes (i, j), (i+1, j), (i, j+1), (i+1, j+1) in this order.
//! - J = ∂(x, y)/∂(ξ, η): Jacobian of the forward map; gradients are ∇N = J⁻ᵀ ∇_(ξ,η) N.
//!
//! # The map
//! Forward: x = Σ N_a x_a, y = Σ N_a y_a. Because the sides are vertical, x depends on ξ only and
//! the inverse is closed form, with no Newton iteration:
//!
//! ```text
//! ξ = (2x − (x1 + x2)) / l                                                   (19)
//! η = (4y − [(1−ξ)(y3+y1) + (1+ξ)(y4+y2)]) / ((1−ξ)(y3−y1) + (1+ξ)(y4−y2))   (20)
//! ```
//!
//! With D(ξ) = (1−ξ)(y3−y1) + (1+ξ)(y4−y2) (the denominator of eq 20), det J = l·D/8. D is linear
//! in ξ, so det J > 0 on the whole cell exactly when both sides have positive height
//! (y3 > y1 and y4 > y2): that is the non-degeneracy condition [`SkewedCell::new`] checks.

use crate::error::{Extent, GridError};
use crate::math::{Matrix, Vector};

/// One skewed rectangle with vertical sides (a trapezoid whose bottom and top edges are straight),
/// mapped onto the reference square by eqs 19–20.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkewedCell {
    x1: f64,
    x2: f64,
    /// y1, y2, y3, y4 in the paper's numbering.
    y: [f64; 4],
}

impl SkewedCell {
    /// the cell with vertical sides at `x1` < `x2` and corner heights `y = [y1, y2, y3, y4]`
    /// (bottom-left, bottom-right, top-left, top-right).
    ///
    /// Errors: non-finite input ([`GridError::NonFinitePoint`] naming the corner), x2 ≤ x1
    /// ([`GridError::NonPositiveSize`]), or a side of non-positive height
    /// ([`GridError::DegenerateCell`]).
    pub fn new(x1: f64, x2: f64, y: [f64; 4]) -> Result<Self, GridError> {
        const NAMES: [&str; 4] = [
            "corner 1 (bottom-left)",
            "corner 2 (bottom-right)",
            "corner 3 (top-left)",
            "corner 4 (top-right)",
        ];
        let xs = [x1, x2, x1, x2];
        for a in 0..4 {
            if !(xs[a].is_finite() && y[a].is_finite()) {
                return Err(GridError::NonFinitePoint { what: NAMES[a], x: xs[a], y: y[a] });
            }
        }
        let width = x2 - x1;
        if !(width > 0.0 && width.is_finite()) {
            return Err(GridError::NonPositiveSize { what: Extent::SkewedCellWidth, value: width });
        }
        let left_height = y[2] - y[0];
        let right_height = y[3] - y[1];
        let ok = |v: f64| v > 0.0 && v.is_finite();
        if !(ok(left_height) && ok(right_height)) {
            return Err(GridError::DegenerateCell { width, left_height, right_height });
        }
        Ok(Self { x1, x2, y })
    }

    /// corner positions in the paper's order 1, 2, 3, 4 (bottom-left, bottom-right, top-left,
    /// top-right).
    pub fn corners(&self) -> [Vector; 4] {
        [
            Vector::new(self.x1, self.y[0]),
            Vector::new(self.x2, self.y[1]),
            Vector::new(self.x1, self.y[2]),
            Vector::new(self.x2, self.y[3]),
        ]
    }

    /// the width l = x2 − x1, m.
    pub fn width(&self) -> f64 {
        self.x2 - self.x1
    }

    /// natural coordinates (ξ, η) of a global point by eqs 19–20. Points outside the cell get
    /// coordinates outside [−1, 1] (the map extrapolates); the caller decides what that means.
    pub fn to_local(&self, p: Vector) -> (f64, f64) {
        let [y1, y2, y3, y4] = self.y;
        let xi = (2.0 * p.x - (self.x1 + self.x2)) / self.width(); // eq 19
        let num = 4.0 * p.y - ((1.0 - xi) * (y3 + y1) + (1.0 + xi) * (y4 + y2));
        let den = (1.0 - xi) * (y3 - y1) + (1.0 + xi) * (y4 - y2);
        (xi, num / den) // eq 20
    }

    /// global point of natural coordinates (ξ, η): the forward isoparametric map Σ N_a x_a.
    pub fn to_global(&self, xi: f64, eta: f64) -> Vector {
        let n = weights(xi, eta);
        Vector::new(
            0.5 * ((1.0 - xi) * self.x1 + (1.0 + xi) * self.x2),
            n[0] * self.y[0] + n[1] * self.y[1] + n[2] * self.y[2] + n[3] * self.y[3],
        )
    }

    /// Jacobian ∂(x, y)/∂(ξ, η) at (ξ, η): columns are ∂/∂ξ and ∂/∂η.
    pub fn jacobian(&self, xi: f64, eta: f64) -> Matrix {
        let [y1, y2, y3, y4] = self.y;
        let dy_dxi = 0.25 * ((1.0 - eta) * (y2 - y1) + (1.0 + eta) * (y4 - y3));
        let dy_deta = 0.25 * ((1.0 - xi) * (y3 - y1) + (1.0 + xi) * (y4 - y2));
        Matrix::from_cols(Vector::new(0.5 * self.width(), dy_dxi), Vector::new(0.0, dy_deta))
    }

    /// weights N_a and gradients ∇N_a (1/m) at a global point, corners in order 1..4. Exact for
    /// points inside the cell; extrapolated outside.
    pub fn shape(&self, p: Vector) -> ([f64; 4], [Vector; 4]) {
        let (xi, eta) = self.to_local(p);
        let j = self.jacobian(xi, eta);
        // J⁻ᵀ for J = [[a, 0], [c, d]] (columns ∂/∂ξ, ∂/∂η): ∂ξ/∂x = 1/a, ∂ξ/∂y = 0,
        // ∂η/∂x = −c/(a d), ∂η/∂y = 1/d.
        let (a, c, d) = (j.x_axis.x, j.x_axis.y, j.y_axis.y);
        let dxi_dx = 1.0 / a;
        let deta_dy = 1.0 / d;
        let deta_dx = -c * dxi_dx * deta_dy;
        let n = weights(xi, eta);
        let dn = natural_gradients(xi, eta);
        let g =
            dn.map(|(n_xi, n_eta)| Vector::new(n_xi * dxi_dx + n_eta * deta_dx, n_eta * deta_dy));
        (n, g)
    }
}

/// bilinear weights ¼(1 ± ξ)(1 ± η) in corner order 1..4.
pub(crate) fn weights(xi: f64, eta: f64) -> [f64; 4] {
    let (xm, xp, em, ep) = (1.0 - xi, 1.0 + xi, 1.0 - eta, 1.0 + eta);
    [0.25 * xm * em, 0.25 * xp * em, 0.25 * xm * ep, 0.25 * xp * ep]
}

/// (∂N/∂ξ, ∂N/∂η) in corner order 1..4.
fn natural_gradients(xi: f64, eta: f64) -> [(f64, f64); 4] {
    let (xm, xp, em, ep) = (1.0 - xi, 1.0 + xi, 1.0 - eta, 1.0 + eta);
    [
        (-0.25 * em, -0.25 * xm),
        (0.25 * em, -0.25 * xp),
        (-0.25 * ep, 0.25 * xm),
        (0.25 * ep, 0.25 * xp),
    ]
}

#[cfg(all(test, not(feature = "dim3")))]
mod tests {
    use super::*;

    /// round-off allowance for O(1) quantities computed in a handful of operations.
    const ROUND_OFF: f64 = 1e-14;

    #[test]
    fn corners_map_to_reference_square_corners() {
        let cell = SkewedCell::new(1.0, 1.5, [2.0, 1.7, 2.2, 2.1]).unwrap();
        let expected = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];
        for (c, (xi, eta)) in cell.corners().into_iter().zip(expected) {
            let (a, b) = cell.to_local(c);
            assert!((a - xi).abs() < ROUND_OFF && (b - eta).abs() < ROUND_OFF, "{c:?} -> {a}, {b}");
        }
    }

    #[test]
    fn jacobian_determinant_is_l_d_over_8() {
        let cell = SkewedCell::new(0.0, 2.0, [0.0, -1.0, 1.0, 0.5]).unwrap();
        for (xi, eta) in [(-1.0, -1.0), (0.3, -0.2), (1.0, 1.0)] {
            let d = (1.0 - xi) * 1.0 + (1.0 + xi) * 1.5;
            assert!((cell.jacobian(xi, eta).determinant() - 2.0 * d / 8.0).abs() < ROUND_OFF);
        }
    }

    #[test]
    fn degenerate_and_non_finite_cells_are_rejected() {
        assert!(matches!(
            SkewedCell::new(0.0, 1.0, [0.0, 0.0, 1.0, 0.0]),
            Err(GridError::DegenerateCell { right_height, .. }) if right_height == 0.0
        ));
        assert!(matches!(
            SkewedCell::new(1.0, 1.0, [0.0, 0.0, 1.0, 1.0]),
            Err(GridError::NonPositiveSize { .. })
        ));
        assert!(matches!(
            SkewedCell::new(0.0, 1.0, [0.0, 0.0, f64::NAN, 1.0]),
            Err(GridError::NonFinitePoint { what: "corner 3 (top-left)", .. })
        ));
    }
}
