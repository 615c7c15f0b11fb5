//! Shared fixtures for the criterion benchmarks: seeded, reproducible inputs.
//!
//! Benchmarks must measure the same work on every run, so every random input
//! comes from [`SplitMix64`] with a fixed seed instead of an entropy source, and every whole-step
//! scene from [`square_on_floor`].

use mpm_constitutive::{ConstitutiveModel, PlaneTensor};
use mpm_contact::Friction;
use mpm_grid::{Bilinear, RegularGrid};
use mpm_solver::generate::{Shape, fill};
use mpm_solver::{
    Boundaries, MassMatrix, NewParticle, Particles, Scheme, Solver, SolverConfig, Vector,
};

/// A 1 m square body of about `n` particles (2 × 2 per cell, ρ = 1600 kg/m³) resting on a
/// frictional floor (μ = 0.5) between frictionless walls 0.5 m from its sides, MUSL with bilinear
/// functions; the objective stress rate is on for plastic models. The whole-step bench and the
/// `profile_step` example run this scene. The walls keep a collapsing sand body on the grid
/// however many steps a benchmark takes (without them it flows off the grid's edge after about
/// 0.4 s of simulated time).
pub fn square_on_floor<M: ConstitutiveModel>(
    n: usize,
    model: M,
) -> Solver<M, Bilinear<RegularGrid>, 4> {
    square_on_floor_with(n, model, MassMatrix::Lumped)
}

/// [`square_on_floor`] with the mass matrix `mass`.
pub fn square_on_floor_with<M: ConstitutiveModel>(
    n: usize,
    model: M,
    mass: MassMatrix,
) -> Solver<M, Bilinear<RegularGrid>, 4> {
    let cells_side = (((n / 4) as f64).sqrt().round() as usize).max(1);
    let cell = 1.0 / cells_side as f64;
    let grid = RegularGrid::new(
        Vector::new(-0.5, 0.0),
        Vector::splat(cell),
        [2 * cells_side, 2 * cells_side],
    )
    .expect("a grid of positive size");
    let state = model.initial_state();
    let mut particles = Particles::with_capacity(n);
    for s in fill(&Shape::Rectangle { min: Vector::ZERO, max: Vector::ONE }, cell / 2.0) {
        particles.push(NewParticle {
            position: s.position,
            velocity: Vector::ZERO,
            volume: s.area,
            density: 1600.0,
            stress: PlaneTensor::ZERO,
            state,
            material: 0,
            body: 0,
        });
    }
    let config = SolverConfig {
        scheme: Scheme::Musl,
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.5 }),
            left_wall: Some(Friction::Coulomb { mu: 0.0 }),
            right_wall: Some(Friction::Coulomb { mu: 0.0 }),
        },
        objective_stress: M::IS_PLASTIC,
        mass,
        ..Default::default()
    };
    Solver::new(Bilinear(grid), vec![model], particles, config).expect("a valid scene")
}

/// A tiny deterministic generator (SplitMix64) for benchmark inputs.
///
/// Not for statistics: it only has to be cheap, seeded and identical on every machine.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// a generator whose sequence is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// uniform sample in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        // 53 random bits give every representable step of [0, 1).
        let unit = (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn uniform_stays_in_range_and_is_reproducible() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        for _ in 0..10_000 {
            let x = a.uniform(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
            assert_eq!(x.to_bits(), b.uniform(-2.0, 3.0).to_bits());
        }
    }
}
