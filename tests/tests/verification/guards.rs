//! Each stability guard fires with the designed, named error: a particle pushed out of the grid, a
//! NaN injected, a Courant number above 1 (refused up front, or reached during a fixed-Δt run).

use mpm_constitutive::LinearElastic;
use mpm_grid::{Bilinear, RegularGrid};
use mpm_solver::generate::Shape;
use mpm_solver::{Field, Solver, SolverConfig, SolverError, TimeStep, Vector};
use mpm_tests::block;

fn small_scene(
    config: SolverConfig,
) -> Result<Solver<LinearElastic, Bilinear<RegularGrid>, 4>, SolverError> {
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.25), [8, 8]).unwrap();
    let particles = block(
        &Shape::Rectangle { min: Vector::splat(0.5), max: Vector::splat(1.5) },
        0.25,
        2,
        1000.0,
        Vector::ZERO,
        (),
    );
    let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
    Solver::new(Bilinear(grid), vec![material], particles, config)
}

#[test]
fn courant_above_one_is_refused_before_any_step() {
    let err = small_scene(SolverConfig { time_step: TimeStep::Courant(1.5), ..Default::default() })
        .unwrap_err();
    assert!(
        matches!(err, SolverError::InvalidSetting { name: "courant", value, .. } if value == 1.5)
    );
    assert!(err.to_string().contains("courant"));
}

#[test]
fn fixed_time_step_that_becomes_unstable_stops_with_the_particle() {
    let mut s =
        small_scene(SolverConfig { time_step: TimeStep::Fixed(1e-3), ..Default::default() })
            .unwrap();
    // c = √((λ+2G)/ρ) = 36.7 m/s, L = 0.25 m: Δt = 1e-3 gives C = 0.15. A particle at 300 m/s
    // raises it to 1.35.
    s.particles_mut().velocity[7] = Vector::new(300.0, 0.0);
    match s.step().unwrap_err() {
        SolverError::CourantExceeded { step, particle, courant, .. } => {
            assert_eq!((step, particle), (1, 7));
            assert!(courant > 1.0 && courant < 1.5);
        }
        other => panic!("unexpected error {other}"),
    }
}

#[test]
fn particle_pushed_out_of_the_grid_is_named() {
    let mut s = small_scene(SolverConfig::default()).unwrap();
    s.step().unwrap();
    s.particles_mut().position[3] = Vector::new(5.0, 1.0);
    match s.step().unwrap_err() {
        SolverError::OutsideGrid { step, particle, position, .. } => {
            assert_eq!((step, particle), (2, 3));
            assert_eq!(position, Vector::new(5.0, 1.0));
        }
        other => panic!("unexpected error {other}"),
    }
}

#[test]
fn injected_nan_is_caught_at_its_particle() {
    let mut s = small_scene(SolverConfig::default()).unwrap();
    s.particles_mut().velocity[11].y = f64::NAN;
    match s.step().unwrap_err() {
        SolverError::NonFinite { particle, field, .. } => {
            assert_eq!((particle, field), (11, Field::Velocity));
        }
        other => panic!("unexpected error {other}"),
    }
    let mut s = small_scene(SolverConfig::default()).unwrap();
    s.particles_mut().stress[5].xy = f64::INFINITY;
    let err = s.step().unwrap_err();
    assert!(
        matches!(
            err,
            SolverError::Constitutive { particle: 5, .. }
                | SolverError::NonFinite { particle: 5, .. }
        ),
        "unexpected error {err}"
    );
}

#[test]
fn particle_starting_outside_the_grid_is_refused() {
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.25), [4, 4]).unwrap();
    let particles = block(
        &Shape::Rectangle { min: Vector::splat(0.5), max: Vector::splat(1.5) },
        0.25,
        2,
        1000.0,
        Vector::ZERO,
        (),
    );
    let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
    let err = Solver::new(Bilinear(grid), vec![material], particles, SolverConfig::default())
        .unwrap_err();
    assert!(matches!(err, SolverError::OutsideGrid { step: 0, .. }), "{err}");
}
