//! Element-test drivers (the paper's §6(3)): a single material point driven along a mixed
//! stress/strain path, solved by Newton iteration on the consistent tangent.
//!
//! # Glossary
//! - `ε` total small strain since the start of the test (tensor components; CSV output also gives
//!   engineering shear `γ = 2ε`), `σ` stress (Pa), `ε̄ᵖ` equivalent plastic strain.
//! - A [`MixedControl`] marks each of the six components `[xx, yy, zz, xy, yz, zx]` as strain
//!   controlled (its strain increment per step is prescribed) or stress controlled (its stress
//!   increment per step is prescribed; the strain component is solved for).
//!
//! Tension positive (compression tests use negative strains), SI units.
//!
//! # Newton iteration
//! In each step the unknown strain increments `x` (the stress-controlled components) solve
//! `r(x) = σ_c(Δε(x)) − σ_c* = 0`, where `σ_c*` are the target stresses `σ0 + n Δσ` (no drift
//! over many steps). The Jacobian is the controlled block of the consistent tangent
//! ([`TangentModel`]), with halving of the Newton step while the residual does not decrease.
//! Convergence: `max |r| ≤ NEWTON_REL_TOL · S`, with the stress scale `S` the largest component
//! magnitude among the start stress, the updated stress and the targets.

use std::io::Write;

use crate::error::ConstitutiveError;
pub use crate::model::TangentModel;
use crate::tensor::{SymTensor, Tangent};

/// required relative residual of the controlled stresses: the 1e-9, far above the
/// ~1e-15 rounding of one update, far below the 0.1 % of the reference checks.
pub const NEWTON_REL_TOL: f64 = 1e-9;

/// Newton iterations allowed per step; a consistent tangent needs 1–3 on a smooth branch.
pub const NEWTON_MAX_ITERATIONS: usize = 50;

/// step halvings tried when a full Newton step does not reduce the residual (branch switches).
const MAX_HALVINGS: usize = 30;

/// Which components are stress controlled, and the per-step increment of every component.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixedControl {
    /// `true`: the stress of this component is prescribed; `false`: its strain is prescribed.
    pub stress_controlled: [bool; 6],
    /// per-step increment in storage order: a tensor strain increment where strain controlled,
    /// a stress increment (Pa) where stress controlled.
    pub increment: [f64; 6],
    /// the duration of one step (s): a rate-dependent model sees the strain rate `Δε/dt`;
    /// rate-independent models ignore it. [`QUASI_STATIC_STEP`] for a slow test.
    pub dt: f64,
}

/// The duration of one step of the convenience drivers ([`uniaxial_plane_strain`],
/// [`simple_shear`], [`isotropic`]): 1 s, so that strain increments of a test (≤ 1e-2) are slow
/// loading. A rate-dependent model is driven at a chosen rate through [`run_mixed`].
pub const QUASI_STATIC_STEP: f64 = 1.0;

/// One point of an element-test path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint<S> {
    /// load step (0 is the start point).
    pub step: usize,
    /// total strain since the start (tensor components).
    pub strain: SymTensor,
    /// stress at the end of the step (Pa).
    pub stress: SymTensor,
    /// internal variables at the end of the step.
    pub state: S,
    /// equivalent plastic strain `ε̄ᵖ`.
    pub eps_p_bar: f64,
    /// the name of the branch the step's update took (the model's
    /// [`BRANCHES`](crate::ConstitutiveModel::BRANCHES) entry).
    pub branch: &'static str,
    /// plastic multiplier of the step.
    pub delta_lambda: f64,
    /// plastic work `σ : Δεᵖ` of the step (J/m³).
    pub dissipation: f64,
    /// Newton iterations used (0 when fully strain controlled or already converged).
    pub iterations: usize,
}

