//! Property tests of the Drucker-Prager return mapping over random parameters, states and strain
//! increments (SPEC §4): admissibility, consistency, monotonicity, hardening rules, isotropy,
//! finiteness, dissipation and the consistent tangent against central finite differences.
//!
//! Conventions: tension positive, SI units, tensor shear strain components. The proptest runner
//! is seeded (`RngSeed::Fixed`) so every run draws the same cases; failures would be persisted
//! next to this file as `properties.proptest-regressions`.

use glam::{DMat3, DQuat, DVec3};
use mpm_constitutive::{
    ConeMatch, ConstitutiveError, ConstitutiveModel, DpBranch, DpPerfectState, DpState,
    DruckerPrager, DruckerPragerParams, LinearElastic, PlaneTensor, SymTensor, UpdateReport,
};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// The step duration passed to the updates: these models are rate-independent, so any Δt > 0
/// gives the same bits.
const DT: f64 = 1e-3;

/// the SPEC's consistency bound after a plastic step: |f| ≤ 1e-10 (|k| + |I1| + 1).
const YIELD_TOL: f64 = 1e-10;
/// a point is "clearly" inside or outside when |f_trial| exceeds this many roundings of the
/// stress magnitudes (1e-16 × a few hundred operations); closer to the surface either branch is
/// correct.
const BRANCH_MARGIN: f64 = 1e-12;
/// rotating inputs and outputs costs a few roundings of the trial magnitude, which the return
/// can carry into the result unamplified (every map used is Lipschitz with constant ≤ 1 in
/// the relevant norm); 1e-10 leaves a 1e4 margin over 1e-14.
const ROTATION_TOL: f64 = 1e-10;
/// central differences with a step 1e-6 of the state's strain scale: truncation ~1e-12 and
/// rounding ~1e-10 relative to the stiffness; entries must agree to 1e-6 of ‖C‖.
const FD_TOL: f64 = 1e-6;
/// relative size of the finite-difference step (see `FD_TOL`).
const FD_STEP: f64 = 1e-6;
/// plastic strains recovered from stress differences carry rounding ~1e-16 of the trial
/// stress over 2G; 1e-9 of that strain scale leaves a wide margin yet catches any wrong Δλ.
const FLOW_TOL: f64 = 1e-9;
const SQRT_2: f64 = std::f64::consts::SQRT_2;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 512,
        rng_seed: RngSeed::Fixed(0x5EED_2005_ABE0_0023),
        max_global_rejects: 4096,
        ..ProptestConfig::default()
    }
}

fn angle_deg() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(40.0), 0.0..65.0f64]
}

fn unit_fraction() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64]
}

prop_compose! {
    /// random admissible parameters, softening included within the well-posed range.
    fn params()(
        young in 1.0e5..1.0e8f64,
        poisson in -0.5..0.49f64,
        phi in angle_deg(),
        psi_frac in unit_fraction(),
        cohesion in prop_oneof![Just(0.0), 0.0..100.0f64],
        h_frac in prop_oneof![Just(0.0), -0.8..2.0f64],
        mixing in unit_fraction(),
        cone in prop_oneof![
            Just(ConeMatch::PlaneStrain),
            Just(ConeMatch::Inner),
            Just(ConeMatch::Outer)
        ],
    ) -> DruckerPragerParams {
        // H as a fraction of G: h_frac > −1 keeps both G + H and G + (1 − M) H positive.
        let shear = young / (2.0 * (1.0 + poisson));
        DruckerPragerParams {
            young,
            poisson,
            cohesion,
            friction_angle_deg: phi,
            dilatancy_angle_deg: psi_frac * phi,
            hardening_modulus: h_frac * shear,
            mixing,
            cone_match: cone,
        }
    }
}

prop_compose! {
    /// a random unit deviatoric direction.
    fn unit_deviator()(c in prop::array::uniform6(-1.0..1.0f64)) -> SymTensor {
        let d = SymTensor::from_array(c).deviator();
        let n = d.norm();
        if n > 1e-3 { d * (1.0 / n) } else { SymTensor::new(1.0, -1.0, 0.0, 0.0, 0.0, 0.0) * (0.5f64).sqrt() }
    }
}

