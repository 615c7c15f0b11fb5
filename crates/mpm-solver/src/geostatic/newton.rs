//! The implicit solve's inner work: which unknowns each node's displacement is made of, the
//! Newton iterations of a load step, the residual and the linear correction.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use mpm_constitutive::{Branch, PlaneTensor, Tangent, TangentModel};
use mpm_contact::Friction;
use mpm_grid::ShapeFunctions;

use crate::math::{Real, Vector};
use crate::solver::Solver;
use crate::stages::grid::held_planes;

use super::*;

impl<M: TangentModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// the Newton iterations of one load step to the load factor `target`, from the committed
    /// stresses and states `base_*`: on success the particles hold the step's stresses and
    /// `work.u_full` its displacement increment.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn newton(
        &mut self,
        target: Real,
        settings: &GeostaticSettings,
        dofs: &[NodeDofs],
        f_grav: &[Vector],
        shift: &[Real],
        load_norm: Real,
        base_stress: &[PlaneTensor],
        base_state: &[M::State],
        work: &mut Work,
        report: &mut GeostaticReport,
    ) -> Result<(), Failed> {
        work.s.fill(0.0);
        let start = work.s.clone();
        self.residual(target, dofs, f_grav, base_stress, base_state, work, &start)?;
        let mut r_norm = norm(&work.r) / load_norm;
        report.history.push(NewtonIteration {
            load_factor: target,
            iteration: 0,
            residual: r_norm,
        });
        for it in 1..=settings.max_iterations {
            if r_norm <= settings.tolerance {
                return Ok(());
            }
            if self.interrupted() {
                return Err(Failed { cause: "interrupted".into() });
            }
            // K from the tangents at the current increment.
            let correction = self.correction(dofs, shift, base_stress, base_state, work)?;
            // Backtracking on ‖R‖: the full Newton step, else halves of it; the last halving
            // (1/32) is taken even if it does not reduce ‖R‖ (the next tangent may).
            let s0 = work.s.clone();
            let mut moved = 0.0;
            let mut factor = 1.0;
            for tries in 1..=6 {
                if self.interrupted() {
                    return Err(Failed { cause: "interrupted".into() });
                }
                let trial: Vec<Real> =
                    s0.iter().zip(&correction).map(|(s, d)| s + factor * d).collect();
                match self.residual(target, dofs, f_grav, base_stress, base_state, work, &trial) {
                    Ok(res) => {
                        let n = norm(&work.r) / load_norm;
                        if n < r_norm || tries == 6 {
                            work.s = trial;
                            moved = res;
                            r_norm = n;
                            break;
                        }
                    }
                    Err(e) if tries == 6 => return Err(e),
                    Err(_) => {}
                }
                factor *= 0.5;
            }
            report.iterations += 1;
            report.history.push(NewtonIteration {
                load_factor: target,
                iteration: it,
                residual: r_norm,
            });
            if moved > self.cell_size {
                return Err(Failed {
                    cause: format!(
                        "a node moved {moved:.3e} m, more than a cell ({:.3e} m): no \
                         small-strain equilibrium (a material that cannot stand, or a body no \
                         boundary holds)",
                        self.cell_size
                    ),
                });
            }
            if !r_norm.is_finite() {
                return Err(Failed { cause: "the residual is not finite".into() });
            }
        }
        if r_norm <= settings.tolerance {
            return Ok(());
        }
        Err(Failed {
            cause: format!(
                "the residual stayed at {r_norm:.3e} (tolerance {:.1e}) after {} iterations",
                settings.tolerance, settings.max_iterations
            ),
        })
    }

    /// the stresses of the increment `s` (unknowns) from the base state, written to the
    /// particles, and the reduced residual in `work.r`; returns the largest nodal displacement.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn residual(
        &mut self,
        target: Real,
        dofs: &[NodeDofs],
        f_grav: &[Vector],
        base_stress: &[PlaneTensor],
        base_state: &[M::State],
        work: &mut Work,
        s: &[Real],
    ) -> Result<Real, Failed> {
        expand(dofs, s, &mut work.u_full);
        let largest = work.u_full.iter().map(|u| u.length()).fold(0.0, Real::max);
        if !largest.is_finite() {
            return Err(Failed {
                cause: "the displacement is not finite (a singular system)".into(),
            });
        }
        let sc = &self.scratch;
        let p = &mut self.particles;
        for q in 0..p.len() {
            if q % INTERRUPT_EVERY == INTERRUPT_EVERY - 1
                && self
                    .interrupt
                    .as_ref()
                    .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
            {
                return Err(Failed { cause: "interrupted".into() });
            }
            let d_eps =
                strain(&self.shape.gradients(&sc.factors[q]), &sc.node_index[q], &work.u_full);
            let model = &self.materials[usize::from(p.material[q])];
            let (mut sigma, mut state) = (base_stress[q], base_state[q]);
            let rep = model
                .update_plane(&mut sigma, &mut state, &d_eps, QUASI_STATIC_DT, None)
                .map_err(|e| Failed {
                    cause: format!(
                        "particle {q} at ({}, {}): {e}",
                        p.position[q].x, p.position[q].y
                    ),
                })?;
            p.stress[q] = sigma;
            p.state[q] = state;
            work.branches[q] = rep.branch;
        }
        self.p2g_internal_force();
        let out = &mut work.r;
        out.clear();
        out.resize(s.len(), 0.0);
        for (i, d) in dofs.iter().enumerate() {
            let r_i = target * f_grav[i] + self.scratch.force[i];
            for &(r, c) in d.rows() {
                out[r as usize] += c.dot(r_i);
            }
        }
        Ok(largest)
    }

    /// solves K δ = R (reduced) with the tangents at the current increment.
    pub(super) fn correction(
        &self,
        dofs: &[NodeDofs],
        shift: &[Real],
        base_stress: &[PlaneTensor],
        base_state: &[M::State],
        work: &Work,
    ) -> Result<Vec<Real>, Failed> {
        let sc = &self.scratch;
        let p = &self.particles;
        let unknowns = shift.len();
        let mut triplets: Vec<Triplet<usize, usize, Real>> =
            Vec::with_capacity(p.len() * N * N * 4);
        for (r, &d) in shift.iter().enumerate() {
            triplets.push(Triplet::new(r, r, d));
        }
        for q in 0..p.len() {
            if q % INTERRUPT_EVERY == INTERRUPT_EVERY - 1 && self.interrupted() {
                return Err(Failed { cause: "interrupted".into() });
            }
            let gr = self.shape.gradients(&sc.factors[q]);
            let idx = &sc.node_index[q];
            let d_eps = strain(&gr, idx, &work.u_full);
            let model = &self.materials[usize::from(p.material[q])];
            let t = model
                .consistent_tangent(
                    &base_stress[q].to_sym(),
                    &base_state[q],
                    &d_eps.to_sym(),
                    QUASI_STATIC_DT,
                )
                .map_err(|e| Failed { cause: format!("tangent of particle {q}: {e}") })?;
            let mut d = plane_block(&t);
            // a vanishing tangent (a point at its cone's apex) gets a floor (module docs)
            let floor = TANGENT_FLOOR * self.p_modulus[usize::from(p.material[q])];
            if d.iter().flatten().all(|x| x.abs() < floor) {
                for (a, row) in d.iter_mut().enumerate() {
                    row[a] += floor;
                }
            }
            let v = p.volume[q];
            for l in 0..N {
                let gl = gr[l];
                // D B_l: the stress of unit displacements of node l along x and y.
                let col = |b: usize| -> [Real; 3] {
                    let (bx, by, bs) =
                        if b == 0 { (gl.x, 0.0, 0.5 * gl.y) } else { (0.0, gl.y, 0.5 * gl.x) };
                    std::array::from_fn(|a| d[a][0] * bx + d[a][1] * by + d[a][2] * bs)
                };
                let (dbx, dby) = (col(0), col(1));
                for k in 0..N {
                    let gk = gr[k];
                    let row = |db: &[Real; 3]| {
                        Vector::new(gk.x * db[0] + gk.y * db[2], gk.y * db[1] + gk.x * db[2]) * v
                    };
                    // the 2 × 2 block K_kl by columns: force on k of unit u_l along x, along y.
                    let (kx, ky) = (row(&dbx), row(&dby));
                    for &(r1, c1) in dofs[idx[k] as usize].rows() {
                        for &(r2, c2) in dofs[idx[l] as usize].entries() {
                            // c1ᵀ K_kl c2
                            let val = c1.dot(kx * c2.x + ky * c2.y);
                            if val != 0.0 {
                                triplets.push(Triplet::new(r1 as usize, r2 as usize, val));
                            }
                        }
                    }
                }
            }
        }
        // (a signal during the assembly is honoured before the factorisation, the longest part)
        if self.interrupted() {
            return Err(Failed { cause: "interrupted".into() });
        }
        let k = SparseColMat::<usize, Real>::try_new_from_triplets(unknowns, unknowns, &triplets)
            .map_err(|e| Failed { cause: format!("cannot assemble the stiffness: {e:?}") })?;
        let rhs = faer::Mat::<Real>::from_fn(unknowns, 1, |r, _| work.r[r]);
        let factor_and_solve = move || -> Result<Vec<Real>, String> {
            let lu = k.sp_lu().map_err(|e| format!("singular stiffness: {e:?}"))?;
            let x = lu.solve(&rhs);
            Ok((0..unknowns).map(|r| x[(r, 0)]).collect())
        };
        let solved = match &self.interrupt {
            None => factor_and_solve(),
            // The factorisation cannot be stopped part-way: it runs on its own thread, and a
            // signal is honoured within a poll while it works (the thread is left to finish
            // and its result dropped).
            Some(flag) => {
                let handle = std::thread::spawn(factor_and_solve);
                while !handle.is_finished() {
                    if flag.load(std::sync::atomic::Ordering::Relaxed) {
                        return Err(Failed { cause: "interrupted".into() });
                    }
                    std::thread::sleep(std::time::Duration::from_millis(FACTOR_POLL_MS));
                }
                handle.join().unwrap_or_else(|_| Err("the factorisation panicked".into()))
            }
        };
        let out = solved.map_err(|cause| Failed { cause })?;
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Failed {
                cause: "the stiffness is singular (a body no boundary holds?)".into(),
            });
        }
        Ok(out)
    }

    /// how each active node's displacement is made of the unknowns (module docs), the number of
    /// unknowns, and how each node is held.
    pub(super) fn node_dofs(
        &self,
        tie: bool,
        released: &[(u32, Vector)],
    ) -> (Vec<NodeDofs>, usize, Vec<Hold>, usize) {
        let sc = &self.scratch;
        let nodes = sc.active.len();
        let mut holds = vec![Hold::Free; nodes];
        let mut buf = Vec::new();
        for b in &sc.boundary {
            let mut planes = held_planes(&mut buf, &sc.node_planes[b.planes()]).to_vec();
            planes.retain(|p| !is_released(released, b.node, p.normal()));
            if planes.is_empty() {
                continue;
            }
            let i = b.node as usize;
            let mirror = b.mirror.filter(|m| !is_released(released, b.node, m.normal));
            if let Some(m) = mirror {
                // As in the grid solve: the ghost meets a wall moving with its image's mirrored
                // normal motion; it slides along it only on a frictionless plane, and not when
                // another plane holds it too (a ghost on the floor's line beside a wall, a
                // corner ghost), whose normal is the mirror plane's tangent.
                let frictionless = planes
                    .iter()
                    .all(|p| matches!(p.friction(), Friction::Coulomb { mu } if mu == 0.0));
                let other = planes.iter().any(|p| 1.0 - p.normal().dot(m.normal) >= SAME_NORMAL);
                holds[i] = Hold::Ghost {
                    image: m.image,
                    normal: m.normal,
                    tangential: frictionless && !m.fixed && !other,
                    fixed: m.fixed,
                };
                continue;
            }
            let sticks = planes
                .iter()
                .any(|p| !matches!(p.friction(), Friction::Coulomb { mu } if mu == 0.0));
            let n0 = planes[0].normal();
            let one_plane = planes.iter().all(|p| 1.0 - p.normal().dot(n0) < SAME_NORMAL);
            holds[i] = if sticks || !one_plane { Hold::Fixed } else { Hold::Roller(n0) };
        }
        // Poorly supported free nodes follow their well-supported neighbours (module docs).
        let mass = &sc.mass;
        let heaviest = mass.iter().copied().fold(0.0, Real::max);
        let poor =
            |i: usize| tie && matches!(holds[i], Hold::Free) && mass[i] < TIE_RATIO * heaviest;
        // A node in a particle's stencil that its weight does not reach (uGIMP's outer nodes: a
        // weight and gradient of 0, or their rounding) carries no stiffness and no load: not an
        // unknown (it would be a zero row of K).
        let empty = |i: usize| mass[i] <= UNREACHED_RATIO * heaviest;
        let mut dofs = vec![NodeDofs::default(); nodes];
        let mut next = 0u32;
        let mut new_dof = || {
            next += 1;
            next - 1
        };
        for (i, (d, h)) in dofs.iter_mut().zip(&holds).enumerate() {
            match *h {
                _ if empty(i) => {}
                Hold::Free if poor(i) => {}
                Hold::Free => {
                    d.push(new_dof(), Vector::X);
                    d.push(new_dof(), Vector::Y);
                }
                Hold::Roller(n) => d.push(new_dof(), n.perp()),
                Hold::Fixed | Hold::Ghost { .. } => {}
            }
        }
        let mut ties = 0;
        for i in 0..nodes {
            if !poor(i) || empty(i) {
                continue;
            }
            let at = sc.active.nodes()[i];
            let mut sources = Vec::new();
            for (di, dj) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                let Some(j) = sc.active.index_of(mpm_grid::NodeId::new(at.i + di, at.j + dj))
                else {
                    continue;
                };
                if !poor(j) && !empty(j) && !matches!(holds[j], Hold::Ghost { .. }) {
                    sources.push(j);
                }
            }
            if sources.is_empty() {
                // nothing to follow: its own unknowns
                dofs[i].push(new_dof(), Vector::X);
                dofs[i].push(new_dof(), Vector::Y);
                continue;
            }
            let w = 1.0 / sources.len() as Real;
            let mut d = NodeDofs::default();
            for j in sources {
                d.add(&dofs[j], |c| w * c);
            }
            dofs[i] = d;
            ties += 1;
        }
        // A ghost mirrors its image's map, which must be final: a corner ghost's image may be
        // a ghost itself, so ghosts are expressed in passes, those whose image is done first.
        let mut pending: Vec<usize> =
            (0..nodes).filter(|&i| matches!(holds[i], Hold::Ghost { .. })).collect();
        while !pending.is_empty() {
            let before = pending.len();
            let waiting: Vec<bool> = {
                let mut w = vec![false; nodes];
                for &i in &pending {
                    w[i] = true;
                }
                w
            };
            pending.retain(|&i| {
                let Hold::Ghost { image, normal, tangential, fixed } = holds[i] else {
                    return false;
                };
                if waiting[image as usize] && image as usize != i {
                    return true;
                }
                let img = dofs[image as usize].clone();
                // a ghost no weight reaches has no stiffness along its wall either
                let own = tangential && !fixed && !empty(i);
                if fixed {
                    dofs[i].add(&img, |c| -c);
                } else {
                    if own {
                        dofs[i].push(new_dof(), normal.perp());
                    }
                    dofs[i].add(&img, |c| -normal.dot(c) * normal);
                }
                dofs[i].rows = Some(usize::from(own));
                false
            });
            if pending.len() == before {
                // a cycle of images (not made by the grids here): those ghosts stay held
                break;
            }
        }
        (dofs, next as usize, holds, ties)
    }
}

