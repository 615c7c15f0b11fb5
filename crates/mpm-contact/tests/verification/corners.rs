//! Nodes on two boundaries: a box corner, a wall meeting the ground, a kink of the ground profile.

use mpm_contact::{
    Boundary, Carriers, ContactOutcome, ContactStatus, Friction, Vector, apply_all,
    constrain_velocity_all,
};

use crate::common::{G, gravity, project_onto_cone};

/// Relative tolerance (times the speed) for results exact up to a few roundings.
const ROUNDING: f64 = 16.0 * f64::EPSILON;

const DT: f64 = 1e-3;
const MASS: f64 = 2.0;

fn coulomb(normal: Vector, mu: f64) -> Boundary {
    Boundary::new(normal, Friction::Coulomb { mu }).unwrap()
}

#[test]
fn box_corner_stops_a_node_pressing_into_both_walls() {
    // Floor (n = +y) and left wall (n = +x): the material fills the quadrant x > 0, y > 0.
    let walls = [coulomb(Vector::Y, 0.3), coulomb(Vector::X, 0.3)];
    let v = Vector::new(-2.0, -1.0);
    let out = apply_all(&walls, MASS, v, gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sticking);
    assert_eq!(out.velocity, Vector::ZERO);
    assert_eq!(out.acceleration, -v / DT);
    let trial = v + gravity() * DT;
    assert!((out.normal_work - 0.5 * MASS * trial.length_squared()).abs() <= ROUNDING * 10.0);
    assert_eq!(out.friction_work, 0.0);
    assert_eq!(constrain_velocity_all(&walls, v), Vector::ZERO);
}

#[test]
fn box_corner_lets_a_node_slide_away_from_the_wall_along_the_floor() {
    let walls = [coulomb(Vector::Y, 0.3), coulomb(Vector::X, 0.3)];
    let v = Vector::new(2.0, 0.0);
    let out = apply_all(&walls, MASS, v, gravity(), DT);
    // Exactly the floor alone: the wall is not pressed and the floor's result does not enter it.
    assert_eq!(out, walls[0].apply(MASS, v, gravity(), DT));
    assert_eq!(out.status, ContactStatus::Sliding);
    assert!((out.acceleration.x + 0.3 * G).abs() <= ROUNDING * G);
    // Sliding into the wall instead: pinned.
    let out = apply_all(&walls, MASS, -v, gravity(), DT);
    assert_eq!(out.velocity, Vector::ZERO);
    // Falling straight down along the wall: only the floor is pressed, and it stops the node.
    let out = apply_all(&walls, MASS, Vector::new(0.0, -3.0), gravity(), DT);
    assert_eq!(out.velocity, Vector::ZERO);
}

#[test]
fn fast_node_crossing_a_gentle_kink_of_the_ground_keeps_sliding() {
    // A slope of 5° descending to the right meets flat ground: normals (sin5°, cos5°) and +y. A node at
    // the kink moving right at 10 m/s and down at 1.5 m/s presses on both, but sliding along
    // the flat takes it away from the slope: it must not stop (a crude "both pressed ⇒ stop" rule would).
    let th = 5f64.to_radians();
    let kink = [coulomb(Vector::new(th.sin(), th.cos()), 0.0), coulomb(Vector::Y, 0.0)];
    let v = Vector::new(10.0, -1.5);
    let trial = v + gravity() * DT;
    assert!(kink.iter().all(|b| trial.dot(b.normal()) < 0.0), "the node presses on both");
    let out = apply_all(&kink, MASS, v, gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sliding);
    // Frictionless: the exact projection of v* onto the admissible cone, i.e. (v*_x, 0).
    let reference = project_onto_cone(&[kink[0].normal(), kink[1].normal()], trial);
    assert!((out.velocity - reference).length() <= ROUNDING * trial.length());
    assert!((out.velocity - Vector::new(trial.x, 0.0)).length() <= ROUNDING * trial.length());
    // With friction it still slides, slowed by μ|v*_n| on the flat.
    let kink = [coulomb(kink[0].normal(), 0.3), coulomb(Vector::Y, 0.3)];
    let out = apply_all(&kink, MASS, v, gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sliding);
    assert!((out.velocity.x - (trial.x + 0.3 * trial.y)).abs() <= ROUNDING * 10.0);
}

