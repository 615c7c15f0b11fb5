//! The small-nodal-mass instability of §2(3): a particle that has just crossed into a new cell gives
//! the nodes on the far side a tiny mass but a full share of its internal force, so their
//! acceleration f_i/m_i is huge. Under USL those nodes' v^L enter the neighbours' strain increments
//! directly, and the first cell crossing of a spinning square inverts its corner particle. Nodes
//! lighter than `small_mass_ratio` × the mean particle mass take no internal force, which is what
//! keeps that run alive; MUSL and USAVG compute strains from remapped velocities and barely notice
//! the threshold at its default.

use mpm_constitutive::LinearElastic;
use mpm_grid::{Bilinear, RegularGrid};
use mpm_solver::generate::Shape;
use mpm_solver::{Scheme, Solver, SolverConfig, SolverError, Vector};
use mpm_tests::block;

/// A 1 m square spinning at 1 rad/s on 0.125 m cells (E = 1e8 Pa), run for 0.25 s (its corners
/// first cross a cell edge near 0.07 s).
fn spin(scheme: Scheme, small_mass_ratio: f64) -> Result<f64, SolverError> {
    let centre = Vector::splat(1.0);
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.125), [16, 16]).unwrap();
    let mut particles = block(
        &Shape::Rectangle { min: centre - 0.5, max: centre + 0.5 },
        0.125,
        2,
        1000.0,
        Vector::ZERO,
        (),
    );
    for i in 0..particles.len() {
        particles.velocity[i] = (particles.position[i] - centre).perp();
    }
    let config = SolverConfig {
        scheme,
        small_mass_ratio,
        gravity: Vector::ZERO,
        objective_stress: true,
        ..Default::default()
    };
    let material = LinearElastic::from_young_poisson(1e8, 0.3).unwrap();
    let mut s = Solver::new(Bilinear(grid), vec![material], particles, config)?;
    s.run_until(0.25, &mut ())?;
    Ok(s.energy().kinetic)
}

#[test]
fn usl_without_threshold_inverts_a_particle_at_the_first_cell_crossing() {
    match spin(Scheme::Usl, 0.0) {
        Err(SolverError::Inverted { step, ratio, .. }) => {
            eprintln!("USL, no threshold: inverted at step {step}, volume ratio {ratio:.2}");
            assert!(ratio <= 0.0);
        }
        other => panic!("expected the inversion guard, got {other:?}"),
    }
}

#[test]
fn usl_with_a_one_percent_threshold_survives_the_crossing() {
    let ke = spin(Scheme::Usl, 1e-2).expect("the run should complete");
    // Initial kinetic energy ½ I Ω² = ½ (1000 · 1/6) · 1 = 83.3 J (the lattice gives 82.8 J).
    // USL is dissipative and noisy at the crossings; it must stay finite and of that order.
    assert!(ke.is_finite() && ke > 0.0 && ke < 2.0 * 83.3, "kinetic energy {ke}");
}

#[test]
fn musl_is_insensitive_to_the_default_threshold() {
    let with = spin(Scheme::Musl, SolverConfig::default().small_mass_ratio).unwrap();
    let without = spin(Scheme::Musl, 0.0).unwrap();
    // Measured difference 0.05 %: the default threshold only touches nodes lighter than 1e-4 of a
    // particle, whose remapped velocities already carry the particles' own.
    assert!((with - without).abs() < 1e-2 * without, "KE {with} vs {without}");
}