/// The particle passes of the solve (assembly, stress update) look for a signal every this many
/// particles (a few milliseconds of work).
const INTERRUPT_EVERY: usize = 8192;

/// How often (ms) a factorisation on its own thread is checked for its end and for a signal.
const FACTOR_POLL_MS: u64 = 10;

/// Vectors reused over the iterations.
pub(super) struct Work {
    /// the load step's increment in the unknowns.
    pub(super) s: Vec<Real>,
    /// ... and at the nodes.
    pub(super) u_full: Vec<Vector>,
    /// the reduced residual.
    pub(super) r: Vec<Real>,
    /// each particle's branch at its last update.
    pub(super) branches: Vec<Branch>,
}

impl Work {
    pub(super) fn new(nodes: usize, unknowns: usize) -> Self {
        Self {
            s: vec![0.0; unknowns],
            u_full: vec![Vector::ZERO; nodes],
            r: vec![0.0; unknowns],
            branches: Vec::new(),
        }
    }
}

/// the nodal displacements of the unknowns `s`.
pub(super) fn expand(dofs: &[NodeDofs], s: &[Real], out: &mut [Vector]) {
    for (u, d) in out.iter_mut().zip(dofs) {
        *u = d.entries().iter().map(|&(r, c)| s[r as usize] * c).sum();
    }
}

/// Δε = sym(Σ_k u_k ⊗ G_k) (eq 9 with displacements).
pub(super) fn strain<const N: usize>(
    grads: &[Vector; N],
    idx: &[u32; N],
    u: &[Vector],
) -> PlaneTensor {
    let (mut xx, mut yy, mut xy, mut yx) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..N {
        let (v, g) = (u[idx[k] as usize], grads[k]);
        xx += v.x * g.x;
        yy += v.y * g.y;
        xy += v.x * g.y;
        yx += v.y * g.x;
    }
    PlaneTensor::new(xx, yy, 0.0, 0.5 * (xy + yx))
}

/// the plane-strain block of a tangent: rows and columns xx, yy, xy (storage places 0, 1, 3).
pub(super) fn plane_block(t: &Tangent) -> [[Real; 3]; 3] {
    const AT: [usize; 3] = [0, 1, 3];
    std::array::from_fn(|a| std::array::from_fn(|b| t[AT[a]][AT[b]]))
}

pub(super) fn norm(v: &[Real]) -> Real {
    v.iter().map(|x| x * x).sum::<Real>().sqrt()
}
