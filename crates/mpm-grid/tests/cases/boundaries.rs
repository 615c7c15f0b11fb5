//! How the 9-node stencils treat the domain boundary (one ghost layer, unclipped splines) and
//! what the regular grid reports as walls.

use mpm_grid::{Gimp, NodeId, QuadraticBSpline, RegularGrid, ShapeFunctions, Vector};

/// weights are exact binary fractions or short polynomials of them.
const ROUND_OFF: f64 = 1e-15;

fn grid() -> RegularGrid {
    RegularGrid::new(Vector::ZERO, Vector::splat(0.1), [10, 10]).unwrap()
}

#[test]
fn bspline_point_on_the_left_wall_weights_the_ghost_node_one_eighth() {
    let sf = QuadraticBSpline::new(grid());
    let s = sf.stencil(Vector::new(0.0, 0.5)).unwrap();
    let w = |i, j| mpm_grid::Stencil::iter(&s).find(|(n, _, _)| *n == NodeId::new(i, j)).unwrap().1;
    assert!((w(-1, 5) - 0.125 * 0.75).abs() < ROUND_OFF);
    assert!((w(0, 5) - 0.75 * 0.75).abs() < ROUND_OFF);
    assert!((w(1, 5) - 0.125 * 0.75).abs() < ROUND_OFF);
    // the ghost node and the wall node both report the left wall, so one boundary condition
    // holds both.
    assert_eq!(sf.boundary_normals(NodeId::new(-1, 5)).left_wall, Some(Vector::X));
    assert_eq!(sf.boundary_normals(NodeId::new(0, 5)).left_wall, Some(Vector::X));
    assert_eq!(sf.node_position(NodeId::new(-1, 5)), Vector::new(-0.1, 0.5));
}

#[test]
fn gimp_particle_clear_of_the_node_weights_like_the_hat() {
    // lp = h/4: a particle whose domain stays inside one cell half sees linear weights.
    let sf = Gimp::with_particles_per_cell(grid(), [2, 2]).unwrap();
    assert_eq!(sf.half_particle(), Vector::splat(0.025));
    let s = sf.stencil(Vector::new(0.54, 0.5)).unwrap();
    let w = |i| s.iter().find(|(n, _, _)| *n == NodeId::new(i, 5)).unwrap().1;
    // along x: r = 0.4 h from node 5 and 0.6 h from node 6 (both in the linear band
    // lp ≤ |r| ≤ h − lp); along y the point is on node 5: 1 − lp/(2h) = 7/8.
    assert!((w(5) - 0.6 * 0.875).abs() < 1e-12);
    assert!((w(6) - 0.4 * 0.875).abs() < 1e-12);
    assert!(w(4).abs() < ROUND_OFF);
}

#[test]
fn floor_and_walls_of_the_regular_grid() {
    let g = grid();
    let corner = g.boundary_normals(NodeId::new(10, 0));
    assert_eq!(corner.ground, Some(Vector::Y));
    assert_eq!(corner.right_wall, Some(Vector::NEG_X));
    assert_eq!(corner.iter().count(), 2);
    assert!(g.boundary_normals(NodeId::new(5, 10)).is_empty());
    assert_eq!(g.boundary_normals(NodeId::new(3, -1)).ground, Some(Vector::Y));
}

#[test]
fn points_within_the_slack_are_located_without_clamping() {
    let g = grid();
    let sf = QuadraticBSpline::new(g);
    let p = Vector::new(1.0 + 1e-12, -1e-12);
    let s = sf.stencil(p).unwrap();
    let sum: f64 = s.weights.iter().sum();
    assert!((sum - 1.0).abs() < 1e-14);
    let x: Vector = s.iter().map(|(n, w, _)| w * sf.node_position(n)).sum();
    assert!((x - p).length() < 1e-15);
    assert!(sf.stencil(Vector::new(1.0 + 1e-6, 0.5)).is_err());
}
