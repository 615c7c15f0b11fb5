//! One node, one step, analytic answers: the rigid block of Abe et al. (2005) §5 reduced to a node.

use mpm_contact::{Boundary, ContactStatus, Friction, Vector};

use crate::common::{G, gravity};

/// Relative tolerance for results that are exact up to the rounding of a handful of products and sums
/// (the decomposition into (n, t) and back): 16 ulps.
const ROUNDING: f64 = 16.0 * f64::EPSILON;

/// Time step of the one-step tests, s (any positive value works; 1 ms is the solver's typical size).
const DT: f64 = 1e-3;

/// Nodal mass, kg.
const MASS: f64 = 2.5;

fn close(actual: f64, expected: f64, scale: f64) -> bool {
    (actual - expected).abs() <= ROUNDING * scale
}

fn ground(mu: f64) -> Boundary {
    Boundary::new(Vector::Y, Friction::Coulomb { mu }).unwrap()
}

/// a slope of `theta_deg` rising to the right: n = (−sinθ, cosθ), up-slope tangent (cosθ, sinθ).
fn slope(theta_deg: f64, friction: Friction) -> Boundary {
    let th = theta_deg.to_radians();
    Boundary::new(Vector::new(-th.sin(), th.cos()), friction).unwrap()
}

#[test]
fn abe2005_horizontal_sliding_decelerates_at_exactly_mu_g() {
    let mu = 0.3;
    for v0 in [10.0, -10.0, 0.5, -3.0] {
        let out = ground(mu).apply(MASS, Vector::new(v0, 0.0), gravity(), DT);
        let decel = -f64::signum(v0) * mu * G;
        // The deceleration is computed as a_t − sign(v*_t) μ r with r = −a_n = g exactly: bit-exact.
        assert_eq!(out.acceleration, Vector::new(decel, 0.0), "v0 = {v0}");
        assert_eq!(out.status, ContactStatus::Sliding);
        assert!(close(out.velocity.x, v0 + decel * DT, v0.abs()));
        assert_eq!(out.velocity.y, 0.0);
        // Work relative to the trial state (v0, −g Δt).
        let normal = 0.5 * MASS * (G * DT).powi(2);
        let friction = 0.5 * MASS * (v0 * v0 - out.velocity.x.powi(2));
        assert!(close(out.normal_work, normal, normal));
        assert!(close(out.friction_work, friction, 0.5 * MASS * v0 * v0));
        // The boundary's impulse is the reaction (μ m g, m g) Δt, pointing against the motion and up.
        assert!(close(out.impulse.x, MASS * decel * DT, MASS * G * DT));
        assert!(close(out.impulse.y, MASS * G * DT, MASS * G * DT));
    }
}

#[test]
fn abe2005_slope_with_mu_below_tan_theta_accelerates_at_g_sin_minus_mu_cos() {
    // SPEC §6: θ = 30°, μ = 0.3 gives 2.356 m/s² along the slope (printed to 4 digits).
    let out = slope(30.0, Friction::Coulomb { mu: 0.3 }).apply(MASS, Vector::ZERO, gravity(), DT);
    assert!((out.acceleration.length() - 2.356).abs() < 5e-4);
    for (theta_deg, mu) in [(30.0, 0.3), (10.0, 0.1), (45.0, 0.9), (60.0, 1.5), (30.0, 0.0)] {
        let th: f64 = f64::to_radians(theta_deg);
        assert!(mu < th.tan());
        let b = slope(theta_deg, Friction::Coulomb { mu });
        let expected = G * (th.sin() - mu * th.cos());
        let downslope = -b.tangent();
        // From rest (the sticking branch breaks loose) and already sliding down (the sliding branch):
        // both give the same acceleration.
        for v in [Vector::ZERO, 1.7 * downslope] {
            let out = b.apply(MASS, v, gravity(), DT);
            assert_eq!(out.status, ContactStatus::Sliding, "θ = {theta_deg}, μ = {mu}");
            assert!(close(out.acceleration.dot(downslope), expected, G));
            // a^c_n = −v_n/Δt also removes the rounding-level normal velocity of 1.7·downslope.
            assert!(out.acceleration.dot(b.normal()).abs() <= ROUNDING * (G + v.length() / DT));
            assert!(close(out.velocity.dot(downslope), v.length() + expected * DT, 2.0));
            // v^L = (v^L·t) t, whose dot with n is zero up to one rounding of each product.
            assert!(out.velocity.dot(b.normal()).abs() <= ROUNDING * out.velocity.length());
        }
    }
}

