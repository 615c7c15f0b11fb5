//! Every kind of bad input is a typed error naming the offending point or value; nothing panics.

use mpm_grid::{
    Bilinear, Extent, Gimp, GridError, KinkPolicy, LocateError, RegularGrid, ShapeFunctions,
    SkewedCell, TerrainGrid, TerrainGridSpec, Vector,
};

fn spec(profile: Vec<Vector>) -> TerrainGridSpec {
    TerrainGridSpec {
        profile,
        cell_width: 0.1,
        row_height: 0.1,
        rows: 4,
        kink_policy: KinkPolicy::Snap,
    }
}

fn v(x: f64, y: f64) -> Vector {
    Vector::new(x, y)
}

#[test]
fn profile_with_fewer_than_two_points() {
    assert_eq!(
        TerrainGrid::new(spec(vec![v(0.0, 0.0)])).unwrap_err(),
        GridError::TooFewProfilePoints { count: 1 }
    );
    assert_eq!(
        TerrainGrid::new(spec(vec![])).unwrap_err(),
        GridError::TooFewProfilePoints { count: 0 }
    );
}

#[test]
fn profile_with_non_increasing_x_names_the_point() {
    let err = TerrainGrid::new(spec(vec![v(0.0, 1.0), v(1.0, 0.5), v(1.0, 0.0)])).unwrap_err();
    assert_eq!(err, GridError::NonIncreasingProfile { index: 2, x: 1.0, previous_x: 1.0 });
    let err = TerrainGrid::new(spec(vec![v(0.0, 1.0), v(-1.0, 0.5)])).unwrap_err();
    assert_eq!(err, GridError::NonIncreasingProfile { index: 1, x: -1.0, previous_x: 0.0 });
}

#[test]
fn profile_with_a_non_finite_value_names_the_point() {
    let err = TerrainGrid::new(spec(vec![v(0.0, 1.0), v(1.0, f64::INFINITY)])).unwrap_err();
    assert!(matches!(err, GridError::NonFiniteProfilePoint { index: 1, x: 1.0, .. }));
    let err = TerrainGrid::new(spec(vec![v(f64::NAN, 1.0), v(1.0, 0.0)])).unwrap_err();
    assert!(matches!(err, GridError::NonFiniteProfilePoint { index: 0, .. }));
    // messages carry the point.
    assert!(err.to_string().contains("point 0"));
}

#[test]
fn cell_sizes_that_are_not_positive() {
    for bad in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        let mut s = spec(vec![v(0.0, 1.0), v(1.0, 0.0)]);
        s.cell_width = bad;
        assert!(matches!(
            TerrainGrid::new(s).unwrap_err(),
            GridError::NonPositiveSize { what: Extent::CellWidth, .. }
        ));
        let mut s = spec(vec![v(0.0, 1.0), v(1.0, 0.0)]);
        s.row_height = bad;
        assert!(matches!(
            TerrainGrid::new(s).unwrap_err(),
            GridError::NonPositiveSize { what: Extent::RowHeight, .. }
        ));
        assert!(matches!(
            RegularGrid::new(Vector::ZERO, v(bad, 0.1), [2, 2]).unwrap_err(),
            GridError::NonPositiveSize { what: Extent::CellSize(0), .. }
        ));
    }
    let mut s = spec(vec![v(0.0, 1.0), v(1.0, 0.0)]);
    s.rows = 0;
    assert!(matches!(
        TerrainGrid::new(s).unwrap_err(),
        GridError::CellCountOutOfRange { what: Extent::Rows, .. }
    ));
    assert!(matches!(
        RegularGrid::new(v(f64::NAN, 0.0), v(0.1, 0.1), [2, 2]).unwrap_err(),
        GridError::NonFinitePoint { what: "grid origin", .. }
    ));
}

