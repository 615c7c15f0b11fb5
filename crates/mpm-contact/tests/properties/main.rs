//! Property tests of the contact law (seeded, deterministic): invariance under rotation, energy,
//! constraint satisfaction, untouched separating nodes, agreement with the paper's acceleration form,
//! and the corner rule against a brute-force projection.

#[path = "../common/mod.rs"]
mod common;

use std::f64::consts::TAU;

use mpm_contact::{
    Boundary, ContactOutcome, ContactStatus, Friction, Vector, apply_all, constrain_velocity_all,
};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

use common::{paper_acceleration_form, project_onto_cone, unit};

/// Relative tolerance for quantities that agree in exact arithmetic and differ only by the rounding of
/// a few dozen operations (rotating the inputs, decomposing into (n, t)): ~1e-15 each, so 1e-12 leaves
/// three orders of margin. Applied to the natural scale of each quantity (see `Scales`).
const REL: f64 = 1e-12;

/// Nodes per property: enough to hit every branch (separating, sliding, sticking, fixed, corners)
/// hundreds of times, and still a fraction of a second per property.
const CASES: u32 = 4096;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: CASES,
        // Deterministic: the same inputs on every run and machine.
        rng_seed: RngSeed::Fixed(0x6d70_6d5f_636f_6e74),
        // About half of random nodes separate; properties about nodes in contact skip those.
        max_global_rejects: 4 * CASES,
        ..ProptestConfig::default()
    }
}

/// One node's state for one step.
#[derive(Clone, Copy, Debug)]
struct Node {
    mass: f64,
    v: Vector,
    a: Vector,
    dt: f64,
}

/// The scales against which differences are judged.
struct Scales {
    /// m/s: |v| + |a| Δt.
    velocity: f64,
    /// m/s²: |a| + |v|/Δt (a^c carries −v_n/Δt).
    acceleration: f64,
    /// J: m (velocity scale)².
    work: f64,
    /// N·s: m (velocity scale).
    impulse: f64,
}

impl Node {
    fn trial(&self) -> Vector {
        self.v + self.a * self.dt
    }

    fn scales(&self) -> Scales {
        let velocity = self.v.length() + self.a.length() * self.dt;
        Scales {
            velocity,
            acceleration: self.a.length() + self.v.length() / self.dt,
            work: self.mass * velocity * velocity,
            impulse: self.mass * velocity,
        }
    }

    fn rotated(&self, r: Vector) -> Node {
        Node { v: r.rotate(self.v), a: r.rotate(self.a), ..*self }
    }
}

fn vector(scale: f64) -> impl Strategy<Value = Vector> {
    (-scale..scale, -scale..scale).prop_map(|(x, y)| Vector::new(x, y))
}

fn node() -> impl Strategy<Value = Node> {
    (1e-3..10.0f64, vector(10.0), vector(100.0), 1e-4..1e-2f64).prop_map(|(mass, v, a, dt)| Node {
        mass,
        v,
        a,
        dt,
    })
}

fn coulomb_mu() -> impl Strategy<Value = f64> {
    prop_oneof![4 => 0.0..2.0f64, 1 => Just(0.0)]
}

fn friction() -> impl Strategy<Value = Friction> {
    prop_oneof![
        5 => coulomb_mu().prop_map(|mu| Friction::Coulomb { mu }),
        1 => Just(Friction::Rough),
        1 => Just(Friction::Fixed),
    ]
}

fn boundary() -> impl Strategy<Value = Boundary> {
    (0.0..TAU, friction()).prop_map(|(angle, f)| Boundary::new(unit(angle), f).unwrap())
}

/// two boundaries without `Fixed` (which would decide alone).
fn corner() -> impl Strategy<Value = [Boundary; 2]> {
    (0.0..TAU, coulomb_mu(), 0.0..TAU, coulomb_mu()).prop_map(|(a0, mu0, a1, mu1)| {
        [
            Boundary::new(unit(a0), Friction::Coulomb { mu: mu0 }).unwrap(),
            Boundary::new(unit(a1), Friction::Coulomb { mu: mu1 }).unwrap(),
        ]
    })
}

fn rotate_boundary(b: &Boundary, r: Vector) -> Boundary {
    Boundary::new(r.rotate(b.normal()), b.friction()).unwrap()
}

fn frictionless(b: &Boundary) -> Boundary {
    Boundary::new(b.normal(), Friction::Coulomb { mu: 0.0 }).unwrap()
}

fn kinetic(mass: f64, v: Vector) -> f64 {
    0.5 * mass * v.length_squared()
}

