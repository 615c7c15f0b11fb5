//! The consistent mass matrix ([`MassMatrix::Consistent`], beyond the paper).
//!
//! # Glossary
//! - M^C_ij = Σ_p m_p S_ip S_jp: the consistent mass matrix over the active nodes; its row sums
//!   are the lumped masses m_i = Σ_p m_p S_ip of eq 1 (the shape functions sum to one).
//! - M^L = diag(m_i): the lumped matrix the paper divides by (eq 4).
//! - α = [`LUMPED_SHARE`]: the solved matrix is M = (1 − α) M^C + α M^L.
//! - b: a right-hand side per node (a 2-vector: both components solve with the same matrix).
//!
//! With the consistent matrix the grid solves M a = f for the accelerations (instead of eq 4) and
//! M v = Σ_p m_p S_ip v_p for the velocities of particle-to-grid and of the MUSL/USAVG remap (eq
//! 8): the velocity is the L2 projection of the particles' velocity field onto the grid, which
//! removes the smoothing, hence the numerical dissipation, of the lumped transfer (Burgess,
//! Sulsky & Brackbill 1992; Love & Sulsky 2006). The boundary conditions (eqs 14–18) then act on
//! the solved accelerations and velocities exactly as with the lumped matrix; then, since with a
//! coupled matrix the held nodes' neighbours must feel the constrained motion, the free nodes are
//! solved again with the held ones' accelerations prescribed (`resolve_constrained`; without it
//! the fixed end of the vibrating bar shortened its period by 1.5 %, measured). A held ghost
//! node's image is prescribed as well, so that the ghost still mirrors its final value. Behind a
//! fixed plane the image is solved for instead (it neighbours the wall node, which it must feel:
//! prescribed, uGIMP had 8× the error of bilinear functions on the manufactured solution) and
//! the ghost is tied to it, a_g = −a_j: the re-solve's system is TᵀMT for that tie (the method
//! of images: row j takes row g mirrored), which brought quadratic B-splines from first to second
//! order on the manufactured solution; the lumped grid solve ties them the same way. The ledger
//! books the reactions r = M a − f once every node is final (`book_reactions`), so the momentum
//! balance holds to rounding with boundaries too.
//!
//! A node that a Coulomb (frictional or frictionless) or rough plane holds in this step keeps its
//! lumped row (is not solved for; nor is the image of a ghost behind such a plane, unless the
//! ghost is behind a fixed plane too, whose tie wins): the Coulomb law (eqs
//! 14–18) computes its normal and friction impulses for a node of mass m_i, and applied to
//! coupled rows it over-braked. Measured (0.5 m cells, USAVG, C = 0.1): the sliding block of
//! eq 21 stopped after 16.24 m bilinear and 13.30 m B-spline against 16.99 m (16.98 and 16.98
//! now), and the flume's floor nodes, solved for, doubled its friction work (6.2 against 2.9
//! kJ/m) and threw a grain above the grid at 0.05 m cells. Fixed planes stay coupled: the held
//! node's acceleration is prescribed and its neighbours solved for again (above).
//!
//! Not with APIC (refused by [`crate::SolverConfig::validate`]): the affine matrix
//! C_p = Σ v_i ⊗ G_ip sees velocity modes that the projection leaves free and the weights do not
//! see; a sand block thrown on a floor (USL, B-spline) blew up within six steps.
//!
//! # Why the matrix stays regular
//! M^C is a sum of rank-one terms m_p S_p S_pᵀ: wherever fewer particles than nodes reach a group
//! of nodes (a lone grain: four nodes, one particle) it is singular, and a force outside its range
//! has no solution. Two things keep the solved matrix symmetric positive definite:
//! - a node below the small-mass threshold (§2(3)) is not solved for: it keeps the lumped value
//!   (for the acceleration, the body force), and the couplings M^C_ij of a solved node i to such
//!   a node (or to a node held by a sliding plane, above) are added to M_ii, so that every
//!   solved row still sums to m_i;
//! - the share α of the lumped matrix: since 0 ≤ xᵀM^C x ≤ xᵀM^L x (Jensen, the weights being a
//!   partition of unity), the eigenvalues of (M^L)⁻¹M lie in [α, 1].
//!
//! Both keep each row sum equal to m_i, and M is symmetric, so Σ_i m_i a_i = Σ_i f_i: the FLIP
//! update (eq 7) changes the particles' momentum by exactly the nodal forces' impulse, as with
//! the lumped matrix, to the solver's tolerance.
//!
//! # The solve
//! Conjugate gradients preconditioned by M^L (a diagonal), started from the lumped answer
//! b_i / m_i, both components at once. With the spectrum in [α, 1] it converges by a factor of at
//! least (1 − √α)/(1 + √α) per iteration; a well-filled grid's spectrum lies in about [0.1, 1]
//! and takes 10–20. The matrix is assembled once per step, in a banded layout: row i holds the
//! (2w − 1)² nodes within w − 1 nodes of node i (w the stencil side), whose dense indices are
//! looked up once per active set. Every sum runs in a fixed order in fixed chunks, so results are
//! bit-identical for any thread count.

