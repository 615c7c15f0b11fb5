//! The 1D vibrating bar (fixed–free), a standard MPM benchmark used by Bardenhagen (2002) and by
//! most MPM codes since: v(x, 0) = v0 sin(βx), β = π/(2L), ω = β √(E/ρ), period T = 2π/ω.
//! With L = 25, E = 100, ρ = 1: c = 10 and T = 4L/c = 10 s.

use mpm_constitutive::LinearElastic;
use mpm_contact::Friction;
use mpm_grid::{Bilinear, QuadraticBSpline, RegularGrid, ShapeFunctions};
use mpm_solver::generate::Shape;
use mpm_solver::{Boundaries, Scheme, Solver, SolverConfig, Vector};
use mpm_tests::{block, mass_mean};

const L: f64 = 25.0;
const E: f64 = 100.0;
const RHO: f64 = 1.0;
const V0: f64 = 0.1;

/// (measured period, largest |E(t) − E0|/E0) over five periods.
fn vibrating_bar(scheme: Scheme, cell: f64, courant: f64, smooth: bool) -> (f64, f64) {
    let grid = RegularGrid::new(
        Vector::new(0.0, -1.0),
        Vector::splat(cell),
        [(28.0 / cell) as usize, (3.0 / cell) as usize],
    )
    .unwrap();
    if smooth {
        bar_on(QuadraticBSpline::new(grid), scheme, cell, courant)
    } else {
        bar_on(Bilinear(grid), scheme, cell, courant)
    }
}

fn bar_on<S: ShapeFunctions<N>, const N: usize>(
    shape: S,
    scheme: Scheme,
    cell: f64,
    courant: f64,
) -> (f64, f64) {
    let beta = std::f64::consts::PI / (2.0 * L);
    let period = 2.0 * std::f64::consts::PI / (beta * (E / RHO).sqrt());
    // ν = 0: plane strain then has no lateral coupling and the bar is one-dimensional.
    let material = LinearElastic::from_young_poisson(E, 0.0).unwrap();
    let mut particles = block(
        &Shape::Rectangle { min: Vector::ZERO, max: Vector::new(L, cell) },
        cell,
        2,
        RHO,
        Vector::ZERO,
        (),
    );
    for i in 0..particles.len() {
        particles.velocity[i] = Vector::new(V0 * (beta * particles.position[i].x).sin(), 0.0);
    }
    let config = SolverConfig {
        scheme,
        time_step: mpm_solver::TimeStep::Courant(courant),
        gravity: Vector::ZERO,
        boundaries: Boundaries { left_wall: Some(Friction::Fixed), ..Default::default() },
        ..Default::default()
    };
    let mut s = Solver::new(shape, vec![material], particles, config).unwrap();
    let e0 = s.energy().total();
    let mut worst: f64 = 0.0;
    let mut crossings = Vec::new();
    let mut last = (0.0, mass_mean(s.particles(), &s.particles().velocity).x);
    while s.time() < 5.0 * period {
        s.step().unwrap();
        let v = mass_mean(s.particles(), &s.particles().velocity).x;
        if (v > 0.0) != (last.1 > 0.0) {
            // Linear interpolation of the zero of the mean velocity within the step.
            crossings.push(last.0 + (s.time() - last.0) * last.1 / (last.1 - v));
        }
        last = (s.time(), v);
        worst = worst.max((s.energy().total() - e0).abs() / e0);
    }
    // Successive zero crossings of cos(ωt) are half a period apart.
    let n = crossings.len();
    let measured = 2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64;
    eprintln!(
        "vibrating bar {} N = {N} cell {cell} C {courant}: period {measured:.4} s (exact {period:.4}), worst |ΔE|/E0 {worst:.3e}",
        scheme.name()
    );
    assert!(n >= 9, "expected ten zero crossings in five periods, got {n}");
    (measured / period, worst)
}

/// Bilinear functions on the standard 25-cell bar. C = 0.05: at C = 0.1 MUSL's energy error is
/// 1.06 % (measured), just over the bound. Refining the bilinear grid makes it worse, not better
/// (2.6 % at 0.5 m, 5.1 % at 0.25 m for USAVG, measured): particles oscillating ±0.16 m cross small
/// cells, the cell-crossing error of §2(3).
#[test]
fn bardenhagen2002_vibrating_bar_musl() {
    let (ratio, energy) = vibrating_bar(Scheme::Musl, 1.0, 0.05, false);
    // Issue tolerances: period and energy within 1 % over five periods.
    assert!((ratio - 1.0).abs() < 0.01, "period ratio {ratio}");
    assert!(energy < 0.01, "energy error {energy}");
}

#[test]
fn bardenhagen2002_vibrating_bar_usavg() {
    let (ratio, energy) = vibrating_bar(Scheme::Usavg, 1.0, 0.05, false);
    assert!((ratio - 1.0).abs() < 0.01, "period ratio {ratio}");
    assert!(energy < 0.01, "energy error {energy}");
}

/// Quadratic B-splines on a grid four times finer (0.25 m): no cell-crossing error, so refinement
/// helps (period error 1.4 % → 0.65 % → 0.31 % for 1, 0.5, 0.25 m cells, measured).
#[test]
fn bardenhagen2002_vibrating_bar_bspline_refined() {
    for scheme in [Scheme::Musl, Scheme::Usavg] {
        let (ratio, energy) = vibrating_bar(scheme, 0.25, 0.1, true);
        assert!((ratio - 1.0).abs() < 0.01, "{}: period ratio {ratio}", scheme.name());
        assert!(energy < 0.01, "{}: energy error {energy}", scheme.name());
    }
}
