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
use mpm_grid::{ShapeFunctions, stencil_nodes};
use std::cell::Cell;
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use crate::config::{PicWeighting, Transfer};
use crate::error::{Field, SolverError};
use crate::math::{Matrix, Real, Vector};
use crate::par::chunk_len;
use crate::scratch::Scratch;
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    pub(crate) fn g2p(&mut self, dt: Real) -> Result<(), SolverError> {
        if self.config.transfer == Transfer::Flip && !self.scratch.held.is_empty() {
            self.correct_held_normals();
        }
        if self.config.transfer == Transfer::Apic {
            return self.g2p_apic(dt);
        }
        let p = &mut self.particles;
        let tallies = flip_update(
            &self.shape,
            &self.scratch,
            (&mut p.position, &mut p.velocity, &p.mass),
            dt,
            self.config.pic_share(dt),
            self.step + 1,
            self.config.pic_weighting == PicWeighting::Noise,
        );
        let mut removed = 0.0;
        for t in tallies {
            removed += t?;
        }
        self.dissipation.transfer += removed;
        Ok(())
    }

    /// the PIC normal correction at nodes held by a plane (module docs), gathered from the
    /// start-of-step particle velocities before any is changed, then applied. Like the difference
    /// between FLIP and PIC anywhere, the kinetic energy it takes has no grid counterpart: the
    /// ledger shows it in the residual, not as constraint work, nor in the transfer dissipation,
    /// which books only the PIC share of [`crate::SolverConfig::pic_fraction`]. Serial: it
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
        // v_i^L = v_i + a_i Δt (eq 5) once per node instead of once per particle and node (the
        // same operations: the same bits)
        let sc = &mut self.scratch;
        end_velocities(&mut sc.end_velocity, &sc.velocity, &sc.acceleration, dt);
        light_nodes(sc);
        let p = &mut self.particles;
        apic_update(
            &self.shape,
            &self.scratch,
            (&mut p.position, &mut p.velocity, &mut p.affine),
            dt,
            self.step + 1,
        )
    }
}

/// the FLIP update of eqs 6–7 with the PIC share `beta`, per chunk of particles in chunk order:
/// the kinetic energy the PIC share removed. A free function generic over the shape functions
/// alone (the constitutive model plays no part here): one copy per shape functions.
#[allow(clippy::type_complexity)]
fn flip_update<S: ShapeFunctions<N>, const N: usize>(
    shape: &S,
    sc: &Scratch<S::Factors, N>,
    (position, velocity, mass): (&mut [Vector], &mut [Vector], &[Real]),
    dt: Real,
    beta: Real,
    step: u64,
    noise_weighted: bool,
) -> Vec<Result<Real, SolverError>> {
    let (idx, factors) = (&sc.node_index, &sc.factors);
    let (a, v) = (&sc.acceleration, &sc.velocity);
    let chunk = chunk_len(mass.len());
    // Per chunk, in chunk order: the kinetic energy the PIC share removed (a sum whose order
    // does not depend on the thread count).
    position
        .par_chunks_mut(chunk)
        .zip(velocity.par_chunks_mut(chunk))
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
                    // Σ_i S_ip v_i^L = dx is the PIC velocity; flip − dx what the grid cannot see
                    let b = if noise_weighted {
                        let noise = (flip - dx).length_squared();
                        let seen = noise + dx.length_squared();
                        if seen > 0.0 { beta * (noise / seen) } else { beta }
                    } else {
                        beta
                    };
                    let blended = flip + b * (dx - flip);
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
        .collect()
}