/// `out` (computed in the rotated frame) equals `reference` rotated by `r`, statuses aside.
fn assert_rotated(out: &ContactOutcome, reference: &ContactOutcome, r: Vector, s: &Scales) {
    let dv = (out.velocity - r.rotate(reference.velocity)).length();
    let da = (out.acceleration - r.rotate(reference.acceleration)).length();
    let dp = (out.impulse - r.rotate(reference.impulse)).length();
    assert!(dv <= REL * s.velocity, "velocity off by {dv}");
    assert!(da <= REL * s.acceleration, "acceleration off by {da}");
    assert!(dp <= REL * s.impulse, "impulse off by {dp}");
    assert!((out.friction_work - reference.friction_work).abs() <= REL * s.work);
    assert!((out.normal_work - reference.normal_work).abs() <= REL * s.work);
}

/// the energy statements every outcome must satisfy: works ≥ 0, summing to the kinetic energy removed
/// from the trial state, and v^L = v + a^c Δt.
fn assert_energy_and_consistency(out: &ContactOutcome, node: &Node) {
    let s = node.scales();
    assert!(out.friction_work >= 0.0 && out.normal_work >= 0.0, "{out:?}");
    let removed = kinetic(node.mass, node.trial()) - kinetic(node.mass, out.velocity);
    assert!(
        (out.friction_work + out.normal_work - removed).abs() <= REL * s.work,
        "works {} + {} vs removed {removed}",
        out.friction_work,
        out.normal_work
    );
    let end = node.v + out.acceleration * node.dt;
    assert!(
        (end - out.velocity).length() <= REL * s.velocity,
        "v + a^c Δt = {end} vs {}",
        out.velocity
    );
    let impulse = node.mass * (out.velocity - node.trial());
    assert!((out.impulse - impulse).length() <= REL * s.impulse);
}