#[test]
fn abe2005_slope_with_mu_at_least_tan_theta_stays_at_rest() {
    let th: f64 = 30f64.to_radians();
    let frictions = [
        // Just above tanθ: μ = tanθ itself is a knife edge that f64 may resolve either way (below).
        Friction::Coulomb { mu: th.tan() * (1.0 + 1e-12) },
        Friction::Coulomb { mu: 0.7 },
        Friction::Coulomb { mu: 3.0 },
        Friction::Rough,
    ];
    for friction in frictions {
        let b = slope(30.0, friction);
        let mut v = Vector::ZERO;
        for _ in 0..10_000 {
            let out = b.apply(MASS, v, gravity(), DT);
            assert_eq!(out.status, ContactStatus::Sticking, "{friction:?}");
            // Exactly at rest: a^c = −v/Δt = 0, v^L = 0.
            assert_eq!(out.acceleration, Vector::ZERO);
            assert_eq!(out.velocity, Vector::ZERO);
            // All of the trial velocity a Δt is removed, split into its normal and tangential parts.
            assert!(close(
                out.normal_work,
                0.5 * MASS * (G * th.cos() * DT).powi(2),
                0.5 * MASS * (G * DT).powi(2)
            ));
            assert!(close(
                out.friction_work,
                0.5 * MASS * (G * th.sin() * DT).powi(2),
                0.5 * MASS * (G * DT).powi(2)
            ));
            v = out.velocity;
        }
    }
}

#[test]
fn abe2005_slope_with_mu_equal_tan_theta_creeps_at_most_by_rounding() {
    // μ = tanθ: the exact answer is rest; in f64 tanθ·g cosθ and g sinθ may differ by an ulp, so the
    // node may break loose with an acceleration of order ulp(g).
    let th: f64 = 30f64.to_radians();
    let b = slope(30.0, Friction::Coulomb { mu: th.tan() });
    let out = b.apply(MASS, Vector::ZERO, gravity(), DT);
    assert!(out.acceleration.length() <= ROUNDING * G, "{:?}", out.acceleration);
}

#[test]
fn abe2005_overshoot_ends_at_exactly_zero_tangential_velocity() {
    let mu = 0.3;
    let capacity = mu * G * DT; // the largest speed friction can remove in one step
    for v0 in [0.1 * capacity, 0.999 * capacity, capacity, -0.5 * capacity] {
        let out = ground(mu).apply(MASS, Vector::new(v0, 0.0), gravity(), DT);
        assert_eq!(out.status, ContactStatus::Sticking, "v0 = {v0}");
        assert_eq!(out.velocity, Vector::ZERO);
        // The deceleration is the one that stops the node exactly: −v0/Δt, at most μg.
        assert_eq!(out.acceleration, Vector::new(-v0 / DT, 0.0));
        assert!(out.acceleration.x.abs() <= mu * G * (1.0 + ROUNDING));
        assert!(close(out.friction_work, 0.5 * MASS * v0 * v0, 0.5 * MASS * v0 * v0));
    }
    // Just above the capacity it slides on, with the sign of its velocity, by the excess.
    let v0 = 1.5 * capacity;
    let out = ground(mu).apply(MASS, Vector::new(v0, 0.0), gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sliding);
    assert!(close(out.velocity.x, 0.5 * capacity, capacity));
    // Moving up a slope with μ > tanθ and slowly: gravity and friction stop it, exactly.
    let b = slope(20.0, Friction::Coulomb { mu: 0.5 });
    let out = b.apply(MASS, 1e-3 * b.tangent(), gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sticking);
    assert_eq!(out.velocity, Vector::ZERO);
}

