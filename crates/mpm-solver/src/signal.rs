//! The time-step rule (eq 13): each particle's fastest signal, the Courant bound it sets, and the
//! stable Δt that the solver's time-step stage and the scene library's first-step estimate both
//! call, so that the rule is written once. Apart from the stage, which is an `impl Solver`
//! block, so that the solver's own code can use the rule without depending on the stage.

use mpm_constitutive::ConstitutiveModel;

use crate::math::Real;

pub use mpm_core::timestep::{StepLimit, displacement_dt, stable_dt};

/// What the time step needs from the particles: the fastest signal max_p s_p and the fastest
/// speed max_p |v_p|, each with its particle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fastest {
    pub(crate) signal: (Real, usize),
    pub(crate) speed: (Real, usize),
}

impl Fastest {
    /// `self` with particle `i` of signal `signal` and speed `speed` taken into account.
    #[inline(always)]
    pub(crate) fn with(self, signal: Real, speed: Real, i: usize) -> Self {
        Self { signal: faster(self.signal, (signal, i)), speed: faster(self.speed, (speed, i)) }
    }

    /// the faster of both parts (an associative, commutative merge of chunk results).
    pub(crate) fn merge(a: Self, b: Self) -> Self {
        Self { signal: faster(a.signal, b.signal), speed: faster(a.speed, b.speed) }
    }
}

/// The identity of [`Fastest::merge`]: no signal, no particle.
pub(crate) const SLOWEST: Fastest = Fastest { signal: (0.0, usize::MAX), speed: (0.0, usize::MAX) };

/// (M, M/ρ_ref) of a particle of material `model` at `state`: the material's `modulus` and
/// `cap`, asked once per material, unless the model's wave speed varies with the state
/// ([`ConstitutiveModel::WAVE_SPEED_VARIES`]); then the model is asked at this particle's state,
/// with ρ_ref its material's `reference` density (∞ for none: no cap).
#[inline(always)]
pub(crate) fn wave_modulus<M: ConstitutiveModel>(
    model: &M,
    state: &M::State,
    modulus: Real,
    cap: Real,
    reference: Real,
) -> (Real, Real) {
    if M::WAVE_SPEED_VARIES {
        let modulus = model.p_wave_modulus(state);
        (modulus, signal_cap(modulus, reference))
    } else {
        (modulus, cap)
    }
}

/// M/ρ_ref, the cap of c̃_p² (module docs); +∞ where no particle of the material gave a
/// reference density ρ_ref (its true signal counts).
pub(crate) fn signal_cap(modulus: Real, reference: Real) -> Real {
    if reference.is_finite() { modulus / reference } else { Real::INFINITY }
}

/// max(ĉ_p + |v_p|, w (c̃_p + |v_p|)) with c̃_p² = M V_p / m_p for P-wave modulus M,
/// ĉ_p² = min(c̃_p², `cap`), `cap` = M/ρ_ref and w = `weight` = C/C_max (module docs), for a
/// particle of speed |v_p| = `speed`; a non-finite value counts as infinite.
#[inline(always)]
pub(crate) fn particle_signal(
    modulus: Real,
    cap: Real,
    weight: Real,
    volume: Real,
    mass: Real,
    speed: Real,
) -> Real {
    let c2 = modulus * volume / mass;
    // A NaN volume must stay NaN (reported below), which `f64::min` would hide.
    let s = if c2 > cap {
        (cap.sqrt() + speed).max(weight * (c2.sqrt() + speed))
    } else {
        c2.sqrt() + speed
    };
    if s.is_finite() { s } else { Real::INFINITY }
}

/// the faster of two (signal, particle) pairs; ties go to the lower index.
#[inline(always)]
pub(crate) fn faster(a: (Real, usize), b: (Real, usize)) -> (Real, usize) {
    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a }
}
