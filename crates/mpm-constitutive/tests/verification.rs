//! Verification of the constitutive crate against the paper's reference numbers (Abe et al. 2005,
//! §6(3)) and closed-form solutions: element tests, hardening rules, apex return, validation.
//!
//! Conventions: tension positive, SI units, tensor shear strain (`γ = 2 ε_xy`).

use mpm_constitutive::element_test::{
    MixedControl, PathPoint, QUASI_STATIC_STEP, isotropic, run_mixed, simple_shear,
    uniaxial_plane_strain,
};
use mpm_constitutive::{
    Branch, ConeMatch, ConstitutiveError, ConstitutiveModel, DpBranch, DpState, DruckerPrager,
    DruckerPragerParams, LinearElastic, PlaneTensor, SymTensor,
};

/// The step duration passed to the updates: these models are rate-independent, so any Δt > 0
/// gives the same bits.
const DT: f64 = 1e-3;

/// the issue's acceptance tolerance on the paper's quoted numbers (0.1 %).
const PAPER_REL: f64 = 1e-3;
/// results that are exact up to the 1e-9 Newton tolerance of the element-test driver.
const NEWTON_REL: f64 = 1e-8;
/// results exact up to a few roundings of the O(1e2) Pa stresses over ~1e3 steps.
const ROUNDING_REL: f64 = 1e-10;

/// the paper's element-test material (E = 2e6 Pa, ν = 0.3, c = 10 Pa, φ = 40°, H = 0).
fn abe2005(psi_deg: f64) -> DruckerPrager {
    DruckerPrager::new(DruckerPragerParams {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 40.0,
        dilatancy_angle_deg: psi_deg,
        hardening_modulus: 0.0,
        mixing: 1.0,
        cone_match: ConeMatch::PlaneStrain,
    })
    .unwrap()
}

fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

mod abe2005_element_tests {
    use super::*;

    /// σ_yy at first yield in plane-strain uniaxial compression from the elastic path:
    /// σ_xx = 0, σ_zz = ν σ_yy, so I1 = (1 + ν) σ_yy and √J2 = √((1 − ν + ν²)/3) |σ_yy|.
    fn first_yield_closed_form(m: &DruckerPrager, nu: f64) -> f64 {
        let sqrt_j2_per_unit = ((1.0 - nu + nu * nu) / 3.0).sqrt();
        -m.k0() / (sqrt_j2_per_unit - m.alpha() * (1.0 + nu))
    }

    #[test]
    fn abe2005_uniaxial_plane_strain_first_yield() {
        for psi in [0.0, 40.0] {
            let m = abe2005(psi);
            let closed = first_yield_closed_form(&m, 0.3);
            assert!(rel_err(closed, -28.50) <= PAPER_REL, "closed form {closed}");
            // 2e-9 strain per step = 4.4e-3 Pa per step, 0.015 % of the yield stress.
            let path = uniaxial_plane_strain(&m, SymTensor::ZERO, -2.0e-5, 10_000).unwrap();
            let i = path.iter().position(|p| p.branch != "elastic").unwrap();
            let (before, after) = (&path[i - 1], &path[i]);
            assert_eq!(after.branch, "cone");
            for p in [before, after] {
                assert!(rel_err(p.stress.yy, -28.50) <= PAPER_REL, "ψ = {psi}: {:?}", p.stress);
            }
            // the closed form is bracketed by the last elastic and the first plastic point.
            assert!(before.stress.yy >= closed && after.stress.yy <= closed);
            // plane strain builds σ_zz = ν σ_yy on the elastic branch.
            assert!(rel_err(before.stress.zz, 0.3 * before.stress.yy) <= NEWTON_REL);
        }
    }

    #[test]
    fn abe2005_uniaxial_plane_strain_steady_state_psi_0() {
        let m = abe2005(0.0);
        // 2e-3 is 150 times the yield strain: the perfectly plastic path has converged.
        let path = uniaxial_plane_strain(&m, SymTensor::ZERO, -2.0e-3, 2_000).unwrap();
        let last = path.last().unwrap();
        assert!(rel_err(last.stress.yy, -36.15) <= PAPER_REL, "{:?}", last.stress);
        // independent steady state: no plastic ε_zz with αg = 0 needs s_zz = β_zz = 0, i.e.
        // σ_zz = (σ_xx + σ_yy + σ_zz)/3 = σ_yy/2; then α·1.5σ + |σ|/2 = k0.
        let closed = -m.k0() / (0.5 - 1.5 * m.alpha());
        assert!(rel_err(last.stress.yy, closed) <= NEWTON_REL);
        assert!(rel_err(last.stress.zz, 0.5 * closed) <= NEWTON_REL);
        assert!(last.stress.xx.abs() <= NEWTON_REL * closed.abs());
        // no plastic volume change with ψ = 0: ε_v = tr σ/(3K).
        let k = m.elasticity().bulk_modulus();
        let elastic_vol = last.stress.trace() / (3.0 * k);
        assert!((last.strain.trace() - elastic_vol).abs() <= ROUNDING_REL * 2.0e-3);
    }

