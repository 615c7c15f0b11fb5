//! The terrain-following grid with bilinear shape functions on random piecewise-linear grounds.

use mpm_grid::{
    Bilinear, KinkPolicy, NodeId, ShapeFunctions, TerrainGrid, TerrainGridSpec, Vector,
};
use proptest::prelude::*;

use crate::common::{
    PARTITION_TOL, RELATIVE_TOL, TerrainCase, check_continuity, check_gradients_by_differences,
    check_identities, config, fraction, terrain_case, weight_of,
};

/// gradients of the fast terrain path against the general eq 19–20 cell: the same quantities
/// computed in a different order, O(1) after scaling by the cell size.
const AGREEMENT_TOL: f64 = 1e-12;
/// central differences with step 1e-3·L: in a parallelogram cell N is bilinear in (a, b), which
/// are affine in (x, y), so N is quadratic and the central difference has no truncation error;
/// round-off is ε·(|x|/L)/1e-3 ≤ ~1e-10 in units of 1/L for the coordinates generated.
const DIFFERENCE_TOL: f64 = 1e-8;
/// one-sided probes at ±1e-10·L across an edge; |∇N| ≤ ~3/L on these cells, so a continuous N
/// changes by ≤ 6e-10 between them.
const CONTINUITY_EPS: f64 = 1e-10;
const CONTINUITY_TOL: f64 = 1e-8;

fn grid_of(case: &TerrainCase, policy: KinkPolicy) -> TerrainGrid {
    TerrainGrid::new(TerrainGridSpec {
        profile: case.points.clone(),
        cell_width: case.l,
        row_height: case.h,
        rows: case.rows,
        kink_policy: policy,
    })
    .unwrap()
}

/// a point of the grid from a column, a fraction across it and a height in rows above ground.
fn point(case: &TerrainCase, column: u32, a: f64, t: f64) -> Vector {
    let x = case.points[0].x + (f64::from(column) + a) * case.l;
    Vector::new(x, case.ground(x) + t * case.h)
}

/// a random terrain and a random point in it (column, fraction, rows above ground).
fn case_and_point() -> impl Strategy<Value = (TerrainCase, Vector)> {
    terrain_case().prop_flat_map(|case| {
        let columns = case.columns();
        let rows = case.rows as f64;
        (Just(case), 0..columns, fraction(), (fraction(), 0.0..=rows)).prop_map(
            |(case, c, a, (t_pick, t))| {
                // t_pick hits the ground (0) and the top (rows) exactly now and then.
                let t = if t_pick == 0.0 {
                    0.0
                } else if t_pick == 1.0 {
                    case.rows as f64
                } else {
                    t
                };
                let p = point(&case, c, a, t);
                (case, p)
            },
        )
    })
}

