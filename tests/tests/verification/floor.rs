//! Wide stencils at a floor: with uGIMP or quadratic B-splines a particle on the floor still
//! takes a share of the first interior row's velocity, so a body pressed onto the floor could be
//! pushed through it. Ghost nodes below the floor mirror the normal velocity of their partners
//! above it, which makes the interpolated normal velocity at the floor zero.

use mpm_constitutive::{
    ConeMatch, ConstitutiveModel, DruckerPrager, DruckerPragerParams, LinearElastic,
};
use mpm_contact::Friction;
use mpm_grid::{Gimp, QuadraticBSpline, RegularGrid, ShapeFunctions};
use mpm_solver::generate::Shape;
use mpm_solver::{Boundaries, Solver, SolverConfig, Vector};
use mpm_tests::block;

/// A soft 1 m block (E = 2e5 Pa) dropped from 0.5 m onto a frictionless floor, then left to
/// bounce and settle for 1.5 s. Returns the lowest particle height seen.
fn drop_on_floor<S: ShapeFunctions<N>, const N: usize>(shape: S) -> f64 {
    let particles = block(
        &Shape::Rectangle { min: Vector::new(0.5, 0.5), max: Vector::new(1.5, 1.5) },
        0.125,
        2,
        1000.0,
        Vector::ZERO,
        (),
    );
    let config = SolverConfig {
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.0 }),
            ..Default::default()
        },
        ..Default::default()
    };
    let material = LinearElastic::from_young_poisson(2e5, 0.3).unwrap();
    let mut s = Solver::new(shape, vec![material], particles, config).unwrap();
    let mut lowest = f64::INFINITY;
    while s.time() < 1.5 {
        s.step().unwrap();
        lowest =
            lowest.min(s.particles().position.iter().map(|p| p.y).fold(f64::INFINITY, f64::min));
    }
    lowest
}

fn grid() -> RegularGrid {
    RegularGrid::new(Vector::ZERO, Vector::splat(0.125), [16, 16]).unwrap()
}

#[test]
fn bspline_particles_stay_above_the_floor() {
    let lowest = drop_on_floor(QuadraticBSpline::new(grid()));
    eprintln!("B-spline: lowest particle {lowest:.4} m");
    assert!(lowest > 0.0, "a particle reached y = {lowest}");
}

#[test]
fn gimp_particles_stay_above_the_floor() {
    let lowest = drop_on_floor(Gimp::with_particles_per_cell(grid(), [2, 2]).unwrap());
    eprintln!("uGIMP: lowest particle {lowest:.4} m");
    assert!(lowest > 0.0, "a particle reached y = {lowest}");
}

/// A cohesionless sand column (0.5 m × 1 m, φ = 30°, ψ = 0) collapsing onto a rough floor
/// (friction angle 20°) and spreading into a thin deposit for 1 s. Returns the lowest height seen.
fn column_collapse<S: ShapeFunctions<N>, const N: usize>(shape: S) -> f64 {
    let sand = DruckerPrager::new(DruckerPragerParams {
        young: 1e6,
        poisson: 0.3,
        cohesion: 0.0,
        friction_angle_deg: 30.0,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        mixing: 1.0,
        cone_match: ConeMatch::PlaneStrain,
    })
    .unwrap();
    let particles = block(
        &Shape::Rectangle { min: Vector::new(0.0, 0.0), max: Vector::new(0.5, 1.0) },
        0.0625,
        2,
        1600.0,
        Vector::ZERO,
        sand.initial_state(),
    );
    let config = SolverConfig {
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 20f64.to_radians().tan() }),
            left_wall: Some(Friction::Coulomb { mu: 0.0 }),
            ..Default::default()
        },
        objective_stress: true,
        ..Default::default()
    };
    let mut s = Solver::new(shape, vec![sand], particles, config).unwrap();
    let mut lowest = f64::INFINITY;
    while s.time() < 1.0 {
        s.step().unwrap();
        lowest =
            lowest.min(s.particles().position.iter().map(|p| p.y).fold(f64::INFINITY, f64::min));
    }
    lowest
}

fn sand_grid() -> RegularGrid {
    RegularGrid::new(Vector::ZERO, Vector::splat(0.0625), [64, 20]).unwrap()
}

#[test]
fn bspline_column_collapse_stays_above_the_floor() {
    let lowest = column_collapse(QuadraticBSpline::new(sand_grid()));
    eprintln!("B-spline column: lowest particle {lowest:.5} m");
    assert!(lowest > 0.0, "a particle reached y = {lowest}");
}

#[test]
fn gimp_column_collapse_stays_above_the_floor() {
    let lowest = column_collapse(Gimp::with_particles_per_cell(sand_grid(), [2, 2]).unwrap());
    eprintln!("uGIMP column: lowest particle {lowest:.5} m");
    assert!(lowest > 0.0, "a particle reached y = {lowest}");
}