/// a margin, relative to the velocity scale, from every switching threshold of the single-boundary law
/// (pressing, stick/slip), so that rounding cannot flip the status.
fn clear_of_thresholds(b: &Boundary, node: &Node) -> bool {
    let trial = node.trial();
    let (vn, vt) = (trial.dot(b.normal()), trial.dot(b.tangent()));
    let margin = 1e-9 * node.scales().velocity;
    let capacity = match b.friction() {
        Friction::Coulomb { mu } => mu * -vn,
        _ => f64::INFINITY,
    };
    vn.abs() > margin && (vt.abs() - capacity).abs() > margin
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn rotating_the_whole_problem_rotates_the_result(b in boundary(), node in node(), angle in 0.0..TAU) {
        let r = unit(angle);
        let reference = b.apply(node.mass, node.v, node.a, node.dt);
        let turned = node.rotated(r);
        let out = rotate_boundary(&b, r).apply(turned.mass, turned.v, turned.a, turned.dt);
        assert_rotated(&out, &reference, r, &node.scales());
        if clear_of_thresholds(&b, &node) {
            prop_assert_eq!(out.status, reference.status);
        }
        let cv = rotate_boundary(&b, r).constrain_velocity(turned.v);
        prop_assert!((cv - r.rotate(b.constrain_velocity(node.v))).length() <= REL * node.v.length());
    }

    #[test]
    fn rotating_a_corner_rotates_the_result(walls in corner(), node in node(), angle in 0.0..TAU) {
        let r = unit(angle);
        let reference = apply_all(&walls, node.mass, node.v, node.a, node.dt);
        let turned = node.rotated(r);
        let turned_walls = [rotate_boundary(&walls[0], r), rotate_boundary(&walls[1], r)];
        let out = apply_all(&turned_walls, turned.mass, turned.v, turned.a, turned.dt);
        assert_rotated(&out, &reference, r, &node.scales());
    }

    #[test]
    fn friction_never_increases_kinetic_energy_and_its_work_is_non_negative(
        normal_angle in 0.0..TAU, mu in 0.0..2.0f64, node in node()
    ) {
        let b = Boundary::new(unit(normal_angle), Friction::Coulomb { mu }).unwrap();
        let with = b.apply(node.mass, node.v, node.a, node.dt);
        let without = frictionless(&b).apply(node.mass, node.v, node.a, node.dt);
        let s = node.scales();
        prop_assert!(with.friction_work >= 0.0);
        prop_assert!(kinetic(node.mass, with.velocity) <= kinetic(node.mass, without.velocity) + REL * s.work);
        // Friction does not change the normal part, and its work is exactly the energy it removes
        // from the frictionless result.
        prop_assert_eq!(with.normal_work, without.normal_work);
        prop_assert_eq!(without.friction_work, 0.0);
        let removed = kinetic(node.mass, without.velocity) - kinetic(node.mass, with.velocity);
        prop_assert!((with.friction_work - removed).abs() <= REL * s.work);
    }

    #[test]
    fn works_are_non_negative_and_close_the_kinetic_energy_balance(b in boundary(), walls in corner(), node in node()) {
        assert_energy_and_consistency(&b.apply(node.mass, node.v, node.a, node.dt), &node);
        assert_energy_and_consistency(&apply_all(&walls, node.mass, node.v, node.a, node.dt), &node);
        assert_energy_and_consistency(&apply_all(&[walls[0], b], node.mass, node.v, node.a, node.dt), &node);
    }

    #[test]
    fn normal_velocity_of_a_node_in_contact_is_zero_after_the_step(b in boundary(), walls in corner(), node in node()) {
        let out = b.apply(node.mass, node.v, node.a, node.dt);
        if out.status != ContactStatus::Separating {
            // v^L = (v^L·t) t: its normal component is one rounding of |v^L|.
            prop_assert!(out.velocity.dot(b.normal()).abs() <= 4.0 * f64::EPSILON * out.velocity.length());
        }
        // In a corner the end velocity is admissible for every boundary.
        let out = apply_all(&walls, node.mass, node.v, node.a, node.dt);
        for w in &walls {
            prop_assert!(out.velocity.dot(w.normal()) >= -REL * node.scales().velocity);
        }
        let cv = constrain_velocity_all(&walls, node.v);
        for w in &walls {
            prop_assert!(cv.dot(w.normal()) >= -REL * node.v.length());
        }
    }

    #[test]
    fn separating_nodes_are_unchanged(
        angle in 0.0..TAU, friction in coulomb_mu().prop_map(|mu| Friction::Coulomb { mu }),
        rough in any::<bool>(), vn in -10.0..10.0f64, vt in -10.0..10.0f64, at in -100.0..100.0f64,
        away in 1e-6..10.0f64, dt in 1e-4..1e-2f64, mass in 1e-3..10.0f64,
    ) {
        let friction = if rough { Friction::Rough } else { friction };
        let b = Boundary::new(unit(angle), friction).unwrap();
        let (n, t) = (b.normal(), b.tangent());
        // Trial normal velocity `away` > 0: the node leaves the boundary.
        let (v, a) = (vn * n + vt * t, ((away - vn) / dt) * n + at * t);
        prop_assume!((v + a * dt).dot(n) > 0.0);
        let out = b.apply(mass, v, a, dt);
        prop_assert_eq!(out.status, ContactStatus::Separating);
        prop_assert_eq!(out.acceleration, a);
        prop_assert_eq!(out.velocity, v + a * dt);
        prop_assert_eq!((out.friction_work, out.normal_work), (0.0, 0.0));
        prop_assert_eq!(out.impulse, Vector::ZERO);
        prop_assert_eq!(b.constrain_velocity(v + a * dt), v + a * dt);
    }

    #[test]
    fn friction_never_reverses_and_sticks_exactly_within_its_capacity(
        normal_angle in 0.0..TAU, mu in 0.0..2.0f64, node in node()
    ) {
        let b = Boundary::new(unit(normal_angle), Friction::Coulomb { mu }).unwrap();
        let out = b.apply(node.mass, node.v, node.a, node.dt);
        prop_assume!(out.status != ContactStatus::Separating);
        let trial = node.trial();
        let (vn, vt) = (trial.dot(b.normal()), trial.dot(b.tangent()));
        let vt_end = out.velocity.dot(b.tangent());
        prop_assert!(vt_end * vt >= 0.0, "reversed: {vt} -> {vt_end}");
        prop_assert!(vt_end.abs() <= vt.abs());
        if vt.abs() <= mu * -vn {
            prop_assert_eq!(out.status, ContactStatus::Sticking);
            prop_assert_eq!(out.velocity, Vector::ZERO);
        } else {
            prop_assert_eq!(out.status, ContactStatus::Sliding);
            prop_assert!((vt.abs() - vt_end.abs() - mu * -vn).abs() <= REL * node.scales().velocity);
        }
    }

    #[test]
    fn a_node_at_rest_stays_at_rest_while_friction_can_hold_it(
        normal_angle in 0.0..TAU, mu in 0.0..2.0f64, an in -100.0..-1e-6f64, at in -100.0..100.0f64,
        dt in 1e-4..1e-2f64,
    ) {
        let b = Boundary::new(unit(normal_angle), Friction::Coulomb { mu }).unwrap();
        // Pressed on the boundary (a_n < 0) from rest.
        let a = an * b.normal() + at * b.tangent();
        let (an, at) = (a.dot(b.normal()), a.dot(b.tangent()));
        let out = b.apply(1.0, Vector::ZERO, a, dt);
        if at.abs() <= mu * -an * (1.0 - 1e-12) {
            prop_assert_eq!(out.status, ContactStatus::Sticking);
            prop_assert_eq!(out.velocity, Vector::ZERO);
            prop_assert_eq!(out.acceleration, Vector::ZERO);
        } else if at.abs() > mu * -an * (1.0 + 1e-12) {
            prop_assert_eq!(out.status, ContactStatus::Sliding);
        }
    }

    #[test]
    fn trial_velocity_and_trial_acceleration_criteria_coincide_at_rest_normally(
        b in boundary(), vt in -10.0..10.0f64, a in vector(100.0), dt in 1e-4..1e-2f64
    ) {
        prop_assume!(b.friction() != Friction::Fixed);
        // v·n = 0 up to the rounding of vt·t; |a_n| Δt far above that.
        let v = vt * b.tangent();
        let an = a.dot(b.normal());
        prop_assume!(an.abs() * dt > 1e-9);
        let out = b.apply(1.0, v, a, dt);
        prop_assert_eq!(out.status != ContactStatus::Separating, an < 0.0);
    }

    #[test]
    fn impulse_form_matches_the_acceleration_form_where_both_apply(
        normal_angle in 0.0..TAU, mu in 0.0..2.0f64,
        vt in prop_oneof![1 => Just(0.0), 3 => -10.0..10.0f64], a in vector(100.0), dt in 1e-4..1e-2f64,
    ) {
        let b = Boundary::new(unit(normal_angle), Friction::Coulomb { mu }).unwrap();
        let v = vt * b.tangent();
        let node = Node { mass: 1.0, v, a, dt };
        let vt_trial = node.trial().dot(b.tangent());
        // The forms differ only when the applied tangential acceleration alone reverses v_t.
        prop_assume!(vt == 0.0 || vt * vt_trial > 0.0);
        let out = b.apply(1.0, v, a, dt);
        let (a_ref, v_ref) = paper_acceleration_form(b.normal(), mu, v, a, dt);
        let s = node.scales();
        prop_assert!((out.acceleration - a_ref).length() <= REL * s.acceleration, "{} vs {a_ref}", out.acceleration);
        prop_assert!((out.velocity - v_ref).length() <= REL * s.velocity, "{} vs {v_ref}", out.velocity);
    }

    #[test]
    fn constrain_velocity_is_the_step_law_of_a_roller_without_force(b in boundary(), v in vector(10.0)) {
        let cv = b.constrain_velocity(v);
        match b.friction() {
            Friction::Coulomb { .. } => {
                let reference = frictionless(&b).apply(1.0, v, Vector::ZERO, 1e-3).velocity;
                prop_assert!((cv - reference).length() <= REL * v.length());
            }
            Friction::Rough => {
                prop_assert_eq!(cv, if v.dot(b.normal()) < 0.0 { Vector::ZERO } else { v });
            }
            Friction::Fixed => prop_assert_eq!(cv, Vector::ZERO),
        }
        // Idempotent: a constrained velocity is admissible.
        prop_assert!((b.constrain_velocity(cv) - cv).length() <= REL * v.length());
    }

    #[test]
    fn frictionless_corner_is_the_projection_onto_the_admissible_cone(
        angles in (0.0..TAU, 0.0..TAU), node in node()
    ) {
        let walls = [
            Boundary::new(unit(angles.0), Friction::Coulomb { mu: 0.0 }).unwrap(),
            Boundary::new(unit(angles.1), Friction::Coulomb { mu: 0.0 }).unwrap(),
        ];
        let normals = [walls[0].normal(), walls[1].normal()];
        let out = apply_all(&walls, node.mass, node.v, node.a, node.dt);
        let reference = project_onto_cone(&normals, node.trial());
        prop_assert!((out.velocity - reference).length() <= REL * node.scales().velocity, "{} vs {reference}", out.velocity);
        let cv = constrain_velocity_all(&walls, node.v);
        prop_assert!((cv - project_onto_cone(&normals, node.v)).length() <= REL * node.v.length());
    }

    #[test]
    fn friction_in_a_corner_never_increases_kinetic_energy(walls in corner(), node in node()) {
        let with = apply_all(&walls, node.mass, node.v, node.a, node.dt);
        let without = apply_all(&[frictionless(&walls[0]), frictionless(&walls[1])], node.mass, node.v, node.a, node.dt);
        prop_assert!(kinetic(node.mass, with.velocity) <= kinetic(node.mass, without.velocity) + REL * node.scales().work);
    }

    #[test]
    fn one_boundary_through_apply_all_is_apply(b in boundary(), node in node()) {
        prop_assert_eq!(apply_all(&[b], node.mass, node.v, node.a, node.dt), b.apply(node.mass, node.v, node.a, node.dt));
        prop_assert_eq!(constrain_velocity_all(&[b], node.v), b.constrain_velocity(node.v));
    }
}
