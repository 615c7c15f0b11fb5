//! Grid kernels: stencil evaluation (weights + gradients) per particle for each shape function,
//! and the sparse active-node set (rebuild, index_of).
//!
//! Throughput is set to the number of points (or nodes) per iteration, so criterion's
//! "elements/s" is evaluations (lookups) per second on one core. Inputs are seeded
//! ([`SplitMix64`]) and identical on every run.

// criterion's macros generate public functions that cannot carry docs.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mpm_benches::SplitMix64;
use mpm_grid::{
    ActiveNodes, Bilinear, Gimp, KinkPolicy, QuadraticBSpline, RegularGrid, ShapeFunctions,
    TerrainGrid, TerrainGridSpec, Vector,
};

/// points per benchmark iteration: enough to amortise the loop, few enough to stay in L1/L2.
const POINTS: usize = 4096;

/// the paper's flume geometry: a 30° slope running into a flat runout, 0.1 m cells.
fn terrain() -> TerrainGrid {
    let t = 30f64.to_radians().tan();
    TerrainGrid::new(TerrainGridSpec {
        profile: vec![Vector::new(0.0, 6.0 * t), Vector::new(6.0, 0.0), Vector::new(10.0, 0.0)],
        cell_width: 0.1,
        row_height: 0.1,
        rows: 20,
        kink_policy: KinkPolicy::Reject,
    })
    .expect("valid terrain")
}

fn regular() -> RegularGrid {
    RegularGrid::new(Vector::ZERO, Vector::splat(0.1), [100, 20]).expect("valid grid")
}

/// seeded points inside the terrain grid (uniform along x, uniform height above the ground).
fn terrain_points(g: &TerrainGrid) -> Vec<Vector> {
    let mut rng = SplitMix64::new(0x6772_6964);
    let (x0, x1) = g.x_range();
    let top = g.rows() as f64 * g.row_height();
    (0..POINTS)
        .map(|_| {
            let x = rng.uniform(x0, x1);
            let ground = g.ground_height(x).expect("x in range");
            Vector::new(x, ground + rng.uniform(0.0, top))
        })
        .collect()
}

fn regular_points(g: &RegularGrid) -> Vec<Vector> {
    let mut rng = SplitMix64::new(0x7265_6775);
    let hi = g.upper_corner();
    (0..POINTS).map(|_| Vector::new(rng.uniform(0.0, hi.x), rng.uniform(0.0, hi.y))).collect()
}

fn bench_stencil<const N: usize, S: ShapeFunctions<N>>(
    c: &mut Criterion,
    name: &str,
    sf: &S,
    points: &[Vector],
) {
    let mut group = c.benchmark_group("stencil");
    group.throughput(Throughput::Elements(points.len() as u64));
    group.bench_function(name, |b| {
        b.iter(|| {
            for &p in points {
                let _ = black_box(sf.stencil(black_box(p)));
            }
        })
    });
    group.finish();
}

fn stencils(c: &mut Criterion) {
    let t = terrain();
    let tp = terrain_points(&t);
    bench_stencil(c, "bilinear_skewed", &Bilinear(t), &tp);
    let g = regular();
    let rp = regular_points(&g);
    bench_stencil(c, "bilinear_regular", &Bilinear(g), &rp);
    let gimp = Gimp::with_particles_per_cell(g, [2, 2]).expect("valid uGIMP");
    bench_stencil(c, "ugimp_ppc2", &gimp, &rp);
    bench_stencil(c, "bspline_quadratic", &QuadraticBSpline::new(g), &rp);
}

fn active_nodes(c: &mut Criterion) {
    // a 2 m × 1 m body of 80 × 40 particles (2 × 2 per cell) on the slope: 3 200 stencils,
    // 12 800 node references, 21 × 11 = 231 distinct nodes.
    let sf = Bilinear(terrain());
    let stencils: Vec<_> = (0..80)
        .flat_map(|a| (0..40).map(move |b| (a, b)))
        .map(|(a, b)| {
            let x = 2.0 + (f64::from(a) + 0.5) * 0.025;
            let y = sf.0.ground_height(x).expect("x in range") + (f64::from(b) + 0.5) * 0.025;
            sf.stencil(Vector::new(x, y)).expect("inside the grid")
        })
        .collect();
    let refs: Vec<_> = stencils.iter().flat_map(|s| s.nodes).collect();
    let mut active = ActiveNodes::new();
    active.rebuild(refs.iter().copied());

    let mut group = c.benchmark_group("active_nodes");
    group.throughput(Throughput::Elements(refs.len() as u64));
    group.bench_function("rebuild_from_stencils", |b| {
        b.iter(|| {
            active.rebuild_from_stencils(black_box(&stencils));
            black_box(active.len())
        })
    });
    group.bench_function("index_of", |b| {
        b.iter(|| {
            let mut sum = 0usize;
            for &n in &refs {
                sum = sum.wrapping_add(active.index_of(black_box(n)).unwrap_or(0));
            }
            black_box(sum)
        })
    });
    group.finish();
}

criterion_group!(benches, stencils, active_nodes);
criterion_main!(benches);
