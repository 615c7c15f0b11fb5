//! Stage 3: particle-to-grid sums.
//!
//! m_i = Σ_p m_p S_ip (eq 1); q_i = Σ_p m_p v_p S_ip and v_i = q_i / m_i;
//! f_i = −Σ_p V_p σ_p · G_ip (eq 2) + Σ_p m_p S_ip b (eq 3, b = gravity).
//! Each node sums its own (particle, slot) list in increasing particle order, in parallel over nodes,
//! so the sums are bit-identical for any number of threads.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;
use rayon::prelude::*;

use crate::config::Transfer;
use crate::math::{Real, Vector};
use crate::particles::Particles;
use crate::solver::Solver;

/// For every node i: out[i] = Σ over its entries e of `term(p, k)` with e = p·N + k.
fn gather<T, const N: usize>(
    start: &[u32],
    entry: &[u32],
    out: &mut [T],
    term: impl Fn(usize, usize) -> T + Sync,
) where
    T: Send + Copy + Default + std::ops::AddAssign,
{
    out.par_iter_mut().enumerate().with_min_len(256).for_each(|(i, o)| {
        let mut acc = T::default();
        for &e in &entry[start[i] as usize..start[i + 1] as usize] {
            let e = e as usize;
            acc += term(e / N, e % N);
        }
        *o = acc;
    });
}

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// nodal mass (eq 1) and velocity q_i / m_i into `scratch.mass` and `scratch.velocity`.
    pub(crate) fn p2g_mass_velocity(&mut self) {
        self.momentum_pass(true, 0.0);
    }

    /// MUSL remap (eq 8): v_i = Σ_p m_p v_p S_ip / m_i from the updated particle velocities, with the
    /// old stencils, then the boundary velocity constraint (eq 18).
    pub(crate) fn remap_velocity(&mut self, dt: Real) {
        // The stencils are the start-of-step ones, so the affine term must use the start-of-step
        // positions too: x_p − Δt v_p, exact under APIC (whose G2P moves x_p by Δt v_p).
        self.momentum_pass(false, dt);
        self.constrain_velocity();
    }

    /// mass, velocity and force in one pass over each node's list (USL and MUSL, whose force
    /// uses the stress of the previous step): a third less memory traffic than separate passes,
    /// and the same sums in the same order.
    pub(crate) fn p2g_all(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        let p = &self.particles;
        let (w, grad) = (&sc.weights, &sc.gradients);
        let (start, entry) = (&sc.start, &sc.entry);
        let apic = self.config.transfer == Transfer::Apic;
        let xi = &sc.node_position;
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        sc.mass
            .par_iter_mut()
            .zip(sc.velocity.par_iter_mut().zip(sc.force.par_iter_mut()))
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, (m, (v, f)))| {
                let (mut ms, mut q, mut fs) = (0.0, Vector::ZERO, Vector::ZERO);
                for &e in &entry[start[i] as usize..start[i + 1] as usize] {
                    let (pi, k) = (e as usize / N, e as usize % N);
                    let mw = p.mass[pi] * w[pi][k];
                    ms += mw;
                    q += momentum(p, pi, mw, apic, xi.get(i), 0.0);
                    fs += force(p, pi, mw, grad[pi][k], g);
                }
                *m = ms;
                *v = if ms > 0.0 { q / ms } else { Vector::ZERO };
                *f = fs;
            });
    }

    /// v_i = q_i / m_i with q_i = Σ_p m_p S_ip v_p (FLIP) or Σ_p m_p S_ip (v_p + C_p (x_i − x_p))
    /// (APIC, with particle positions taken back by `dt_back` along v_p); also m_i when
    /// `with_mass`. One pass over each node's list, in particle order.
    fn momentum_pass(&mut self, with_mass: bool, dt_back: Real) {
        let sc = &mut self.scratch;
        let p = &self.particles;
        let w = &sc.weights;
        let (start, entry) = (&sc.start, &sc.entry);
        let apic = self.config.transfer == Transfer::Apic;
        let xi = &sc.node_position;
        sc.mass
            .par_iter_mut()
            .zip(sc.velocity.par_iter_mut())
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, (m, v))| {
                let (mut ms, mut q) = (0.0, Vector::ZERO);
                for &e in &entry[start[i] as usize..start[i + 1] as usize] {
                    let (pi, k) = (e as usize / N, e as usize % N);
                    let mw = p.mass[pi] * w[pi][k];
                    ms += mw;
                    q += momentum(p, pi, mw, apic, xi.get(i), dt_back);
                }
                if with_mass {
                    *m = ms;
                }
                // the remap divides by the same m_i: Σ m_p S_ip over the same list.
                *v = if ms > 0.0 { q / ms } else { Vector::ZERO };
            });
    }

    /// nodal force f_i^int + f_i^ext (eqs 2–3) into `scratch.force`.
    pub(crate) fn p2g_force(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        let p = &self.particles;
        let (w, grad) = (&sc.weights, &sc.gradients);
        // Gravity at mid-step (it only changes during a ramp).
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        gather::<_, N>(&sc.start, &sc.entry, &mut sc.force, |q, k| {
            force(p, q, p.mass[q] * w[q][k], grad[q][k], g)
        });
    }
}

/// particle `q`'s share of a node's momentum, `mw` = m_q S_iq: mw v_q (FLIP), or
/// mw (v_q + C_q (x_i − x_q)) with x_q taken back by `dt_back` along v_q (APIC).
#[inline(always)]
fn momentum<S>(
    p: &Particles<S>,
    q: usize,
    mw: Real,
    apic: bool,
    node_position: Option<&Vector>,
    dt_back: Real,
) -> Vector {
    match (apic, node_position) {
        (true, Some(&xi)) => {
            let x0 = p.position[q] - dt_back * p.velocity[q];
            mw * (p.velocity[q] + p.affine[q] * (xi - x0))
        }
        _ => mw * p.velocity[q],
    }
}

/// particle `q`'s share of a node's force: m_q S_iq b − V_q σ_q · G_iq (eqs 2–3). Tension
/// positive, so −V σ·G pulls nodes towards stretched regions.
#[inline(always)]
fn force<S>(p: &Particles<S>, q: usize, mw: Real, gr: Vector, g: Vector) -> Vector {
    let s = &p.stress[q];
    let sigma_g = Vector::new(s.xx * gr.x + s.xy * gr.y, s.xy * gr.x + s.yy * gr.y);
    mw * g - p.volume[q] * sigma_g
}
