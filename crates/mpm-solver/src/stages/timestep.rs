//! Stage 1: the time step from the Courant condition (eq 13, SPEC §1 "Time step").
//!
//! c_p = √((λ + 2G)/ρ_p) is the dilatational wave speed at particle p, L the smallest cell size.
//! The fastest signal is s = max_p (c_p + |v_p|); Δt = C·L/s for a Courant number C, or a fixed Δt
//! whose Courant number Δt·s/L must stay ≤ 1.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;
use rayon::prelude::*;

use crate::config::TimeStep;
use crate::error::{Field, SolverError};
use crate::math::Real;
use crate::par::CHUNK;
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// (Δt, Courant number) of the next step, with Δt ≤ `max_dt`.
    pub(crate) fn time_step(&self, max_dt: Real) -> Result<(Real, Real), SolverError> {
        let (signal, particle, speed) = self.fastest_signal();
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

    /// (max_p (c_p + |v_p|), that particle, its speed). Ties go to the lowest index, so the
    /// answer does not depend on the thread count; a non-finite signal counts as infinite so that
    /// the first such particle is the one reported.
    fn fastest_signal(&self) -> (Real, usize, Real) {
        let p = &self.particles;
        let n = p.len();
        let better = |a: (Real, usize), b: (Real, usize)| {
            if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a }
        };
        let (signal, particle) = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut best = (0.0, usize::MAX);
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    let m = self.p_modulus[usize::from(p.material[i])];
                    let c = (m * p.volume[i] / p.mass[i]).sqrt();
                    let s = c + p.velocity[i].length();
                    best = better(best, (if s.is_finite() { s } else { Real::INFINITY }, i));
                }
                best
            })
            .reduce(|| (0.0, usize::MAX), better);
        (signal, particle, p.velocity[particle].length())
    }
}
