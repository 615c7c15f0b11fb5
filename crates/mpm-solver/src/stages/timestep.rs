//! Stage 1: the time step from the Courant condition (eq 13, SPEC §1 "Time step").
//!
//! c_p = √((λ + 2G)/ρ_p) is the dilatational wave speed at particle p, L the smallest cell size.
//! The fastest signal is s = max_p (c_p + |v_p|); Δt = C·L/s for a Courant number C, or a fixed Δt
//! whose Courant number Δt·s/L must stay ≤ 1.
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
use crate::par::CHUNK;
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
        (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut best = SLOWEST;
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    let m = self.p_modulus[usize::from(p.material[i])];
                    best = faster(
                        best,
                        (particle_signal(m, p.volume[i], p.mass[i], p.velocity[i]), i),
                    );
                }
                best
            })
            .reduce(|| SLOWEST, faster)
    }
}

/// The identity of [`faster`]: no signal, no particle.
pub(crate) const SLOWEST: (Real, usize) = (0.0, usize::MAX);

/// c_p + |v_p| with c_p = √(M V_p / m_p) for P-wave modulus M; a non-finite value counts as
/// infinite.
#[inline(always)]
pub(crate) fn particle_signal(modulus: Real, volume: Real, mass: Real, velocity: Vector) -> Real {
    let s = (modulus * volume / mass).sqrt() + velocity.length();
    if s.is_finite() { s } else { Real::INFINITY }
}

/// the faster of two (signal, particle) pairs; ties go to the lower index.
#[inline(always)]
pub(crate) fn faster(a: (Real, usize), b: (Real, usize)) -> (Real, usize) {
    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a }
}
