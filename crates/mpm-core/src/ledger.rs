//! The energy ledger (SPEC §5): what is stored, what was dissipated, and the residual.
//!
//! Stored: kinetic Σ ½ m_p |v_p|², elastic strain Σ V_p ½ σ_p : C⁻¹ : σ_p, and gravitational potential
//! Σ −m_p g·x_p (zero at the origin). Dissipated (accumulated over the run): plastic work
//! Σ V_p σ_p : Δεᵖ_p, friction work and normal-constraint work at boundary nodes, and the kinetic
//! energy the PIC share of a blended transfer removed (the settings' `pic_fraction`), and the
//! friction work of side walls across the plane ([`crate::SideWalls`]). External work is the
//! energy put in by loads that change in time: while gravity is ramped up, the potential
//! −m g(t)·x changes with g at fixed x, and that change Σ −m_p Δg·x_p is booked as external work.
//!
//! The residual is (stored + dissipated) − (initial stored + external work): a perfect integrator
//! gives zero; its size is the numerical energy error a user reads to judge a run's accuracy.

use serde::{Deserialize, Serialize};

use crate::settings::Real;

/// Energies of one instant (J; J per metre of thickness in plane strain).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyLedger {
    /// Σ ½ m_p |v_p|².
    pub kinetic: Real,
    /// Σ V_p ½ σ_p : C⁻¹ : σ_p (recoverable elastic energy).
    pub strain: Real,
    /// Σ −m_p g·x_p.
    pub potential: Real,
    /// Plastic dissipation accumulated since the start.
    pub plastic_dissipation: Real,
    /// Work done against boundary friction since the start.
    pub friction_work: Real,
    /// Kinetic energy removed by normal boundary constraints since the start.
    pub constraint_work: Real,
    /// Kinetic energy removed by the PIC share of the velocity transfer since the start
    /// (the settings' `pic_fraction`; 0 under pure FLIP).
    #[serde(default)]
    pub transfer_dissipation: Real,
    /// Work done against the friction of side walls across the plane since the start
    /// ([`crate::SideWalls`]; 0 without them).
    #[serde(default)]
    pub side_wall_friction: Real,
    /// Work of non-conservative external loads since the start.
    pub external_work: Real,
    /// Energy (kinetic, elastic and potential, as the stored terms count them) carried out of
    /// the run by particles that left through outflow faces since the start
    /// (the solver's outflow faces; 0 without them). Neither stored nor dissipated: it left.
    #[serde(default)]
    pub outflow: Real,
    /// (stored + dissipated + outflow) − (initial stored + external work).
    pub residual: Real,
}

impl EnergyLedger {
    /// kinetic + strain + potential.
    pub fn stored(&self) -> Real {
        self.kinetic + self.strain + self.potential
    }

    /// plastic + friction + constraint work + transfer dissipation + side-wall friction.
    pub fn dissipated(&self) -> Real {
        self.plastic_dissipation
            + self.friction_work
            + self.constraint_work
            + self.transfer_dissipation
            + self.side_wall_friction
    }

    /// stored + dissipated + what left through outflow faces: constant for a perfect integrator
    /// without external work.
    pub fn total(&self) -> Real {
        self.stored() + self.dissipated() + self.outflow
    }
}

/// The size of a run's energy error, judged against the energy the run can move around.
///
/// The ledger's residual alone has no scale: the potential energy's zero is arbitrary. It is
/// judged against
/// `scale(t) = KE₀ + U₀ + Σ_p m_p |g| h_p + released(t)`:
/// the initial kinetic and strain energy, the potential energy of every particle above the
/// ground below it at the start (h_p ≥ 0, full gravity), and the largest energy the motion has
/// released so far, max over time of (P₀ − (P(t) + O(t) − W_ext(t))): the drop of potential
/// energy not counting what a gravity ramp booked as external work (which depends on where the
/// origin is, not on the motion), nor the energy O(t) that particles carried out through outflow
/// sides (their potential would otherwise count as released, by their height above the origin).
/// The relative residual `residual / scale` is 0 for a perfect integrator, positive when the
/// integration creates energy and negative when it loses energy it does not book as dissipation
/// (a body crushed into the floor, a collapse that a contact law absorbs without friction work).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyCheck {
    /// KE₀ + U₀ + Σ m_p |g| h_p (J/m).
    pub initial_scale: Real,
    /// potential energy at the start (J/m).
    pub initial_potential: Real,
    /// largest drop of potential energy below its initial value so far (J/m).
    pub released: Real,
    /// the relative residual of largest magnitude seen so far (signed).
    pub worst: Real,
    /// when it was seen (s).
    pub worst_time: Real,
}