prop_compose! {
    /// a material point: σ = p I + β + ξ with √J2(ξ) = frac (k − 3αp); frac ≤ 1 is admissible.
    fn point(m: DruckerPrager)(
        k_extra in prop_oneof![Just(0.0), 0.0..200.0f64],
        p in prop_oneof![-1.0e4..0.0f64, -10.0..10.0f64],
        frac in prop_oneof![3 => 0.0..1.0f64, 1 => 0.0..1.5f64],
        beta_dir in unit_deviator(),
        beta_size in prop_oneof![Just(0.0), 0.0..100.0f64],
        xi_dir in unit_deviator(),
        eps_p_bar in 0.0..0.1f64,
    ) -> (DruckerPrager, SymTensor, DpState) {
        let k = (m.k0() + k_extra).max(0.0);
        // keep p below the tip so that the available radius is non-negative.
        let p = if m.alpha() > 0.0 { p.min(k / (3.0 * m.alpha())) } else { p };
        let radius = (k - 3.0 * m.alpha() * p).max(0.0);
        let beta = beta_dir * (std::f64::consts::SQRT_2 * beta_size);
        let sigma = SymTensor::IDENTITY * p + beta + xi_dir * (std::f64::consts::SQRT_2 * frac * radius);
        (m.clone(), sigma, DpState { back_stress: beta, k, eps_p_bar })
    }
}

prop_compose! {
    /// a strain increment with log-uniform magnitude 1e-8 .. 1e-2.
    fn increment()(c in prop::array::uniform6(-1.0..1.0f64), log_mag in -8.0..-2.0f64) -> SymTensor {
        SymTensor::from_array(c) * 10f64.powf(log_mag)
    }
}

fn case() -> impl Strategy<Value = (DruckerPrager, SymTensor, DpState, SymTensor)> {
    params()
        .prop_map(|p| DruckerPrager::new(p).expect("generated parameters are admissible"))
        .prop_flat_map(point)
        .prop_flat_map(|(m, s, st)| (Just(m), Just(s), Just(st), increment()))
}

fn rotation() -> impl Strategy<Value = DMat3> {
    (prop::array::uniform3(-1.0..1.0f64), 0.0..std::f64::consts::TAU).prop_map(|(a, angle)| {
        let axis = DVec3::from_array(a).try_normalize().unwrap_or(DVec3::Z);
        DMat3::from_quat(DQuat::from_axis_angle(axis, angle))
    })
}

/// the stress magnitude a case works with: start, trial increment and cone size.
fn stress_scale(m: &DruckerPrager, sigma: &SymTensor, state: &DpState, d: &SymTensor) -> f64 {
    sigma.norm() + m.elasticity().stress_increment(d).norm() + state.k.abs() + 1.0
}

/// one update on copies; `None` when a friction-free cone has softened away (checked on its own
/// in `outputs_are_finite`), any other error fails the test.
fn run(
    m: &DruckerPrager,
    sigma: SymTensor,
    state: DpState,
    d: &SymTensor,
) -> Option<(SymTensor, DpState, UpdateReport)> {
    let (mut s, mut st) = (sigma, state);
    match m.update(&mut s, &mut st, d, DT) {
        Ok(rep) => Some((s, st, rep)),
        Err(ConstitutiveError::EmptyElasticDomain { .. }) if m.alpha() == 0.0 => None,
        Err(e) => panic!("unexpected error {e} for {sigma:?} {state:?} {d:?}"),
    }
}