// the 3D build keeps only the stubs at the end
#![cfg_attr(feature = "dim3", allow(unused_imports, dead_code))]

use mpm_constitutive::ConstitutiveModel;
use mpm_contact::Friction;
use mpm_grid::{NodeId, ShapeFunctions, stencil_side};

use rayon::prelude::*;

use crate::config::MassMatrix;
use crate::consistent::{ConsistentScratch, Solve};
use crate::error::SolverError;
use crate::math::{Real, Vector};
use crate::par::{chunk_len, map_chunks};
use crate::scratch::NodePlane;
use crate::solver::Solver;

/// α, the share of the lumped matrix in the solved one (module docs): bounds the preconditioned
/// condition number by 1/α = 20, so a singular M^C (a lone grain) still has one bounded answer.
/// Measured on the vibrating bar (MUSL, C = 0.05, five periods), energy error: bilinear 1 m
/// cells 0.39 % at α = 0.05 against 0.36 % at α = 0 and 0.64 % lumped; B-spline 0.25 m cells
/// 0.64 % at α = 0.05 against 0.86 % lumped, where α = 0 and 0.01 failed (no convergence, and a
/// particle thrown out of the grid: the three node rows of a one-cell-thick bar are underfilled).
pub const LUMPED_SHARE: Real = 0.05;

/// The conjugate-gradient solve stops when the residual's M^L⁻¹ norm is this fraction of the
/// right-hand side's: 1e-13, a few hundred ulps, so that the momentum balance Σ m_i a_i = Σ f_i
/// holds to rounding, not to the solver's tolerance.
pub const SOLVE_TOLERANCE: Real = 1e-13;

/// Iterations allowed: with the spectrum in [α, 1] the bound of the module docs reaches
/// [`SOLVE_TOLERANCE`] in about 70; more means the matrix is not what this module built.
pub const MAX_ITERATIONS: usize = 300;

/// the band place of the entry (row node at stencil slot k, column node at slot l), w the
/// stencil side: offsets −(w − 1)…w − 1 along each axis, x fastest.
#[cfg(not(feature = "dim3"))]
const fn band_place(k: usize, l: usize, w: usize) -> usize {
    let wide = 2 * w - 1;
    (l % w + w - 1 - k % w) + wide * (l / w + w - 1 - k / w)
}

/// Σ over fixed chunks of `f(chunk range)`, in chunk order: bit-identical for any thread count.
#[cfg(not(feature = "dim3"))]
fn chunked_sum(n: usize, f: impl Fn(std::ops::Range<usize>) -> Vector + Sync) -> Vector {
    let chunk = chunk_len(n);
    let part = |c: usize| f(c * chunk..((c + 1) * chunk).min(n));
    let parts = map_chunks(n.div_ceil(chunk), &part);
    parts.iter().fold(Vector::ZERO, |s, &v| s + v)
}

/// (M v)_i for the banded matrix `values` (rows of `band` entries, columns `neighbours`).
#[cfg(not(feature = "dim3"))]
fn row_times(values: &[Real], neighbours: &[u32], band: usize, i: usize, v: &[Vector]) -> Vector {
    let row = &values[i * band..][..band];
    let cols = &neighbours[i * band..][..band];
    row.iter().zip(cols).fold(Vector::ZERO, |s, (&a, &j)| s + a * v[j as usize])
}

