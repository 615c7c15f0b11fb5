//! Stage 5: grid to particle.
//!
//! x_p ← x_p + Δt Σ_i v_i^L S_ip (eq 6), v_p ← v_p + Δt Σ_i a_i S_ip (eq 7, the FLIP update).
//! A non-finite result stops the run with the particle that produced it.
//!
//! Under FLIP with a PIC share β ([`crate::SolverConfig::pic_fraction`]) the new velocity is
//! (1 − β)(v_p + Δt Σ S a) + β Σ S v^L: the share β of whatever the grid cannot see is taken out
//! each step, and the kinetic energy that removes is booked as transfer dissipation. Pure FLIP
//! keeps that part for ever: on the flume run past its stop, particles of the deposit kept
//! 0.3–0.5 m/s while their positions did not change in 10 s (6 J/m of kinetic energy that moved
//! nothing), until the lone grain at the front, fed by it, was thrown out of the grid.
//!
//! Under surface contact ([`crate::Contact::Surface`]) a node that a plane pushed on in this step
//! passes its normal velocity to its particles as in PIC: particle p's share of node i becomes
//! S_ip (v_i^L − v_p)·n instead of the FLIP increment S_ip (v_i^L − v_i)·n, i.e. a correction
//! S_ip ((v_i − v_p)·n) n. Momentum is unchanged (Σ_p m_p S_ip v_p = m_i v_i) and the correction
//! can only take kinetic energy away, whereas the FLIP increment leaves in each particle the part
//! of its approach velocity that the node's average did not see, to be stopped again, and turned
//! into strain energy, at the next step.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use crate::config::Transfer;
use crate::error::{Field, SolverError};
use crate::math::{Matrix, Real, Vector};
use crate::par::chunk_len;
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    pub(crate) fn g2p(&mut self, dt: Real) -> Result<(), SolverError> {
        if self.config.transfer == Transfer::Flip && !self.scratch.held.is_empty() {
            self.correct_held_normals();
        }
        if self.config.transfer == Transfer::Apic {
            return self.g2p_apic(dt);
        }
        let sc = &self.scratch;
        let (idx, factors, shape) = (&sc.node_index, &sc.factors, &self.shape);
        let (a, v) = (&sc.acceleration, &sc.velocity);
        let step = self.step + 1;
        let beta = self.config.pic_fraction;
        let chunk = chunk_len(self.particles.len());
        let mass = &self.particles.mass;
        // Per chunk, in chunk order: the kinetic energy the PIC share removed (a sum whose order
        // does not depend on the thread count).
        let tallies: Vec<Result<Real, SolverError>> = self
            .particles
            .position
            .par_chunks_mut(chunk)
            .zip(self.particles.velocity.par_chunks_mut(chunk))
            .enumerate()
            .map(|(c, (xs, vs))| {
                let mut removed = 0.0;
                for (j, (x, vp)) in xs.iter_mut().zip(vs.iter_mut()).enumerate() {
                    let p = c * chunk + j;
                    let w = shape.weights(&factors[p]);
                    let mut dx = Vector::ZERO;
                    let mut dv = Vector::ZERO;
                    for k in 0..N {
                        let i = idx[p][k] as usize;
                        // v_i^L = v_i + a_i Δt (eq 5)
                        dx += w[k] * (v[i] + a[i] * dt);
                        dv += w[k] * a[i];
                    }
                    let flip = *vp + dt * dv;
                    let v_new = if beta > 0.0 {
                        // Σ_i S_ip v_i^L = dx is the PIC velocity.
                        let blended = flip + beta * (dx - flip);
                        removed += 0.5 * mass[p] * (flip.length_squared() - blended.length_squared());
                        blended
                    } else {
                        flip
                    };
                    let x_new = *x + dt * dx;
                    check_finite(step, p, *x, x_new, v_new)?;
                    *x = x_new;
                    *vp = v_new;
                }
                Ok(removed)
            })
            .collect();
        let mut removed = 0.0;
        for t in tallies {
            removed += t?;
        }
        self.dissipation.transfer += removed;
        Ok(())
    }

    /// the PIC normal correction at nodes held by a plane (module docs), gathered from the
    /// start-of-step particle velocities before any is changed, then applied. Like the difference
    /// between FLIP and PIC anywhere, the kinetic energy it takes is a transfer dissipation with no
    /// grid counterpart: the ledger shows it in the residual, not as constraint work. Serial: it
    /// visits only the particles of held boundary nodes.
    pub(crate) fn correct_held_normals(&mut self) {
        let sc = &mut self.scratch;
        let p = &mut self.particles;
        sc.corrections.clear();
        for &(i, n) in &sc.held {
            let i = i as usize;
            let b = sc.boundary_of[i] as usize;
            for e in
                &sc.contact_entry[sc.contact_start[b] as usize..sc.contact_start[b + 1] as usize]
            {
                let e = e.load(Ordering::Relaxed);
                let (q, k) = (e as usize / N, e as usize % N);
                let w = self.shape.weights(&sc.factors[q])[k];
                let dv = w * (sc.velocity[i] - p.velocity[q]).dot(n) * n;
                sc.corrections.push((q as u32, dv));
            }
        }
        for &(q, dv) in &sc.corrections {
            p.velocity[q as usize] += dv;
        }
    }

    /// APIC grid to particle: v_p = Σ v_i^L S_ip, C_p = Σ v_i^L ⊗ G_ip, x_p += Δt v_p.
    fn g2p_apic(&mut self, dt: Real) -> Result<(), SolverError> {
        let sc = &self.scratch;
        let (idx, factors, shape) = (&sc.node_index, &sc.factors, &self.shape);
        let (a, v) = (&sc.acceleration, &sc.velocity);
        let step = self.step + 1;
        let p = &mut self.particles;
        let chunk = chunk_len(p.len());
        let failure = p
            .position
            .par_chunks_mut(chunk)
            .zip(p.velocity.par_chunks_mut(chunk))
            .zip(p.affine.par_chunks_mut(chunk))
            .enumerate()
            .map(|(c, ((xs, vs), cs))| {
                for (j, ((x, vp), cp)) in xs.iter_mut().zip(vs.iter_mut()).zip(cs).enumerate() {
                    let q = c * chunk + j;
                    let (w, grad) = (shape.weights(&factors[q]), shape.gradients(&factors[q]));
                    let mut v_new = Vector::ZERO;
                    let mut c_new = Matrix::ZERO;
                    for k in 0..N {
                        let i = idx[q][k] as usize;
                        let v_end = v[i] + a[i] * dt;
                        v_new += w[k] * v_end;
                        let g = grad[k];
                        c_new += Matrix::from_cols(v_end * g.x, v_end * g.y);
                    }
                    let x_new = *x + dt * v_new;
                    check_finite(step, q, *x, x_new, v_new)?;
                    *x = x_new;
                    *vp = v_new;
                    *cp = c_new;
                }
                Ok(())
            })
            .find_first(Result::is_err);
        failure.unwrap_or(Ok(()))
    }
}

/// the guard of eqs 6–7: a non-finite new position or velocity stops the run at particle `q`,
/// reported at its last finite position.
#[inline(always)]
fn check_finite(
    step: u64,
    q: usize,
    x: Vector,
    x_new: Vector,
    v_new: Vector,
) -> Result<(), SolverError> {
    if x_new.is_finite() && v_new.is_finite() {
        return Ok(());
    }
    let field = if x_new.is_finite() { Field::Velocity } else { Field::Position };
    Err(SolverError::NonFinite { step, particle: q, position: x, field })
}