    #[test]
    fn abe2005_uniaxial_plane_strain_steady_state_psi_phi() {
        let m = abe2005(40.0);
        let path = uniaxial_plane_strain(&m, SymTensor::ZERO, -2.0e-3, 2_000).unwrap();
        let last = path.last().unwrap();
        assert!(rel_err(last.stress.yy, -42.89) <= PAPER_REL, "{:?}", last.stress);
        // associated flow with the plane-strain match reproduces Mohr-Coulomb's unconfined
        // strength 2c cosφ/(1 − sinφ) exactly.
        let (s, c) = 40f64.to_radians().sin_cos();
        let mc = -2.0 * 10.0 * c / (1.0 - s);
        assert!(rel_err(last.stress.yy, mc) <= NEWTON_REL);
        // and it dilates.
        assert!(last.strain.trace() > 0.0);
    }

    /// the simple-shear material: the paper's sand consolidated under σ_yy = −100 Pa, K0 = 0.5.
    fn sheared(psi: f64) -> (DruckerPrager, Vec<PathPoint<DpState>>) {
        let m = abe2005(psi);
        let sigma0 = SymTensor::new(-50.0, -100.0, -50.0, 0.0, 0.0, 0.0);
        // yield near γ = 4.9e-5: steps of 1e-6 resolve the elastic range with ~49 points.
        let path = simple_shear(&m, sigma0, 0.005, 5_000).unwrap();
        (m, path)
    }

    #[test]
    fn abe2005_simple_shear_elastic_slope_is_g() {
        let (m, path) = sheared(0.0);
        let g = m.elasticity().shear_modulus();
        let elastic: Vec<_> = path.iter().skip(1).take_while(|p| p.branch == "elastic").collect();
        assert!(elastic.len() >= 5, "{} elastic points", elastic.len());
        for p in elastic {
            let slope = p.stress.xy / (2.0 * p.strain.xy);
            assert!(rel_err(slope, g) <= ROUNDING_REL, "τ/γ = {slope}, G = {g}");
            // no coupling in the elastic range: σ_yy held, normal strains unchanged.
            assert!((p.stress.yy + 100.0).abs() <= NEWTON_REL * 100.0);
        }
        assert!(path.iter().any(|p| p.branch == "cone"));
        // σ_yy is held throughout.
        assert!(path.iter().all(|p| (p.stress.yy + 100.0).abs() <= NEWTON_REL * 100.0));
    }

    #[test]
    fn abe2005_simple_shear_psi_0_has_no_plastic_volume_change() {
        let (m, path) = sheared(0.0);
        let k = m.elasticity().bulk_modulus();
        let i1_0 = path[0].stress.trace();
        for p in &path {
            let plastic_vol = p.strain.trace() - (p.stress.trace() - i1_0) / (3.0 * k);
            // strains here are ≤ 1e-2: rounding of sums of ~1e3 increments.
            assert!(plastic_vol.abs() <= ROUNDING_REL * 1e-2, "step {}: {plastic_vol}", p.step);
        }
    }

    #[test]
    fn abe2005_simple_shear_psi_positive_dilates_by_the_flow_rule() {
        for psi in [10.0, 20.0, 40.0] {
            let (m, path) = sheared(psi);
            let k = m.elasticity().bulk_modulus();
            let mut plastic_steps = 0;
            for w in path.windows(2) {
                let d_vol = w[1].strain.trace() - w[0].strain.trace();
                let d_vol_p = d_vol - (w[1].stress.trace() - w[0].stress.trace()) / (3.0 * k);
                let flow_rule = 3.0 * m.alpha_g() * w[1].delta_lambda;
                // Δεᵖ_v ~ 1e-6 per plastic step; rounding of the strain sums is ~1e-18.
                assert!(
                    (d_vol_p - flow_rule).abs() <= ROUNDING_REL * flow_rule.abs() + 1e-16,
                    "ψ = {psi}, step {}: Δεᵖ_v = {d_vol_p}, 3αgΔλ = {flow_rule}",
                    w[1].step
                );
                if w[1].branch == "cone" {
                    plastic_steps += 1;
                    assert!(d_vol_p > 0.0);
                }
            }
            assert!(plastic_steps > 4_900, "ψ = {psi}: {plastic_steps} plastic steps");
            assert!(path.last().unwrap().strain.trace() > 0.0, "ψ = {psi} must dilate");
        }
    }

