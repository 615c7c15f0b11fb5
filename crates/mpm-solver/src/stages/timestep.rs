//! Stage 1: the time step from the Courant condition (eq 13, SPEC §1 "Time step").
//!
//! c_p = √((λ + 2G)/ρ*_p) is the dilatational wave speed at particle p, L the smallest cell size.
//! The fastest signal is s = max_p (c_p + |v_p|); Δt = C·L/s for a Courant number C, or a fixed Δt
//! whose Courant number Δt·s/L must stay ≤ 1.
//!
//! **Which density.** ρ*_p = max(ρ_p, ρ_ref), with ρ_ref the lightest initial density of the
//! particle's material: a particle compacted above it counts with its current density, a dilated
//! one with ρ_ref. Eq 13 with the current density alone lets the loosest particle set Δt for
//! everyone, and the loosest particles are those that have separated from the mass: grains
//! thrown off the free surface or the front, whose volume grows by the FLIP strain increments of
//! the few nodes they share with nothing, carry no stress (a cohesionless material cannot hold
//! the tension) and transmit no wave. Their √(V_p/V_0) made the flume take 2.7× and a
//! collapsing cohesionless column 3–9× the steps of the initial estimate. Capping c_p at the
//! material's initial wave speed keeps Δt where the connected mass needs it. What it gives up:
//! an elastic body stretched by a volumetric strain ε really carries waves √(1 + ε) faster, which
//! the cap ignores, so its true Courant number is up to √(1 + ε) times the reported one (1 %
//! at ε = 2 %; C ≤ 1 keeps a margin for that).
//!
//! The signal needs every particle's final velocity and volume. Where a scheme's last particle loop
//! sees both (the stress update that ends USL, MUSL and USAVG), that loop computes it for the next
//! step with [`particle_signal`] and [`faster`], which saves a pass over the particles; otherwise
//! (USF, the first step, after `particles_mut`) [`Solver::fastest_signal`] does. Both give the
//! same bits.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;
use rayon::prelude::*;

use crate::config::TimeStep;
use crate::error::{Field, SolverError};
use crate::math::{Real, Vector};
use crate::par::chunk_len;
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// (Δt, Courant number) of the next step, with Δt ≤ `max_dt`.
    pub(crate) fn time_step(&mut self, max_dt: Real) -> Result<(Real, Real), SolverError> {
        let (signal, particle) = match self.next_signal.take() {
            Some(known) => known,
            None => self.fastest_signal(),
        };
        let speed = self.particles.velocity[particle.min(self.particles.len() - 1)].length();
        if !signal.is_finite() {
            // A NaN or infinite velocity or volume: name it before it spreads through the grid.
            let p = &self.particles;
            let field =
                if p.velocity[particle].is_finite() { Field::Volume } else { Field::Velocity };
            return Err(SolverError::NonFinite {
                step: self.step + 1,
                particle,
                position: p.position[particle],
                field,
            });
        }
        let l = self.cell_size;
        match self.config.time_step {
            TimeStep::Courant(c) => {
                let dt = (c * l / signal).min(max_dt);
                Ok((dt, dt * signal / l))
            }
            TimeStep::Fixed(dt) => {
                let courant = dt * signal / l;
                if courant > 1.0 {
                    return Err(SolverError::CourantExceeded {
                        step: self.step + 1,
                        particle,
                        courant,
                        speed,
                        dt,
                    });
                }
                let dt = dt.min(max_dt);
                Ok((dt, dt * signal / l))
            }
        }
    }

    /// (max_p (c_p + |v_p|), that particle). Ties go to the lowest index, so the answer does not
    /// depend on the thread count; a non-finite signal counts as infinite so that the first such
    /// particle is the one reported.
    fn fastest_signal(&self) -> (Real, usize) {
        let p = &self.particles;
        let n = p.len();
        let chunk = chunk_len(n);
        (0..n.div_ceil(chunk))
            .into_par_iter()
            .map(|c| {
                let mut best = SLOWEST;
                for i in c * chunk..((c + 1) * chunk).min(n) {
                    let m = usize::from(p.material[i]);
                    let (modulus, cap) = (self.p_modulus[m], self.signal_cap[m]);
                    let signal =
                        particle_signal(modulus, cap, p.volume[i], p.mass[i], p.velocity[i]);
                    best = faster(best, (signal, i));
                }
                best
            })
            .reduce(|| SLOWEST, faster)
    }
}

/// The identity of [`faster`]: no signal, no particle.
pub(crate) const SLOWEST: (Real, usize) = (0.0, usize::MAX);