#[cfg(not(feature = "dim3"))]
impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// assembles M (module docs) from the step's stencils and nodal masses; nothing under the
    /// lumped matrix. Call after the particle-to-grid mass.
    pub(crate) fn assemble_mass_matrix(&mut self) {
        if self.config.mass != MassMatrix::Consistent {
            return;
        }
        let w = stencil_side(N);
        let wide = 2 * w - 1;
        let band = wide * wide;
        let centre = (w - 1) * (1 + wide);
        let sc = &mut self.scratch;
        let nodes = sc.active.len();
        let cm = &mut sc.consistent;
        if cm.generation != sc.active_generation || cm.band != band {
            cm.band = band;
            cm.generation = sc.active_generation;
            cm.neighbours.resize(nodes * band, 0);
            let active = &sc.active;
            cm.neighbours.par_chunks_mut(band).enumerate().for_each(|(i, row)| {
                let at = active.nodes()[i];
                for (o, slot) in row.iter_mut().enumerate() {
                    let (di, dj) =
                        ((o % wide) as i32 - (w as i32 - 1), (o / wide) as i32 - (w as i32 - 1));
                    *slot = active
                        .index_of(NodeId::new(at.i + di, at.j + dj))
                        .map_or(i as u32, |j| j as u32);
                }
            });
        }
        cm.values.clear();
        cm.values.resize(nodes * band, 0.0);
        for v in [&mut cm.rhs, &mut cm.residual, &mut cm.direction, &mut cm.product] {
            v.resize(nodes, Vector::ZERO);
        }
        let small = self.small_mass;
        cm.free.clear();
        cm.free.extend(sc.mass.iter().map(|&m| m > small));
        // A node a Coulomb or rough plane holds this step keeps its lumped row, and so does a
        // ghost's image behind such a plane (module docs: the contact law's impulse is the
        // lumped one).
        // (a ghost behind a fixed plane is its image mirrored whatever else holds it)
        let sliding = |p: &NodePlane| p.held && p.wall.boundary().friction() != Friction::Fixed;
        for b in sc.boundary.iter().filter(|b| !b.mirror.is_some_and(|m| m.fixed)) {
            if sc.node_planes[b.planes()].iter().any(sliding) {
                cm.free[b.node as usize] = false;
                if let Some(m) = b.mirror {
                    cm.free[m.image as usize] = false;
                }
            }
        }

        // Σ_p m_p S_ip S_jp, particle by particle in index order.
        let place: [[usize; N]; N] =
            std::array::from_fn(|k| std::array::from_fn(|l| band_place(k, l, w)));
        let p = &self.particles;
        for q in 0..p.len() {
            let s = self.shape.weights(&sc.factors[q]);
            let idx = &sc.node_index[q];
            let m = p.mass[q];
            for k in 0..N {
                let row = &mut cm.values[idx[k] as usize * band..][..band];
                let mk = m * s[k];
                for l in 0..N {
                    row[place[k][l]] += mk * s[l];
                }
            }
        }

        // Couplings to nodes not solved for go onto the diagonal, then the lumped share.
        let (neighbours, free, mass) = (&cm.neighbours[..], &cm.free[..], &sc.mass[..]);
        cm.values.par_chunks_mut(band).enumerate().with_min_len(256).for_each(|(i, row)| {
            if !free[i] {
                row.fill(0.0);
                row[centre] = mass[i];
                return;
            }
            let mut lumped = 0.0;
            for (o, v) in row.iter_mut().enumerate() {
                if o != centre && !free[neighbours[i * band + o] as usize] {
                    lumped += *v;
                    *v = 0.0;
                }
            }
            for v in row.iter_mut() {
                *v *= 1.0 - LUMPED_SHARE;
            }
            row[centre] += (1.0 - LUMPED_SHARE) * lumped + LUMPED_SHARE * mass[i];
        });
    }

    /// with the consistent matrix, replaces the lumped nodal velocities v_i = q_i / m_i in
    /// `scratch.velocity` by the solution of M v = q (the L2 projection); nodes not solved for
    /// keep theirs. Nothing under the lumped matrix.
    pub(crate) fn project_velocity(&mut self, which: Solve) -> Result<(), SolverError> {
        if self.config.mass != MassMatrix::Consistent {
            return Ok(());
        }
        let sc = &mut self.scratch;
        for ((b, &v), &m) in sc.consistent.rhs.iter_mut().zip(&sc.velocity).zip(&sc.mass) {
            *b = m * v;
        }
        let mut x = std::mem::take(&mut sc.velocity);
        let result = self.solve_consistent(&mut x, which);
        self.scratch.velocity = x;
        result
    }

    /// with the consistent matrix, replaces the accelerations f_i / m_i already in
    /// `scratch.acceleration` by the solution of M a = f (nodes below the small-mass threshold
    /// keep the body force).
    pub(crate) fn solve_acceleration(&mut self) -> Result<(), SolverError> {
        if self.config.mass != MassMatrix::Consistent {
            return Ok(());
        }
        let sc = &mut self.scratch;
        sc.consistent.rhs.copy_from_slice(&sc.force);
        let mut x = std::mem::take(&mut sc.acceleration);
        let result = self.solve_consistent(&mut x, Solve::Acceleration);
        self.scratch.acceleration = x;
        result
    }

    /// with the consistent matrix, after the boundary conditions changed the accelerations of
    /// the held nodes: solves again for the other nodes with the held ones' accelerations as
    /// prescribed values, M_ff a_f = f_f − M_fc a_c, so that their neighbours feel the constrained
    /// motion (with the lumped matrix no other node sees it). Nothing when no node is held.
    pub(crate) fn resolve_constrained(&mut self) -> Result<(), SolverError> {
        let cm = &mut self.scratch.consistent;
        if self.config.mass != MassMatrix::Consistent || cm.constrained.is_empty() {
            return Ok(());
        }
        // A ghost behind a fixed plane that carries mass (B-splines) is tied to its image, so
        // the system solved is TᵀMT with T the tie a_ghost = −a_image: the image's row takes
        // the ghost's row, mirrored (the method of images). Ties where either node is not
        // solved for (an image that is itself held, a ghost below the small-mass threshold,
        // whose coupling is on the image's diagonal already) leave the ghost to follow after.
        // (a held ghost is in `constrained`: not solved for, the tie moves it)
        let free = &cm.free;
        let tied = self.scratch.fixed_ghosts.iter().map(|f| (f.ghost, f.image));
        cm.slaves.clear();
        cm.slaves.extend(tied.filter(|&(g, _)| free[g as usize]));
        cm.prescribed.clear();
        for &i in &cm.constrained {
            if std::mem::replace(&mut cm.free[i as usize], false) {
                cm.prescribed.push(i);
            }
        }
        let free = &cm.free;
        cm.slaves.retain(|&(_, j)| free[j as usize]);
        if cm.prescribed.is_empty() {
            // Only lumped rows are held (sliding planes): no solved row couples to them, so
            // there is nothing to solve again (and no tie: a tied ghost is held and solved for).
            cm.slaves.clear();
            return Ok(());
        }
        let sc = &mut self.scratch;
        sc.consistent.rhs.copy_from_slice(&sc.force);
        let mut x = std::mem::take(&mut sc.acceleration);
        let result = self.solve_consistent(&mut x, Solve::Acceleration);
        let sc = &mut self.scratch;
        sc.acceleration = x;
        sc.consistent.slaves.clear();
        // The held nodes are prescribed for this solve only: the remap's projection solves for
        // them again.
        let cm = &mut sc.consistent;
        for &i in &cm.prescribed {
            cm.free[i as usize] = true;
        }
        result
    }

    /// with the consistent matrix, books the boundary conditions' impulse and work in the ledger
    /// once every node is final: the reaction at node i is r_i = (M a)_i − f_i (m_i a_i − f_i
    /// on a lumped row, m_i (a_i − g) below the small-mass threshold, whose trial acceleration
    /// is g), booked where the contact law or a prescription set the acceleration (held nodes,
    /// prescribed images, tied ghosts and their images); elsewhere it is the solver's residual.
    /// The rows of M sum to the lumped masses and M is symmetric, so Σ_i r_i = Σ_i (m_i a_i −
    /// f_i) over the solved nodes: the momentum balance holds to that residual, which it thereby
    /// checks (the contact law's own impulse, m_i Δa_i Δt at the lumped mass, was 7–28 % off on
    /// the manufactured solution, and its work made the flume's ledger gain 60 kJ/m). The work
    /// is r_i · (v_i + ½ a_i Δt) Δt, the midpoint rule that closes the grid's kinetic energy
    /// (½ vᵀ M v changes by Δt (f + r) · (v + ½ a Δt)), relative to the moving "wall" of a ghost
    /// behind a Coulomb or rough plane as the lumped booking does; at a held node its part along
    /// the first held plane's normal is constraint work, the rest friction work, and the
    /// remainder (prescribed images; a tied ghost and its image do no work together) is
    /// constraint work.
    pub(crate) fn book_reactions(&mut self, dt: Real) {
        if self.config.mass != MassMatrix::Consistent {
            return;
        }
        // The nodes whose accelerations something other than M a = f set: the held ones (and
        // the images they prescribed), the ghosts tied to their images and those images.
        let sc = &mut self.scratch;
        let cm = &mut sc.consistent;
        cm.reacting.clear();
        cm.reacting.extend_from_slice(&cm.constrained);
        cm.reacting.extend(sc.fixed_ghosts.iter().flat_map(|g| [g.ghost, g.image]));
        cm.reacting.sort_unstable();
        cm.reacting.dedup();
        // Each one's boundary, for the loads: a held node's first held plane; an image, its
        // ghost's mirror plane (the first ghost's, for an image of two).
        cm.sources.clear();
        for b in &sc.boundary {
            let planes = &sc.node_planes[b.planes()];
            let Some(p) = planes.iter().find(|p| p.held) else { continue };
            cm.sources.push((b.node, p.source, p.wall.normal()));
            if let Some(m) = b.mirror {
                let (source, normal) = crate::stages::grid::mirror_source(planes, m.normal);
                cm.sources.push((m.image, source, normal));
            }
        }
        cm.sources.sort_by_key(|s| s.0);
        cm.sources.dedup_by_key(|s| s.0);
        let sc = &self.scratch;
        let cm = &sc.consistent;
        let band = cm.band;
        let (values, neighbours, free) = (&cm.values[..], &cm.neighbours[..], &cm.free[..]);
        let (a, f, v, mass) = (&sc.acceleration[..], &sc.force[..], &sc.velocity[..], &sc.mass[..]);
        let small = self.small_mass;
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        // (M a)_i − f_i, with M's row where the node is solved for and its lumped row elsewhere;
        // m_i (a_i − g) below the small-mass threshold, whose trial acceleration is g (as the
        // lumped booking has it)
        let reaction = |i: usize| -> Vector {
            if mass[i] <= small {
                return mass[i] * (a[i] - g);
            }
            if !free[i] {
                return mass[i] * a[i] - f[i];
            }
            row_times(values, neighbours, band, i, a) - f[i]
        };
        // (impulse x, impulse y, work) over them, absolute velocities; elsewhere r_i is the
        // solver's residual, left out, so that the momentum balance checks it is negligible.
        let total = cm.reacting.iter().map(|&i| i as usize).fold(glam::DVec3::ZERO, |s, i| {
            let r = reaction(i) * dt;
            s + r.extend(r.dot(v[i] + 0.5 * dt * a[i]))
        });
        // The split at the held nodes (periodic sides, whose pairs would be booked twice, are
        // refused with this matrix). A tied ghost and its image do no work together.
        let (mut work, mut friction) = (total.z, 0.0);
        for b in &sc.boundary {
            let i = b.node as usize;
            let Some(plane) = sc.node_planes[b.planes()].iter().find(|p| p.held) else { continue };
            if b.mirror.is_some_and(|m| m.fixed) {
                continue;
            }
            let r = reaction(i) * dt;
            // (as the contact law saw it: the image's v^L is final, prescribed by its ghost)
            let wall = b.mirror.map_or(Vector::ZERO, |m| {
                let j = m.image as usize;
                m.wall_velocity(v[j] + a[j] * dt)
            });
            work -= r.dot(wall);
            let mean_v = v[i] + 0.5 * dt * a[i] - wall;
            let n = plane.wall.boundary().normal();
            friction += r.dot(mean_v) - r.dot(n) * mean_v.dot(n);
        }
        for &i in &cm.reacting {
            if let Ok(k) = cm.sources.binary_search_by_key(&i, |s| s.0) {
                let (_, source, normal) = cm.sources[k];
                self.loads[source as usize].add(reaction(i as usize) * dt, normal);
            }
        }
        let d = &mut self.dissipation;
        d.impulse += total.truncate();
        d.friction -= friction;
        d.constraint -= work - friction;
    }

    /// preconditioned conjugate gradients on M x = rhs over the free nodes, from the x given
    /// (the lumped answer); the other nodes' x stay.
    fn solve_consistent(&mut self, x: &mut [Vector], which: Solve) -> Result<(), SolverError> {
        let sc = &mut self.scratch;
        solve_consistent(self.step + 1, &sc.mass, &mut sc.consistent, x, which)
    }
}

