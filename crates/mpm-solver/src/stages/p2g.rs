//! Stage 3: particle-to-grid sums.
//!
//! m_i = Σ_p m_p S_ip (eq 1); q_i = Σ_p m_p v_p S_ip and v_i = q_i / m_i;
//! f_i = −Σ_p V_p σ_p · G_ip (eq 2) + Σ_p m_p S_ip b (eq 3, b = gravity, plus the particle's own
//! body force where the caller prescribed one: [`Solver::set_body_force`]).
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
use mpm_grid::{BLOCK_SIDE, ShapeFunctions, slot_offset, stencil_side};
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use crate::config::Transfer;
use crate::consistent::Solve;
use crate::error::SolverError;
use crate::math::{DIM, Matrix, Real, Stress, Vector};
use crate::scratch::{NEIGHBOURS, PatchSums, Scratch};
use crate::solver::Solver;

/// nodes along each side of a block's patch for stencils of `n` nodes: the block's 8 and the
/// w − 1 beyond its upper and right edges that stencils anchored in it reach.
pub(crate) const fn patch_side(n: usize) -> usize {
    BLOCK_SIDE as usize + stencil_side(n) - 1
}

/// the most nodes a patch can have (stencils up to 4 × 4): places in a patch fit a byte.
#[cfg(not(feature = "dim3"))]
const MAX_PATCH: usize = (BLOCK_SIDE as usize + 3) * (BLOCK_SIDE as usize + 3);
/// the most nodes a patch can have in 3D (stencils up to 3 × 3 × 3): places fit a byte.
#[cfg(feature = "dim3")]
const MAX_PATCH: usize = (BLOCK_SIDE as usize + 2).pow(3);

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
    /// With the consistent mass matrix the remapped velocity is its L2 projection
    /// (`stages/mass.rs`), whose failure is the only error.
    pub(crate) fn remap_velocity(&mut self, dt: Real) -> Result<(), SolverError> {
        // The stencils are the start-of-step ones, so the affine term must use the start-of-step
        // positions too: x_p − Δt v_p, exact under APIC (whose G2P moves x_p by Δt v_p).
        match self.config.transfer {
            Transfer::Flip => self.scatter::<false, true, false, false>(dt, Vector::ZERO),
            Transfer::Apic => self.scatter::<false, true, false, true>(dt, Vector::ZERO),
        }
        self.project_velocity(Solve::Remap)?;
        self.constrain_velocity();
        Ok(())
    }

    /// mass, velocity and force in one pass (USL and MUSL, whose force uses the stress of the
    /// previous step): each particle is read once for all three sums.
    pub(crate) fn p2g_all(&mut self, dt: Real) {
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        match self.config.transfer {
            Transfer::Flip => self.scatter::<true, true, true, false>(0.0, g),
            Transfer::Apic => self.scatter::<true, true, true, true>(0.0, g),
        }
        if let Some(walls) = self.config.side_walls() {
            self.p2g_side_walls(walls);
        }
    }

    /// nodal force f_i^int + f_i^ext (eqs 2–3) into `scratch.force`.
    pub(crate) fn p2g_force(&mut self, dt: Real) {
        // Gravity at mid-step (it only changes during a ramp).
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        self.scatter::<false, false, true, false>(0.0, g);
        if let Some(walls) = self.config.side_walls() {
            self.p2g_side_walls(walls);
        }
    }

    /// −f_i^int = −Σ_p V_p σ_p · G_ip alone (no gravity) into `scratch.force`: the implicit
    /// initial state's internal force (`geostatic.rs`), summed as every step sums it.
    #[cfg_attr(feature = "dim3", allow(dead_code))] // used by the implicit initial state
    pub(crate) fn p2g_internal_force(&mut self) {
        self.scatter::<false, false, true, false>(0.0, Vector::ZERO);
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
        let p = &self.particles;
        let sources = Sources {
            mass: &p.mass,
            velocity: &p.velocity,
            volume: &p.volume,
            stress: &p.stress,
            position: &p.position,
            affine: &p.affine,
            body: &self.body_force,
        };
        scatter::<S, N, MASS, MOMENTUM, FORCE, APIC>(
            &self.shape,
            &sources,
            &mut self.scratch,
            dt_back,
            g,
        );
        if self.config.periodic.is_some() {
            self.fold_periodic::<MASS, MOMENTUM, FORCE>();
        }
    }

    /// Periodic sides ([`crate::Periodic`]): node columns `i` and `i ± columns` are one column,
    /// so each active image node (outside `0..columns`) and its active partner
    /// (`scratch.periodic_pairs`) get the sums of both: masses and forces add, a velocity formed
    /// in this pass (`MASS`) is the mass-weighted mean, and a remapped one (divided by the
    /// shared mass already) adds. A partner no particle reaches has nothing to add. Serial over
    /// the pairs: only periodic scenes pay for it.
    fn fold_periodic<const MASS: bool, const MOMENTUM: bool, const FORCE: bool>(&mut self) {
        let sc = &mut self.scratch;
        for &(a, b) in &sc.periodic_pairs {
            let (a, b) = (a as usize, b as usize);
            if MASS {
                let (ma, mb) = (sc.mass[a], sc.mass[b]);
                let m = ma + mb;
                if MOMENTUM {
                    let q = ma * sc.velocity[a] + mb * sc.velocity[b];
                    let v = if m > 0.0 { q / m } else { Vector::ZERO };
                    (sc.velocity[a], sc.velocity[b]) = (v, v);
                }
                (sc.mass[a], sc.mass[b]) = (m, m);
            } else if MOMENTUM {
                let v = sc.velocity[a] + sc.velocity[b];
                (sc.velocity[a], sc.velocity[b]) = (v, v);
            }
            if FORCE {
                let f = sc.force[a] + sc.force[b];
                (sc.force[a], sc.force[b]) = (f, f);
            }
        }
    }
}