#[test]
fn valley_between_two_slopes_is_the_exact_projection_when_frictionless() {
    // Two 40° slopes forming a V: a node at the bottom pushed down and sideways.
    let th = 40f64.to_radians();
    let valley = [
        coulomb(Vector::new(th.sin(), th.cos()), 0.0),
        coulomb(Vector::new(-th.sin(), th.cos()), 0.0),
    ];
    let normals = [valley[0].normal(), valley[1].normal()];
    for v in [
        Vector::new(3.0, -1.0),
        Vector::new(-3.0, -1.0),
        Vector::new(0.0, -1.0),
        Vector::new(5.0, 0.5),
        Vector::new(0.5, 4.0),
    ] {
        let out = apply_all(&valley, MASS, v, gravity(), DT);
        let trial = v + gravity() * DT;
        let reference = project_onto_cone(&normals, trial);
        assert!((out.velocity - reference).length() <= ROUNDING * trial.length(), "v = {v}");
        assert!(
            (constrain_velocity_all(&valley, v) - project_onto_cone(&normals, v)).length()
                <= ROUNDING * v.length()
        );
    }
}

#[test]
fn corner_result_does_not_depend_on_the_order_of_the_boundaries() {
    let th = 30f64.to_radians();
    let a = coulomb(Vector::new(th.sin(), th.cos()), 0.4);
    let b = Boundary::new(Vector::X, Friction::Rough).unwrap();
    for v in [
        Vector::new(3.0, -1.0),
        Vector::new(-3.0, -1.0),
        Vector::new(1.0, 1.0),
        Vector::new(-0.1, -5.0),
    ] {
        let ab = apply_all(&[a, b], MASS, v, gravity(), DT);
        let ba = apply_all(&[b, a], MASS, v, gravity(), DT);
        let bare = |o: ContactOutcome| ContactOutcome { carriers: Carriers::None, ..o };
        assert_eq!(bare(ab), bare(ba));
        // the same boundary carried it: its index mirrored in the other order
        let mirrored = match ba.carriers {
            Carriers::One(k) => Carriers::One(1 - k),
            other => other,
        };
        assert_eq!(ab.carriers, mirrored, "v = {v}");
    }
}

#[test]
fn fixed_boundary_in_a_corner_fixes_the_node() {
    let walls = [coulomb(Vector::Y, 0.3), Boundary::new(Vector::X, Friction::Fixed).unwrap()];
    let out = apply_all(&walls, MASS, Vector::new(2.0, 3.0), gravity(), DT);
    assert_eq!(out.status, ContactStatus::Fixed);
    assert_eq!(out.velocity, Vector::ZERO);
    assert_eq!(constrain_velocity_all(&walls, Vector::new(2.0, 3.0)), Vector::ZERO);
}

#[test]
fn no_boundary_leaves_the_node_untouched_and_one_boundary_is_apply() {
    let v = Vector::new(1.0, -2.0);
    let out = apply_all(&[], MASS, v, gravity(), DT);
    assert_eq!(out.status, ContactStatus::Separating);
    assert_eq!(out.velocity, v + gravity() * DT);
    assert_eq!(constrain_velocity_all(&[], v), v);
    let b = coulomb(Vector::new(0.6, 0.8), 0.25);
    assert_eq!(apply_all(&[b], MASS, v, gravity(), DT), b.apply(MASS, v, gravity(), DT));
    assert_eq!(constrain_velocity_all(&[b], v), b.constrain_velocity(v));
}