proptest! {
    #![proptest_config(config())]

    /// A material point carried into other parameters (a strength reduction between steps)
    /// keeps its hardening: the yield function of the new material at the carried state equals
    /// the old one's at the old state minus the drop of the cone, (k0 − k0') at fixed α, to
    /// round-off (1e-12 of the stress scale); the back stress and ε̄ᵖ are kept. A new cohesion
    /// therefore takes effect at once on a hardened point.
    #[test]
    fn a_state_carried_into_a_new_cohesion_keeps_its_hardening(
        (m, sigma, state) in params().prop_flat_map(|p| {
            point(DruckerPrager::new(p).expect("generated parameters are admissible"))
        }),
        c_new in 0.0..100.0f64,
    ) {
        let p = DruckerPragerParams { cohesion: c_new, ..*m.params() };
        let next = DruckerPrager::new(p).unwrap();
        let carried = next.carried_state(&m, &state);
        prop_assert_eq!(carried.back_stress, state.back_stress);
        prop_assert_eq!(carried.eps_p_bar, state.eps_p_bar);
        let drop = m.k0() - next.k0();
        let (f_old, f_new) = (m.yield_function(&sigma, &state), next.yield_function(&sigma, &carried));
        let scale = sigma.norm() + state.k.abs() + m.k0().abs() + next.k0().abs() + 1.0;
        prop_assert!((f_new - (f_old + drop)).abs() <= 1e-12 * scale, "{} {} {}", f_old, f_new, drop);
    }

    #[test]
    fn elastic_trial_inside_is_returned_unchanged((m, sigma, state, d) in case()) {
        let trial = sigma + m.elasticity().stress_increment(&d);
        let f_trial = m.yield_function(&trial, &state);
        let scale = stress_scale(&m, &sigma, &state, &d);
        let Some((s, st, rep)) = run(&m, sigma, state, &d) else { return Ok(()); };
        if f_trial < -BRANCH_MARGIN * scale {
            prop_assert_eq!(rep.branch, DpBranch::ELASTIC);
            prop_assert_eq!(st, state);
            prop_assert!((s - trial).norm() <= BRANCH_MARGIN * scale);
            prop_assert_eq!(rep.delta_lambda, 0.0);
        } else if f_trial > BRANCH_MARGIN * scale {
            prop_assert_ne!(rep.branch, DpBranch::ELASTIC);
        }
    }

    #[test]
    fn plastic_step_lands_on_the_yield_surface((m, sigma, state, d) in case()) {
        let Some((s, st, rep)) = run(&m, sigma, state, &d) else { return Ok(()); };
        if rep.branch != DpBranch::ELASTIC {
            let f = m.yield_function(&s, &st);
            let bound = YIELD_TOL * (st.k.abs() + s.trace().abs() + 1.0);
            prop_assert!(f.abs() <= bound, "f = {f:e} > {bound:e} on {:?}", rep.branch);
        }
    }

    #[test]
    fn plastic_strain_obeys_the_flow_rule_and_hardening_law((m, sigma, state, d) in case()) {
        // independent of how the return is assembled: Δεᵖ = C⁻¹ : (σᵗʳ − σ_{n+1}).
        let Some((s, st, rep)) = run(&m, sigma, state, &d) else { return Ok(()); };
        let el = m.elasticity();
        let trial = sigma + el.stress_increment(&d);
        let d_eps_p = el.strain_from_stress(&(trial - s));
        // strain scale of the trial stress; rounding of the stress differences is ~1e-16 of it.
        let tol = FLOW_TOL * (trial.norm() + s.norm() + 1.0) / el.shear_modulus();
        let dl = rep.delta_lambda;
        match rep.branch {
            DpBranch::ELASTIC => prop_assert!(d_eps_p.norm() <= tol),
            // eq 25: Δεᵖ = Δλ (αg I + n̂/√2), n̂ the trial relative deviator direction (radial
            // return; taken from the trial because a cone of size 0 returns to ξ = 0).
            DpBranch::CONE => {
                let g = m.flow_direction(&trial, &state);
                prop_assert!((d_eps_p - g * dl).norm() <= tol, "{:?} vs {:?}", d_eps_p, g * dl);
            }
            // apex: the multiplier is the equivalent plastic shear strain √2 ‖dev Δεᵖ‖, and the
            // volumetric part is at least the flow rule's 3αg Δλ.
            DpBranch::APEX => {
                prop_assert!((SQRT_2 * d_eps_p.deviator().norm() - dl).abs() <= tol);
                prop_assert!(d_eps_p.trace() >= 3.0 * m.alpha_g() * dl - tol);
            }
            other => prop_assert!(false, "Drucker-Prager names no branch {:?}", other),
        }
        // plastic work as reported.
        let work = s.ddot(&d_eps_p);
        prop_assert!((rep.dissipation - work).abs() <= tol * (s.norm() + trial.norm() + 1.0));
        // Prager mixed hardening: k grows by M H Δλ, β travels (1 − M) H Δλ in √J2 units.
        let p = m.params();
        let dk = st.k - state.k;
        prop_assert!((dk - p.mixing * p.hardening_modulus * dl).abs() <= 1e-12 * (state.k.abs() + dk.abs() + 1.0));
        let travel = (st.back_stress - state.back_stress.deviator()).norm() / SQRT_2;
        let expected = (1.0 - p.mixing) * p.hardening_modulus.abs() * dl;
        prop_assert!((travel - expected).abs() <= 1e-12 * (state.back_stress.norm() + travel + 1.0));
    }

    #[test]
    fn multiplier_and_plastic_strain_never_decrease((m, sigma, state, d) in case()) {
        let Some((_, st, rep)) = run(&m, sigma, state, &d) else { return Ok(()); };
        prop_assert!(rep.delta_lambda >= 0.0);
        prop_assert!(st.eps_p_bar >= state.eps_p_bar);
        prop_assert_eq!(st.eps_p_bar, state.eps_p_bar + rep.delta_lambda);
    }

    #[test]
    fn mixing_limits_freeze_beta_or_k((m, sigma, state, d) in case()) {
        let mixing = m.params().mixing;
        // M = 1 from β = 0 keeps β = 0; M = 0 keeps k.
        let start = if mixing == 1.0 { DpState { back_stress: SymTensor::ZERO, ..state } } else { state };
        let Some((_, st, rep)) = run(&m, sigma, start, &d) else { return Ok(()); };
        if mixing == 1.0 {
            prop_assert_eq!(st.back_stress, SymTensor::ZERO);
            let dk = st.k - start.k;
            let h = m.params().hardening_modulus;
            prop_assert!((dk - h * rep.delta_lambda).abs() <= 1e-12 * (start.k.abs() + dk.abs() + 1.0));
        }
        if mixing == 0.0 {
            prop_assert_eq!(st.k, start.k);
        }
    }

    #[test]
    fn rotating_the_input_rotates_the_output((m, sigma, state, d) in case(), r in rotation()) {
        let Some((s1, st1, rep1)) = run(&m, sigma, state, &d) else { return Ok(()); };
        let mut state_r = state;
        m.rotate_state(&mut state_r, &r);
        let Some((s2, st2, rep2)) = run(&m, sigma.rotated(&r), state_r, &d.rotated(&r)) else {
            return Ok(());
        };
        let scale = stress_scale(&m, &sigma, &state, &d);
        prop_assert!((s2 - s1.rotated(&r)).norm() <= ROTATION_TOL * scale);
        prop_assert!((st2.back_stress - st1.back_stress.rotated(&r)).norm() <= ROTATION_TOL * scale);
        prop_assert!((st2.k - st1.k).abs() <= ROTATION_TOL * scale);
        let g = m.elasticity().shear_modulus();
        prop_assert!((rep2.delta_lambda - rep1.delta_lambda).abs() <= ROTATION_TOL * scale / g);
    }

    /// The plane-strain update (the solver's) gives the bits of the full update of the same
    /// in-plane point, rotation included, for Drucker-Prager, linear elasticity and a model
    /// that keeps the trait's default `update_plane`: it is the same algorithm, not an
    /// approximation of it.
    #[test]
    fn plane_update_gives_the_bits_of_the_full_update(
        (m, sigma, state, d) in case(),
        theta in prop_oneof![Just(None), (-0.05..0.05f64).prop_map(Some)],
    ) {
        let sigma = PlaneTensor::from_sym(&sigma);
        let state = DpState { back_stress: PlaneTensor::from_sym(&state.back_stress).to_sym(), ..state };
        let d = PlaneTensor::new(d.xx, d.yy, 0.0, d.xy);
        let rotation = theta.map(|t: f64| (t.cos(), t.sin()));
        same_bits(&m, sigma, state, d, rotation)?;
        same_bits(m.elasticity(), sigma, (), d, rotation)?;
        same_bits(&DefaultPlane::new(*m.elasticity()), sigma, (), d, rotation)?;
    }

    /// A material that does not harden gives the same bits whether its points store only ε̄ᵖ
    /// (`DpPerfectState`, what `mpm` picks for H = 0) or the mixed-hardening variables, whose
    /// k and β then stay k0 and 0: full and plane updates, turned or not, every branch.
    #[test]
    fn perfect_plasticity_gives_the_bits_of_the_hardening_variables_at_h_zero(
        (m, sigma, state, d) in case(),
        theta in prop_oneof![Just(None), (-0.05..0.05f64).prop_map(Some)],
    ) {
        let p = DruckerPragerParams { hardening_modulus: 0.0, ..*m.params() };
        let hardening = DruckerPrager::new(p).expect("H = 0 is admissible");
        let perfect = hardening.without_hardening().expect("H = 0");
        let eps_p_bar = state.eps_p_bar;
        let full = DpState { back_stress: SymTensor::ZERO, k: hardening.k0(), eps_p_bar };
        let lean = DpPerfectState { eps_p_bar };
        let bits = |t: SymTensor| t.to_array().map(f64::to_bits);
        let (mut s1, mut st1, mut s2, mut st2) = (sigma, full, sigma, lean);
        let (r1, r2) = (hardening.update(&mut s1, &mut st1, &d, DT), perfect.update(&mut s2, &mut st2, &d, DT));
        prop_assert_eq!(r1.map_err(|e| e.to_string()), r2.map_err(|e| e.to_string()));
        prop_assert_eq!(bits(s1), bits(s2));
        prop_assert_eq!(st1.eps_p_bar.to_bits(), st2.eps_p_bar.to_bits());
        prop_assert_eq!((st1.k, st1.back_stress), (hardening.k0(), SymTensor::ZERO));

        let rotation = theta.map(|t: f64| (t.cos(), t.sin()));
        let (sigma, d) = (PlaneTensor::from_sym(&sigma), PlaneTensor::new(d.xx, d.yy, 0.0, d.xy));
        let (mut s1, mut st1, mut s2, mut st2) = (sigma, full, sigma, lean);
        let r1 = hardening.update_plane(&mut s1, &mut st1, &d, DT, rotation);
        let r2 = perfect.update_plane(&mut s2, &mut st2, &d, DT, rotation);
        prop_assert_eq!(r1.map_err(|e| e.to_string()), r2.map_err(|e| e.to_string()));
        prop_assert_eq!(bits(s1.to_sym()), bits(s2.to_sym()));
        prop_assert_eq!(st1.eps_p_bar.to_bits(), st2.eps_p_bar.to_bits());
        same_bits(&perfect, sigma, lean, d, rotation)?;
    }

    #[test]
    fn outputs_are_finite((m, sigma, state, d) in case()) {
        let (mut s, mut st) = (sigma, state);
        match m.update(&mut s, &mut st, &d, DT) {
            Ok(rep) => {
                prop_assert!(s.is_finite() && st.back_stress.is_finite());
                prop_assert!(st.k.is_finite() && st.eps_p_bar.is_finite());
                prop_assert!(rep.delta_lambda.is_finite() && rep.dissipation.is_finite());
            }
            // the only admissible failure: a friction-free cone softened below zero size.
            Err(e) => prop_assert!(
                matches!(e, ConstitutiveError::EmptyElasticDomain { .. }) && m.alpha() == 0.0,
                "{e}"
            ),
        }
    }

    #[test]
    fn dissipation_is_non_negative_under_compression((m, sigma, state, d) in case()) {
        // without back stress σ : Δεᵖ = Δλ (αg I1 + √J2) on the cone and I1 (I1ᵗʳ − I1)/(9K) at
        // the apex; both are ≥ 0 for I1 ≤ 0 as long as the cone size k stays ≥ 0.
        let m = DruckerPrager::new(DruckerPragerParams { mixing: 1.0, ..*m.params() }).unwrap();
        let start = DpState { back_stress: SymTensor::ZERO, ..state };
        let Some((s, st, rep)) = run(&m, sigma, start, &d) else { return Ok(()); };
        if s.trace() <= 0.0 && st.k >= 0.0 {
            let scale = stress_scale(&m, &sigma, &start, &d) * d.norm();
            prop_assert!(rep.dissipation >= -1e-12 * scale, "{:?}", rep);
        }
    }

    #[test]
    fn consistent_tangent_matches_central_differences((m, sigma, state, d) in case()) {
        let e = m.elasticity().young_modulus();
        let h = FD_STEP * (d.norm() + (sigma.norm() + state.k.abs()) / e);
        let Some((_, _, rep0)) = run(&m, sigma, state, &d) else { return Ok(()); };
        let tangent = m.consistent_tangent(&sigma, &state, &d).unwrap();
        let c_norm = m.elasticity().p_wave_modulus();
        for j in 0..6 {
            let mut plus = d.to_array();
            let mut minus = d.to_array();
            plus[j] += h;
            minus[j] -= h;
            let (Some((sp, _, rp)), Some((sm, _, rm))) = (
                run(&m, sigma, state, &SymTensor::from_array(plus)),
                run(&m, sigma, state, &SymTensor::from_array(minus)),
            ) else {
                return Ok(());
            };
            // a kink of the return (branch switch) within ±h: no derivative to compare.
            prop_assume!(rp.branch == rep0.branch && rm.branch == rep0.branch);
            let fd = (sp - sm) * (0.5 / h);
            for (i, fd_i) in fd.to_array().into_iter().enumerate() {
                prop_assert!(
                    (fd_i - tangent[i][j]).abs() <= FD_TOL * c_norm,
                    "T[{i}][{j}] = {:e}, FD {fd_i:e}, {:?}",
                    tangent[i][j],
                    rep0.branch
                );
            }
        }
    }
}