/// the APIC update: v_p = Σ v_i^L S_ip, C_p = Σ v_i^L ⊗ G_ip, x_p += Δt v_p, with the end
/// velocities v_i^L of `scratch.end_velocity`; generic over the shape functions alone.
///
/// **Light nodes.** A node a particle has only just reached holds a small fraction ξ of a cell's
/// mass but a full share of the particle's internal force, so its acceleration f_i/m_i grows like
/// 1/ξ. Its weight S_ip ~ ξ tames that in v_p, but its gradient G_ip does not: C_p would carry the
/// 1/ξ into the next particle-to-grid transfer, and with it into every scheme's strains (the
/// multilinear functions' D_p = Σ S_ip (x_i − x_p)⊗(x_i − x_p) vanishes at a node plane). An
/// explicit node is stable while Δt² k_i / m_i stays below 4, which for a node of mass ξ m_cell
/// means ξ ≳ C²/4 (C the step's Courant number). A node lighter than C² m_cell
/// (`scratch.light_mass`, a factor 4 of margin), and not on a boundary (a ghost mirrors a heavier
/// image, a plane prescribes what it holds), enters C_p with the particle's own affine velocity
/// v_p + C_p^n (x_i − x_p) instead of v_i^L: no acceleration of its own, and an affine field is
/// still reproduced exactly (Σ_i (x_i − x_p) ⊗ G_ip = I). Only particles with a light node in
/// their stencil pay for the second gather.
fn apic_update<S: ShapeFunctions<N>, const N: usize>(
    shape: &S,
    sc: &Scratch<S::Factors, N>,
    (position, velocity, affine): (&mut [Vector], &mut [Vector], &mut [Matrix]),
    dt: Real,
    step: u64,
) -> Result<(), SolverError> {
    let (idx, factors) = (&sc.node_index, &sc.factors);
    let (end, light, first) = (&sc.end_velocity, &sc.light, &sc.first_node);
    let chunk = chunk_len(position.len());
    let failure = position
        .par_chunks_mut(chunk)
        .zip(velocity.par_chunks_mut(chunk))
        .zip(affine.par_chunks_mut(chunk))
        .enumerate()
        .map(|(c, ((xs, vs), cs))| {
            for (j, ((x, vp), cp)) in xs.iter_mut().zip(vs.iter_mut()).zip(cs).enumerate() {
                let q = c * chunk + j;
                // whether a stencil node is light, read with its end velocity (one pass over
                // the stencil's indices)
                let touches_light = Cell::new(false);
                let (v_new, mut c_new) = shape.interpolate(&factors[q], |k| {
                    let i = idx[q][k] as usize;
                    touches_light.set(touches_light.get() | light[i]);
                    end[i]
                });
                if touches_light.get() {
                    let nodes = stencil_nodes::<N>(first[q]);
                    let (x0, c0) = (*x, *cp);
                    c_new = shape.gradient(&factors[q], |k| {
                        let i = idx[q][k] as usize;
                        if light[i] {
                            v_new + c0 * (shape.node_position(nodes[k]) - x0)
                        } else {
                            end[i]
                        }
                    });
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

/// which active nodes are light for APIC's affine matrix (`apic_update`): lighter than
/// `light_mass`, and not on a boundary, whose ghosts mirror a heavier image and whose planes
/// prescribe what they hold (not generic: one copy).
fn light_nodes<F, const N: usize>(sc: &mut Scratch<F, N>) {
    let threshold = sc.light_mass;
    sc.light.clear();
    sc.light.par_extend(sc.mass.par_iter().map(|&m| m < threshold));
    for b in &sc.boundary {
        sc.light[b.node as usize] = false;
    }
}

/// v_i^L = v_i + a_i Δt (eq 5) of every node into `end` (not generic: one copy).
fn end_velocities(end: &mut Vec<Vector>, v: &[Vector], a: &[Vector], dt: Real) {
    end.clear();
    end.par_extend(v.par_iter().zip(a).map(|(v, a)| *v + *a * dt));
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

#[cfg(test)]
mod tests {
    use mpm_constitutive::LinearElastic;
    use mpm_grid::Bilinear;
    use mpm_grid::testing::{at, grid, volume};

    use crate::particles::{NewParticle, Particles};
    use crate::solver::Solver;
    use crate::{SolverConfig, Vector};

    /// Two particles at one point with opposite velocities: every node sees exactly zero
    /// momentum, so the whole motion lies in FLIP's null space (the grid has nothing to move or
    /// strain). Returns (initial kinetic energy, kinetic energy, transfer dissipation, residual)
    /// after `steps` steps with PIC share `beta`.
    fn null_mode(beta: f64, steps: usize) -> (f64, f64, f64, f64) {
        let config =
            SolverConfig { gravity: Vector::ZERO, pic_fraction: beta, ..Default::default() };
        let (ke0, ke, transfer, residual, _) = null_mode_with(config, steps);
        (ke0, ke, transfer, residual)
    }

    /// [`null_mode`] under `config`, with the time reached.
    fn null_mode_with(config: SolverConfig, steps: usize) -> (f64, f64, f64, f64, f64) {
        let grid = grid([0.0; 2], [0.5; 2], [8, 8]).unwrap();
        let mut particles = Particles::default();
        for v in [at(0.3, -0.2), at(-0.3, 0.2)] {
            let x = at(2.1, 1.7);
            particles.push(NewParticle::unstressed(x, v, volume(0.25), 1000.0, ()));
        }
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        let mut s = Solver::new(Bilinear(grid), vec![material], particles, config).unwrap();
        let e0 = s.energy();
        for _ in 0..steps {
            s.step().unwrap();
        }
        let e = s.energy();
        (e0.kinetic, e.kinetic, e.transfer_dissipation, e.residual, s.time())
    }

    /// Given as a relaxation time τ, the PIC share takes the null-space motion's kinetic energy
    /// down as exp(−2t/τ) whatever the time step: at Courant 0.1 and 0.5 (Δt five times
    /// longer) alike, the closed form holds to rounding, where a share per step would damp five
    /// times more per second at the shorter step.
    #[test]
    fn a_pic_relaxation_time_damps_at_the_same_rate_whatever_the_time_step() {
        let tau = 0.01;
        for (courant, steps) in [(0.1, 400), (0.5, 80)] {
            let config = SolverConfig {
                gravity: Vector::ZERO,
                pic_relaxation: tau,
                time_step: crate::TimeStep::Courant(courant),
                ..Default::default()
            };
            let (ke0, ke, transfer, residual, t) = null_mode_with(config, steps);
            let expected = ke0 * (-2.0 * t / tau).exp();
            eprintln!("Courant {courant}: t = {t:.4e} s, KE/KE0 = {:.6e}", ke / ke0);
            // a few hundred rounded factors: a few ulps each
            assert!((ke - expected).abs() <= 1e-12 * ke0, "kinetic {ke} against {expected}");
            assert!((transfer - (ke0 - ke)).abs() <= 1e-12 * ke0, "booked {transfer}");
            assert!(residual.abs() <= 1e-12 * ke0, "residual {residual}");
            assert!(ke < 0.5 * ke0, "the test must damp measurably: {ke} of {ke0}");
        }
    }

    /// Pure FLIP keeps the null-space motion for ever; a PIC share β takes (1 − β)² of its
    /// kinetic energy away per step, exactly (the grid's velocity is exactly zero), and the
    /// ledger books what left as transfer dissipation, so the residual stays at rounding.
    #[test]
    fn the_pic_share_damps_the_null_space_and_books_what_it_takes() {
        let (ke0, ke, transfer, residual) = null_mode(0.0, 50);
        assert_eq!(ke, ke0, "pure FLIP must keep the grid-invisible motion unchanged");
        assert_eq!(transfer, 0.0);
        assert!(residual.abs() <= 1e-15 * ke0, "residual {residual}");

        let (beta, steps) = (0.01, 50);
        let (ke0, ke, transfer, residual) = null_mode(beta, steps);
        let expected = ke0 * (1.0 - beta).powi(2 * steps as i32);
        // 50 products of rounded factors: a few ulps each.
        assert!((ke - expected).abs() <= 1e-13 * ke0, "kinetic {ke} against {expected}");
        assert!((transfer - (ke0 - ke)).abs() <= 1e-13 * ke0, "booked {transfer}");
        assert!(residual.abs() <= 1e-13 * ke0, "residual {residual}");
    }

    /// Weighted by noise, the share is the full β where the grid sees nothing of a particle's
    /// velocity: on the null mode (node momenta exactly zero, w = 1) it damps bit for bit as the
    /// uniform share does.
    #[test]
    fn a_noise_weighted_share_takes_the_full_share_of_a_motion_the_grid_cannot_see() {
        let config = |pic_weighting| SolverConfig {
            gravity: Vector::ZERO,
            pic_fraction: 0.01,
            pic_weighting,
            ..Default::default()
        };
        let uniform = null_mode_with(config(crate::PicWeighting::Uniform), 50);
        let noise = null_mode_with(config(crate::PicWeighting::Noise), 50);
        assert_eq!(noise, uniform);
        assert!(uniform.1 < 0.5 * uniform.0, "the test must damp: {uniform:?}");
    }

    /// A free elastic bar (4 m × 0.5 m, 16 cells along it, 4 particles per cell) vibrating in
    /// its first axial mode, v_x = V cos(π ξ / L) (V = 1 cm/s, strains of 1e-5): a motion the
    /// grid sees, but for the small part bilinear nodes smooth out. A uniform share of 0.01 per
    /// step takes a share of that part at every particle and every step; a share weighted by
    /// noise, w ~ (what the grid misses / what it sees)², almost nothing. Over 400 steps at
    /// Courant 0.5 (about six periods) the uniform share takes 2.8 % of the mode's energy, the
    /// weighted one 1.6e-6 of it: the bound, a hundredth of the uniform share's, leaves a margin
    /// of 200. Both ledgers close to the explicit steps' own error (0.25 %, the same for both).
    #[test]
    fn a_noise_weighted_share_spares_a_motion_the_grid_sees() {
        let run = |pic_weighting| {
            let grid = grid([0.0; 2], [0.25; 2], [24, 8]).unwrap();
            let mut particles = Particles::default();
            let (x0, len) = (1.0, 4.0);
            for i in 0..32 {
                for j in 0..4 {
                    let x = at(x0 + 0.0625, 0.5 + 0.0625) + 0.125 * at(i as f64, j as f64);
                    let v = at(0.01 * (std::f64::consts::PI * (x.x - x0) / len).cos(), 0.0);
                    particles.push(NewParticle::unstressed(x, v, volume(0.125), 1000.0, ()));
                }
            }
            let material = LinearElastic::from_young_poisson(1e6, 0.0).unwrap();
            let config = SolverConfig {
                gravity: Vector::ZERO,
                pic_fraction: 0.01,
                pic_weighting,
                time_step: crate::TimeStep::Courant(0.5),
                ..Default::default()
            };
            let mut s = Solver::new(Bilinear(grid), vec![material], particles, config).unwrap();
            let e0 = s.energy();
            for _ in 0..400 {
                s.step().unwrap();
            }
            let e = s.energy();
            (e.transfer_dissipation / e0.kinetic, e.residual / e0.kinetic)
        };
        let (lost_uniform, res_uniform) = run(crate::PicWeighting::Uniform);
        let (lost_noise, res_noise) = run(crate::PicWeighting::Noise);
        eprintln!(
            "share of the mode's energy taken: uniform {lost_uniform:.3e}, noise {lost_noise:.3e}; \
             residuals {res_uniform:.1e}, {res_noise:.1e}"
        );
        assert!(lost_uniform > 0.01, "the uniform share must damp the mode: {lost_uniform}");
        assert!(lost_noise >= 0.0 && lost_noise < 0.01 * lost_uniform, "{lost_noise}");
        assert!(res_uniform.abs() < 0.01 && res_noise.abs() < 0.01);
    }

    /// The PIC share is a setting with a range: outside [0, 1], and with APIC, it is refused.
    #[test]
    fn the_pic_share_is_checked() {
        let bad = |c: SolverConfig| c.validate().is_err();
        assert!(bad(SolverConfig { pic_fraction: -0.1, ..Default::default() }));
        assert!(bad(SolverConfig { pic_fraction: 1.5, ..Default::default() }));
        assert!(bad(SolverConfig { pic_fraction: f64::NAN, ..Default::default() }));
        assert!(bad(SolverConfig {
            pic_fraction: 0.01,
            transfer: crate::Transfer::Apic,
            ..Default::default()
        }));
        assert!(!bad(SolverConfig { pic_fraction: 1.0, ..Default::default() }));
        assert!(bad(SolverConfig { pic_relaxation: -1.0, ..Default::default() }));
        assert!(bad(SolverConfig { pic_relaxation: f64::INFINITY, ..Default::default() }));
        assert!(bad(SolverConfig {
            pic_relaxation: 0.1,
            pic_fraction: 0.01,
            ..Default::default()
        }));
        assert!(bad(SolverConfig {
            pic_relaxation: 0.1,
            transfer: crate::Transfer::Apic,
            ..Default::default()
        }));
        assert!(!bad(SolverConfig { pic_relaxation: 0.1, ..Default::default() }));
    }
}
