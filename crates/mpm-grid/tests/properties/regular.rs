//! The regular grid with each of its shape functions: bilinear, uGIMP, quadratic B-spline.

use mpm_grid::{Bilinear, Gimp, NodeId, QuadraticBSpline, RegularGrid, ShapeFunctions, Vector};
use proptest::prelude::*;

use crate::common::{
    RELATIVE_TOL, check_continuity, check_gradients_by_differences, check_identities, config,
    fraction,
};

/// uGIMP and B-spline weights are C¹ piecewise quadratics: central differences with step
/// 1e-6·L have no truncation error inside a piece and ≤ 1e-6·h/lp ≤ 8e-6 (in units of 1/L)
/// where a piece boundary falls inside the step (the second derivative jumps by ≤ 1/(h·lp),
/// lp ≥ h/8 here); round-off adds ε·(|x|/L)/1e-6 ≤ ~1e-7.
const DIFFERENCE_TOL: f64 = 1e-5;
/// one-sided probes at ±1e-10·L across a stencil switch line; |∇N| ≤ 2/L, so a continuous N
/// changes by ≤ 4e-10 between them.
const CONTINUITY_EPS: f64 = 1e-10;
const CONTINUITY_TOL: f64 = 1e-8;

/// origin in [−20, 20]², dx, dy ∈ [0.05, 2] m, 1–20 cells per axis.
fn grid() -> impl Strategy<Value = RegularGrid> {
    (-20.0f64..20.0, -20.0f64..20.0, 0.05f64..2.0, 0.05f64..2.0, 1usize..=20, 1usize..=20).prop_map(
        |(ox, oy, dx, dy, nx, ny)| {
            RegularGrid::new(Vector::new(ox, oy), Vector::new(dx, dy), [nx, ny]).unwrap()
        },
    )
}

/// a grid and a point in it; the point falls on cell edges, walls and the floor now and then.
fn grid_and_point() -> impl Strategy<Value = (RegularGrid, Vector)> {
    grid().prop_flat_map(|g| {
        let [nx, ny] = g.cells();
        (Just(g), 0..nx, 0..ny, fraction(), fraction()).prop_map(|(g, i, j, a, b)| {
            let p = g.origin() + g.cell_size() * Vector::new(i as f64 + a, j as f64 + b);
            (g, p)
        })
    })
}

/// uGIMP with 1–4 particles per cell along each axis.
fn gimp_and_point() -> impl Strategy<Value = (Gimp, Vector)> {
    (grid_and_point(), 1usize..=4, 1usize..=4)
        .prop_map(|((g, p), px, py)| (Gimp::with_particles_per_cell(g, [px, py]).unwrap(), p))
}

fn size(g: &RegularGrid) -> f64 {
    g.min_cell_size()
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn bilinear_identities_hold((g, p) in grid_and_point()) {
        check_identities(&Bilinear(g), p, size(&g))?;
    }

    #[test]
    fn gimp_identities_hold((sf, p) in gimp_and_point()) {
        check_identities(&sf, p, size(sf.grid()))?;
    }

    #[test]
    fn bspline_identities_hold((g, p) in grid_and_point()) {
        check_identities(&QuadraticBSpline::new(g), p, size(&g))?;
    }

    #[test]
    fn gradients_match_central_differences((sf, p) in gimp_and_point()) {
        let g = *sf.grid();
        let h = size(&g);
        check_gradients_by_differences(&Bilinear(g), p, h, 1e-6 * h, DIFFERENCE_TOL)?;
        check_gradients_by_differences(&sf, p, h, 1e-6 * h, DIFFERENCE_TOL)?;
        check_gradients_by_differences(&QuadraticBSpline::new(g), p, h, 1e-6 * h, DIFFERENCE_TOL)?;
    }

    #[test]
    fn inverse_map_round_trips((g, p) in grid_and_point()) {
        let c = g.locate(p).unwrap();
        let q = g.position(c);
        prop_assert!((q - p).length() <= RELATIVE_TOL * p.length().max(size(&g)));
    }

    /// across cell edges (bilinear) and across the half-cell lines where the 3×3 stencils
    /// switch their centre node (uGIMP, B-spline), every node's weight is continuous.
    #[test]
    fn weights_are_continuous_where_stencils_switch(
        (sf, p) in gimp_and_point(), along in 0.0f64..=1.0,
    ) {
        let g = *sf.grid();
        let [nx, ny] = g.cells();
        let (o, d) = (g.origin(), g.cell_size());
        let u = (p - o) / d;
        let eps = CONTINUITY_EPS * size(&g);
        // a vertical cell edge and a vertical half-cell line through the point's row, and the
        // horizontal ones through its column.
        let i = (u.x.floor() as usize).min(nx - 1);
        let j = (u.y.floor() as usize).min(ny - 1);
        let edge_x = o + d * Vector::new(i as f64, j as f64 + along);
        let half_x = o + d * Vector::new(i as f64 + 0.5, j as f64 + along);
        let edge_y = o + d * Vector::new(i as f64 + along, j as f64);
        let half_y = o + d * Vector::new(i as f64 + along, j as f64 + 0.5);
        let bs = QuadraticBSpline::new(g);
        for (q, dir) in [(edge_x, Vector::X), (edge_y, Vector::Y)] {
            check_continuity(&Bilinear(g), q, dir, eps, CONTINUITY_TOL)?;
        }
        for (q, dir) in [(half_x, Vector::X), (half_y, Vector::Y), (edge_x, Vector::X), (edge_y, Vector::Y)] {
            check_continuity(&sf, q, dir, eps, CONTINUITY_TOL)?;
            check_continuity(&bs, q, dir, eps, CONTINUITY_TOL)?;
        }
    }

    /// a 3×3 stencil leaves out only nodes whose weight is exactly zero: the weight of every
    /// node two layers from the centre, evaluated with the 1D formulas, vanishes.
    #[test]
    fn bspline_weights_match_the_closed_form((g, p) in grid_and_point()) {
        let s = QuadraticBSpline::new(g).stencil(p).unwrap();
        let u = (p - g.origin()) / g.cell_size();
        let spline = |q: f64| {
            let q = q.abs();
            if q < 0.5 { 0.75 - q * q } else if q < 1.5 { 0.5 * (1.5 - q) * (1.5 - q) } else { 0.0 }
        };
        for (n, w, _) in s.iter() {
            let expect = spline(u.x - f64::from(n.i)) * spline(u.y - f64::from(n.j));
            prop_assert!((w - expect).abs() <= 1e-14, "{n:?}: {w} vs {expect}");
        }
        let NodeId { i: ci, j: cj } = s.nodes[4];
        for di in -2i32..=2 {
            for dj in -2i32..=2 {
                if di.abs() == 2 || dj.abs() == 2 {
                    let w = spline(u.x - f64::from(ci + di)) * spline(u.y - f64::from(cj + dj));
                    prop_assert_eq!(w, 0.0);
                }
            }
        }
    }
}
