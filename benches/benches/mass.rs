//! The consistent mass matrix's cost (`[solver] mass = "consistent"`, `stages/mass.rs`): whole
//! steps with the lumped and the consistent matrix at 1 k, 10 k and 100 k particles (the square
//! of `square_on_floor`, elastic, MUSL: four consistent solves a step, P2G velocity,
//! acceleration, its re-solve with the held floor nodes, remap), against faer's sparse Cholesky
//! factorisation of the same kind of matrix (assembled here from the same particle layout:
//! symbolic and numeric factorisation and a solve for both components), which a direct solver
//! would have to redo whenever the active set changes and refactor every step.
//!
//! Read: (consistent step − lumped step) is what the CG solves and the assembly cost; compare it
//! with four Cholesky solves (or one factorisation plus four triangular solves).

// criterion's macros generate public functions that cannot carry docs.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use mpm_constitutive::LinearElastic;
use mpm_solver::MassMatrix;

/// 0.95 Σ m_p S_ip S_jp + 0.05 diag(m_i) of the bilinear square of about `n` particles (2 × 2
/// per cell, unit particle mass) on its own grid of (k + 1)² nodes: the solver's matrix for that
/// layout, as triplets.
fn consistent_triplets(n: usize) -> (usize, Vec<Triplet<usize, usize, f64>>) {
    let k = (((n / 4) as f64).sqrt().round() as usize).max(1);
    let nodes = (k + 1) * (k + 1);
    let mut entries = Vec::with_capacity(16 * 4 * k * k + nodes);
    let mut lumped = vec![0.0; nodes];
    for cj in 0..k {
        for ci in 0..k {
            for (a, b) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                let w = [(1.0 - a) * (1.0 - b), a * (1.0 - b), (1.0 - a) * b, a * b];
                let at = [0, 1, k + 1, k + 2].map(|o| cj * (k + 1) + ci + o);
                for r in 0..4 {
                    lumped[at[r]] += w[r];
                    for c in 0..4 {
                        entries.push(Triplet::new(at[r], at[c], 0.95 * w[r] * w[c]));
                    }
                }
            }
        }
    }
    entries.extend(lumped.iter().enumerate().map(|(i, &m)| Triplet::new(i, i, 0.05 * m)));
    (nodes, entries)
}

fn mass(c: &mut Criterion) {
    let mut group = c.benchmark_group("mass");
    group.sample_size(10);
    let elastic = LinearElastic::from_young_poisson(2e6, 0.3).unwrap();
    for n in [1_000usize, 10_000, 100_000] {
        for (name, kind) in [("lumped", MassMatrix::Lumped), ("consistent", MassMatrix::Consistent)]
        {
            let mut solver = mpm_benches::square_on_floor_with(n, elastic, kind);
            for _ in 0..3 {
                solver.step().unwrap();
            }
            let np = solver.particles().len();
            group.throughput(Throughput::Elements(np as u64));
            group.bench_function(BenchmarkId::new(format!("step_{name}"), np), |b| {
                b.iter(|| black_box(solver.step().unwrap()))
            });
            if kind == MassMatrix::Consistent {
                let steps = solver.step_count() as f64;
                eprintln!(
                    "consistent, {np} particles: {:.1} CG iterations per step (4 solves)",
                    solver.mass_solve_iterations() as f64 / steps
                );
            }
        }
        let (nodes, entries) = consistent_triplets(n);
        let rhs = faer::Mat::<f64>::from_fn(nodes, 2, |i, j| 1.0 + ((i * 7 + j) % 5) as f64);
        group.bench_function(BenchmarkId::new("faer_cholesky", nodes), |b| {
            b.iter(|| {
                let m = SparseColMat::<usize, f64>::try_new_from_triplets(nodes, nodes, &entries)
                    .unwrap();
                let llt = m.sp_cholesky(Side::Lower).unwrap();
                black_box(llt.solve(&rhs))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, mass);
criterion_main!(benches);