#[test]
fn degenerate_cells_are_named() {
    // a general cell whose top-right corner sits below its bottom-right corner.
    let err = SkewedCell::new(0.0, 1.0, [0.0, 0.5, 1.0, 0.4]).unwrap_err();
    assert!(
        matches!(err, GridError::DegenerateCell { right_height, .. } if (right_height + 0.1).abs() < 1e-15)
    );
    // a profile segment so steep that h·cos θ underflows: a cliff of 1e300 m over one column.
    let err = TerrainGrid::new(spec(vec![v(0.0, 0.0), v(0.1, 1e300), v(0.2, 1e300)])).unwrap_err();
    assert!(matches!(err, GridError::DegenerateSegment { index: 0, .. }), "{err:?}");
}

#[test]
fn snapping_two_points_onto_one_boundary_names_the_second() {
    let err = TerrainGrid::new(spec(vec![v(0.0, 1.0), v(0.52, 0.5), v(0.54, 0.4), v(1.0, 0.0)]))
        .unwrap_err();
    assert!(matches!(err, GridError::SnappedPointsCoincide { index: 2, x, boundary_x }
        if x == 0.54 && (boundary_x - 0.5).abs() < 1e-12));
    // a profile shorter than half a column collapses onto its first point.
    let err = TerrainGrid::new(spec(vec![v(0.0, 1.0), v(0.04, 0.5)])).unwrap_err();
    assert!(matches!(err, GridError::SnappedPointsCoincide { index: 1, .. }));
}

#[test]
fn absurd_extents_are_errors_not_overflows() {
    let err = TerrainGrid::new(TerrainGridSpec {
        profile: vec![v(0.0, 0.0), v(1e12, 0.0)],
        cell_width: 1e-3,
        row_height: 0.1,
        rows: 1,
        kink_policy: KinkPolicy::Snap,
    })
    .unwrap_err();
    assert!(matches!(err, GridError::CellCountOutOfRange { what: Extent::Columns, .. }));
    let err = RegularGrid::new(Vector::ZERO, v(0.1, 0.1), [usize::MAX, 1]).unwrap_err();
    assert!(matches!(err, GridError::CellCountOutOfRange { what: Extent::Cells(0), .. }));
}

#[test]
fn bad_gimp_particle_sizes() {
    let g = RegularGrid::new(Vector::ZERO, v(0.1, 0.2), [2, 2]).unwrap();
    for (lp, axis) in [(v(0.0, 0.05), "x"), (v(0.05, 0.11), "y"), (v(f64::NAN, 0.05), "x")] {
        assert!(matches!(
            Gimp::new(g, lp).unwrap_err(),
            GridError::InvalidParticleHalfSize { axis: a, .. } if a == axis
        ));
    }
}

#[test]
fn locating_bad_points_is_a_typed_result() {
    let t = 30f64.to_radians().tan();
    let g = TerrainGrid::new(spec(vec![v(0.0, t), v(1.0, 0.0)])).unwrap();
    let sf = Bilinear(g.clone());
    assert!(matches!(
        sf.stencil(v(f64::NAN, 0.0)),
        Err(LocateError::NonFinite { x, y: 0.0 }) if x.is_nan()
    ));
    assert!(matches!(sf.stencil(v(0.5, f64::INFINITY)), Err(LocateError::NonFinite { .. })));
    assert!(matches!(sf.stencil(v(0.5, f64::NEG_INFINITY)), Err(LocateError::NonFinite { .. })));
    assert!(matches!(sf.stencil(v(-0.01, 1.0)), Err(LocateError::Outside { .. })));
    assert!(matches!(sf.stencil(v(1.01, 0.1)), Err(LocateError::Outside { .. })));
    assert!(matches!(sf.stencil(v(0.5, 0.5 * t + 0.41)), Err(LocateError::Outside { .. })));
    let err = sf.stencil(v(0.5, 0.0)).unwrap_err();
    assert!(matches!(err, LocateError::BelowGround { x: 0.5, y: 0.0, ground_y }
        if (ground_y - 0.5 * t).abs() < 1e-15));
    assert!(err.to_string().contains("below the ground"));
}
