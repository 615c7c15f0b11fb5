//! Whole-step benchmarks of the 3D build (`mpm-solver3d`): a cube of Drucker-Prager sand
//! resting on the floor of a box and collapsing, as in Taichi's `mpm3d_bench.py` (2 × 2 × 2
//! particles per cell), at 10 k and 100 k particles, for trilinear FLIP (the cheapest) and
//! B-spline APIC (the 27-node stencil the side-by-side with Taichi measures), MUSL; and trilinear
//! FLIP on a terrain-following grid over a flat DEM (the same nodes and answer as the regular
//! grid, `mpm_grid3d::TerrainGrid`): the price of locating points and forming gradients through
//! the terrain's columns, which issue 41 bounds at 1.3 times the regular grid's step.
//!
//! Criterion reports time per step; throughput is the particle count, so "elements/s" is
//! particle-steps per second. Thread count follows RAYON_NUM_THREADS. Heap bytes per particle
//! are printed once per size.

// criterion's macros generate public functions that cannot carry docs.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mpm_constitutive::{ConeMatch, ConstitutiveModel, DruckerPrager, DruckerPragerParams};
use mpm_contact3d::Friction;
use mpm_grid3d::{
    Bilinear, QuadraticBSpline, RegularGrid, ShapeFunctions, TerrainGrid, TerrainGridSpec,
};
use mpm_solver3d::generate::{Shape, fill};
use mpm_solver3d::{
    Boundaries, NewParticle, Particles, Scheme, Solver, SolverConfig, Stress, TimeStep, Transfer,
    Vector,
};

/// Klar's sand of the Taichi benchmark: E = 353.7 kPa, ν = 0.3, φ = 30°, no cohesion.
fn sand() -> DruckerPrager {
    DruckerPrager::new(DruckerPragerParams {
        young: 3.537e5,
        poisson: 0.3,
        cohesion: 0.0,
        friction_angle_deg: 30.0,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        mixing: 1.0,
        cone_match: ConeMatch::Outer,
    })
    .expect("valid parameters")
}

/// a cube of about `n` particles (side 0.4 of the unit box, 2 per cell along each axis) on the
/// floor band, frictionless faces; the grid as Taichi's.
/// `shape` makes the grid and its shape functions from the cell size and the cells per side.
fn cube<S: ShapeFunctions<N>, const N: usize>(
    n: usize,
    transfer: Transfer,
    shape: impl Fn(f64, usize) -> S,
) -> Solver<DruckerPrager, S, N> {
    let per_side = ((n as f64).cbrt() / 2.0).round().max(4.0);
    let n_grid = (per_side / 0.4).ceil();
    let dx = 1.0 / n_grid;
    let min = Vector::new(0.3, 3.0 * dx, 0.3);
    let block = Shape::Box { min, max: min + Vector::splat(per_side * dx) };
    let model = sand();
    let mut p = Particles::default();
    for s in fill(&block, 0.5 * dx) {
        p.push(NewParticle {
            position: s.position,
            velocity: Vector::ZERO,
            volume: s.volume,
            density: 2200.0,
            stress: Stress::ZERO,
            state: model.initial_state(),
            material: 0,
            body: 0,
        });
    }
    let config = SolverConfig {
        scheme: Scheme::Musl,
        transfer,
        time_step: TimeStep::Courant(0.1),
        boundaries: Boundaries::all(Friction::Coulomb { mu: 0.0 }),
        ..Default::default()
    };
    Solver::new(shape(dx, n_grid as usize), vec![model], p, config).unwrap()
}

fn bench<S: ShapeFunctions<N>, const N: usize>(
    c: &mut Criterion,
    name: &str,
    transfer: Transfer,
    shape: impl Fn(f64, usize) -> S + Copy,
) {
    let mut group = c.benchmark_group(format!("step3d/{name}"));
    group.sample_size(10);
    for n in [10_000usize, 100_000] {
        let mut solver = cube(n, transfer, shape);
        for _ in 0..3 {
            solver.step().unwrap();
        }
        let np = solver.particles().len();
        eprintln!(
            "{name}: {np} particles, {} active nodes, {:.0} heap bytes per particle",
            solver.active_nodes().len(),
            solver.heap_bytes() as f64 / np as f64
        );
        group.throughput(Throughput::Elements(np as u64));
        group.bench_function(BenchmarkId::from_parameter(np), |b| {
            b.iter(|| black_box(solver.step().unwrap()))
        });
    }
    group.finish();
}

/// the unit box of `n`³ cells of side `dx`.
fn regular(dx: f64, n: usize) -> RegularGrid {
    RegularGrid::new(Vector::ZERO, Vector::splat(dx), [n; 3]).unwrap()
}

/// the same box as a terrain grid over a flat DEM at y = 0.
fn flat_terrain(dx: f64, n: usize) -> TerrainGrid {
    TerrainGrid::new(TerrainGridSpec {
        origin: [0.0, 0.0],
        spacing: [dx, dx],
        cells: [n, n],
        heights: vec![0.0; (n + 1) * (n + 1)],
        layer_height: dx,
        layers: n,
    })
    .unwrap()
}

fn steps(c: &mut Criterion) {
    bench(c, "trilinear_flip", Transfer::Flip, |dx, n| Bilinear(regular(dx, n)));
    bench(c, "terrain_trilinear_flip", Transfer::Flip, |dx, n| Bilinear(flat_terrain(dx, n)));
    bench(c, "bspline_apic", Transfer::Apic, |dx, n| QuadraticBSpline::new(regular(dx, n)));
}

criterion_group!(benches, steps);
criterion_main!(benches);
