//! The 1D vibrating bar (fixed–free), a standard MPM benchmark used by Bardenhagen (2002) and by
//! most MPM codes since: v(x, 0) = v0 sin(βx), β = π/(2L), ω = β √(E/ρ), period T = 2π/ω.
//! With L = 25, E = 100, ρ = 1: c = 10 and T = 4L/c = 10 s. The driver lives in the `mpm-tests`
//! library ([`mpm_tests::vibrating_bar`]), shared with `cargo xtask verify`.

use mpm_solver::Scheme;
use mpm_tests::{Discretisation, MassMatrix, ShapeKind, bar, vibrating_bar as run_bar};

/// (measured period / exact period, largest |E(t) − E0|/E0) over five periods, 2 × 2 particles
/// per cell.
fn vibrating_bar(scheme: Scheme, cell: f64, courant: f64, smooth: bool) -> (f64, f64) {
    vibrating_bar_with(scheme, cell, courant, smooth, MassMatrix::Lumped)
}

fn vibrating_bar_with(
    scheme: Scheme,
    cell: f64,
    courant: f64,
    smooth: bool,
    mass: MassMatrix,
) -> (f64, f64) {
    let shape = if smooth { ShapeKind::BSpline } else { ShapeKind::Bilinear };
    let d = Discretisation { cell, ppc: 2, scheme, shape, courant, mass };
    let r = run_bar(&d).unwrap();
    eprintln!(
        "vibrating bar {} {} {mass:?} cell {cell} C {courant}: period {:.4} s (exact {:.4}), worst |ΔE|/E0 {:.3e}",
        scheme.name(),
        shape.name(),
        r.period_ratio * bar::period(),
        bar::period(),
        r.worst_energy
    );
    assert!(r.crossings >= 9, "expected ten zero crossings in five periods, got {}", r.crossings);
    (r.period_ratio, r.worst_energy)
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
/// helps. The fixed end's ghost nodes mirror their images (v₋₁ = −v₁ normal to the wall), so the
/// interpolated velocity vanishes at the wall: period error 0.15 %, energy 0.86 % at C = 0.05
/// (measured; 1.15 % energy at C = 0.1, just over the bound, as for bilinear MUSL).
#[test]
fn bardenhagen2002_vibrating_bar_bspline_refined() {
    for scheme in [Scheme::Musl, Scheme::Usavg] {
        let (ratio, energy) = vibrating_bar(scheme, 0.25, 0.05, true);
        assert!((ratio - 1.0).abs() < 0.01, "{}: period ratio {ratio}", scheme.name());
        assert!(energy < 0.01, "{}: energy error {energy}", scheme.name());
    }
}

/// The consistent mass matrix (`mpm_solver::MassMatrix::Consistent`) removes the lumped
/// transfer's smoothing: on the same bar, grid and time step its period and energy errors are
/// both below the lumped matrix's (measured: period 0.014 % against 0.059 %, energy 0.38 %
/// against 0.64 %, MUSL). The literature's claim (Burgess, Sulsky & Brackbill 1992; Love &
/// Sulsky 2006), asserted as an inequality with the 1 % bounds kept.
#[test]
fn consistent_mass_vibrating_bar_beats_lumped() {
    let lumped = vibrating_bar_with(Scheme::Musl, 1.0, 0.05, false, MassMatrix::Lumped);
    let consistent = vibrating_bar_with(Scheme::Musl, 1.0, 0.05, false, MassMatrix::Consistent);
    assert!((consistent.0 - 1.0).abs() < (lumped.0 - 1.0).abs(), "{consistent:?} vs {lumped:?}");
    assert!(consistent.1 < lumped.1, "energy {consistent:?} vs {lumped:?}");
    assert!(consistent.1 < 0.01 && (consistent.0 - 1.0).abs() < 0.01, "{consistent:?}");
}