/// [`Solver::solve_consistent`]: not generic (one copy for every model and shape functions).
#[cfg(not(feature = "dim3"))]
fn solve_consistent(
    step: u64,
    mass: &[Real],
    cm: &mut ConsistentScratch,
    x: &mut [Vector],
    which: Solve,
) -> Result<(), SolverError> {
    let band = cm.band;
    let n = x.len();
    let chunk = chunk_len(n);
    let (values, neighbours, free) = (&cm.values[..], &cm.neighbours[..], &cm.free[..]);
    let multiply = |i: usize, v: &[Vector]| row_times(values, neighbours, band, i, v);
    // Tied ghosts (re-solve only): x_g = −x_j in every vector the matrix multiplies, and the
    // image's row gets the ghost's, mirrored (Tᵀ: row j minus row g). Serial: a few nodes.
    let slaves = &cm.slaves[..];
    let tie = |v: &mut [Vector]| {
        for &(g, j) in slaves {
            v[g as usize] = -v[j as usize];
        }
    };
    tie(x);
    // r = b − M x; z = r / m; p = z.
    {
        let (xr, b) = (&*x, &cm.rhs[..]);
        cm.residual.par_chunks_mut(chunk).enumerate().for_each(|(c, r)| {
            for (k, r) in r.iter_mut().enumerate() {
                let i = c * chunk + k;
                *r = if free[i] { b[i] - multiply(i, xr) } else { Vector::ZERO };
            }
        });
        for &(g, j) in slaves {
            cm.residual[j as usize] -= b[g as usize] - multiply(g as usize, xr);
        }
    }
    let rhs = chunked_sum(n, |range| {
        range.filter(|&i| free[i]).fold(Vector::ZERO, |s, i| s + cm.rhs[i] * cm.rhs[i] / mass[i])
    });
    for ((p, &r), &m) in cm.direction.iter_mut().zip(&cm.residual).zip(mass) {
        *p = if m > 0.0 { r / m } else { Vector::ZERO };
    }
    tie(&mut cm.direction);
    let mut rz = chunked_sum(n, |range| {
        range.fold(Vector::ZERO, |s, i| s + cm.residual[i] * cm.direction[i])
    });
    // The scale is the right-hand side's norm, or the starting residual's where prescribed
    // nodes (a re-solve) make that larger: a free node's right-hand side is then f minus
    // the prescribed nodes' share, which can be all there is (a body at rest on a fixed wall).
    let scale = (rhs.x + rhs.y).max(rz.x + rz.y);
    let target = SOLVE_TOLERANCE * SOLVE_TOLERANCE * scale;
    let mut iterations = 0;
    // (a NaN residual enters the loop and is reported, not accepted)
    while rz.x + rz.y > target || (rz.x + rz.y).is_nan() {
        if iterations == MAX_ITERATIONS || !(rz.x + rz.y).is_finite() {
            cm.iterations += iterations as u64;
            return Err(SolverError::MassSolve {
                step,
                solve: which.name(),
                iterations,
                relative_residual: ((rz.x + rz.y) / scale).sqrt(),
            });
        }
        iterations += 1;
        let direction = &cm.direction[..];
        cm.product.par_chunks_mut(chunk).enumerate().for_each(|(c, q)| {
            for (k, q) in q.iter_mut().enumerate() {
                let i = c * chunk + k;
                *q = if free[i] { multiply(i, direction) } else { Vector::ZERO };
            }
        });
        for &(g, j) in slaves {
            cm.product[j as usize] -= multiply(g as usize, direction);
        }
        let pq = chunked_sum(n, |range| {
            range.fold(Vector::ZERO, |s, i| s + cm.direction[i] * cm.product[i])
        });
        let alpha = Vector::new(
            if pq.x > 0.0 { rz.x / pq.x } else { 0.0 },
            if pq.y > 0.0 { rz.y / pq.y } else { 0.0 },
        );
        let (residual, product) = (&mut cm.residual, &cm.product);
        x.par_chunks_mut(chunk).zip(residual.par_chunks_mut(chunk)).enumerate().for_each(
            |(c, (xs, rs))| {
                for (k, (x, r)) in xs.iter_mut().zip(rs).enumerate() {
                    let i = c * chunk + k;
                    *x += alpha * direction[i];
                    *r -= alpha * product[i];
                }
            },
        );
        let rz_new = chunked_sum(n, |range| {
            range
                .filter(|&i| free[i])
                .fold(Vector::ZERO, |s, i| s + cm.residual[i] * cm.residual[i] / mass[i])
        });
        let beta = Vector::new(
            if rz.x > 0.0 { rz_new.x / rz.x } else { 0.0 },
            if rz.y > 0.0 { rz_new.y / rz.y } else { 0.0 },
        );
        rz = rz_new;
        let residual = &cm.residual[..];
        cm.direction.par_chunks_mut(chunk).enumerate().for_each(|(c, ps)| {
            for (k, p) in ps.iter_mut().enumerate() {
                let i = c * chunk + k;
                *p = if free[i] { residual[i] / mass[i] + beta * *p } else { Vector::ZERO };
            }
        });
        tie(&mut cm.direction);
    }
    cm.iterations += iterations as u64;
    Ok(())
}