/// Drives `model` from (`sigma0`, `state0`) through `n_steps` equal steps of `control`.
///
/// Returns `n_steps + 1` points, the first being the start state.
pub fn run_mixed<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    state0: M::State,
    control: &MixedControl,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    if n_steps == 0 {
        return Err(ConstitutiveError::InvalidParameter {
            name: "n_steps",
            value: 0.0,
            range: "n_steps >= 1",
        });
    }
    if let Some(&v) = control.increment.iter().find(|v| !v.is_finite()) {
        return Err(ConstitutiveError::InvalidParameter {
            name: "increment",
            value: v,
            range: "finite components",
        });
    }
    if !(control.dt.is_finite() && control.dt > 0.0) {
        return Err(ConstitutiveError::InvalidParameter {
            name: "dt",
            value: control.dt,
            range: "finite and > 0",
        });
    }
    let dt = control.dt;
    let ctrl: Vec<usize> = (0..6).filter(|&i| control.stress_controlled[i]).collect();
    let s0 = sigma0.to_array();
    let mut points = Vec::with_capacity(n_steps + 1);
    points.push(PathPoint {
        step: 0,
        strain: SymTensor::ZERO,
        stress: sigma0,
        state: state0,
        eps_p_bar: model.equivalent_plastic_strain(&state0),
        branch: M::BRANCHES[0],
        delta_lambda: 0.0,
        dissipation: 0.0,
        iterations: 0,
    });
    let (mut sigma, mut state, mut strain) = (sigma0, state0, SymTensor::ZERO);
    // unknown strain increments, continued from the previous step.
    let mut x = [0.0; 6];
    for step in 1..=n_steps {
        let mut target = [0.0; 6];
        for &i in &ctrl {
            target[i] = s0[i] + step as f64 * control.increment[i];
        }
        let build = |x: &[f64; 6]| {
            let mut e = control.increment;
            for &i in &ctrl {
                e[i] = x[i];
            }
            SymTensor::from_array(e)
        };
        let eval = |x: &[f64; 6]| -> Result<(SymTensor, M::State, _, f64, f64), _> {
            let d_eps = build(x);
            let (mut s, mut st) = (sigma, state);
            let rep = model.update(&mut s, &mut st, &d_eps, dt)?;
            let sa = s.to_array();
            let mut scale = max_abs(&sigma.to_array()).max(max_abs(&sa));
            let mut res = 0.0f64;
            for &i in &ctrl {
                scale = scale.max(target[i].abs());
                res = res.max((sa[i] - target[i]).abs());
            }
            Ok((s, st, rep, res, scale))
        };
        let mut cur = eval(&x)?;
        let mut iterations = 0;
        // residual and scale are finite: the update refuses non-finite results.
        while cur.3 > NEWTON_REL_TOL * cur.4 {
            if iterations == NEWTON_MAX_ITERATIONS {
                return Err(ConstitutiveError::NewtonDidNotConverge {
                    step,
                    iterations,
                    relative_residual: cur.3 / cur.4,
                    tolerance: NEWTON_REL_TOL,
                });
            }
            iterations += 1;
            let t = model.consistent_tangent(&sigma, &state, &build(&x), dt)?;
            let sa = cur.0.to_array();
            let dx = solve_block(&t, &ctrl, |i| target[i] - sa[i])
                .ok_or(ConstitutiveError::SingularTangent { step })?;
            // full step, halved while the residual grows (kinks between branches).
            let mut lambda = 1.0;
            let mut accepted = None;
            for _ in 0..=MAX_HALVINGS {
                let mut xn = x;
                for &i in &ctrl {
                    xn[i] += lambda * dx[i];
                }
                let trial = eval(&xn)?;
                if trial.3 < cur.3 || trial.3 <= NEWTON_REL_TOL * trial.4 {
                    accepted = Some((xn, trial));
                    break;
                }
                lambda *= 0.5;
            }
            match accepted {
                Some((xn, next)) => {
                    x = xn;
                    cur = next;
                }
                None => {
                    return Err(ConstitutiveError::NewtonDidNotConverge {
                        step,
                        iterations,
                        relative_residual: cur.3 / cur.4,
                        tolerance: NEWTON_REL_TOL,
                    });
                }
            }
        }
        let (s, st, rep, _, _) = cur;
        strain += build(&x);
        sigma = s;
        state = st;
        points.push(PathPoint {
            step,
            strain,
            stress: sigma,
            state,
            eps_p_bar: model.equivalent_plastic_strain(&state),
            branch: M::BRANCHES.get(rep.branch.index()).copied().unwrap_or("unnamed"),
            delta_lambda: rep.delta_lambda,
            dissipation: rep.dissipation,
            iterations,
        });
    }
    Ok(points)
}

/// Plane-strain uniaxial compression (or extension): `ε_yy` prescribed from 0 to `eps_yy_end` in
/// `n_steps` equal steps, `σ_xx` held at `sigma0.xx` (lateral stress free when 0),
/// `ε_zz = 0` (so `σ_zz` builds up), shear strains zero.
pub fn uniaxial_plane_strain<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    eps_yy_end: f64,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    axial(model, sigma0, eps_yy_end, n_steps, [true, false, false, false, false, false])
}