    #[test]
    fn isotropic_compression_is_elastic_and_extension_ends_at_the_apex() {
        let m = abe2005(0.0);
        let k = m.elasticity().bulk_modulus();
        let path = isotropic(&m, SymTensor::ZERO, -1e-3, 10).unwrap();
        let last = path.last().unwrap();
        assert!(path.iter().all(|p| p.branch == "elastic"));
        assert!(rel_err(last.stress.mean(), -1e-3 * k) <= ROUNDING_REL);
        // extension: the cone's tip p = k0/(3α) is the largest mean tension.
        let path = isotropic(&m, SymTensor::ZERO, 1e-4, 10).unwrap();
        let tip = m.k0() / (3.0 * m.alpha());
        let last = path.last().unwrap();
        assert_eq!(last.branch, "apex");
        for s in [last.stress.xx, last.stress.yy, last.stress.zz] {
            assert!(rel_err(s, tip) <= ROUNDING_REL);
        }
        assert!(last.stress.deviator().norm() <= ROUNDING_REL * tip);
        // hydrostatic extension has no deviatoric plastic strain: ε̄ᵖ stays 0.
        assert_eq!(last.eps_p_bar, 0.0);
    }
}

mod hardening {
    use super::*;

    const E: f64 = 2.0e6;
    const NU: f64 = 0.3;
    const H: f64 = 2.0e5;

    fn material(mixing: f64) -> DruckerPrager {
        DruckerPrager::new(DruckerPragerParams {
            young: E,
            poisson: NU,
            cohesion: 10.0,
            friction_angle_deg: 30.0,
            dilatancy_angle_deg: 0.0,
            hardening_modulus: H,
            mixing,
            cone_match: ConeMatch::PlaneStrain,
        })
        .unwrap()
    }

    /// pure shear ε_xy only (strain controlled): with ψ = 0, I1 stays 0 and √J2 = |σ_xy|, so
    /// the test is the 1D linear-hardening problem τ = G(γ − γᵖ), |τ − b| = k with b = β_xy.
    fn shear(
        m: &DruckerPrager,
        sigma: SymTensor,
        state: DpState,
        d_gamma: f64,
        n: usize,
    ) -> Vec<PathPoint<DpState>> {
        let control = MixedControl {
            stress_controlled: [false; 6],
            increment: [0.0, 0.0, 0.0, 0.5 * d_gamma, 0.0, 0.0],
            dt: QUASI_STATIC_STEP,
        };
        run_mixed(m, sigma, state, &control, n).unwrap()
    }

    /// analytic monotonic curve τ(γ) = k0 + (GH/(G+H)) (γ − k0/G) after yield.
    fn tau_analytic(g: f64, k0: f64, gamma: f64) -> f64 {
        let gy = k0 / g;
        if gamma <= gy { g * gamma } else { k0 + g * H / (g + H) * (gamma - gy) }
    }

    #[test]
    fn isotropic_hardening_keeps_beta_zero_and_grows_k_by_h_dlambda() {
        let m = material(1.0);
        let g = m.elasticity().shear_modulus();
        let gy = m.k0() / g;
        let path = shear(&m, SymTensor::ZERO, m.initial_state(), gy / 10.0, 100);
        for w in path.windows(2) {
            assert_eq!(w[1].state.back_stress, SymTensor::ZERO);
            let dk = w[1].state.k - w[0].state.k;
            assert!((dk - H * w[1].delta_lambda).abs() <= ROUNDING_REL * m.k0());
        }
        let last = path.last().unwrap();
        assert!(rel_err(last.state.k, m.k0() + H * last.eps_p_bar) <= ROUNDING_REL);
        let gamma = 2.0 * last.strain.xy;
        assert!(rel_err(last.stress.xy, tau_analytic(g, m.k0(), gamma)) <= ROUNDING_REL);
        // γᵖ = γ − τ/G equals ε̄ᵖ in pure shear.
        assert!(rel_err(last.eps_p_bar, gamma - last.stress.xy / g) <= 1e-8);
    }

    #[test]
    fn kinematic_hardening_keeps_k_and_moves_beta() {
        let m = material(0.0);
        let g = m.elasticity().shear_modulus();
        let gy = m.k0() / g;
        let path = shear(&m, SymTensor::ZERO, m.initial_state(), gy / 10.0, 100);
        for p in &path {
            assert_eq!(p.state.k, m.k0());
            // β moves along n̂ = (e_x⊗e_y + e_y⊗e_x)/√2 by H ε̄ᵖ in √J2 units: β_xy = H ε̄ᵖ.
            assert!((p.state.back_stress.xy - H * p.eps_p_bar).abs() <= ROUNDING_REL * m.k0());
            assert!(p.state.back_stress.j2().sqrt() <= H * p.eps_p_bar * (1.0 + ROUNDING_REL));
        }
        let last = path.last().unwrap();
        assert!(last.state.back_stress.xy > 0.0);
        let gamma = 2.0 * last.strain.xy;
        assert!(rel_err(last.stress.xy, tau_analytic(g, m.k0(), gamma)) <= ROUNDING_REL);
    }