fn scale(g: &TerrainGrid) -> f64 {
    g.min_cell_size()
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn bilinear_identities_hold((case, p) in case_and_point()) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let size = scale(&g);
        check_identities(&Bilinear(g), p, size)?;
    }

    #[test]
    fn fast_path_agrees_with_the_general_eq_20_cell((case, p) in case_and_point()) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let size = scale(&g);
        let s = Bilinear(g.clone()).stencil(p).unwrap();
        let cell = g.cell(s.nodes[0]).expect("stencil's first node is its cell");
        let corners = cell.corners();
        let (n, grad) = cell.shape(p);
        for a in 0..4 {
            prop_assert_eq!(g.node_position(s.nodes[a]), corners[a]);
            prop_assert!((s.weights[a] - n[a]).abs() <= AGREEMENT_TOL);
            prop_assert!((s.gradients[a] - grad[a]).length() * size <= AGREEMENT_TOL,
                "corner {}: {} vs {}", a, s.gradients[a], grad[a]);
        }
    }

    #[test]
    fn gradients_match_central_differences((case, p) in case_and_point()) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let size = scale(&g);
        check_gradients_by_differences(&Bilinear(g), p, size, 1e-3 * size, DIFFERENCE_TOL)?;
    }

    #[test]
    fn inverse_map_round_trips((case, p) in case_and_point()) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let c = g.locate(p).unwrap();
        prop_assert!(c.xi.abs() <= 1.0 + 1e-12 && c.eta.abs() <= 1.0 + 1e-12);
        let q = g.position(c);
        prop_assert!((q - p).length() <= RELATIVE_TOL * p.length().max(scale(&g)), "x(ξ(x)) = {q}, x = {p}");
    }

    #[test]
    fn ground_nodes_lie_on_the_ground(case in terrain_case()) {
        let g = grid_of(&case, KinkPolicy::Reject);
        prop_assert_eq!(g.columns() as u32, case.columns());
        for i in 0..=case.columns() as i32 {
            let p = g.node_position(NodeId::new(i, 0));
            let expect_x = case.points[0].x + f64::from(i) * case.l;
            prop_assert_eq!(p.x, expect_x);
            let y = case.ground(p.x);
            prop_assert!((p.y - y).abs() <= RELATIVE_TOL * y.abs().max(case.l), "node {i}: {} vs ground {y}", p.y);
            // the row above is h higher, and the ground function agrees with the node.
            let q = g.node_position(NodeId::new(i, 1));
            prop_assert!((q.y - p.y - case.h).abs() <= RELATIVE_TOL * q.y.abs().max(case.h));
            let gy = g.ground_height(p.x).unwrap();
            prop_assert!((gy - p.y).abs() <= RELATIVE_TOL * y.abs().max(case.l));
        }
        for (k, pt) in case.points.iter().enumerate() {
            prop_assert_eq!(g.node_position(NodeId::new(case.point_columns[k] as i32, 0)), *pt);
        }
    }

    /// points exactly on a vertical column boundary or a horizontal row line, evaluated in the
    /// two cells that share it (exact) and by the grid's stencil on either side (continuity).
    #[test]
    fn weights_are_continuous_across_shared_edges(
        case in terrain_case(), col in 0u32..1000, row in 0usize..1000, s in 0.0f64..=1.0,
    ) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let (columns, rows) = (g.columns() as i32, g.rows() as i32);
        let sf = Bilinear(g.clone());
        let eps = CONTINUITY_EPS * scale(&g);
        if columns >= 2 {
            // vertical edge at node column i, between cells (i−1, j) and (i, j).
            let i = 1 + (col as i32 % (columns - 1));
            let j = row as i32 % rows;
            let bottom = g.node_position(NodeId::new(i, j));
            let top = g.node_position(NodeId::new(i, j + 1));
            let p = bottom + s * (top - bottom);
            let (nl, _) = g.cell(NodeId::new(i - 1, j)).unwrap().shape(p);
            let (nr, _) = g.cell(NodeId::new(i, j)).unwrap().shape(p);
            prop_assert!((nl[1] - nr[0]).abs() <= PARTITION_TOL && (nl[3] - nr[2]).abs() <= PARTITION_TOL);
            prop_assert!(nl[0].abs() + nl[2].abs() + nr[1].abs() + nr[3].abs() <= 4.0 * PARTITION_TOL);
            check_continuity(&sf, p, Vector::X, eps, CONTINUITY_TOL)?;
            // the grid's stencil on the edge itself gives the shared nodes the same weights.
            let st = sf.stencil(p).unwrap();
            prop_assert!((weight_of(&st, NodeId::new(i, j)) - nr[0]).abs() <= PARTITION_TOL);
            prop_assert!((weight_of(&st, NodeId::new(i, j + 1)) - nr[2]).abs() <= PARTITION_TOL);
        }
        if rows >= 2 {
            // horizontal edge at node row j, between cells (i, j−1) and (i, j).
            let i = col as i32 % columns;
            let j = 1 + (row as i32 % (rows - 1));
            let left = g.node_position(NodeId::new(i, j));
            let right = g.node_position(NodeId::new(i + 1, j));
            let p = left + s * (right - left);
            let (nb, _) = g.cell(NodeId::new(i, j - 1)).unwrap().shape(p);
            let (nt, _) = g.cell(NodeId::new(i, j)).unwrap().shape(p);
            prop_assert!((nb[2] - nt[0]).abs() <= PARTITION_TOL && (nb[3] - nt[1]).abs() <= PARTITION_TOL);
            prop_assert!(nb[0].abs() + nb[1].abs() + nt[2].abs() + nt[3].abs() <= 4.0 * PARTITION_TOL);
            check_continuity(&sf, p, Vector::Y, eps, CONTINUITY_TOL)?;
        }
    }

    /// snapping a profile whose points sit up to 0.4 l off the column boundaries gives the same
    /// grid as the exact profile; rejecting it names the first offending point.
    #[test]
    fn snap_moves_points_onto_column_boundaries(
        case in terrain_case(), offsets in prop::collection::vec(-0.4f64..0.4, 31),
    ) {
        let exact = grid_of(&case, KinkPolicy::Reject);
        let mut moved = case.clone();
        for (k, p) in moved.points.iter_mut().enumerate().skip(1) {
            p.x += offsets[k] * case.l;
        }
        let snapped = grid_of(&moved, KinkPolicy::Snap);
        prop_assert_eq!(snapped.profile(), exact.profile());
        prop_assert_eq!(snapped.columns(), exact.columns());
        let first_off = (1..moved.points.len()).find(|&k| offsets[k].abs() > 1e-9);
        let rejected = TerrainGrid::new(TerrainGridSpec {
            profile: moved.points.clone(),
            cell_width: case.l,
            row_height: case.h,
            rows: case.rows,
            kink_policy: KinkPolicy::Reject,
        });
        match (first_off, rejected) {
            (Some(k), Err(mpm_grid::GridError::KinkOffColumnBoundary { index, .. })) => prop_assert_eq!(index, k),
            (None, Ok(_)) => {}
            (expected, got) => prop_assert!(false, "expected rejection at {:?}, got {:?}", expected, got),
        }
    }

    /// points just outside the grid are typed errors, never panics.
    #[test]
    fn points_off_the_grid_are_typed_errors(case in terrain_case(), a in 0.0f64..1.0, d in 1e-6f64..10.0) {
        let g = grid_of(&case, KinkPolicy::Reject);
        let sf = Bilinear(g.clone());
        let (x0, x1) = g.x_range();
        let x = x0 + a * (x1 - x0);
        let ground = g.ground_height(x).unwrap();
        let below = Vector::new(x, ground - d * case.h);
        let below_ok = matches!(sf.stencil(below), Err(mpm_grid::LocateError::BelowGround { ground_y, .. }) if ground_y == ground);
        prop_assert!(below_ok, "below ground");
        let above = Vector::new(x, ground + (case.rows as f64 + d) * case.h);
        prop_assert!(matches!(sf.stencil(above), Err(mpm_grid::LocateError::Outside { .. })), "above top");
        let left = Vector::new(x0 - d * case.l, ground);
        prop_assert!(matches!(sf.stencil(left), Err(mpm_grid::LocateError::Outside { .. })), "left");
        let right = Vector::new(x1 + d * case.l, ground);
        prop_assert!(matches!(sf.stencil(right), Err(mpm_grid::LocateError::Outside { .. })), "right");
    }
}
