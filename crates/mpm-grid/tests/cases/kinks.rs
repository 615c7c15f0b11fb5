//! A 30° slope running into a flat runout (the geometry of the paper's §5(2) and §7 scenes):
//! node normals inside segments and the documented bisector normal at the kink.

use mpm_grid::{
    Bilinear, KinkPolicy, NodeId, ShapeFunctions, TerrainGrid, TerrainGridSpec, Vector,
};

/// unit vectors built from sin/cos of exact angles: round-off only.
const ROUND_OFF: f64 = 1e-14;

fn slope_into_runout() -> TerrainGrid {
    let t = 30f64.to_radians().tan();
    TerrainGrid::new(TerrainGridSpec {
        // 20 columns of slope from (0, 2 tan 30°) down to (2, 0), then 20 flat columns.
        profile: vec![Vector::new(0.0, 2.0 * t), Vector::new(2.0, 0.0), Vector::new(4.0, 0.0)],
        cell_width: 0.1,
        row_height: 0.1,
        rows: 10,
        kink_policy: KinkPolicy::Reject,
    })
    .unwrap()
}

fn close(a: Vector, b: Vector) -> bool {
    (a - b).length() < ROUND_OFF
}

#[test]
fn abe2005_slope_node_normals_are_the_segment_normals() {
    let g = slope_into_runout();
    let th = 30f64.to_radians();
    // the slope descends to the right: its upward normal leans towards +x.
    assert!(close(g.node_ground_normal(5), Vector::new(th.sin(), th.cos())));
    assert!(close(g.node_ground_normal(30), Vector::Y));
}

#[test]
fn abe2005_kink_node_lies_on_both_segment_planes() {
    let g = slope_into_runout();
    let half = 15f64.to_radians();
    let n = g.node_ground_normal(20);
    assert!(close(n, Vector::new(half.sin(), half.cos())), "{n}");
    let segs = g.ground_segments(20);
    let (left, right) = (segs.left.unwrap(), segs.right.unwrap());
    assert_eq!((left.index, right.index), (0, 1));
    assert_eq!(left.end, right.start);
    assert_eq!(right.start, Vector::new(2.0, 0.0));
    assert_eq!(right.normal, Vector::Y);
    // the boundary conditions hold the kink node on both segments' planes, not the bisector
    let b = Bilinear(g.clone()).boundary_normals(NodeId::new(20, 0));
    assert_eq!((b.ground, b.ground_kink), (Some(right.normal), Some(left.normal)));
    assert!(b.left_wall.is_none() && b.right_wall.is_none());
    assert_eq!(b.iter().count(), 2);
    // a node inside a segment, or above the ground, has no kink plane
    assert_eq!(g.boundary_normals(NodeId::new(7, 0)).ground_kink, None);
    assert_eq!(g.boundary_normals(NodeId::new(20, 1)).ground_kink, None);
    // inside a segment both neighbours are that segment.
    let inside = g.ground_segments(7);
    assert_eq!(inside.left, inside.right);
}

#[test]
fn abe2005_grid_ends_report_walls_and_one_segment() {
    let g = slope_into_runout();
    let first = g.ground_segments(0);
    assert!(first.left.is_none() && first.right.unwrap().index == 0);
    let last = g.ground_segments(40);
    assert!(last.left.unwrap().index == 1 && last.right.is_none());
    let b = g.boundary_normals(NodeId::new(0, 0));
    assert_eq!(b.left_wall, Some(Vector::X));
    assert!(b.ground.is_some());
    let b = g.boundary_normals(NodeId::new(40, 3));
    assert_eq!((b.right_wall, b.ground), (Some(Vector::NEG_X), None));
    assert!(g.boundary_normals(NodeId::new(12, 1)).is_empty());
}

#[test]
fn abe2005_slope_cells_are_parallelograms_with_h_cos_theta_height() {
    let g = slope_into_runout();
    let c = g.cell(NodeId::new(3, 2)).unwrap().corners();
    assert!(((c[2].y - c[0].y) - 0.1).abs() < ROUND_OFF);
    assert!(((c[3].y - c[1].y) - 0.1).abs() < ROUND_OFF);
    assert!(((c[1].y - c[0].y) / 0.1 + 30f64.to_radians().tan()).abs() < 1e-12);
    assert!((g.min_cell_size() - 0.1 * 30f64.to_radians().cos()).abs() < ROUND_OFF);
    // η from eq 20 is measured along the vertical: a point h/2 above the ground is mid-row 0.
    let x = 0.55;
    let c = g.locate(Vector::new(x, g.ground_height(x).unwrap() + 0.05)).unwrap();
    assert_eq!(c.cell, NodeId::new(5, 0));
    assert!(c.xi.abs() < 1e-12 && c.eta.abs() < 1e-12);
}

#[test]
fn snap_moves_a_kink_to_the_nearest_column_boundary_keeping_its_height() {
    let spec = |policy| TerrainGridSpec {
        profile: vec![Vector::new(0.0, 1.0), Vector::new(2.03, 0.0), Vector::new(4.0, 0.0)],
        cell_width: 0.1,
        row_height: 0.1,
        rows: 5,
        kink_policy: policy,
    };
    let g = TerrainGrid::new(spec(KinkPolicy::Snap)).unwrap();
    assert!((g.profile()[1] - Vector::new(2.0, 0.0)).length() < 1e-12);
    let err = TerrainGrid::new(spec(KinkPolicy::Reject)).unwrap_err();
    match err {
        mpm_grid::GridError::KinkOffColumnBoundary { index, x, nearest_boundary_x } => {
            assert_eq!((index, x), (1, 2.03));
            assert!((nearest_boundary_x - 2.0).abs() < 1e-12);
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn reject_accepts_boundaries_that_are_off_only_by_round_off() {
    // 12.3 / 0.1 = 122.99999999999999 in f64.
    let g = TerrainGrid::new(TerrainGridSpec {
        profile: vec![Vector::new(0.0, 0.0), Vector::new(12.3, 1.0)],
        cell_width: 0.1,
        row_height: 0.1,
        rows: 1,
        kink_policy: KinkPolicy::Reject,
    })
    .unwrap();
    assert_eq!(g.columns(), 123);
}