    /// loads in shear to 10 γ_y, reverses, and checks the re-yield stress b − k of each rule.
    #[test]
    fn load_reversal_reyields_where_each_rule_predicts() {
        let mut reyield = Vec::new();
        for mixing in [1.0, 0.5, 0.0] {
            let m = material(mixing);
            let g = m.elasticity().shear_modulus();
            let gy = m.k0() / g;
            let load = shear(&m, SymTensor::ZERO, m.initial_state(), gy / 10.0, 100);
            let top = load.last().unwrap();
            let tau1 = top.stress.xy;
            let ep = top.eps_p_bar;
            // predictions: b = (1 − M) H ε̄ᵖ, k = k0 + M H ε̄ᵖ, re-yield at τ = b − k.
            let (b, k) = ((1.0 - mixing) * H * ep, m.k0() + mixing * H * ep);
            let predicted = b - k;
            assert!(rel_err(tau1, b + k) <= ROUNDING_REL);
            // a step incommensurate with k0/G so that no point lands exactly on the surface.
            let back = shear(&m, top.stress, top.state, -gy / 7.3, 300);
            let i = back.iter().position(|p| p.branch != "elastic").unwrap();
            let (before, after) = (&back[i - 1], &back[i]);
            assert!(
                before.stress.xy > predicted && after.stress.xy <= predicted,
                "M = {mixing}: τ1 = {tau1}, predicted {predicted}, bracket {} .. {} at {i}",
                before.stress.xy,
                after.stress.xy
            );
            // reverse plastic branch: linear hardening makes the return exact, so every plastic
            // point lies on τ = τ_r − GH/(G+H)(γ_r − γ) with γ_r the re-yield strain.
            let gamma_r = 2.0 * top.strain.xy - (tau1 - predicted) / g;
            for p in &back[i..] {
                let gamma = 2.0 * (top.strain.xy + p.strain.xy);
                let tau = predicted - g * H / (g + H) * (gamma_r - gamma);
                assert!((p.stress.xy - tau).abs() <= ROUNDING_REL * tau1, "M = {mixing}");
            }
            reyield.push((mixing, tau1, predicted));
        }
        // Bauschinger: isotropic re-yields at −τ1, kinematic and mixed earlier (|τ_r| < τ1).
        let (_, tau1, iso) = reyield[0];
        assert!(rel_err(iso, -tau1) <= ROUNDING_REL);
        assert!(reyield[1].2 > iso && reyield[2].2 > reyield[1].2);
        let k0 = material(0.0).k0();
        assert!(rel_err(reyield[2].2, reyield[2].1 - 2.0 * k0) <= ROUNDING_REL);
    }

    #[test]
    fn uniaxial_compression_hardens_under_every_rule() {
        for mixing in [1.0, 0.5, 0.0] {
            let m = material(mixing);
            let path = uniaxial_plane_strain(&m, SymTensor::ZERO, -2e-4, 200).unwrap();
            let last = path.last().unwrap();
            // on the yield surface at the end, with σ_xx held at 0.
            assert!(m.yield_function(&last.stress, &last.state).abs() <= 1e-10 * 100.0);
            assert!(last.stress.xx.abs() <= NEWTON_REL * last.stress.yy.abs());
            // H > 0: stress keeps growing after yield.
            let mid = &path[path.len() / 2];
            assert!(mid.branch == "cone" && last.stress.yy < mid.stress.yy);
        }
    }
}

mod apex {
    use super::*;

    fn sand(cohesion: f64, psi: f64, h: f64, mixing: f64) -> DruckerPrager {
        DruckerPrager::new(DruckerPragerParams {
            young: 2.0e6,
            poisson: 0.3,
            cohesion,
            friction_angle_deg: 40.0,
            dilatancy_angle_deg: psi,
            hardening_modulus: h,
            mixing,
            cone_match: ConeMatch::PlaneStrain,
        })
        .unwrap()
    }