impl EnergyCheck {
    /// starts from the initial ledger of particles at `position` (points of either dimension)
    /// with masses `mass`, under gravity of magnitude `g`, `height(x)` above the ground under a
    /// particle at x (h_p: a particle below the ground counts 0).
    pub fn new<V: Copy>(
        initial: &EnergyLedger,
        position: &[V],
        mass: &[Real],
        g: Real,
        height: impl Fn(V) -> Real,
    ) -> Self {
        let height_energy: Real =
            position.iter().zip(mass).map(|(x, m)| m * g * height(*x).max(0.0)).sum();
        Self {
            initial_scale: initial.kinetic + initial.strain + height_energy,
            initial_potential: initial.potential,
            ..Self::default()
        }
    }

    /// the scale of `e` (see the type's docs), after taking its potential energy into account.
    fn scale(&mut self, e: &EnergyLedger) -> Real {
        // (what left through outflow sides counts with the potential: else each particle that
        // leaves would "release" its height above the origin)
        let potential = e.potential + e.outflow;
        self.released = self.released.max(self.initial_potential - (potential - e.external_work));
        self.initial_scale + self.released
    }

    /// the relative residual of `e` at time `t`, remembered if it is the largest in magnitude so
    /// far. A residual without any scale (nothing moves, nothing is stored) counts as 0; a
    /// non-finite one as +∞.
    pub fn observe(&mut self, t: Real, e: &EnergyLedger) -> Real {
        let scale = self.scale(e);
        let r = if !e.residual.is_finite() || !scale.is_finite() {
            Real::INFINITY
        } else if scale > 0.0 {
            e.residual / scale
        } else {
            0.0
        };
        if r.abs() > self.worst.abs() || r.is_nan() {
            self.worst = r;
            self.worst_time = t;
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ledger(kinetic: Real, potential: Real, residual: Real) -> EnergyLedger {
        EnergyLedger { kinetic, potential, residual, ..Default::default() }
    }

    #[test]
    fn the_scale_grows_with_the_released_potential_and_keeps_the_worst_residual() {
        // A body of m g h = 100 J/m above the ground, at rest: 1 kg at 10 m under g = 10 m/s²
        // (a particle at y = 12 over ground at y = 2), and a particle below the ground, which
        // adds nothing.
        let height = |y: Real| y - 2.0;
        let mut c =
            EnergyCheck::new(&ledger(0.0, 500.0, 0.0), &[12.0, -1.0], &[1.0, 5.0], 10.0, height);
        assert_eq!(c.initial_scale, 100.0);
        assert_eq!(c.observe(0.0, &ledger(0.0, 500.0, 0.0)), 0.0);
        // It falls 60 J/m and shows a residual of −16 J/m: −16 / (100 + 60).
        assert_eq!(c.observe(1.0, &ledger(44.0, 440.0, -16.0)), -0.1);
        // It rises again: the released energy keeps its largest value (60), so +8 J/m is 0.05.
        assert_eq!(c.observe(2.0, &ledger(0.0, 470.0, 8.0)), 0.05);
        assert_eq!((c.worst, c.worst_time), (-0.1, 1.0));
        // A non-finite residual is the worst possible.
        assert_eq!(c.observe(3.0, &ledger(0.0, 470.0, Real::NAN)), Real::INFINITY);
        assert_eq!(c.worst, Real::INFINITY);
    }
}