/// the particle arrays a scatter reads.
struct Sources<'a> {
    mass: &'a [Real],
    velocity: &'a [Vector],
    volume: &'a [Real],
    stress: &'a [Stress],
    position: &'a [Vector],
    affine: &'a [Matrix],
    /// empty unless a caller prescribed per-particle body forces (then one per particle)
    body: &'a [Vector],
}

/// the block scatter of [`Solver::scatter`] into the patches, then [`reduce`]. A free function
/// generic over the shape functions and the sums formed, not over the constitutive model, which
/// it does not use: every model of a scene shares one copy.
fn scatter<
    S: ShapeFunctions<N>,
    const N: usize,
    const MASS: bool,
    const MOMENTUM: bool,
    const FORCE: bool,
    const APIC: bool,
>(
    shape: &S,
    p: &Sources<'_>,
    sc: &mut Scratch<S::Factors, N>,
    dt_back: Real,
    g: Vector,
) {
    const { assert!(patch_side(N).pow(DIM as u32) <= MAX_PATCH) };
    let side = patch_side(N);
    let cells = side.pow(DIM as u32);
    let w = stencil_side(N);
    // slot k of a stencil lies k mod w, k div w (, k div w²) nodes from its first node
    let offset: [usize; N] = std::array::from_fn(|k| {
        let d = slot_offset(k, w);
        (0..DIM).rev().fold(0, |p, a| p * side + d[a] as usize)
    });
    // (3D) each slot's offset from the first node along each axis, and the patch's strides
    #[cfg(feature = "dim3")]
    let slots: [[usize; DIM]; N] = std::array::from_fn(|k| slot_offset(k, w).map(|d| d as usize));
    #[cfg(feature = "dim3")]
    let stride = [1, side, side * side];
    let (mass, velocity, volume, stress) = (p.mass, p.velocity, p.volume, p.stress);
    let (position, affine) = (p.position, p.affine);
    // empty unless a caller prescribed per-particle body forces (then one per particle)
    let body = p.body;
    let Scratch {
        factors,
        bin_start,
        bin_particle,
        base,
        active,
        patch,
        node_block,
        node_local,
        neighbours,
        mass: nodal_mass,
        velocity: nodal_velocity,
        force: nodal_force,
        ..
    } = sc;
    let (factors, base) = (&factors[..], &base[..]);
    patch.par_chunks_mut(cells).enumerate().for_each(|(b, sums)| {
        let mut place = [Vector::ZERO; MAX_PATCH];
        // the sums this pass does not form stay zero, unread
        sums.fill(PatchSums::default());
        if APIC {
            let o = active.block_origin(b);
            for (c, x) in place[..cells].iter_mut().enumerate() {
                let d = std::array::from_fn(|a| ((c / side.pow(a as u32)) % side) as i32);
                *x = shape.node_position(o.offset(d));
            }
        }
        let bin = &bin_particle[bin_start[b] as usize..bin_start[b + 1] as usize];
        for q in bin {
            let q = q.load(Ordering::Relaxed) as usize;
            let at = usize::from(base[q]);
            let (m, v, f) = (mass[q], velocity[q], &factors[q]);
            let wq = shape.weights(f);
            let b = if FORCE && !body.is_empty() { g + body[q] } else { g };
            // In 3D the tensor-product stencils form the forces with sums factorised per axis;
            // in the plane each slot's force is formed where it is added (the same terms),
            // which measured fewer instructions than an array of them (callgrind).
            #[cfg(feature = "dim3")]
            let fq = if FORCE {
                shape.nodal_forces(f, &wq, (m, b), volume[q], columns(&stress[q]))
            } else {
                [Vector::ZERO; N]
            };
            #[cfg(not(feature = "dim3"))]
            let (gq, [sx, sy], vol) = if FORCE {
                (shape.gradients(f), columns(&stress[q]), volume[q])
            } else {
                ([Vector::ZERO; N], [Vector::ZERO; DIM], 0.0)
            };
            let (c_q, x0) =
                if APIC { (affine[q], position[q] - dt_back * v) } else { Default::default() };
            // In 3D on a regular grid x_i − x_p separates by axis, so C (x_i − x_p) is
            // the sum of one column term per axis, C_:a (x_i − x_p)_a, for the w nodes
            // along each axis: 3w products per particle instead of 9 per node. (Not on a
            // terrain grid, whose node heights depend on their column.)
            #[cfg(feature = "dim3")]
            let affine_terms: [[Vector; 3]; DIM] = if APIC && S::SEPARABLE_NODES {
                std::array::from_fn(|a| {
                    std::array::from_fn(|t| {
                        let node = place[at + t.min(w - 1) * stride[a]];
                        c_q.col(a) * (node[a] - x0[a])
                    })
                })
            } else {
                Default::default()
            };
            for k in 0..N {
                let c = at + offset[k];
                let mw = m * wq[k];
                #[cfg(not(feature = "dim3"))]
                let momentum = if APIC { mw * (v + c_q * (place[c] - x0)) } else { mw * v };
                #[cfg(feature = "dim3")]
                let momentum = if APIC && S::SEPARABLE_NODES {
                    let [tx, ty, tz] = slots[k];
                    mw * (v + (affine_terms[0][tx] + affine_terms[1][ty] + affine_terms[2][tz]))
                } else if APIC {
                    mw * (v + c_q * (place[c] - x0))
                } else {
                    mw * v
                };
                let sums = &mut sums[c];
                if MASS {
                    sums.mass += mw;
                }
                if MOMENTUM {
                    sums.momentum += momentum;
                }
                if FORCE {
                    #[cfg(feature = "dim3")]
                    let force = fq[k];
                    #[cfg(not(feature = "dim3"))]
                    let force = mw * b - vol * (sx * gq[k].x + sy * gq[k].y);
                    sums.force += force;
                }
            }
        }
    });
    reduce::<N, MASS, MOMENTUM, FORCE>(
        &patch[..],
        (&node_block[..], &node_local[..], &neighbours[..]),
        (&mut nodal_mass[..], &mut nodal_velocity[..], &mut nodal_force[..]),
    );
}