/// linear elasticity through the trait's default `update_plane` and `rotate_state_z`; with a
/// non-zero `twist`, its update also adds that much out-of-plane shear `σ_yz` to any stress.
struct DefaultPlane {
    elastic: LinearElastic,
    twist: f64,
}

impl DefaultPlane {
    fn new(elastic: LinearElastic) -> Self {
        Self { elastic, twist: 0.0 }
    }
}

impl ConstitutiveModel for DefaultPlane {
    type State = ();
    const IS_PLASTIC: bool = false;
    const BRANCHES: &'static [&'static str] = &["elastic"];
    fn initial_state(&self) {}
    fn p_wave_modulus(&self, _state: &()) -> f64 {
        self.elastic.p_wave_modulus()
    }
    fn stored_energy_density(&self, sigma: &SymTensor, _state: &()) -> f64 {
        self.elastic.strain_energy_density(sigma)
    }
    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut (),
        d_eps: &SymTensor,
        dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let report = self.elastic.update(sigma, state, d_eps, dt)?;
        sigma.yz += self.twist;
        Ok(report)
    }
    fn rotate_state(&self, _state: &mut (), _r: &DMat3) {}
    fn equivalent_plastic_strain(&self, _state: &()) -> f64 {
        0.0
    }
}

/// Through `update_plane`, elasticity (its own override and the trait's default) refuses
/// non-finite input by name as `update` does and leaves the point untouched; the default
/// refuses an update that creates an out-of-plane shear instead of dropping it.
#[test]
fn plane_update_refuses_what_it_cannot_carry() {
    let elastic = LinearElastic::from_young_poisson(2e6, 0.3).unwrap();
    let sigma0 = PlaneTensor::new(-10.0, -20.0, -9.0, 1.5);
    let cases = [
        (sigma0, PlaneTensor::new(f64::NAN, 0.0, 0.0, 0.0)),
        (PlaneTensor::new(0.0, f64::INFINITY, 0.0, 0.0), PlaneTensor::ZERO),
        // finite but overflowing
        (sigma0, PlaneTensor::new(f64::MAX, f64::MAX, 0.0, 0.0)),
    ];
    for (s0, d) in cases {
        let full = elastic.update(&mut s0.to_sym(), &mut (), &d.to_sym(), DT).unwrap_err();
        for rotation in [None, Some((0.6, 0.8))] {
            let mut s = s0;
            let e = elastic.update_plane(&mut s, &mut (), &d, DT, rotation).unwrap_err();
            assert_eq!(
                s.to_sym().to_array().map(f64::to_bits),
                s0.to_sym().to_array().map(f64::to_bits)
            );
            let mut s = s0;
            let e_default = DefaultPlane::new(elastic)
                .update_plane(&mut s, &mut (), &d, DT, rotation)
                .unwrap_err();
            assert_eq!(
                s.to_sym().to_array().map(f64::to_bits),
                s0.to_sym().to_array().map(f64::to_bits)
            );
            if rotation.is_none() {
                // (as text: a NaN value is not equal to itself)
                assert_eq!(e.to_string(), full.to_string());
                assert_eq!(e_default.to_string(), full.to_string());
            }
        }
    }
    let mut s = sigma0;
    let d = PlaneTensor::new(1e-5, 0.0, 0.0, 0.0);
    let twisting = DefaultPlane { elastic, twist: 1.0 };
    let e = twisting.update_plane(&mut s, &mut (), &d, DT, None).unwrap_err();
    assert_eq!(e, ConstitutiveError::OutOfPlane { name: "stress.yz", value: 1.0 });
    assert_eq!(s, sigma0);
}