/// c_p + |v_p| with c_p² = min(M V_p / m_p, `cap`) for P-wave modulus M and `cap` = M/ρ_ref (module
/// docs); a non-finite value counts as infinite.
#[inline(always)]
pub(crate) fn particle_signal(
    modulus: Real,
    cap: Real,
    volume: Real,
    mass: Real,
    velocity: Vector,
) -> Real {
    let c2 = modulus * volume / mass;
    // A NaN volume must stay NaN (reported below), which `f64::min` would hide.
    let c2 = if c2 > cap { cap } else { c2 };
    let s = c2.sqrt() + velocity.length();
    if s.is_finite() { s } else { Real::INFINITY }
}

/// the faster of two (signal, particle) pairs; ties go to the lower index.
#[inline(always)]
pub(crate) fn faster(a: (Real, usize), b: (Real, usize)) -> (Real, usize) {
    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a }
}

#[cfg(test)]
mod tests {
    use mpm_constitutive::{LinearElastic, SymTensor};
    use mpm_grid::{Bilinear, RegularGrid};

    use crate::particles::{NewParticle, Particles};
    use crate::{Solver, SolverConfig, TimeStep, Vector};

    /// Two particles at rest of one material (ρ₀ = 1000 kg/m³, E = 1 MPa) on 0.25 m cells.
    fn pair() -> Solver<LinearElastic, Bilinear<RegularGrid>, 4> {
        let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.25), [8, 8]).unwrap();
        let mut particles = Particles::default();
        for x in [0.6, 1.4] {
            particles.push(NewParticle {
                position: Vector::new(x, 1.0),
                velocity: Vector::ZERO,
                volume: 0.125 * 0.125,
                density: 1000.0,
                stress: SymTensor::ZERO,
                state: (),
                material: 0,
                body: 0,
            });
        }
        let config = SolverConfig {
            gravity: Vector::ZERO,
            time_step: TimeStep::Courant(0.5),
            ..Default::default()
        };
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        Solver::new(Bilinear(grid), vec![material], particles, config).unwrap()
    }

    /// Δt of eq 13 with c = √(M/ρ) and no speed: C·L/c.
    fn expected_dt(s: &Solver<LinearElastic, Bilinear<RegularGrid>, 4>, density: f64) -> f64 {
        0.5 * 0.25 / (s.materials()[0].p_wave_modulus() / density).sqrt()
    }

    /// One rounding of a square root and a division.
    const DT_TOL: f64 = 1e-14;

    #[test]
    fn a_dilated_particle_does_not_shrink_the_time_step() {
        let mut s = pair();
        let dt0 = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt0 / expected_dt(&s, 1000.0) - 1.0).abs() < DT_TOL);
        // Ten times its volume (a grain thrown off the mass): the current density would give
        // a √10 shorter step; the reference density keeps it.
        s.particles_mut().volume[1] *= 10.0;
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert_eq!(dt, dt0);
    }

    #[test]
    fn a_compacted_particle_counts_with_its_current_density() {
        let mut s = pair();
        // Both compacted to 80 % of their volume: ρ = 1250 kg/m³ sets the (longer) step.
        for v in &mut s.particles_mut().volume {
            *v *= 0.8;
        }
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / expected_dt(&s, 1250.0) - 1.0).abs() < DT_TOL);
        // and speed still adds to the signal: 10 m/s on one particle.
        s.particles_mut().velocity[0] = Vector::new(10.0, 0.0);
        let c = (s.materials()[0].p_wave_modulus() / 1250.0).sqrt();
        let dt = s.time_step(f64::INFINITY).unwrap().0;
        assert!((dt / (0.5 * 0.25 / (c + 10.0)) - 1.0).abs() < DT_TOL);
    }

    #[test]
    fn a_resumed_run_keeps_the_reference_density_of_its_start() {
        let mut s = pair();
        let dt0 = s.time_step(f64::INFINITY).unwrap().0;
        // Every particle dilates, then the run is checkpointed and resumed: the reference stays
        // at the initial density instead of becoming the dilated one.
        for v in &mut s.particles_mut().volume {
            *v *= 4.0;
        }
        let c = s.checkpoint();
        assert_eq!(c.reference_density, vec![1000.0]);
        let (shape, materials, config) = (s.shape().clone(), s.materials().to_vec(), *s.config());
        let mut resumed = Solver::from_checkpoint(shape, materials, config, c).unwrap();
        assert_eq!(resumed.time_step(f64::INFINITY).unwrap().0, dt0);
    }
}