#[test]
fn separating_node_is_left_untouched() {
    // Pulled away from the ground (a_n > 0), or moving away faster than gravity pulls it back.
    let cases =
        [(Vector::new(3.0, 0.0), Vector::new(1.0, 5.0)), (Vector::new(3.0, 1.0), gravity())];
    for friction in [Friction::Coulomb { mu: 0.3 }, Friction::Rough] {
        let b = Boundary::new(Vector::Y, friction).unwrap();
        for (v, a) in cases {
            let out = b.apply(MASS, v, a, DT);
            assert_eq!(out.status, ContactStatus::Separating);
            assert_eq!(out.acceleration, a);
            assert_eq!(out.velocity, v + a * DT);
            assert_eq!((out.friction_work, out.normal_work), (0.0, 0.0));
            assert_eq!(out.impulse, Vector::ZERO);
        }
    }
}

#[test]
fn frictionless_roller_slides_at_g_sin_theta() {
    let th: f64 = 25f64.to_radians();
    let b = slope(25.0, Friction::Coulomb { mu: 0.0 });
    let out = b.apply(MASS, Vector::ZERO, gravity(), DT);
    assert!(close(out.acceleration.dot(-b.tangent()), G * th.sin(), G));
    assert_eq!(out.friction_work, 0.0);
}

#[test]
fn rough_boundary_stops_a_pressing_node_and_fixed_stops_every_node() {
    let rough = Boundary::new(Vector::Y, Friction::Rough).unwrap();
    let out = rough.apply(MASS, Vector::new(4.0, -1.0), gravity(), DT);
    assert_eq!(out.status, ContactStatus::Sticking);
    assert_eq!(out.velocity, Vector::ZERO);
    assert_eq!(out.acceleration, Vector::new(-4.0, 1.0) / DT);

    let fixed = Boundary::new(Vector::Y, Friction::Fixed).unwrap();
    // Even when pulled away from the boundary.
    let (v, a) = (Vector::new(4.0, 2.0), Vector::new(1.0, 30.0));
    let out = fixed.apply(MASS, v, a, DT);
    assert_eq!(out.status, ContactStatus::Fixed);
    assert_eq!(out.velocity, Vector::ZERO);
    assert_eq!(out.acceleration, -v / DT);
    let trial = v + a * DT;
    assert!(close(out.normal_work, 0.5 * MASS * trial.y * trial.y, MASS * trial.length_squared()));
    assert!(close(
        out.friction_work,
        0.5 * MASS * trial.x * trial.x,
        MASS * trial.length_squared()
    ));
}

#[test]
fn approaching_node_loses_its_normal_velocity_and_pays_friction_on_the_impact() {
    // A node arriving at the ground at 2 m/s (after particle-to-grid), no force: the trial acceleration
    // alone would say "no contact"; the trial velocity catches it.
    let mu = 0.3;
    let (v, a) = (Vector::new(1.0, -2.0), Vector::ZERO);
    let out = ground(mu).apply(MASS, v, a, DT);
    assert_eq!(out.status, ContactStatus::Sliding);
    assert_eq!(out.velocity.y, 0.0);
    // Friction impulse per unit mass μ|v*_n| = 0.6 m/s, against the motion.
    assert!(close(out.velocity.x, 1.0 - mu * 2.0, 1.0));
    assert!(close(out.normal_work, 0.5 * MASS * 4.0, MASS * 4.0));
    // a^c carries the impulse: v^L = v + a^c Δt.
    assert!((v + out.acceleration * DT - out.velocity).length() <= ROUNDING * 2.0);
}

#[test]
fn constrain_velocity_removes_only_an_inward_normal_velocity() {
    let v = Vector::new(3.0, -2.0);
    let coulomb = ground(0.5);
    assert_eq!(coulomb.constrain_velocity(v), Vector::new(3.0, 0.0));
    assert_eq!(coulomb.constrain_velocity(Vector::new(3.0, 2.0)), Vector::new(3.0, 2.0));
    let rough = Boundary::new(Vector::Y, Friction::Rough).unwrap();
    assert_eq!(rough.constrain_velocity(v), Vector::ZERO);
    assert_eq!(rough.constrain_velocity(Vector::new(3.0, 2.0)), Vector::new(3.0, 2.0));
    let fixed = Boundary::new(Vector::Y, Friction::Fixed).unwrap();
    assert_eq!(fixed.constrain_velocity(Vector::new(3.0, 2.0)), Vector::ZERO);
}
