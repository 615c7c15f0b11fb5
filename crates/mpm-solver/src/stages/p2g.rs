//! Stage 3: particle-to-grid sums.
//!
//! m_i = Σ_p m_p S_ip (eq 1); q_i = Σ_p m_p v_p S_ip and v_i = q_i / m_i;
//! f_i = −Σ_p V_p σ_p · G_ip (eq 2) + Σ_p m_p S_ip b (eq 3, b = gravity).
//!
//! A block scatter with a fixed reduction order. The active nodes come in 8 × 8 blocks
//! ([`mpm_grid::ActiveNodes`]) and `locate` bins every particle with the block that holds its
//! stencil's first (lowest) node. Each block owns a patch of (8 + w − 1)² partial sums, w the
//! stencil side: its own nodes plus the w − 1 rows and columns above and right of it that its
//! particles' stencils reach. In parallel over blocks, each block zeroes its patch and adds its
//! particles' shares in increasing particle order. Then, in parallel over nodes, each node adds
//! the patches that hold it in a fixed order: the blocks below-left, below and left of its own
//! block, then its own. Every sum is thus taken in an order set by the particles' positions and
//! indices, never by the threads: the results are bit-identical for any thread count. Each
//! particle is read once per pass (the node-list gather this replaced read it once per node)
//! and the partial sums stay in a few kilobytes of cache.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::{BLOCK_SIDE, NodeId, ShapeFunctions, stencil_side};
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use crate::config::Transfer;
use crate::math::{Real, Vector};
use crate::solver::{Scratch, Solver};

/// nodes along each side of a block's patch for stencils of `n` nodes: the block's 8 and the
/// w − 1 beyond its upper and right edges that stencils anchored in it reach.
pub(crate) const fn patch_side(n: usize) -> usize {
    BLOCK_SIDE as usize + stencil_side(n) - 1
}