    #[test]
    fn cohesionless_non_dilatant_sand_separates_to_zero_stress() {
        let m = sand(0.0, 0.0, 0.0, 0.8);
        // a compressed, sheared point pulled apart in one step.
        let mut sigma = SymTensor::new(-300.0, -500.0, -350.0, 60.0, 0.0, 0.0);
        let mut state = m.initial_state();
        let d_eps = SymTensor::new(2e-3, 3e-3, 0.0, 4e-4, 0.0, 0.0);
        let g = m.elasticity().shear_modulus();
        let trial = sigma + m.elasticity().stress_increment(&d_eps);
        let rep = m.update(&mut sigma, &mut state, &d_eps, DT).unwrap();
        assert_eq!(rep.branch, DpBranch::APEX);
        assert_eq!(sigma, SymTensor::ZERO);
        // Δλ = qᵗʳ/G: the deviatoric plastic strain that removes the trial deviator.
        assert!(rel_err(rep.delta_lambda, trial.j2().sqrt() / g) <= ROUNDING_REL);
        assert_eq!(state.eps_p_bar, rep.delta_lambda);
        assert_eq!(state.k, 0.0);
        // stress-free end state: no plastic work.
        assert_eq!(rep.dissipation, 0.0);
        // pure hydrostatic tension from zero stress: still zero, no multiplier.
        let rep =
            m.update(&mut sigma, &mut state, &SymTensor::new(1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0), DT);
        assert_eq!(rep.unwrap().delta_lambda, 0.0);
        assert_eq!(sigma, SymTensor::ZERO);
    }

    #[test]
    fn apex_with_hardening_lands_on_the_hardened_tip_with_deviator_beta() {
        for (psi, mixing) in [(0.0, 1.0), (0.0, 0.5), (20.0, 0.0), (40.0, 0.3)] {
            let h = 3.0e5;
            let m = sand(10.0, psi, h, mixing);
            let el = *m.elasticity();
            let g = el.shear_modulus();
            let beta0 = SymTensor::new(1.0, -2.0, 1.0, 3.0, 0.0, -1.0);
            let state0 = DpState { back_stress: beta0, k: m.k0() + 2.0, eps_p_bar: 0.1 };
            let sigma0 = SymTensor::new(-20.0, -30.0, -25.0, 5.0, 1.0, 0.0);
            let d_eps = SymTensor::new(4e-4, 5e-4, 3e-4, 1e-5, 0.0, 2e-5);
            let (mut sigma, mut state) = (sigma0, state0);
            let rep = m.update(&mut sigma, &mut state, &d_eps, DT).unwrap();
            assert_eq!(rep.branch, DpBranch::APEX, "ψ = {psi}, M = {mixing}");
            let trial = sigma0 + el.stress_increment(&d_eps);
            let xi = trial.deviator() - beta0;
            let b = g + (1.0 - mixing) * h;
            let dl = xi.j2().sqrt() / b;
            assert!(rel_err(rep.delta_lambda, dl) <= ROUNDING_REL);
            assert!(rel_err(state.k, state0.k + mixing * h * dl) <= ROUNDING_REL);
            // deviator = β, on the hardened surface: α I1 = k.
            assert!((sigma.deviator() - state.back_stress).norm() <= ROUNDING_REL * 100.0);
            assert!(rel_err(m.alpha() * sigma.trace(), state.k) <= ROUNDING_REL);
            assert!(m.yield_function(&sigma, &state).abs() <= 1e-10 * (state.k + 1.0));
            // plastic work from the compliance: σ : C⁻¹ : (σᵗʳ − σ).
            let work = sigma.ddot(&el.strain_from_stress(&(trial - sigma)));
            assert!((rep.dissipation - work).abs() <= ROUNDING_REL * (work.abs() + 1e-3));
            // at least the flow rule's share of volumetric plastic strain.
            let vol_p = (trial.trace() - sigma.trace()) / (3.0 * el.bulk_modulus());
            assert!(vol_p >= 3.0 * m.alpha_g() * dl);
        }
    }

    #[test]
    fn cone_and_apex_returns_meet_continuously() {
        // sweep the increment's tension across the cone/apex boundary in fine steps.
        let m = sand(10.0, 10.0, 1.0e5, 0.6);
        let sigma0 = SymTensor::new(-10.0, -20.0, -10.0, 4.0, 0.0, 0.0);
        let shear = SymTensor::plane(0.0, 0.0, 3e-5);
        let mut prev: Option<(SymTensor, Branch)> = None;
        let mut switched = false;
        for i in 0..=2000 {
            let t = 1e-7 * i as f64;
            let d_eps = shear + SymTensor::new(t, t, t, 0.0, 0.0, 0.0);
            let (mut s, mut st) = (sigma0, m.initial_state());
            let rep = m.update(&mut s, &mut st, &d_eps, DT).unwrap();
            if let Some((ps, surf)) = prev {
                // Lipschitz bound: |Δσ| ≤ ‖C‖ |Δε| with ‖C‖ ≤ 3K + 2G for this isotropic map.
                let el = m.elasticity();
                let lip = 3.0 * el.bulk_modulus() + 2.0 * el.shear_modulus();
                assert!((s - ps).norm() <= lip * 1e-7 * 3f64.sqrt() * (1.0 + 1e-9));
                switched |= surf == DpBranch::CONE && rep.branch == DpBranch::APEX;
            }
            prev = Some((s, rep.branch));
        }
        assert!(switched, "the sweep must cross from the cone to the apex");
    }

