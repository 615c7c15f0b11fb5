//! The crate's impulse form against the paper's acceleration form (eqs 14–17) on the analytic cases,
//! and the one situation where they differ.

use mpm_contact::{Boundary, Friction, Vector};

use crate::common::{G, gravity, paper_acceleration_form, unit};

/// Absolute tolerance on accelerations, m/s². Both forms compute a_t − sign μ|a_n| from the same
/// products, to ~1e-15 g; but a rotated velocity is tangent only to rounding, v_n ~ 1e-16 |v|, which the
/// impulse form removes as a^c_n = −v_n/Δt: 16 ε · 10 m/s / 1 ms ≈ 4e-11.
const ACCEL_TOLERANCE: f64 = 16.0 * f64::EPSILON * 10.0 / DT;

/// Absolute tolerance on velocities, m/s (velocities up to 10 m/s, so ~1e-15 rounding).
const VELOCITY_TOLERANCE: f64 = 1e-13;

const DT: f64 = 1e-3;

/// both forms on one case: returns the largest differences (acceleration, velocity).
fn compare(normal: Vector, mu: f64, v: Vector, a: Vector) -> (f64, f64) {
    let b = Boundary::new(normal, Friction::Coulomb { mu }).unwrap();
    let out = b.apply(1.0, v, a, DT);
    let (a_ref, v_ref) = paper_acceleration_form(b.normal(), mu, v, a, DT);
    ((out.acceleration - a_ref).length(), (out.velocity - v_ref).length())
}

#[test]
fn impulse_form_reproduces_the_acceleration_form_on_the_analytic_cases() {
    let th = 30f64.to_radians();
    let slope_n = Vector::new(-th.sin(), th.cos());
    let down = Vector::new(-th.cos(), -th.sin());
    let cases = [
        // horizontal sliding, both directions, and the overshoot that must end at zero
        (Vector::Y, 0.3, Vector::new(10.0, 0.0)),
        (Vector::Y, 0.3, Vector::new(-10.0, 0.0)),
        (Vector::Y, 0.3, Vector::new(1e-3, 0.0)),
        // slope from rest and sliding down, μ below and above tanθ
        (slope_n, 0.3, Vector::ZERO),
        (slope_n, 0.3, 2.0 * down),
        (slope_n, 0.8, Vector::ZERO),
        (slope_n, 0.8, 2.0 * down),
        (slope_n, 0.8, 1e-3 * down),
        // frictionless roller
        (slope_n, 0.0, Vector::ZERO),
    ];
    for (n, mu, v) in cases {
        let (da, dv) = compare(n, mu, v, gravity());
        assert!(
            da <= ACCEL_TOLERANCE && dv <= VELOCITY_TOLERANCE,
            "n = {n}, μ = {mu}, v = {v}: {da}, {dv}"
        );
    }
    // The same on rotated copies of the whole problem (gravity rotated too).
    for k in 0..12 {
        let r = unit(k as f64 * std::f64::consts::FRAC_PI_6 + 0.1);
        for (n, mu, v) in cases {
            let (da, dv) = compare(r.rotate(n), mu, r.rotate(v), r.rotate(gravity()));
            assert!(
                da <= ACCEL_TOLERANCE && dv <= VELOCITY_TOLERANCE,
                "rotated by {r}: {da}, {dv}"
            );
        }
    }
}

#[test]
fn the_forms_differ_only_when_gravity_reverses_the_velocity_within_one_step() {
    // Moving up a steep slope slowly: gravity alone reverses v_t within the step. The acceleration form
    // stops the node; the impulse form lets it start back down at the reduced rate. The exact answer
    // for a constant force lies between; the gap is below (g sinθ + μ g cosθ) Δt, first order in Δt.
    let th = 60f64.to_radians();
    let mu = 0.2;
    let n = Vector::new(-th.sin(), th.cos());
    let up = Vector::new(th.cos(), th.sin());
    for dt in [1e-2, 1e-3, 1e-4] {
        let v = 0.5 * G * th.sin() * dt * up;
        let b = Boundary::new(n, Friction::Coulomb { mu }).unwrap();
        let out = b.apply(1.0, v, gravity(), dt);
        let (_, v_ref) = paper_acceleration_form(n, mu, v, gravity(), dt);
        assert_eq!(v_ref, Vector::ZERO);
        assert!(out.velocity.dot(up) < 0.0);
        let gap = (out.velocity - v_ref).length();
        assert!(gap <= G * (th.sin() + mu * th.cos()) * dt, "dt = {dt}: gap {gap}");
    }
}