/// the most nodes a patch can have (stencils up to 4 × 4): places in a patch fit a byte.
const MAX_PATCH: usize = (BLOCK_SIDE as usize + 3) * (BLOCK_SIDE as usize + 3);

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// nodal mass (eq 1) and velocity q_i / m_i into `scratch.mass` and `scratch.velocity`.
    pub(crate) fn p2g_mass_velocity(&mut self) {
        match self.config.transfer {
            Transfer::Flip => self.scatter::<true, true, false, false>(0.0, Vector::ZERO),
            Transfer::Apic => self.scatter::<true, true, false, true>(0.0, Vector::ZERO),
        }
    }

    /// MUSL remap (eq 8): v_i = Σ_p m_p v_p S_ip / m_i from the updated particle velocities, with the
    /// old stencils, then the boundary velocity constraint (eq 18). m_i is the step's P2G mass:
    /// the same sum over the same stencils.
    pub(crate) fn remap_velocity(&mut self, dt: Real) {
        // The stencils are the start-of-step ones, so the affine term must use the start-of-step
        // positions too: x_p − Δt v_p, exact under APIC (whose G2P moves x_p by Δt v_p).
        match self.config.transfer {
            Transfer::Flip => self.scatter::<false, true, false, false>(dt, Vector::ZERO),
            Transfer::Apic => self.scatter::<false, true, false, true>(dt, Vector::ZERO),
        }
        self.constrain_velocity();
    }

    /// mass, velocity and force in one pass (USL and MUSL, whose force uses the stress of the
    /// previous step): each particle is read once for all three sums.
    pub(crate) fn p2g_all(&mut self, dt: Real) {
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        match self.config.transfer {
            Transfer::Flip => self.scatter::<true, true, true, false>(0.0, g),
            Transfer::Apic => self.scatter::<true, true, true, true>(0.0, g),
        }
    }

    /// nodal force f_i^int + f_i^ext (eqs 2–3) into `scratch.force`.
    pub(crate) fn p2g_force(&mut self, dt: Real) {
        // Gravity at mid-step (it only changes during a ramp).
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        self.scatter::<false, false, true, false>(0.0, g);
    }

    /// the block scatter of the module docs, forming m_i (`MASS`; else the stored m_i divides
    /// the momentum), q_i and v_i = q_i / m_i (`MOMENTUM`) and f_i (`FORCE`). q_i sums
    /// m_p S_ip v_p, or with `APIC` m_p S_ip (v_p + C_p (x_i − x_p)), the particle positions taken
    /// back by `dt_back` along v_p; f_i sums m_p S_ip g − V_p σ_p · G_ip (eqs 2–3; tension
    /// positive, so −V σ·G pulls nodes towards stretched regions).
    fn scatter<const MASS: bool, const MOMENTUM: bool, const FORCE: bool, const APIC: bool>(
        &mut self,
        dt_back: Real,
        g: Vector,
    ) {
        const { assert!(patch_side(N) * patch_side(N) <= MAX_PATCH) };
        let side = patch_side(N);
        let cells = side * side;
        let w = stencil_side(N);
        // slot k of a stencil lies k mod w, k div w nodes from its first node
        let offset: [usize; N] = std::array::from_fn(|k| k % w + side * (k / w));
        let shape = &self.shape;
        let p = &self.particles;
        let (mass, velocity, volume, stress) =
            (&p.mass[..], &p.velocity[..], &p.volume[..], &p.stress[..]);
        let (position, affine) = (&p.position[..], &p.affine[..]);
        let Scratch {
            weights,
            gradients,
            bin_start,
            bin_particle,
            base,
            active,
            patch_mass,
            patch_momentum,
            patch_force,
            node_block,
            node_local,
            neighbours,
            mass: nodal_mass,
            velocity: nodal_velocity,
            force: nodal_force,
            ..
        } = &mut self.scratch;
        let (weights, gradients, base) = (&weights[..], &gradients[..], &base[..]);
        patch_mass
            .par_chunks_mut(cells)
            .zip(patch_momentum.par_chunks_mut(cells))
            .zip(patch_force.par_chunks_mut(cells))
            .enumerate()
            .for_each(|(b, ((bm, bq), bf))| {
                let mut place = [Vector::ZERO; MAX_PATCH];
                if MASS {
                    bm.fill(0.0);
                }
                if MOMENTUM {
                    bq.fill(Vector::ZERO);
                }
                if FORCE {
                    bf.fill(Vector::ZERO);
                }
                if APIC {
                    let o = active.block_origin(b);
                    for (c, x) in place[..cells].iter_mut().enumerate() {
                        let node = NodeId::new(o.i + (c % side) as i32, o.j + (c / side) as i32);
                        *x = shape.node_position(node);
                    }
                }
                let bin = &bin_particle[bin_start[b] as usize..bin_start[b + 1] as usize];
                for q in bin {
                    let q = q.load(Ordering::Relaxed) as usize;
                    let at = usize::from(base[q]);
                    let (m, v, wq, gq) = (mass[q], velocity[q], &weights[q], &gradients[q]);
                    let (vol, s) = (volume[q], stress[q]);
                    let (c_q, x0) = if APIC {
                        (affine[q], position[q] - dt_back * v)
                    } else {
                        Default::default()
                    };
                    for k in 0..N {
                        let c = at + offset[k];
                        let mw = m * wq[k];
                        if MASS {
                            bm[c] += mw;
                        }
                        if MOMENTUM {
                            bq[c] += if APIC { mw * (v + c_q * (place[c] - x0)) } else { mw * v };
                        }
                        if FORCE {
                            let gr = gq[k];
                            let sigma_g =
                                Vector::new(s.xx * gr.x + s.xy * gr.y, s.xy * gr.x + s.yy * gr.y);
                            bf[c] += mw * g - vol * sigma_g;
                        }
                    }
                }
            });
        let (pm, pq, pf) = (&patch_mass[..], &patch_momentum[..], &patch_force[..]);
        let edge = w - 1;
        let block = BLOCK_SIDE as usize;
        nodal_mass
            .par_iter_mut()
            .zip(nodal_velocity.par_iter_mut().zip(nodal_force.par_iter_mut()))
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, (m, (v, f)))| {
                let b = node_block[i] as usize;
                let c = usize::from(node_local[i]);
                let (ci, cj) = (c % side, c / side);
                let [below_left, below, left] = neighbours[b];
                let (mut ms, mut q, mut fs) = (0.0, Vector::ZERO, Vector::ZERO);
                let mut add = |src: u32, at: usize| {
                    if src != u32::MAX {
                        let at = src as usize * cells + at;
                        if MASS {
                            ms += pm[at];
                        }
                        if MOMENTUM {
                            q += pq[at];
                        }
                        if FORCE {
                            fs += pf[at];
                        }
                    }
                };
                if ci < edge && cj < edge {
                    add(below_left, c + block + side * block);
                }
                if cj < edge {
                    add(below, c + side * block);
                }
                if ci < edge {
                    add(left, c + block);
                }
                add(b as u32, c);
                if MASS {
                    *m = ms;
                }
                if MOMENTUM {
                    *v = if *m > 0.0 { q / *m } else { Vector::ZERO };
                }
                if FORCE {
                    *f = fs;
                }
            });
    }
}