    #[test]
    fn frictionless_cone_softened_away_is_an_error_not_a_nan() {
        let m = DruckerPrager::new(DruckerPragerParams {
            young: 1.0e6,
            poisson: 0.25,
            cohesion: 10.0,
            friction_angle_deg: 0.0,
            dilatancy_angle_deg: 0.0,
            hardening_modulus: -1.0e5,
            mixing: 1.0,
            cone_match: ConeMatch::PlaneStrain,
        })
        .unwrap();
        let mut sigma = SymTensor::ZERO;
        let mut state = m.initial_state();
        let big = SymTensor::plane(0.0, 0.0, 1.0);
        let before = (sigma, state);
        let err = m.update(&mut sigma, &mut state, &big, DT).unwrap_err();
        assert!(matches!(err, ConstitutiveError::EmptyElasticDomain { k } if k < 0.0));
        assert_eq!((sigma, state), before);
        // a small shear is fine: von Mises-like cone, softening.
        // 2G ε_xy = 16 Pa > k0 = c = 10 Pa (α = 0): yields, softens k by 2 Pa.
        let small = SymTensor::plane(0.0, 0.0, 2e-5);
        let rep = m.update(&mut sigma, &mut state, &small, DT).unwrap();
        assert_eq!(rep.branch, DpBranch::CONE);
        assert!(state.k < m.k0());
    }
}

mod cone_match {
    use super::*;

    fn cone(cm: ConeMatch, phi: f64, c: f64) -> DruckerPrager {
        DruckerPrager::new(DruckerPragerParams {
            young: 1.0e7,
            poisson: 0.2,
            cohesion: c,
            friction_angle_deg: phi,
            dilatancy_angle_deg: 0.0,
            hardening_modulus: 0.0,
            mixing: 1.0,
            cone_match: cm,
        })
        .unwrap()
    }

    /// f on a Mohr-Coulomb failure state is O(rounding) relative to the stresses.
    const ON_SURFACE: f64 = 1e-12;

    #[test]
    fn triaxial_matches_pass_through_mohr_coulomb_corners() {
        for (phi, c) in [(30.0f64, 5.0), (40.0, 10.0), (15.0, 0.0)] {
            let (s, co) = phi.to_radians().sin_cos();
            let pc = 200.0;
            let state = |m: &DruckerPrager| DpState { k: m.k0(), ..DpState::default() };
            // triaxial compression: radial σ_r = −pc, axial σ_a more compressive (MC limit).
            let sa = -(pc * (1.0 + s) / (1.0 - s) + 2.0 * c * co / (1.0 - s));
            let comp = SymTensor::new(-pc, sa, -pc, 0.0, 0.0, 0.0);
            let outer = cone(ConeMatch::Outer, phi, c);
            assert!(outer.yield_function(&comp, &state(&outer)).abs() <= ON_SURFACE * sa.abs());
            // triaxial extension: axial σ_a less compressive than the radial stress.
            let se = -(pc * (1.0 - s) / (1.0 + s) - 2.0 * c * co / (1.0 + s));
            let ext = SymTensor::new(-pc, se, -pc, 0.0, 0.0, 0.0);
            let inner = cone(ConeMatch::Inner, phi, c);
            assert!(inner.yield_function(&ext, &state(&inner)).abs() <= ON_SURFACE * pc);
            // ordering: the plane-strain cone is the smallest, then inner, then outer.
            let ps = cone(ConeMatch::PlaneStrain, phi, c);
            assert!(ps.alpha() <= inner.alpha() && inner.alpha() < outer.alpha());
        }
    }

    #[test]
    fn plane_strain_match_values_for_40_degrees() {
        // hand values: tan 40° = 0.83909963, √(9 + 12 tan²) = 4.1772070, α = 0.20087576,
        // k0 = 30/4.1772070 = 7.1818323 Pa.
        let m = abe2005(0.0);
        assert!((m.alpha() - 0.200_875_76).abs() <= 1e-8);
        assert!((m.k0() - 7.181_832_3).abs() <= 1e-7);
        assert_eq!(m.alpha_g(), 0.0);
        assert_eq!(abe2005(40.0).alpha_g(), m.alpha());
    }
}

mod validation {
    use super::*;

    fn base() -> DruckerPragerParams {
        DruckerPragerParams::ABE2005_DRY_SAND
    }

    fn rejected(p: DruckerPragerParams) -> ConstitutiveError {
        DruckerPrager::new(p).unwrap_err()
    }