/// `ε_yy` prescribed from 0 to `eps_yy_end` in `n_steps` equal steps, the components marked in
/// `held` stress controlled at their start values, every other strain component zero.
fn axial<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    eps_yy_end: f64,
    n_steps: usize,
    held: [bool; 6],
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    let n = n_steps.max(1) as f64;
    let control = MixedControl {
        stress_controlled: held,
        increment: [0.0, eps_yy_end / n, 0.0, 0.0, 0.0, 0.0],
        dt: QUASI_STATIC_STEP,
    };
    run_mixed(model, sigma0, model.initial_state(), &control, n_steps)
}

/// Drained simple shear at constant vertical stress: engineering shear `γ_xy = 2ε_xy` prescribed
/// from 0 to `gamma_end`, `σ_yy` held at `sigma0.yy` (`ε_yy` free: dilation or contraction),
/// `ε_xx = ε_zz = 0`, `ε_yz = ε_zx = 0`.
pub fn simple_shear<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    gamma_end: f64,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    shear(model, sigma0, gamma_end, n_steps, QUASI_STATIC_STEP)
}

/// [`simple_shear`] at the shear rate `rate = γ̇` (1/s): each of the `n_steps` steps lasts
/// `(gamma_end / n_steps) / rate`, for a rate-dependent model.
pub fn simple_shear_at_rate<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    gamma_end: f64,
    n_steps: usize,
    rate: f64,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    let dt = (gamma_end / n_steps.max(1) as f64 / rate).abs();
    shear(model, sigma0, gamma_end, n_steps, dt)
}

/// the mixed control of [`simple_shear`] with steps of duration `dt`.
fn shear<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    gamma_end: f64,
    n_steps: usize,
    dt: f64,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    let n = n_steps.max(1) as f64;
    let control = MixedControl {
        stress_controlled: [false, true, false, false, false, false],
        increment: [0.0, 0.0, 0.0, 0.5 * gamma_end / n, 0.0, 0.0],
        dt,
    };
    run_mixed(model, sigma0, model.initial_state(), &control, n_steps)
}

/// Drained triaxial compression (`eps_axial_end < 0`) or extension (`> 0`) along y: `ε_yy`
/// prescribed from 0 in `n_steps` equal steps, the lateral stresses `σ_xx` and `σ_zz` held at
/// their start values (`sigma0`, e.g. an isotropic confining stress), shear strains zero.
pub fn triaxial<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    eps_axial_end: f64,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    axial(model, sigma0, eps_axial_end, n_steps, [true, false, true, false, false, false])
}

/// One-dimensional (oedometric, K0) compression along y: `ε_yy` prescribed from 0 in `n_steps`
/// equal steps, every other strain component held at zero (fully strain controlled).
pub fn oedometric<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    eps_yy_end: f64,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    axial(model, sigma0, eps_yy_end, n_steps, [false; 6])
}

/// Isotropic compression (`eps_v_end < 0`) or extension (`> 0`): `ε_xx = ε_yy = ε_zz = ε_v/3`
/// prescribed, shear strains zero (fully strain controlled, so it also runs past the apex).
pub fn isotropic<M: TangentModel>(
    model: &M,
    sigma0: SymTensor,
    eps_v_end: f64,
    n_steps: usize,
) -> Result<Vec<PathPoint<M::State>>, ConstitutiveError> {
    let d = eps_v_end / (3.0 * n_steps.max(1) as f64);
    let control = MixedControl {
        stress_controlled: [false; 6],
        increment: [d, d, d, 0.0, 0.0, 0.0],
        dt: QUASI_STATIC_STEP,
    };
    run_mixed(model, sigma0, model.initial_state(), &control, n_steps)
}

/// CSV header matching [`write_csv`] rows.
pub const CSV_HEADER: &str = "test,step,eps_xx,eps_yy,eps_zz,gamma_xy,gamma_yz,gamma_zx,eps_v,\
sig_xx,sig_yy,sig_zz,sig_xy,sig_yz,sig_zx,p,sqrt_j2,eps_p_bar,surface,delta_lambda,dissipation";

