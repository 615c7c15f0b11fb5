//! `apply` integrated over many steps: the single-node versions of Abe et al. (2005) §5(1) and §5(2).
//!
//! The node's position is advanced with the constrained end-of-step velocity, x ← x + v^L Δt, as the
//! solver moves particles (eq 6). On a linearly changing velocity that rule is a one-sided rectangle
//! rule, so positions carry an error of ½ |Δv/Δt| t Δt: first order in Δt, which the tests bound and
//! whose order they measure.

use mpm_contact::{Boundary, ContactStatus, Friction, Vector};

use crate::common::{G, gravity};

/// Nodal mass, kg.
const MASS: f64 = 1.0;

/// Relative tolerance on sums of per-step works over a few thousand steps: each term is exact to a few
/// ulps, and 10⁴ of them accumulate to well below 1e-10 of the total.
const WORK_SUM_TOLERANCE: f64 = 1e-10;

struct Slide {
    /// distance travelled when the node came to rest, m.
    distance: f64,
    /// time of the first step that ended at rest, s.
    stop_time: f64,
    /// positions after each step while still moving: (t, x).
    trajectory: Vec<(f64, f64)>,
    friction_work: f64,
    normal_work: f64,
    steps: usize,
}

/// a node sliding from `v0` on the ground with coefficient `mu`, stepped until 1 s after it stops.
fn slide_horizontal(v0: f64, mu: f64, dt: f64) -> Slide {
    let ground = Boundary::new(Vector::Y, Friction::Coulomb { mu }).unwrap();
    let (mut x, mut v) = (Vector::ZERO, Vector::new(v0, 0.0));
    let mut slide = Slide {
        distance: f64::NAN,
        stop_time: f64::NAN,
        trajectory: Vec::new(),
        friction_work: 0.0,
        normal_work: 0.0,
        steps: 0,
    };
    let budget = (2.0 * v0 / (mu * G) / dt) as usize + (1.0 / dt) as usize;
    for step in 1..=budget {
        let out = ground.apply(MASS, v, gravity(), dt);
        x += out.velocity * dt;
        v = out.velocity;
        slide.friction_work += out.friction_work;
        slide.normal_work += out.normal_work;
        slide.steps = step;
        assert_eq!(x.y, 0.0, "the node never leaves the ground");
        if v == Vector::ZERO {
            if slide.stop_time.is_nan() {
                slide.stop_time = step as f64 * dt;
                slide.distance = x.x;
            }
            // Once stopped, it stays stopped exactly.
            assert_eq!(out.status, ContactStatus::Sticking);
            assert_eq!(x.x, slide.distance);
        } else {
            assert!(v.x > 0.0, "friction never reverses the velocity");
            slide.trajectory.push((step as f64 * dt, x.x));
        }
    }
    slide
}

#[test]
fn abe2005_sliding_block_horizontal_single_node_stops_at_v0_squared_over_2_mu_g() {
    // SPEC §6: v0 = 10 m/s, μ = 0.3, g = 9.81: stops at t = v0/(μg) = 3.398 s after v0²/(2μg) = 16.99 m.
    let (v0, mu, dt) = (10.0, 0.3, 1e-3);
    let (distance, stop_time) = (v0 * v0 / (2.0 * mu * G), v0 / (mu * G));
    assert!((distance - 16.99).abs() < 5e-3 && (stop_time - 3.398).abs() < 5e-4);
    let slide = slide_horizontal(v0, mu, dt);
    // Position: one-sided rectangle rule, error v0 Δt/2 (derivation in the module doc).
    assert!((slide.distance - distance).abs() <= v0 * dt, "{} vs {distance}", slide.distance);
    // The first step that ends at rest is the step containing t = v0/(μg).
    assert!(slide.stop_time >= stop_time && slide.stop_time - stop_time <= dt);
    // Eq 21: x = v0 t − ½ μ g t² all the way.
    for &(t, x) in &slide.trajectory {
        assert!((x - (v0 * t - 0.5 * mu * G * t * t)).abs() <= v0 * dt, "t = {t}");
    }
    // All the kinetic energy went into friction work (the trial tangential velocity is v_t each step).
    let kinetic = 0.5 * MASS * v0 * v0;
    assert!((slide.friction_work - kinetic).abs() <= WORK_SUM_TOLERANCE * kinetic);
    // The normal constraint removed the trial velocity g Δt every step, moving or not.
    let normal = slide.steps as f64 * 0.5 * MASS * (G * dt).powi(2);
    assert!((slide.normal_work - normal).abs() <= WORK_SUM_TOLERANCE * normal);
    println!(
        "horizontal slide, dt = {dt}: stopped at {:.6} m (exact {distance:.6}), t = {:.4} s (exact {stop_time:.4})",
        slide.distance, slide.stop_time
    );
}