    fn name_of(e: &ConstitutiveError) -> &'static str {
        match e {
            ConstitutiveError::InvalidParameter { name, .. } => name,
            ConstitutiveError::IllPosedSoftening { .. } => "hardening_modulus",
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn every_range_of_the_issue_is_enforced_and_named() {
        let cases: Vec<(DruckerPragerParams, &str)> = vec![
            (DruckerPragerParams { young: 0.0, ..base() }, "young"),
            (DruckerPragerParams { young: f64::INFINITY, ..base() }, "young"),
            (DruckerPragerParams { poisson: 0.5, ..base() }, "poisson"),
            (DruckerPragerParams { poisson: -1.0, ..base() }, "poisson"),
            (DruckerPragerParams { friction_angle_deg: 90.0, ..base() }, "friction_angle_deg"),
            (DruckerPragerParams { friction_angle_deg: -1.0, ..base() }, "friction_angle_deg"),
            (DruckerPragerParams { dilatancy_angle_deg: 41.0, ..base() }, "dilatancy_angle_deg"),
            (DruckerPragerParams { dilatancy_angle_deg: -0.1, ..base() }, "dilatancy_angle_deg"),
            (DruckerPragerParams { cohesion: -1.0, ..base() }, "cohesion"),
            (DruckerPragerParams { cohesion: f64::NAN, ..base() }, "cohesion"),
            (DruckerPragerParams { mixing: 1.5, ..base() }, "mixing"),
            (DruckerPragerParams { mixing: -0.1, ..base() }, "mixing"),
            (DruckerPragerParams { hardening_modulus: f64::NAN, ..base() }, "hardening_modulus"),
        ];
        for (p, name) in cases {
            let e = rejected(p);
            assert_eq!(name_of(&e), name, "{e}");
            let msg = e.to_string();
            assert!(msg.contains(name), "{msg}");
        }
        let msg = rejected(DruckerPragerParams { poisson: 0.7, ..base() }).to_string();
        assert!(msg.contains("0.7") && msg.contains("-1 < poisson < 0.5"), "{msg}");
    }

    #[test]
    fn softening_is_allowed_only_while_well_posed() {
        let g = LinearElastic::from_young_poisson(2.0e6, 0.3).unwrap().shear_modulus();
        // ψ = 0: D = G + H, so H = −G is the limit of the cone return.
        let ok = DruckerPragerParams { hardening_modulus: -0.5 * g, mixing: 1.0, ..base() };
        assert!(DruckerPrager::new(ok).is_ok());
        let e = rejected(DruckerPragerParams { hardening_modulus: -g, mixing: 1.0, ..base() });
        match e {
            ConstitutiveError::IllPosedSoftening { lower_bound, hardening_modulus, .. } => {
                assert!(rel_err(lower_bound, -g) <= ROUNDING_REL);
                assert_eq!(hardening_modulus, -g);
            }
            other => panic!("{other:?}"),
        }
        // with dilatancy the cone denominator 9Kααg + G + H admits more softening, but the apex
        // still needs G + (1 − M) H > 0.
        let dil = DruckerPragerParams {
            dilatancy_angle_deg: 40.0,
            hardening_modulus: -1.5 * g,
            mixing: 1.0,
            ..base()
        };
        let m = DruckerPrager::new(dil).unwrap();
        assert!(m.cone_denominator() > 0.0);
        let e = rejected(DruckerPragerParams { mixing: 0.0, ..dil });
        assert!(matches!(e, ConstitutiveError::IllPosedSoftening { lower_bound, .. }
            if rel_err(lower_bound, -g) <= ROUNDING_REL));
    }

    #[test]
    fn non_finite_input_is_an_error_and_leaves_the_point_untouched() {
        let m = DruckerPrager::new(base()).unwrap();
        let sigma0 = SymTensor::new(-10.0, -20.0, -10.0, 1.0, 0.0, 0.0);
        let state0 = m.initial_state();
        let cases = [
            (sigma0, state0, SymTensor::plane(f64::NAN, 0.0, 0.0)),
            (sigma0, state0, SymTensor::new(0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0)),
            (SymTensor::plane(0.0, f64::NEG_INFINITY, 0.0), state0, SymTensor::ZERO),
            (sigma0, DpState { k: f64::NAN, ..state0 }, SymTensor::ZERO),
            (sigma0, DpState { eps_p_bar: f64::INFINITY, ..state0 }, SymTensor::ZERO),
            (
                sigma0,
                DpState { back_stress: SymTensor::plane(0.0, 0.0, f64::NAN), ..state0 },
                SymTensor::ZERO,
            ),
            // finite but overflowing: the trial stress is infinite.
            (sigma0, state0, SymTensor::new(f64::MAX, f64::MAX, f64::MAX, 0.0, 0.0, 0.0)),
        ];
        for (s0, st0, d) in cases {
            let (mut s, mut st) = (s0, st0);
            let r = m.update(&mut s, &mut st, &d, DT);
            assert!(r.is_err(), "{d:?} {s0:?} {st0:?}");
            assert_eq!(s.to_array().map(f64::to_bits), s0.to_array().map(f64::to_bits));
            assert_eq!(st.k.to_bits(), st0.k.to_bits());
            let inputs_finite = s0.is_finite()
                && d.is_finite()
                && st0.k.is_finite()
                && st0.eps_p_bar.is_finite()
                && st0.back_stress.is_finite();
            assert_eq!(m.consistent_tangent(&s0, &st0, &d).is_err(), !inputs_finite);
            // The plane-strain update (turned or not) refuses the in-plane ones alike.
            if d.yz != 0.0 || d.zx != 0.0 {
                continue;
            }
            let (sp0, dp) = (PlaneTensor::from_sym(&s0), PlaneTensor::from_sym(&d));
            for rotation in [None, Some((0.6, 0.8))] {
                let (mut sp, mut stp) = (sp0, st0);
                let e = m.update_plane(&mut sp, &mut stp, &dp, DT, rotation).unwrap_err();
                if rotation.is_none() {
                    // (turned, a NaN spreads to other components and the name may differ)
                    assert_eq!(e.to_string(), r.as_ref().unwrap_err().to_string());
                }
                let bits = |t: SymTensor| t.to_array().map(f64::to_bits);
                assert_eq!(bits(sp.to_sym()), bits(sp0.to_sym()));
                assert_eq!(bits(stp.back_stress), bits(st0.back_stress));
                assert_eq!(stp.k.to_bits(), st0.k.to_bits());
                assert_eq!(stp.eps_p_bar.to_bits(), st0.eps_p_bar.to_bits());
            }
        }
        // A back stress plane strain cannot carry is refused by name, not dropped.
        for (value, expected) in [(1.0, "out-of-plane"), (f64::NAN, "not finite")] {
            let st0 =
                DpState { back_stress: SymTensor::new(0.0, 0.0, 0.0, 0.0, 0.0, value), ..state0 };
            let (sp0, mut stp) = (PlaneTensor::from_sym(&sigma0), st0);
            let mut sp = sp0;
            let e = m.update_plane(&mut sp, &mut stp, &PlaneTensor::ZERO, DT, None).unwrap_err();
            assert!(e.to_string().contains("back_stress.zx") && e.to_string().contains(expected));
            assert_eq!(sp, sp0);
            assert_eq!(
                stp.back_stress.to_array().map(f64::to_bits),
                st0.back_stress.to_array().map(f64::to_bits)
            );
        }
        let (mut s, mut st) = (sigma0, state0);
        let msg = m
            .update(&mut s, &mut st, &SymTensor::plane(0.0, 0.0, f64::NAN), DT)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("xy") && msg.contains("NaN"), "{msg}");
    }
}

