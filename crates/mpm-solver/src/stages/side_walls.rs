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
//! A ghost node behind a slip plane (wide stencils) takes its image's factor instead of its
//! own, so that the mirrored constraint the contact law met (linear in both velocities) still
//! holds.
//!
//! The work of its impulse J_i = m_i (v^L_new − v^L) at the mean of the node's start and end
//! velocities (the contact law's midpoint rule) is booked as its own dissipation
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
        // a ghost behind a slip plane met a wall moving with its image's mirrored velocity:
        // it takes its image's factor, so that the constraint the contact law met, linear in
        // both velocities, still holds (own capacity aside).
        let mut ghosts = std::mem::take(&mut sc.wall_ghosts);
        ghosts.clear();
        ghosts.extend(
            sc.boundary
                .iter()
                .filter_map(|b| b.mirror.filter(|m| !m.fixed).map(|m| (b.node, m.image))),
        );
        ghosts.sort_unstable();
        let is_ghost =
            |i: u32| !ghosts.is_empty() && ghosts.binary_search_by_key(&i, |g| g.0).is_ok();
        sc.wall_scale.clear();
        sc.wall_scale.resize(sc.mass.len(), 1.0);
        let (mut work, mut impulse, mut normal) = (0.0, Vector::ZERO, 0.0);
        // the impulse m (v_new − v^L) at node i, booked with the work it does at the mean of the
        // node's start and end velocities (the midpoint rule of the contact law's booking:
        // a friction that holds a node against a steady force books no work)
        let mut book = |sc: &mut Scratch<S::Factors, N>, i: usize, scale: Real| {
            let end = sc.velocity[i] + sc.acceleration[i] * dt;
            let new = end * scale;
            sc.acceleration[i] += (new - end) / dt;
            if skip.is_empty() || skip.binary_search(&(i as u32)).is_err() {
                let j = (new - end) * sc.mass[i];
                work -= j.dot(0.5 * (sc.velocity[i] + new));
                impulse += j;
            }
        };
        for i in 0..sc.mass.len() {
            let n = sc.wall_normal[i];
            if n <= 0.0 {
                continue;
            }
            if skip.is_empty() || skip.binary_search(&(i as u32)).is_err() {
                normal += n * dt;
            }
            let m = sc.mass[i];
            if m <= small || is_ghost(i as u32) {
                // (a small-mass node takes body force only, §2(3); its share of the normal
                // load is booked all the same)
                continue;
            }
            let speed = (sc.velocity[i] + sc.acceleration[i] * dt).length();
            if speed == 0.0 {
                continue;
            }
            let cut = (walls.friction * n * dt / m).min(speed);
            let scale = 1.0 - cut / speed;
            sc.wall_scale[i] = scale;
            book(sc, i, scale);
        }
        for &(g, image) in &ghosts {
            let scale = sc.wall_scale[image as usize];
            if scale < 1.0 && sc.mass[g as usize] > small {
                book(sc, g as usize, scale);
            }
        }
        sc.wall_skip = skip;
        sc.wall_ghosts = ghosts;
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