/// `update_plane` against the rotation (`SymTensor::rotated_z`, `rotate_state_z`) and `update`
/// of the full tensors: the same result, report and error, bit for bit.
fn same_bits<M: ConstitutiveModel>(
    m: &M,
    sigma: PlaneTensor,
    state: M::State,
    d: PlaneTensor,
    rotation: Option<(f64, f64)>,
) -> Result<(), TestCaseError> {
    let (mut full, mut full_state) = (sigma.to_sym(), state);
    if let Some((c, s)) = rotation {
        full = full.rotated_z(c, s);
        m.rotate_state_z(&mut full_state, c, s);
    }
    let expected = m.update(&mut full, &mut full_state, &d.to_sym(), DT);
    let (mut plane, mut plane_state) = (sigma, state);
    let got = m.update_plane(&mut plane, &mut plane_state, &d, DT, rotation);
    match (expected, got) {
        (Ok(a), Ok(b)) => {
            prop_assert_eq!(a, b);
            let bits = |t: SymTensor| t.to_array().map(f64::to_bits);
            prop_assert_eq!(bits(plane.to_sym()), bits(PlaneTensor::from_sym(&full).to_sym()));
            // (the report's and the state's numbers are compared as values: a zero may differ
            // in sign, see `PlaneTensor`)
            prop_assert_eq!(plane_state, full_state);
        }
        (Err(a), Err(b)) => {
            prop_assert_eq!(a.to_string(), b.to_string());
            prop_assert_eq!(plane, sigma);
            prop_assert_eq!(plane_state, state);
        }
        (a, b) => prop_assert!(false, "full {:?} against plane {:?}", a, b),
    }
    Ok(())
}