/// The μ(I) element test: simple shear at a constant rate γ̇ under a held normal stress. Once
/// the elastic shear strain is built up (γ ≫ μ p/G) the stress ratio is Jop et al.'s law,
/// τ/p = μ(I) with I = γ̇ d/√(p/ρ_s), at every rate, and the pressure never changes (no
/// dilatancy).
mod mu_i_element_test {
    use mpm_constitutive::element_test::simple_shear_at_rate;
    use mpm_constitutive::{MuI, MuIParams, SymTensor};

    /// the Newton tolerance of the held σ_yy (1e-9) and the central-difference tangent: the
    /// steady state is reached to far below this after 40 relaxation strains.
    const STEADY_REL: f64 = 1e-6;

    #[test]
    fn steady_simple_shear_follows_mu_of_i_at_every_rate() {
        let m = MuI::new(MuIParams::glass_beads(1.0e6, 0.3)).unwrap();
        let p = 400.0;
        let sigma0 = SymTensor::IDENTITY * -p;
        let mut ratios = Vec::new();
        // inertial numbers from 1e-4 to ~1: rates spanning four decades.
        for rate in [0.1, 1.0, 10.0, 100.0, 1000.0] {
            // γ = 0.01 in 200 steps: the elastic strain μ p/G ≈ 4e-4 builds within ~10 steps.
            let path = simple_shear_at_rate(&m, sigma0, 0.01, 200, rate).unwrap();
            let last = path.last().unwrap();
            let pressure = -last.stress.mean();
            assert!((pressure - p).abs() <= STEADY_REL * p, "p = {pressure}");
            assert_eq!(last.branch, "flowing");
            let expected = m.friction(m.inertial_number(rate, p));
            let ratio = last.stress.xy.abs() / pressure;
            assert!(
                (ratio - expected).abs() <= STEADY_REL * expected,
                "γ̇ = {rate}: τ/p = {ratio}, μ(I) = {expected}"
            );
            ratios.push(ratio);
        }
        // rate-dependent: friction grows with the rate, between μ_s and μ_2.
        assert!(ratios.windows(2).all(|w| w[1] > w[0]));
        let p = m.params();
        assert!(ratios[0] > p.mu_s && ratios[4] < p.mu_2);
    }
}