/// The 3D build has the lumped matrix only: the solver's settings refuse the consistent one
/// (`SolverConfig::validate`), so these steps of the module docs have nothing to do.
#[cfg(feature = "dim3")]
impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// nothing: no consistent matrix in 3D.
    pub(crate) fn assemble_mass_matrix(&mut self) {}

    /// nothing: no consistent matrix in 3D.
    pub(crate) fn project_velocity(&mut self, _which: Solve) -> Result<(), SolverError> {
        Ok(())
    }

    /// nothing: no consistent matrix in 3D.
    pub(crate) fn solve_acceleration(&mut self) -> Result<(), SolverError> {
        Ok(())
    }

    /// nothing: no consistent matrix in 3D.
    pub(crate) fn resolve_constrained(&mut self) -> Result<(), SolverError> {
        Ok(())
    }

    /// nothing: no consistent matrix in 3D.
    pub(crate) fn book_reactions(&mut self, _dt: Real) {}
}

#[cfg(all(test, not(feature = "dim3")))]
mod tests {
    use super::band_place;

    /// the band place of (k, l) and of (l, k) mirror each other about the centre (the matrix is
    /// symmetric), and a node's own entry is the centre. The momentum balance, the thread
    /// independence and the vibrating bar are tested at the workspace level
    /// (`tests/tests/verification/consistent_mass.rs`, `stages/stress.rs`).
    #[test]
    fn band_places_mirror_about_the_centre() {
        for w in [2, 3] {
            let wide = 2 * w - 1;
            let centre = (w - 1) * (1 + wide);
            for k in 0..w * w {
                assert_eq!(band_place(k, k, w), centre);
                for l in 0..w * w {
                    assert_eq!(band_place(k, l, w) + band_place(l, k, w), 2 * centre);
                }
            }
        }
    }
}