/// Writes a path as CSV rows labelled `test` (strains dimensionless, engineering shear `γ = 2ε`,
/// stresses in Pa, tension positive); writes [`CSV_HEADER`] first when `header` is true.
pub fn write_csv<W: Write, S>(
    w: &mut W,
    test: &str,
    path: &[PathPoint<S>],
    header: bool,
) -> std::io::Result<()> {
    if header {
        writeln!(w, "{CSV_HEADER}")?;
    }
    for p in path {
        let (e, s) = (p.strain, p.stress);
        writeln!(
            w,
            "{test},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{:e},{:e}",
            p.step,
            e.xx,
            e.yy,
            e.zz,
            2.0 * e.xy,
            2.0 * e.yz,
            2.0 * e.zx,
            e.trace(),
            s.xx,
            s.yy,
            s.zz,
            s.xy,
            s.yz,
            s.zx,
            s.mean(),
            s.j2().sqrt(),
            p.eps_p_bar,
            p.branch,
            p.delta_lambda,
            p.dissipation,
        )?;
    }
    Ok(())
}

fn max_abs(a: &[f64; 6]) -> f64 {
    a.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// solves `T[c][c] dx[c] = rhs(c)` over the controlled indices with faer's LU factorisation
/// with partial pivoting; `None` if the block is singular to working precision (a pivot of U
/// below 1e-13 of the block's largest entry, or not finite).
fn solve_block(t: &Tangent, ctrl: &[usize], rhs: impl Fn(usize) -> f64) -> Option<[f64; 6]> {
    use faer::linalg::solvers::Solve;
    let n = ctrl.len();
    let a = faer::Mat::<f64>::from_fn(n, n, |r, c| t[ctrl[r]][ctrl[c]]);
    let norm = (0..n)
        .flat_map(|r| (0..n).map(move |c| (r, c)))
        .fold(0.0f64, |m, (r, c)| m.max(a[(r, c)].abs()));
    // pivots below this are rounding noise of the block entries.
    let tiny = norm * 1e-13;
    let b = faer::Mat::<f64>::from_fn(n, 1, |r, _| rhs(ctrl[r]));
    let lu = a.partial_piv_lu();
    let u = lu.U();
    let y = if (0..n).any(|k| u[(k, k)].abs() <= tiny || !u[(k, k)].is_finite()) {
        min_norm(&a, &b, tiny)?
    } else {
        lu.solve(&b)
    };
    let mut dx = [0.0; 6];
    for (r, &i) in ctrl.iter().enumerate() {
        dx[i] = y[(r, 0)];
    }
    dx.iter().all(|v| v.is_finite()).then_some(dx)
}

/// The minimum-norm solution of a singular block `A x = b` (through its SVD, singular values
/// below `tiny` dropped) when `b` lies in its range to 1e-9 — a stress-controlled pair held
/// on a perfectly plastic corner (triaxial compression on Mohr–Coulomb's edge: the two lateral
/// strains are free along the edge, the symmetric split is the least one); `None` when `b` is
/// outside the range (no strain reaches the targets).
fn min_norm(a: &faer::Mat<f64>, b: &faer::Mat<f64>, tiny: f64) -> Option<faer::Mat<f64>> {
    let n = a.nrows();
    let svd = a.thin_svd().ok()?;
    let (u, v, s) = (svd.U(), svd.V(), svd.S().column_vector());
    let mut x = faer::Mat::<f64>::zeros(n, 1);
    for k in 0..n {
        if s[k].is_nan() || s[k] <= tiny {
            continue;
        }
        let coef = (0..n).map(|r| u[(r, k)] * b[(r, 0)]).sum::<f64>() / s[k];
        for r in 0..n {
            x[(r, 0)] += v[(r, k)] * coef;
        }
    }
    let b_norm = (0..n).fold(0.0f64, |m, r| m.max(b[(r, 0)].abs()));
    let residual = (0..n).fold(0.0f64, |m, r| {
        let ax: f64 = (0..n).map(|c| a[(r, c)] * x[(c, 0)]).sum();
        m.max((ax - b[(r, 0)]).abs())
    });
    (residual <= 1e-9 * b_norm).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elastic::LinearElastic;

    /// elastic closed forms through a 1e-9 Newton tolerance: a few times 1e-9 relative.
    const ELASTIC_REL: f64 = 1e-8;

    #[test]
    fn elastic_uniaxial_plane_strain_matches_closed_form() {
        // σ_xx = 0, ε_zz = 0: σ_yy = E/(1 − ν²) ε_yy, ε_xx = −ν/(1 − ν) ε_yy, σ_zz = ν σ_yy.
        let (e, nu) = (2.0e6, 0.3);
        let m = LinearElastic::from_young_poisson(e, nu).unwrap();
        let path = uniaxial_plane_strain(&m, SymTensor::ZERO, -1e-3, 10).unwrap();
        assert_eq!(path.len(), 11);
        let last = path.last().unwrap();
        let syy = e / (1.0 - nu * nu) * -1e-3;
        assert!((last.stress.yy - syy).abs() <= ELASTIC_REL * syy.abs());
        assert!((last.stress.zz - nu * syy).abs() <= ELASTIC_REL * syy.abs());
        assert!(last.stress.xx.abs() <= ELASTIC_REL * syy.abs());
        let exx = -nu / (1.0 - nu) * -1e-3;
        assert!((last.strain.xx - exx).abs() <= ELASTIC_REL * exx.abs());
        // linear problem: Newton converges in at most one iteration per step.
        assert!(path.iter().all(|p| p.iterations <= 1));
    }

    #[test]
    fn stress_controlled_isotropic_path_hits_targets() {
        let m = LinearElastic::from_young_poisson(1.0e7, 0.25).unwrap();
        let control = MixedControl {
            stress_controlled: [true; 6],
            increment: [-100.0; 6],
            dt: QUASI_STATIC_STEP,
        };
        let path = run_mixed(&m, SymTensor::ZERO, (), &control, 5).unwrap();
        let last = path.last().unwrap();
        for (s, target) in last.stress.to_array().into_iter().zip([-500.0; 6]) {
            assert!((s - target).abs() <= ELASTIC_REL * 500.0);
        }
        // ε = C⁻¹ : σ.
        let e = m.strain_from_stress(&last.stress);
        assert!((last.strain - e).norm() <= ELASTIC_REL * e.norm());
    }

    /// the controlled block of a known matrix is solved to rounding (1e-14 relative: a few ulps
    /// of a well-conditioned 3 × 3 system), and a singular block is refused, not divided by ~0.
    #[test]
    fn solve_block_solves_the_controlled_block_and_refuses_an_inconsistent_singular_one() {
        let mut t: Tangent = [[0.0; 6]; 6];
        for (i, row) in t.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = if i == j { 4.0 + i as f64 } else { 1.0 / (1.0 + (i + j) as f64) };
            }
        }
        let ctrl = [0, 2, 5];
        let want = [1.5, 0.0, -2.0, 0.0, 0.0, 0.25];
        let rhs = |i: usize| ctrl.iter().map(|&j| t[i][j] * want[j]).sum::<f64>();
        let got = solve_block(&t, &ctrl, rhs).expect("regular block");
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-14 * 2.0, "{got:?} vs {want:?}");
        }
        // rows 0 and 2 made equal: the block is singular; a right-hand side outside its
        // range is refused, one inside gets the minimum-norm solution.
        t[2] = t[0];
        assert!(solve_block(&t, &ctrl, |i| if i == 2 { 2.0 } else { 1.0 }).is_none());
        let got = solve_block(&t, &ctrl, |_| 1.0).expect("consistent singular block");
        for &i in &ctrl {
            let lhs: f64 = ctrl.iter().map(|&j| t[i][j] * got[j]).sum();
            assert!((lhs - 1.0).abs() <= 1e-12, "row {i}: {lhs}");
        }
    }

    #[test]
    fn bad_loading_is_rejected() {
        let m = LinearElastic::from_young_poisson(1.0e7, 0.25).unwrap();
        assert!(matches!(
            uniaxial_plane_strain(&m, SymTensor::ZERO, -1e-3, 0),
            Err(ConstitutiveError::InvalidParameter { name: "n_steps", .. })
        ));
        assert!(matches!(
            simple_shear(&m, SymTensor::ZERO, f64::NAN, 3),
            Err(ConstitutiveError::InvalidParameter { name: "increment", .. })
        ));
    }

    #[test]
    fn csv_has_one_row_per_point_and_matching_columns() {
        let m = LinearElastic::from_young_poisson(1.0e7, 0.25).unwrap();
        let path = isotropic(&m, SymTensor::ZERO, -1e-3, 4).unwrap();
        let mut out = Vec::new();
        write_csv(&mut out, "iso", &path, true).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines.len(), 1 + path.len());
        let ncol = CSV_HEADER.split(',').count();
        assert!(lines.iter().all(|l| l.split(',').count() == ncol));
    }
}
