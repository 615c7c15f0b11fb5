//! Whole-step benchmarks: an elastic block and a Drucker-Prager sand column, bilinear shape
//! functions on a regular grid, MUSL, at 10 k, 100 k and 1 M particles. The sand is the paper's,
//! which does not harden, so its particles store only ε̄ᵖ as in `mpm run`
//! (`drucker_prager`); `drucker_prager_mixed_state` runs the same sand storing the
//! mixed-hardening variables (k, β) as a hardening material must.
//!
//! Criterion reports time per step; throughput is set to the particle count, so the "elements/s"
//! figure is particle-steps per second. Thread count follows RAYON_NUM_THREADS (run once with 1 and
//! once with 2 to read the speed-up). The heap bytes per particle are printed once per size.

// criterion's macros generate public functions that cannot carry docs.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mpm_constitutive::{ConstitutiveModel, DruckerPrager, DruckerPragerParams, LinearElastic};

/// the paper's dry sand (§7, Table 2), with the mixed-hardening variables.
fn sand() -> DruckerPrager {
    DruckerPrager::new(DruckerPragerParams::ABE2005_DRY_SAND).expect("valid parameters")
}

fn bench_model<M: ConstitutiveModel + Clone>(c: &mut Criterion, name: &str, model: M) {
    let mut group = c.benchmark_group(format!("step/{name}"));
    group.sample_size(10);
    for n in [10_000usize, 100_000, 1_000_000] {
        let mut solver = mpm_benches::square_on_floor(n, model.clone());
        // Settle the first transients and warm the scratch memory.
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

fn steps(c: &mut Criterion) {
    bench_model(c, "elastic", LinearElastic::from_young_poisson(2e6, 0.3).unwrap());
    bench_model(c, "drucker_prager", sand().without_hardening().expect("H = 0"));
    bench_model(c, "drucker_prager_mixed_state", sand());
}

criterion_group!(benches, steps);
criterion_main!(benches);
