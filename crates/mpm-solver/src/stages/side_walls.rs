//! The friction of side walls across the plane of a plane-strain run ([`crate::SideWalls`]):
//! a channel of width W whose two walls press on the material with its out-of-plane stress
//! σ_zz (known at every particle in plane strain) and rub with friction μ_w.
//!
//! Per unit volume the walls take the body force 2 μ_w max(−σ_zz, 0)/W against the in-plane
//! velocity (Jop, Forterre & Pouliquen 2005 showed this μ_w h/W term first-order in channel
//! flows). It is applied at the nodes as the basal Coulomb law is (eqs 15–16): each node
//! gathers the walls' normal force N_i = Σ_p S_ip V_p 2 max(−σ_zz,p, 0)/W in a scatter of its
//! own (the force pass's stresses, the same block order as `p2g.rs`: bit-identical for any
//! thread count), and after the contact law its end velocity v^L is cut by
//! min(|v^L|, μ_w N_i Δt/m_i) along −v^L/|v^L|: the friction stops a node but never reverses
//! it. Only the acceleration changes (v^L = v + aΔt), so FLIP's increment, the PIC share and
//! APIC's velocities all carry it, and every contact constraint already met stays met (v^L is
//! scaled by a factor in [0, 1]).
//!
//! The kinetic energy it takes, ½ m_i (|v^L|² − |v^L_new|²), is booked as its own dissipation
//! (`Dissipation::side_walls`), its impulse with the boundaries' (`Dissipation::impulse`, the
//! momentum balance) and in the loads as the last entry, whose normal part is the walls' normal
//! impulse Σ N_i Δt (both walls, acting across the plane) and whose tangential part is the
//! friction's.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

use crate::config::SideWalls;
use crate::math::{DIM, Real, Vector};
use crate::scratch::Scratch;
use crate::solver::Solver;
use crate::stages::p2g::{patch_side, visit_patches};

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// N_i, the side walls' normal force on each active node, into `scratch.wall_normal`
    /// (from the particles' current σ_zz: call it in the pass that forms the forces).
    pub(crate) fn p2g_side_walls(&mut self, walls: SideWalls) {
        let p = &self.particles;
        let k = 2.0 / walls.width;
        scatter_normal::<S, N>(&self.shape, (&p.volume, &p.stress), &mut self.scratch, k);
        let sc = &mut self.scratch;
        for &(a, b) in &sc.periodic_pairs {
            let (a, b) = (a as usize, b as usize);
            let n = sc.wall_normal[a] + sc.wall_normal[b];
            (sc.wall_normal[a], sc.wall_normal[b]) = (n, n);
        }
    }

    /// the walls' friction on every node's end velocity (the module docs), after the contact
    /// law; booked in the ledger and the loads.
    pub(crate) fn side_wall_friction(&mut self, walls: SideWalls, dt: Real) {
        let small = self.small_mass;
        let sc = &mut self.scratch;
        // a periodic image holds its partner's sums and ends as it does: booked once, by the
        // partner; a ghost behind a fixed side is overwritten by its image (`grid.rs`).
        let mut skip = std::mem::take(&mut sc.wall_skip);
        skip.clear();
        skip.extend(sc.periodic_pairs.iter().map(|&(image, _)| image));
        skip.extend(sc.fixed_ghosts.iter().map(|f| f.ghost));
        skip.sort_unstable();
        let (mut work, mut impulse, mut normal) = (0.0, Vector::ZERO, 0.0);
        for i in 0..sc.mass.len() {
            let n = sc.wall_normal[i];
            if n <= 0.0 {
                continue;
            }
            let books = skip.is_empty() || skip.binary_search(&(i as u32)).is_err();
            let m = sc.mass[i];
            if books {
                normal += n * dt;
            }
            if m <= small {
                // (a small-mass node takes body force only, §2(3))
                continue;
            }
            let end = sc.velocity[i] + sc.acceleration[i] * dt;
            let speed = end.length();
            if speed == 0.0 {
                continue;
            }
            let cut = (walls.friction * n * dt / m).min(speed);
            sc.acceleration[i] -= end * (cut / (speed * dt));
            if books {
                work += m * cut * (speed - 0.5 * cut);
                impulse -= end * (m * cut / speed);
            }
        }
        sc.wall_skip = skip;
        self.dissipation.side_walls += work;
        self.dissipation.impulse += impulse;
        let load = self.loads.last_mut().expect("the side walls' entry (Solver::new)");
        load.impulse += impulse;
        load.tangential += impulse;
        load.normal += normal;
    }
}

/// N_i = Σ_p S_ip V_p k max(−σ_zz,p, 0) into `sc.wall_normal`: a block scatter into
/// `sc.wall_patch` and the reduction of `p2g.rs`, in the same orders.
fn scatter_normal<S: ShapeFunctions<N>, const N: usize>(
    shape: &S,
    (volume, stress): (&[Real], &[crate::math::Stress]),
    sc: &mut Scratch<S::Factors, N>,
    k: Real,
) {
    let side = patch_side(N);
    let cells = side.pow(DIM as u32);
    let w = mpm_grid::stencil_side(N);
    let offset: [usize; N] = std::array::from_fn(|s| {
        let d = mpm_grid::slot_offset(s, w);
        (0..DIM).rev().fold(0, |p, a| p * side + d[a] as usize)
    });
    sc.wall_patch.resize(sc.patch.len(), 0.0);
    sc.wall_normal.resize(sc.mass.len(), 0.0);
    let Scratch {
        factors,
        bin_start,
        bin_particle,
        base,
        node_block,
        node_local,
        neighbours,
        wall_patch,
        wall_normal,
        ..
    } = sc;
    wall_patch.par_chunks_mut(cells).enumerate().for_each(|(b, sums)| {
        sums.fill(0.0);
        let bin = &bin_particle[bin_start[b] as usize..bin_start[b + 1] as usize];
        for q in bin {
            let q = q.load(Ordering::Relaxed) as usize;
            let press = volume[q] * k * (-stress[q].zz).max(0.0);
            if press == 0.0 {
                continue;
            }
            let at = usize::from(base[q]);
            let wq = shape.weights(&factors[q]);
            for s in 0..N {
                sums[at + offset[s]] += wq[s] * press;
            }
        }
    });
    let (patch, tables) = (&wall_patch[..], (&node_block[..], &node_local[..], &neighbours[..]));
    wall_normal.par_iter_mut().enumerate().with_min_len(256).for_each(|(i, n)| {
        let mut sum = 0.0;
        visit_patches::<N>(i, tables, |src, at| sum += patch[src as usize * cells + at]);
        *n = sum;
    });
}
