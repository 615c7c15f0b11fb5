//! A ground of kinks holds the material: a particle above the ground stays above it after a
//! step, whatever the kink (concave or convex) and whatever the nodes' trial velocities.
//!
//! With bilinear weights a particle's new position is the convex combination of its cell's four
//! nodes moved by Δt v_i (the weights are non-negative and sum to one), so it lies above a line
//! whenever all four moved nodes do. The contact law makes a ground node's end velocity
//! admissible for every plane the grid gives it (`mpm_contact::constrain_velocity_all`); a kink
//! node's velocity is interpolated into the columns on both sides, so the grid gives it both
//! segments' planes (`TerrainGrid::boundary_normals`). Checked here over a sweep of kinks,
//! trial velocities and particle positions; and the bisector of the two normals, held instead,
//! is shown to let particles through.

use mpm_contact::{Boundary, Friction, constrain_velocity_all};
use mpm_grid::{CellCoords, KinkPolicy, NodeId, TerrainGrid, TerrainGridSpec, Vector};

/// the node's frictionless ground planes: `both` the grid's boundary planes (one per segment
/// at a kink), otherwise the bisector alone.
fn planes(grid: &TerrainGrid, node: NodeId, both: bool) -> Vec<Boundary> {
    let normals: Vec<Vector> = if both {
        grid.boundary_normals(node).iter().collect()
    } else {
        vec![grid.node_ground_normal(node.i)]
    };
    normals.into_iter().map(|n| Boundary::new(n, Friction::Coulomb { mu: 0.0 }).unwrap()).collect()
}

/// the deepest any particle of the two columns beside the kink ends below the ground over the
/// sweep (m; ≤ 0 when none does), for a ground of slopes `s1` then `s2` with the kink at x = 2.
fn deepest(s1: f64, s2: f64, both: bool) -> f64 {
    let grid = TerrainGrid::new(TerrainGridSpec {
        profile: vec![
            Vector::new(0.0, 0.0),
            Vector::new(2.0, 2.0 * s1),
            Vector::new(4.0, 2.0 * (s1 + s2)),
        ],
        cell_width: 1.0,
        row_height: 0.5,
        rows: 4,
        kink_policy: KinkPolicy::Reject,
    })
    .unwrap();
    // Each node moves at most 0.4 of a column: Δt |v*| = 0.4 m on the ground, half of it on the
    // row above (under the 0.5 m row height, so that row stays above the ground).
    let dt = 0.4;
    let mut worst = f64::NEG_INFINITY;
    for k in 0..24 {
        let angle = std::f64::consts::TAU * k as f64 / 24.0;
        let trial = Vector::new(angle.cos(), angle.sin());
        let velocity = |node: NodeId| {
            if node.j == 0 {
                constrain_velocity_all(&planes(&grid, node, both), trial)
            } else {
                0.5 * trial
            }
        };
        for i in [1, 2] {
            let corners = [(i, 0), (i + 1, 0), (i, 1), (i + 1, 1)].map(|(i, j)| NodeId::new(i, j));
            let moved = corners.map(|n| grid.node_position(n) + dt * velocity(n));
            for a in 0..=10 {
                for b in 0..=10 {
                    let (xi, eta) = (-1.0 + 0.2 * f64::from(a), -1.0 + 0.2 * f64::from(b));
                    let w = [
                        0.25 * (1.0 - xi) * (1.0 - eta),
                        0.25 * (1.0 + xi) * (1.0 - eta),
                        0.25 * (1.0 - xi) * (1.0 + eta),
                        0.25 * (1.0 + xi) * (1.0 + eta),
                    ];
                    let cell = CellCoords { cell: NodeId::new(i, 0), xi, eta };
                    assert!(
                        grid.position(cell).y
                            >= grid.ground_height(grid.position(cell).x).unwrap() - 1e-12
                    );
                    let p = (0..4).fold(Vector::ZERO, |acc, c| acc + w[c] * moved[c]);
                    worst = worst.max(grid.ground_height(p.x).unwrap() - p.y);
                }
            }
        }
    }
    worst
}

const SLOPES: [f64; 5] = [-0.8, -0.3, 0.0, 0.4, 0.9];

#[test]
fn kink_nodes_held_on_both_segments_keep_every_particle_above_the_ground() {
    for s1 in SLOPES {
        for s2 in SLOPES.into_iter().filter(|&s| s != s1) {
            // round-off of positions of size ~10 m: 1e-12 m
            let d = deepest(s1, s2, true);
            assert!(d <= 1e-12, "slopes {s1} then {s2}: a particle ends {d} m below the ground");
        }
    }
}

/// Why both planes: the bisector lets a particle through at every kink of the sweep, concave
/// (slope increasing, the ground bending up) and convex alike.
#[test]
fn a_kink_node_held_to_the_bisector_lets_particles_below_the_ground() {
    for s1 in SLOPES {
        for s2 in SLOPES.into_iter().filter(|&s| s != s1) {
            let d = deepest(s1, s2, false);
            // at least half the depth the kink node itself reaches below the next segment's
            // line (Δt |v| sin(Δθ/2) with Δt |v| = 0.4 m): the particles near it go that deep
            let half_turn = 0.5 * (s2.atan() - s1.atan()).abs();
            assert!(d > 0.5 * 0.4 * half_turn.sin(), "slopes {s1} then {s2}: deepest {d} m");
        }
    }
}
