//! Shared fixtures of the verification tests: particle blocks and probes.
//!
//! Each fixture builds what the paper or the benchmark's source describes, in SI units, so that a
//! test reads as its set-up: "a 1 m × 1 m elastic block, 2 × 2 particles per cell, on a 0.5 m grid".

use mpm_constitutive::SymTensor;
use mpm_solver::generate::{Shape, fill};
use mpm_solver::{NewParticle, Particles, Vector};

/// Particles filling `shape` at `ppc × ppc` per cell of size `cell`, all of one material.
pub fn block<S: Copy>(
    shape: &Shape,
    cell: f64,
    ppc: usize,
    density: f64,
    velocity: Vector,
    state: S,
) -> Particles<S> {
    let seeds = fill(shape, cell / ppc as f64);
    let mut p = Particles::with_capacity(seeds.len());
    for s in seeds {
        p.push(NewParticle {
            position: s.position,
            velocity,
            volume: s.area,
            density,
            stress: SymTensor::ZERO,
            state,
            material: 0,
            body: 0,
        });
    }
    p
}

/// Mass-weighted mean of a per-particle vector (centre of mass, mean velocity).
pub fn mass_mean<S>(p: &Particles<S>, field: &[Vector]) -> Vector {
    let m: f64 = p.mass.iter().sum();
    p.mass.iter().zip(field).map(|(&mi, &f)| mi * f).sum::<Vector>() / m
}