/// the patches' sums into the nodal arrays: each node adds the patches that hold it in a fixed
/// order (the module docs). Generic over the stencil size and the sums formed only: one copy per
/// stencil size, whatever the model and shape functions.
fn reduce<const N: usize, const MASS: bool, const MOMENTUM: bool, const FORCE: bool>(
    patch: &[PatchSums],
    (node_block, node_local, neighbours): (&[u32], &[u8], &[[u32; NEIGHBOURS]]),
    (nodal_mass, nodal_velocity, nodal_force): (&mut [Real], &mut [Vector], &mut [Vector]),
) {
    let cells = patch_side(N).pow(DIM as u32);
    nodal_mass
        .par_iter_mut()
        .zip(nodal_velocity.par_iter_mut().zip(nodal_force.par_iter_mut()))
        .enumerate()
        .with_min_len(256)
        .for_each(|(i, (m, (v, f)))| {
            let (mut ms, mut q, mut fs) = (0.0, Vector::ZERO, Vector::ZERO);
            let add = |src: u32, at: usize| {
                let s = &patch[src as usize * cells + at];
                if MASS {
                    ms += s.mass;
                }
                if MOMENTUM {
                    q += s.momentum;
                }
                if FORCE {
                    fs += s.force;
                }
            };
            visit_patches::<N>(i, (node_block, node_local, neighbours), add);
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

/// calls `add(block, place)` for every patch that holds active node `i`, in the fixed order
/// of the module docs (the blocks below-left, below, left, then its own; in 3D the seven lower
/// neighbours in order, then its own), so that every sum over patches adds its terms in one
/// order whatever the thread count.
#[inline(always)]
pub(crate) fn visit_patches<const N: usize>(
    i: usize,
    (node_block, node_local, neighbours): (&[u32], &[u8], &[[u32; NEIGHBOURS]]),
    mut add: impl FnMut(u32, usize),
) {
    let side = patch_side(N);
    let edge = stencil_side(N) - 1;
    let block = BLOCK_SIDE as usize;
    let b = node_block[i] as usize;
    let c = usize::from(node_local[i]);
    let mut add = |src: u32, at: usize| {
        if src != u32::MAX {
            add(src, at);
        }
    };
    #[cfg(not(feature = "dim3"))]
    {
        let (ci, cj) = (c % side, c / side);
        let [below_left, below, left] = neighbours[b];
        if ci < edge && cj < edge {
            add(below_left, c + block + side * block);
        }
        if cj < edge {
            add(below, c + side * block);
        }
        if ci < edge {
            add(left, c + block);
        }
    }
    // neighbour m lies one block lower along the axes whose bit of m is 0
    // (`locate.rs`), in the order m = 0, 1, …: the node is in its patch where it is
    // within the w − 1 edge layers along each of those axes.
    #[cfg(feature = "dim3")]
    {
        let local = [c % side, (c / side) % side, c / (side * side)];
        let stride = [1, side, side * side];
        for (m, &src) in neighbours[b].iter().enumerate() {
            let mut at = c;
            let mut inside = true;
            for a in 0..DIM {
                if (m >> a) & 1 == 0 {
                    inside &= local[a] < edge;
                    at += block * stride[a];
                }
            }
            if inside {
                add(src, at);
            }
        }
    }
    add(b as u32, c);
}

/// the stress's columns σ e_a in the plane of the analysis (plane strain: σ_zz does not act
/// on an in-plane gradient).
#[inline(always)]
#[cfg(not(feature = "dim3"))]
fn columns(s: &Stress) -> [Vector; DIM] {
    [Vector::new(s.xx, s.xy), Vector::new(s.xy, s.yy)]
}

/// the stress's columns σ e_a (in 3D the whole tensor).
#[inline(always)]
#[cfg(feature = "dim3")]
fn columns(s: &Stress) -> [Vector; DIM] {
    [Vector::new(s.xx, s.xy, s.zx), Vector::new(s.xy, s.yy, s.yz), Vector::new(s.zx, s.yz, s.zz)]
}

#[cfg(all(test, not(feature = "dim3")))]
mod tests {
    use mpm_constitutive::LinearElastic;
    use mpm_grid::{Gimp, RegularGrid, ShapeFunctions};

    use crate::particles::{NewParticle, Particles};
    use crate::solver::Solver;
    use crate::{SolverConfig, Transfer, Vector};

    /// The block scatter against the definition, summed node by node from the stencils: a body
    /// spread over many 8 × 8 blocks, ghost nodes at negative indices included (uGIMP at the
    /// grid's lower-left corner), moving and stressed, FLIP and APIC. Tolerance: the two sums add
    /// the same terms in different orders, so they agree to a few ulps of the largest term.
    #[test]
    fn scatter_matches_the_sums_of_eqs_1_to_3() {
        for transfer in [Transfer::Flip, Transfer::Apic] {
            let grid = RegularGrid::new(Vector::ZERO, Vector::splat(0.1), [40, 30]).unwrap();
            let mut particles = Particles::default();
            for k in 0..2000 {
                let (a, b) =
                    ((k * 7919 % 1999) as f64 / 1999.0, (k * 104_729 % 1997) as f64 / 1997.0);
                let x = Vector::new(0.02 + 3.9 * a, 0.01 + 2.9 * b);
                let mut p =
                    NewParticle::unstressed(x, Vector::new(b - 0.5, a * a), 0.0025, 1500.0, ());
                p.stress.xx = -1000.0 * a;
                p.stress.xy = 300.0 * (b - 0.5);
                p.stress.yy = -2000.0 * b;
                particles.push(p);
            }
            let config = SolverConfig { transfer, ..Default::default() };
            let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
            let mut s = Solver::new(
                Gimp::new(grid, Vector::splat(0.025)).unwrap(),
                vec![material],
                particles,
                config,
            )
            .unwrap();
            // (C_p exists under APIC only)
            for p in 0..s.particles.affine.len() {
                let (x, y) = (p as f64 * 0.37).sin_cos();
                s.particles.affine[p] =
                    crate::math::Matrix::from_cols(Vector::new(x, y), Vector::new(-y, 2.0 * x));
            }
            s.locate().unwrap();
            s.p2g_all(1e-4);
            let g = s.config.gravity_at(s.time + 0.5e-4);
            let sc = &s.scratch;
            let p = &s.particles;
            let nodes = sc.active.len();
            let (mut m, mut q, mut f) =
                (vec![0.0; nodes], vec![Vector::ZERO; nodes], vec![Vector::ZERO; nodes]);
            let (mut m_scale, mut q_scale, mut f_scale) = (0.0f64, 0.0f64, 0.0f64);
            for i in 0..p.len() {
                let st = s.shape.stencil(p.position[i]).unwrap();
                for (k, (node, w, gr)) in st.iter().enumerate() {
                    let n = sc.active.index_of(node).unwrap();
                    assert_eq!(n, sc.node_index[i][k] as usize);
                    let mw = p.mass[i] * w;
                    let v = match transfer {
                        Transfer::Flip => p.velocity[i],
                        Transfer::Apic => {
                            p.velocity[i]
                                + p.affine[i] * (s.shape.node_position(node) - p.position[i])
                        }
                    };
                    let s_ = &p.stress[i];
                    let [cx, cy] = super::columns(s_);
                    let sg = cx * gr.x + cy * gr.y;
                    m[n] += mw;
                    q[n] += mw * v;
                    f[n] += mw * g - p.volume[i] * sg;
                    m_scale = m_scale.max(mw);
                    q_scale = q_scale.max((mw * v).abs().max_element());
                    f_scale = f_scale.max((mw * g - p.volume[i] * sg).abs().max_element());
                }
            }
            assert!(sc.active.nodes().iter().any(|n| n.i < 0 && n.j < 0), "ghost nodes reached");
            assert!(sc.active.block_count() > 12, "many blocks");
            let tol = 64.0 * f64::EPSILON;
            for n in 0..nodes {
                assert!((sc.mass[n] - m[n]).abs() <= tol * m_scale, "mass at {n}");
                if m[n] > 0.0 {
                    let v = q[n] / m[n];
                    assert!(
                        (sc.velocity[n] - v).abs().max_element() * m[n] <= tol * q_scale * 4.0,
                        "velocity at {n}"
                    );
                }
                assert!((sc.force[n] - f[n]).abs().max_element() <= tol * f_scale, "force at {n}");
            }
            // The passes USF and USAVG take apart (mass and velocity, then force) and the
            // remap (eq 8, over the stored mass) add the same terms in the same order as the
            // all-in-one pass: the same bits. (The remap at Δt = 0 finds the particles where
            // P2G did; this scene declares no boundary, so its velocity constraint is void.)
            let all = (sc.mass.clone(), sc.velocity.clone(), sc.force.clone());
            let scratch = &mut s.scratch;
            for v in [&mut scratch.velocity, &mut scratch.force] {
                v.fill(Vector::NAN);
            }
            scratch.mass.fill(f64::NAN);
            s.p2g_mass_velocity();
            s.p2g_force(1e-4);
            fn bits(v: &[Vector]) -> Vec<u64> {
                v.iter().flat_map(|x| [x.x, x.y]).map(f64::to_bits).collect()
            }
            let mass_bits = |m: &[f64]| m.iter().map(|m| m.to_bits()).collect::<Vec<_>>();
            assert_eq!(mass_bits(&s.scratch.mass), mass_bits(&all.0), "{transfer:?} split mass");
            assert_eq!(bits(&s.scratch.velocity), bits(&all.1), "{transfer:?} split velocity");
            assert_eq!(bits(&s.scratch.force), bits(&all.2), "{transfer:?} split force");
            s.scratch.velocity.fill(Vector::NAN);
            s.remap_velocity(0.0).unwrap();
            assert_eq!(bits(&s.scratch.velocity), bits(&all.1), "{transfer:?} remap");
        }
    }
}