/// Only a material that does not harden can drop its hardening variables, and what it keeps is
/// one number.
#[test]
fn perfect_plasticity_needs_h_zero() {
    let sand = DruckerPragerParams::ABE2005_DRY_SAND;
    assert!(DruckerPrager::new(sand).unwrap().without_hardening().is_some());
    assert!(DruckerPrager::perfectly_plastic(sand).is_ok());
    let hardening = DruckerPragerParams { hardening_modulus: 1.0e4, ..sand };
    assert!(DruckerPrager::new(hardening).unwrap().without_hardening().is_none());
    match DruckerPrager::perfectly_plastic(hardening) {
        Err(ConstitutiveError::InvalidParameter { name, value, .. }) => {
            assert_eq!((name, value), ("hardening_modulus", 1.0e4));
        }
        other => panic!("expected the hardening modulus refused, got {other:?}"),
    }
    assert_eq!(std::mem::size_of::<DpPerfectState>(), 8);
    assert_eq!(std::mem::size_of::<DpState>(), 64);
    // A cone size that overflows is refused, not stored (a perfect state never tests k).
    let huge = DruckerPragerParams { cohesion: 1.0e308, ..sand };
    assert!(matches!(
        DruckerPrager::new(huge),
        Err(ConstitutiveError::InvalidParameter { name: "cohesion", .. })
    ));
}

