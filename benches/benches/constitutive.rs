//! Constitutive kernels: one stress update per material point on the elastic path (linear
//! elasticity and the Drucker-Prager elastic branch), the Drucker-Prager cone return and the
//! apex return; `*_plane` is the solver's call, `update_plane` on in-plane points turned by an
//! objective rotation first.
//!
//! Throughput is set to the number of updates per iteration, so criterion's "elements/s" is
//! updates per second on one core (target: ≥ 15 M plastic updates/s). Inputs are seeded
//! ([`SplitMix64`]), identical on every run, and checked to take the intended branch; each update
//! starts from a copy of its input so that every iteration measures the same branch.

// criterion's macros generate public functions that cannot carry docs.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mpm_benches::SplitMix64;
use mpm_constitutive::{
    Branch, ConeMatch, ConstitutiveModel, DpBranch, DpState, DruckerPrager, DruckerPragerParams,
    PlaneTensor, SymTensor,
};

/// The step duration passed to the updates: these models are rate-independent, so any Δt > 0
/// gives the same bits.
const DT: f64 = 1e-3;

/// updates per benchmark iteration: enough to amortise the loop, few enough to stay in L1/L2.
const POINTS: usize = 1024;

/// one material point's input: stress, internal state, strain increment.
type Input = (SymTensor, DpState, SymTensor);

/// the paper's flume sand (table 2) with some hardening so that every term of the return runs.
fn sand() -> DruckerPrager {
    DruckerPrager::new(DruckerPragerParams {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 40.0,
        dilatancy_angle_deg: 10.0,
        hardening_modulus: 1.0e4,
        mixing: 0.8,
        cone_match: ConeMatch::PlaneStrain,
    })
    .expect("valid parameters")
}

/// a random tensor; with `plane`, without out-of-plane shear.
fn tensor(rng: &mut SplitMix64, scale: f64, plane: bool) -> SymTensor {
    let t = SymTensor::from_array([0; 6].map(|_| rng.uniform(-scale, scale)));
    if plane { PlaneTensor::from_sym(&t).to_sym() } else { t }
}

/// seeded inputs whose update takes `surface`: compressed states (mean −1e3 .. −1e2 Pa) with a
/// back stress, and increments of the kind each branch needs.
fn inputs(m: &DruckerPrager, surface: Branch, seed: u64, plane: bool) -> Vec<Input> {
    let mut rng = SplitMix64::new(seed);
    let tensor = |rng: &mut SplitMix64, scale| tensor(rng, scale, plane);
    let mut out = Vec::with_capacity(POINTS);
    while out.len() < POINTS {
        let p = rng.uniform(-1.0e3, -1.0e2);
        let state = DpState {
            back_stress: tensor(&mut rng, 5.0).deviator(),
            k: m.k0() + rng.uniform(0.0, 5.0),
            eps_p_bar: rng.uniform(0.0, 0.01),
        };
        let sigma = SymTensor::IDENTITY * p + tensor(&mut rng, 0.2 * p.abs()).deviator();
        let d_eps = match surface {
            DpBranch::CONE => tensor(&mut rng, 2e-4).deviator(),
            // pulled apart: volumetric extension well beyond the tip.
            DpBranch::APEX => {
                let v = rng.uniform(2e-3, 5e-3);
                SymTensor::new(v, v, v, 0.0, 0.0, 0.0) + tensor(&mut rng, 1e-4)
            }
            _ => tensor(&mut rng, 1e-6),
        };
        let (mut s, mut st) = (sigma, state);
        if m.update(&mut s, &mut st, &d_eps, DT).map(|r| r.branch) == Ok(surface) {
            out.push((sigma, state, d_eps));
        }
    }
    out
}

/// the rotation (cos θ, sin θ) of the plane benches: a spin of 1e-4 rad per step.
const TURN: (f64, f64) = (0.999_999_995, 1e-4);

