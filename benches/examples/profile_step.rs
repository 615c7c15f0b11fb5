//! Runs a fixed number of MUSL steps of an elastic block for profilers (callgrind, perf), which need
//! a plain binary rather than criterion's harness: `cargo build --release -p mpm-benches --example
//! profile_step`, then `valgrind --tool=callgrind target/release/examples/profile_step 20000 20`.

use mpm_constitutive::{LinearElastic, SymTensor};
use mpm_contact::Friction;
use mpm_grid::{Bilinear, RegularGrid};
use mpm_solver::generate::{Shape, fill};
use mpm_solver::{Boundaries, NewParticle, Particles, Scheme, Solver, SolverConfig, Vector};

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let side = ((n / 4) as f64).sqrt().round() as usize;
    let cell = 1.0 / side as f64;
    let grid = RegularGrid::new(Vector::new(-0.5, 0.0), Vector::splat(cell), [2 * side, 2 * side])
        .expect("a valid grid");
    let mut particles = Particles::with_capacity(n);
    for s in fill(&Shape::Rectangle { min: Vector::ZERO, max: Vector::ONE }, cell / 2.0) {
        particles.push(NewParticle {
            position: s.position,
            velocity: Vector::ZERO,
            volume: s.area,
            density: 1600.0,
            stress: SymTensor::ZERO,
            state: (),
            material: 0,
            body: 0,
        });
    }
    let config = SolverConfig {
        scheme: Scheme::Musl,
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.5 }),
            ..Default::default()
        },
        ..Default::default()
    };
    let material = LinearElastic::from_young_poisson(2e6, 0.3).expect("valid elasticity");
    let mut solver =
        Solver::new(Bilinear(grid), vec![material], particles, config).expect("a valid scene");
    let start = std::time::Instant::now();
    for _ in 0..steps {
        solver.step().expect("a stable step");
    }
    let per = start.elapsed().as_secs_f64() / (steps * solver.particles().len()) as f64;
    println!(
        "{} particles, {steps} steps: {:.1} ns per particle-step ({:.2} M particle-steps/s)",
        solver.particles().len(),
        per * 1e9,
        1e-6 / per
    );
}