#[test]
fn abe2005_sliding_block_horizontal_single_node_converges_at_first_order() {
    let (v0, mu) = (10.0, 0.3);
    let exact = v0 * v0 / (2.0 * mu * G);
    let errors: Vec<f64> = [4e-3, 2e-3, 1e-3, 5e-4]
        .iter()
        .map(|&dt| (slide_horizontal(v0, mu, dt).distance - exact).abs())
        .collect();
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        // Error = v0 Δt/2 + O(Δt²): halving Δt halves it, up to the O(Δt²) remainder.
        assert!((ratio - 2.0).abs() < 0.1, "errors {errors:?}");
    }
    println!("horizontal slide distance errors for dt = 4, 2, 1, 0.5 ms: {errors:?}");
}

#[test]
fn abe2005_sliding_block_inclined_single_node_accelerates_at_g_sin_minus_mu_cos() {
    // SPEC §6: θ = 30°, μ = 0.3, from rest: a = g(sinθ − μcosθ) = 2.356 m/s² along the slope.
    let (theta, mu, dt) = (30f64.to_radians(), 0.3, 1e-3);
    let b =
        Boundary::new(Vector::new(-theta.sin(), theta.cos()), Friction::Coulomb { mu }).unwrap();
    let down = -b.tangent();
    let accel = G * (theta.sin() - mu * theta.cos());
    let (mut s, mut v) = (0.0, Vector::ZERO);
    let (mut friction_work, mut input, mut removed) = (0.0, 0.0, 0.0);
    let steps = 2000;
    for _ in 0..steps {
        let out = b.apply(MASS, v, gravity(), dt);
        assert_eq!(out.status, ContactStatus::Sliding);
        // The kinetic-energy balance of the node closes every step: ½m|v^L|² = ½m|v|² + input − works.
        let trial = v + gravity() * dt;
        let step_input = 0.5 * MASS * (trial.length_squared() - v.length_squared());
        let balance = 0.5 * MASS * v.length_squared() + step_input
            - out.normal_work
            - out.friction_work
            - 0.5 * MASS * out.velocity.length_squared();
        assert!(balance.abs() <= 1e-12 * (1.0 + 0.5 * MASS * trial.length_squared()));
        input += step_input;
        removed += out.normal_work + out.friction_work;
        friction_work += out.friction_work;
        s += out.velocity.dot(down) * dt;
        v = out.velocity;
    }
    let t = steps as f64 * dt;
    // Velocity is linear in time: exact to rounding.
    assert!((v.dot(down) - accel * t).abs() <= 1e-12 * accel * t);
    assert!(v.dot(b.normal()).abs() <= 1e-15);
    // Distance: ½ a t², with the rectangle-rule error ½ a t Δt.
    assert!((s - 0.5 * accel * t * t).abs() <= accel * t * dt);
    // Summed over the run the ledger closes too.
    assert!((input - removed - 0.5 * MASS * v.length_squared()).abs() <= 1e-9 * input);
    // Friction work against the trial state equals, to first order in Δt, the rigid-body value
    // μ m g cosθ s: the relative difference is ≈ g sinθ Δt / (2 v_mean), 1e-3 here.
    let rigid = mu * MASS * G * theta.cos() * s;
    assert!((friction_work - rigid).abs() <= 2e-3 * rigid, "{friction_work} vs {rigid}");
    println!(
        "inclined slide, dt = {dt}: v(2 s) = {:.6} m/s (exact {:.6}), s = {s:.6} m (exact {:.6})",
        v.dot(down),
        accel * t,
        0.5 * accel * t * t
    );
}