/// the H = 0 cases of `perfect_plasticity_gives_the_bits_of_the_hardening_variables_at_h_zero`
/// reach every branch, and on non-finite input both states refuse with the same error.
#[test]
fn perfect_state_cases_cover_every_branch_and_refuse_alike() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::new(config());
    let mut counts = [0usize; 3];
    for _ in 0..2000 {
        let (m, sigma, state, d) = case().new_tree(&mut runner).unwrap().current();
        let p = DruckerPragerParams { hardening_modulus: 0.0, ..*m.params() };
        let perfect = DruckerPrager::perfectly_plastic(p).unwrap();
        let (mut s, mut st) = (sigma, DpPerfectState { eps_p_bar: state.eps_p_bar });
        if let Ok(rep) = perfect.update(&mut s, &mut st, &d, DT) {
            counts[rep.branch.index()] += 1;
        }
    }
    assert!(counts.iter().all(|&c| c >= 100), "elastic/cone/apex counts {counts:?}");

    let hardening = DruckerPrager::new(DruckerPragerParams::ABE2005_DRY_SAND).unwrap();
    let perfect = hardening.without_hardening().unwrap();
    let sigma = SymTensor::IDENTITY * -1.0e3;
    let d = SymTensor::new(1e-4, -2e-4, 0.0, 3e-5, 0.0, 0.0);
    let full = hardening.initial_state();
    let nan = f64::NAN;
    for (s, eps, d) in [
        (sigma, nan, d),
        (SymTensor { xy: nan, ..sigma }, 0.0, d),
        (sigma, 0.0, SymTensor { yy: f64::INFINITY, ..d }),
        (sigma, 0.0, d * 1e308),
    ] {
        let (mut s1, mut st1) = (s, DpState { eps_p_bar: eps, ..full });
        let (mut s2, mut st2) = (s, DpPerfectState { eps_p_bar: eps });
        let e1 = hardening.update(&mut s1, &mut st1, &d, DT).unwrap_err();
        let e2 = perfect.update(&mut s2, &mut st2, &d, DT).unwrap_err();
        assert_eq!(e1.to_string(), e2.to_string());
        assert_eq!(st2.eps_p_bar.to_bits(), eps.to_bits(), "the state is left untouched");
    }
}

/// the random cases must exercise every branch, or the properties above prove little.
#[test]
fn generated_cases_cover_every_branch() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::new(config());
    let mut counts = [0usize; 3];
    for _ in 0..2000 {
        let (m, mut s, mut st, d) = case().new_tree(&mut runner).unwrap().current();
        if let Ok(rep) = m.update(&mut s, &mut st, &d, DT) {
            counts[rep.branch.index()] += 1;
        }
    }
    assert!(counts.iter().all(|&c| c >= 100), "elastic/cone/apex counts {counts:?}");
}
