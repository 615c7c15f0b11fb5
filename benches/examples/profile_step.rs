//! Runs a fixed number of MUSL steps of a block on a floor for profilers (callgrind, perf), which
//! need a plain binary rather than criterion's harness: `cargo build --release -p mpm-benches
//! --example profile_step`, then `valgrind --tool=callgrind target/release/examples/profile_step
//! 20000 20 [WARMUP] [elastic|sand|sand_full|sand_any]` (the step bench's elastic body, or its
//! Drucker-Prager sand: storing ε̄ᵖ only as `mpm run` does, the full hardening state, or the full
//! state inside the composite model a scene of several soil models runs as).

use mpm_constitutive::{ConstitutiveModel, DruckerPrager, DruckerPragerParams, LinearElastic};

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let warmup: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(0);
    match args.next().as_deref() {
        None | Some("elastic") => {
            let material = LinearElastic::from_young_poisson(2e6, 0.3).expect("valid elasticity");
            run(n, steps, warmup, material);
        }
        Some("sand") => {
            // (as `mpm run` stores it: only ε̄ᵖ, since it does not harden)
            let sand = DruckerPrager::perfectly_plastic(DruckerPragerParams::ABE2005_DRY_SAND)
                .expect("the paper's sand is valid and does not harden");
            run(n, steps, warmup, sand);
        }
        Some("sand_full") => {
            let sand = DruckerPrager::new(DruckerPragerParams::ABE2005_DRY_SAND)
                .expect("the paper's sand is valid");
            run(n, steps, warmup, sand);
        }
        Some("sand_any") => {
            let sand = DruckerPrager::new(DruckerPragerParams::ABE2005_DRY_SAND)
                .expect("the paper's sand is valid");
            run(n, steps, warmup, mpm_scene::materials::AnyModel::DruckerPrager(sand));
        }
        Some(other) => {
            eprintln!("unknown material {other:?}: elastic, sand, sand_full or sand_any")
        }
    }
}

fn run<M: ConstitutiveModel>(n: usize, steps: usize, warmup: usize, material: M) {
    let mut solver = mpm_benches::square_on_floor(n, material);
    // Steps before the timed ones: the block settles and particles begin to cross cells.
    for _ in 0..warmup {
        solver.step().expect("a stable step");
    }
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