/// the plane-strain inputs (Δε_zz = 0) among `input` whose turned update still takes `surface`.
fn bench_dp_plane(
    c: &mut Criterion,
    name: &str,
    m: &DruckerPrager,
    input: &[Input],
    surface: Branch,
) {
    let input: Vec<_> = input
        .iter()
        .map(|(s, st, d)| {
            (PlaneTensor::from_sym(s), *st, PlaneTensor { zz: 0.0, ..PlaneTensor::from_sym(d) })
        })
        .filter(|(s, st, d)| {
            let (mut s, mut st) = (*s, *st);
            m.update_plane(&mut s, &mut st, d, DT, Some(TURN)).map(|r| r.branch) == Ok(surface)
        })
        .collect();
    assert!(input.len() >= POINTS / 2, "{name}: {} points keep their branch", input.len());
    let mut group = c.benchmark_group("constitutive");
    group.throughput(Throughput::Elements(input.len() as u64));
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (sigma, state, d_eps) in black_box(&input) {
                let (mut s, mut st) = (*sigma, *state);
                let rep = m.update_plane(&mut s, &mut st, d_eps, DT, Some(TURN));
                acc += black_box(s).xx + rep.map_or(0.0, |r| r.delta_lambda);
            }
            acc
        })
    });
    group.finish();
}

fn bench_dp(c: &mut Criterion, name: &str, m: &DruckerPrager, input: &[Input]) {
    let mut group = c.benchmark_group("constitutive");
    group.throughput(Throughput::Elements(input.len() as u64));
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (sigma, state, d_eps) in black_box(input) {
                let (mut s, mut st) = (*sigma, *state);
                let rep = m.update(&mut s, &mut st, d_eps, DT);
                acc += black_box(s).xx + rep.map_or(0.0, |r| r.delta_lambda);
            }
            acc
        })
    });
    group.finish();
}

fn constitutive(c: &mut Criterion) {
    let m = sand();

    let elastic = *m.elasticity();
    let el_input: Vec<(SymTensor, SymTensor)> = {
        let mut rng = SplitMix64::new(0x656c_6173);
        (0..POINTS).map(|_| (tensor(&mut rng, 1e3, false), tensor(&mut rng, 1e-4, false))).collect()
    };
    let mut group = c.benchmark_group("constitutive");
    group.throughput(Throughput::Elements(POINTS as u64));
    group.bench_function("linear_elastic", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (sigma, d_eps) in black_box(&el_input) {
                let mut s = *sigma;
                let _ = elastic.update(&mut s, &mut (), d_eps, DT);
                acc += black_box(s).xx;
            }
            acc
        })
    });
    group.finish();

    bench_dp(c, "dp_elastic", &m, &inputs(&m, DpBranch::ELASTIC, 0x6470_656c, false));
    bench_dp(c, "dp_cone", &m, &inputs(&m, DpBranch::CONE, 0x636f_6e65, false));
    bench_dp(c, "dp_apex", &m, &inputs(&m, DpBranch::APEX, 0x6170_6578, false));
    let elastic_plane = inputs(&m, DpBranch::ELASTIC, 0x6470_656c, true);
    bench_dp_plane(c, "dp_elastic_plane", &m, &elastic_plane, DpBranch::ELASTIC);
    let cone_plane = inputs(&m, DpBranch::CONE, 0x636f_6e65, true);
    bench_dp_plane(c, "dp_cone_plane", &m, &cone_plane, DpBranch::CONE);

    // the paper's cohesionless, non-dilatant limit (c = 0, ψ = 0): the separating-sand apex.
    let loose = DruckerPrager::new(DruckerPragerParams {
        cohesion: 0.0,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        ..*m.params()
    })
    .expect("valid parameters");
    bench_dp(c, "dp_apex_c0_psi0", &loose, &inputs(&loose, DpBranch::APEX, 0x6c6f_6f73, false));
}

criterion_group!(benches, constitutive);
criterion_main!(benches);
