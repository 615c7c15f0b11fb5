//! The geostatic initial state: the stresses of material at rest under gravity, from an implicit
//! quasi-static solve on the run's own grid, shape functions and boundaries (beyond the paper,
//! whose runs start stress-free).
//!
//! # Glossary
//! - u_i: displacement of active node i during the solve (m). The particles do not move: their
//!   stencils S_ip, G_ip stay those of their current positions, and only their stresses and
//!   internal variables change; velocities stay the bodies' own.
//! - Δε_p = sym(Σ_i u_i ⊗ G_ip): a particle's strain increment over one load step (eq 9 with
//!   u in place of v Δt), tension positive.
//! - λ: the load factor, the share of gravity applied; f_i^ext = λ Σ_p m_p S_ip g (eq 3).
//! - f_i^int = Σ_p V_p σ_p G_ip (eq 2 with its sign), R = f^ext − f^int: the out-of-balance
//!   force, zero at equilibrium. Its norm over the unknowns (free components) is measured
//!   against that of f^ext at λ = 1 over the same unknowns: the gravity load the solve moves.
//! - D_p: the 3 × 3 plane-strain block (rows and columns xx, yy, xy with tensor shear) of the
//!   model's consistent tangent ([`TangentModel::consistent_tangent`]) at the load step's start
//!   state and the current increment; K_ij = Σ_p V_p F_ipᵀ D_p B_jp with B_jp the strain of a
//!   unit displacement of node j and F_ip the force on node i of a unit stress.
//!
//! # Constraints
//! Every plane that holds a node in the explicit run's first step holds it here
//! (`Solver::detect_contact` with Δt = 0: under surface contact, where a particle's edge lies on
//! the plane), read as a displacement constraint:
//! - a frictionless plane fixes the normal component u·n = 0 (a roller); two planes of different
//!   normals (a corner) fix the node;
//! - a plane with friction (Coulomb μ > 0, rough, fixed) fixes the node (stuck). Afterwards the
//!   reactions are checked against the friction law: where, on one Coulomb plane, the sum of the
//!   tangential reactions (as vectors) exceeds μ times the sum of the normal ones, the material
//!   would slide as a whole, and the solve fails (`SolverError::SlidingBase`);
//! - a ghost node of a wide stencil (uGIMP, B-spline) mirrors its image's normal displacement
//!   as in the explicit run: u_g·n = −u_image·n, its tangential part free on a frictionless plane
//!   held by no other plane and zero otherwise, u_g = −u_image on a fixed plane. Its normal
//!   force goes to its wall, not to its image (the grid solve gives the image none of it);
//! - planes hold one way, as in the grid solve: a plane (other than a fixed one) that would
//!   have to pull its node lets it go, and the solve starts again without it.
//!
//! So the state found is the explicit run's own equilibrium: its steps from it keep the
//! material at rest to rounding (tested with bilinear and B-spline functions).
//!
//! The free components are the unknowns (a node on an inclined frictionless plane has one, along
//! the plane): the system is K reduced to them, assembled as triplets and factorised with faer's
//! sparse LU (partial pivoting: the tangent of non-associated flow is not symmetric).
//!
//! # The iteration
//! Gravity is applied in load steps (`GeostaticSettings::load_steps`, 1 by default). Each load
//! step runs Newton iterations from the stresses and internal variables at its start: the
//! stresses of an increment come from one return mapping from that start (backward Euler, as an
//! implicit finite element code integrates them), the tangent is the model's consistent one, and
//! each correction is damped by a backtracking line search on ‖R‖. A load step that does not
//! converge within `max_iterations`, or whose nodes move more than a cell (no small-strain
//! equilibrium: a material that cannot stand, or a body no boundary holds), is retried with
//! half the load increment, at most `max_cutbacks` times in a row (and within a budget of
//! `max_iterations × (load_steps + 2 max_cutbacks + 2)` iterations in all, so that a state
//! reachable only in ever smaller steps cannot creep on for ever); then the solve fails with the
//! last load factor in equilibrium, which is a gravity-increase factor of safety in disguise.
//!
//! Poorly supported nodes ([`TIE_RATIO`]) are tied to their neighbours only when the state
//! has no equilibrium without (the first load step fails): the ties leave those nodes' own
//! forces unbalanced, which the explicit run then feels.
//!
//! A zero tangent (a cohesionless point returned to the apex of its cone) or an hourglass mode
//! of a cell with few particles would make K singular: a shift of [`DIAGONAL_SHIFT`] times the
//! elastic diagonal keeps it regular. It changes only the path, not the answer (the residual
//! is evaluated without it), at the price of one or two more iterations of a linear problem.

use mpm_constitutive::{Branch, TangentModel};
use mpm_contact::Friction;
use mpm_grid::ShapeFunctions;

use crate::error::SolverError;
use crate::math::{Real, Vector};
use crate::solver::Solver;
use crate::stages::grid::held_planes;

mod newton;
mod settle;
#[cfg(all(test, not(feature = "dim3")))]
mod tests;

pub use settle::SettleReport;

use newton::{Work, norm};

/// Relative shift of the stiffness matrix's diagonal (module docs): 1e-8 of the elastic diagonal
/// keeps K regular where a tangent vanishes, while a linear problem still converges by a factor
/// of about 1e-8 × the condition number per iteration (two iterations at the K0 layer's size).
pub const DIAGONAL_SHIFT: Real = 1e-8;

/// A point whose tangent has no entry above this share of its P-wave modulus in size (a
/// cohesionless point returned to its cone's apex has a zero tangent) gets this share added to
/// its diagonal in K: the node it alone supports then moves a bounded amount and its particles
/// are compressed back onto the cone at the next iteration, instead of the node flying off with
/// only the diagonal shift to hold it. It changes the iteration, not its converged answer.
pub const TANGENT_FLOOR: Real = 1e-2;

/// A free node whose mass is below this share of the heaviest node's (a node reached only by
/// the far corners of one or two particles, where the free surface cuts a cell) is poorly
/// supported: its own equilibrium would ask a surface particle for a traction that a
/// cohesionless material cannot give (no equilibrium exists on that grid), and its
/// displacement is not an unknown but the mean of its well-supported neighbours'. Its
/// out-of-balance force then goes to them (the reduced residual Tᵀ R). A node reached by the
/// nearest quarter of one particle of a 2 × 2 lattice has 6 % (a full node 100 %, one on a
/// straight free surface 50 %, at a body's corner 25 %).
pub const TIE_RATIO: Real = 0.05;

/// A node whose mass is at most this share of the heaviest node's is not reached by any
/// particle's weight (uGIMP's stencil includes nodes at the edge of a particle's support, with a
/// weight of 0 or its rounding): it has no unknown in the solve.
pub const UNREACHED_RATIO: Real = 1e-12;

/// Bytes the implicit solve needs beyond the explicit run's ([`crate::estimated_bytes`]) for
/// `particles` with `stencil`-node stencils: the stiffness triplets (reserved for every
/// particle's 2 × 2 blocks of stencil × stencil node pairs, 24 B each) and an allowance for the
/// assembled matrix and its LU factors, fitted from the measured peak resident memory of the
/// geostatic slope (about 3.5 kB per particle beyond the triplets with bilinear stencils at
/// 12 k–200 k particles, 6 kB with B-splines) and rounded up.
pub fn estimated_bytes(particles: usize, stencil: usize) -> u64 {
    let triplets = (stencil * stencil * 4 * 24) as u64;
    let factors = 1_000 * stencil as u64;
    particles as u64 * (triplets + factors)
}

/// The time over which a load step is taken (s), for rate-dependent models (μ(I)): a
/// quasi-static increment, whose strain rate is that of a 1 s loading.
pub const QUASI_STATIC_DT: Real = 1.0;

/// Most load steps a solve may take (`GeostaticSettings::load_steps`).
pub const MAX_LOAD_STEPS: u32 = 1000;
/// Most Newton iterations a load step may take (`GeostaticSettings::max_iterations`).
pub const MAX_NEWTON_ITERATIONS: u32 = 1000;
/// The open range of `GeostaticSettings::tolerance`: below 1e-15 is below rounding of ‖f^ext‖.
pub const TOLERANCE_RANGE: (Real, Real) = (1e-15, 1.0);
/// Most halvings in a row (`GeostaticSettings::max_cutbacks`): 2⁻⁵⁰ of gravity is nothing.
pub const MAX_CUTBACKS: u32 = 50;

/// Settings of the implicit solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeostaticSettings {
    /// Load steps that share gravity equally (≥ 1). More steps follow a plastic loading path
    /// more closely; a load step that fails is split anyway.
    pub load_steps: u32,
    /// Newton iterations allowed per load step.
    pub max_iterations: u32,
    /// Equilibrium: ‖R‖ ≤ tolerance · ‖f^ext‖ at full gravity (both over the unknowns).
    pub tolerance: Real,
    /// Halvings of a load increment allowed in a row before the solve fails.
    pub max_cutbacks: u32,
}

impl Default for GeostaticSettings {
    /// one load step, 50 iterations, 1e-10, 10 halvings (the smallest increment 1/1024 of
    /// gravity).
    fn default() -> Self {
        Self { load_steps: 1, max_iterations: 50, tolerance: 1e-10, max_cutbacks: 10 }
    }
}

impl GeostaticSettings {
    /// checks every setting's range.
    pub fn validate(&self) -> Result<(), SolverError> {
        let bad =
            |name, value: f64, expected| Err(SolverError::InvalidSetting { name, value, expected });
        if self.load_steps == 0 || self.load_steps > MAX_LOAD_STEPS {
            return bad(
                "initial_state.load_steps",
                self.load_steps.into(),
                "1 ≤ load_steps ≤ MAX_LOAD_STEPS (1000)",
            );
        }
        if self.max_iterations == 0 || self.max_iterations > MAX_NEWTON_ITERATIONS {
            return bad(
                "initial_state.max_iterations",
                self.max_iterations.into(),
                "1 ≤ max_iterations ≤ MAX_NEWTON_ITERATIONS (1000)",
            );
        }
        let (low, high) = TOLERANCE_RANGE;
        if !(self.tolerance > low && self.tolerance < high) {
            return bad("initial_state.tolerance", self.tolerance, "1e-15 < tolerance < 1");
        }
        if self.max_cutbacks > MAX_CUTBACKS {
            return bad(
                "initial_state.max_cutbacks",
                self.max_cutbacks.into(),
                "0 ≤ max_cutbacks ≤ 50",
            );
        }
        Ok(())
    }
}

/// One Newton iteration of the solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonIteration {
    /// the load factor the iteration aims at.
    pub load_factor: Real,
    /// its number within the load step (0: the residual before any correction).
    pub iteration: u32,
    /// ‖R‖ / ‖f^ext(λ = 1)‖ after it.
    pub residual: Real,
}

/// What the implicit solve did.
#[derive(Clone, Debug, PartialEq)]
pub struct GeostaticReport {
    /// Load steps that converged.
    pub load_steps: u32,
    /// Load increments halved after a failed attempt.
    pub cutbacks: u32,
    /// Newton iterations (linear solves), over all load steps and attempts.
    pub iterations: u32,
    /// The residual history, every iteration of every attempt in order.
    pub history: Vec<NewtonIteration>,
    /// The final ‖R‖ / ‖f^ext‖.
    pub residual: Real,
    /// Unknowns of the reduced system.
    pub unknowns: usize,
    /// Nodes a boundary constrains.
    pub constrained_nodes: usize,
    /// Particles whose last update left the elastic branch.
    pub plastic_particles: usize,
    /// Largest nodal displacement of the solve (m): its small-strain measure.
    pub max_displacement: Real,
    /// Nodes stuck on one Coulomb plane whose tangential reaction exceeds μ times their normal
    /// one (the material there would slip locally; see `base_friction_ratio`).
    pub slipping_nodes: usize,
    /// The largest, over the Coulomb planes with μ > 0, of |Σ tangential reaction| / μ Σ normal
    /// reaction at the nodes stuck on that plane alone (0 where there are none): above 1 the
    /// base cannot hold the material.
    pub base_friction_ratio: Real,
    /// Free nodes whose mass is below [`TIE_RATIO`] of the heaviest node's, which follow their
    /// neighbours instead of being unknowns of their own (0 when the state exists without).
    pub tied_nodes: usize,
    /// Planes that let their node go because they would have had to pull it.
    pub released_planes: usize,
}

/// How one node's displacement is made of the unknowns: u_i = Σ_k c_k s_{r_k}; and which of
/// those entries carry the node's own force into the equations (`rows`).
#[derive(Clone, Debug, Default)]
struct NodeDofs {
    entries: Vec<(u32, Vector)>,
    /// the leading entries whose unknowns the node's force enters (all, except at a ghost: a
    /// ghost's normal force goes to its wall, not to its image, as in the grid solve).
    rows: Option<usize>,
}

impl NodeDofs {
    /// the node's displacement in the unknowns (the trial map).
    fn entries(&self) -> &[(u32, Vector)] {
        &self.entries
    }
    /// where the node's force enters the reduced equations (the test map).
    fn rows(&self) -> &[(u32, Vector)] {
        let n = self.rows.unwrap_or(self.entries.len()).min(self.entries.len());
        &self.entries[..n]
    }
    fn push(&mut self, r: u32, c: Vector) {
        self.entries.push((r, c));
    }
    /// adds `weight` times the map `other`, merging equal unknowns.
    fn add(&mut self, other: &NodeDofs, weight: impl Fn(Vector) -> Vector) {
        for &(r, c) in &other.entries {
            match self.entries.iter_mut().find(|e| e.0 == r) {
                Some(e) => e.1 += weight(c),
                None => self.entries.push((r, weight(c))),
            }
        }
    }
}

/// How a boundary node is held (before ghosts are expressed through their images).
#[derive(Clone, Copy, Debug)]
enum Hold {
    Free,
    /// u·n = 0.
    Roller(Vector),
    Fixed,
    /// a ghost node: mirrors its image across a plane of this normal.
    Ghost {
        image: u32,
        normal: Vector,
        tangential: bool,
        fixed: bool,
    },
}

/// Normals closer than this (1 − cos θ) are one plane's (the two planes of a kink of a few
/// degrees are not: 1 − cos 1° = 1.5e-4).
const SAME_NORMAL: Real = 1e-9;

/// A plane pulls a node when its reaction along the normal is below −this × the node's force
/// scale (|m_i g| + |f_i^int|): rounding of a node at rest on it is ~1e-16 of that.
const PULL_TOLERANCE: Real = 1e-9;

/// At most this many planes are let go (each a new solve); past it the state is kept as is.
const MAX_RELEASED: usize = 64;

/// whether the plane of normal `n` at `node` was let go.
fn is_released(released: &[(u32, Vector)], node: u32, n: Vector) -> bool {
    released.iter().any(|&(k, m)| k == node && 1.0 - m.dot(n) < SAME_NORMAL)
}

/// A load step's attempt that did not reach equilibrium, and why.
struct Failed {
    cause: String,
}

impl<M: TangentModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// Puts the material into equilibrium with gravity (module docs): particle stresses and
    /// internal variables become those of the geostatic state, positions and velocities (the
    /// bodies' own) do not change, and the energy ledger starts from the new stored energy. Call before the first
    /// step.
    ///
    /// On failure the particles keep the state they had, and the error names the last load
    /// factor in equilibrium, the residual and the cause.
    pub fn solve_geostatic(
        &mut self,
        settings: &GeostaticSettings,
    ) -> Result<GeostaticReport, SolverError> {
        settings.validate()?;
        if self.step != 0 {
            return Err(SolverError::InvalidSetting {
                name: "initial_state",
                value: self.step as f64,
                expected: "an initial state is solved before the first step",
            });
        }
        if self.config.gravity_ramp > 0.0 {
            return Err(SolverError::Incompatible {
                setting: "initial_state",
                with: "gravity_ramp",
                reason: "the solve puts the material at rest under full gravity; set the ramp to 0",
            });
        }
        if self.config.periodic.is_some() {
            return Err(SolverError::Incompatible {
                setting: "initial_state",
                with: "periodic",
                reason: "the implicit solve does not pair periodic columns; start stress-free",
            });
        }
        // gravity alone loads the initial state (the body force is for the run's steps)
        let body = std::mem::take(&mut self.body_force);
        let solved = self.solve_geostatic_under_gravity(settings);
        self.body_force = body;
        solved
    }

    /// [`Solver::solve_geostatic`] once its settings are checked, with no body force set.
    fn solve_geostatic_under_gravity(
        &mut self,
        settings: &GeostaticSettings,
    ) -> Result<GeostaticReport, SolverError> {
        self.locate()?;
        self.detect_contact(0.0);
        // m_i (eq 1), as every step sums it; f^ext = m_i g at full gravity.
        self.p2g_mass_velocity();
        // Every node its own unknowns first: then the explicit run starts in the same
        // equilibrium, node by node. Only where that has none (the first load step fails: a
        // cohesionless free surface cutting cells) do poorly supported nodes follow their
        // neighbours (module docs), from the start again.
        let untied = GeostaticSettings { max_cutbacks: 0, ..*settings };
        // Planes hold one way, as in the grid solve: a plane that would have to pull a node
        // (a corner ghost drawn away from a side wall) lets it go, and the solve starts again.
        let (start_stress, start_state) =
            (self.particles.stress.clone(), self.particles.state.clone());
        let mut released: Vec<(u32, Vector)> = Vec::new();
        let mut iterations = 0;
        loop {
            let mut report = match self.solve_with(&untied, false, &released) {
                Err(SolverError::InitialState { iterations: spent, .. }) => {
                    iterations += spent;
                    self.solve_with(settings, true, &released)?
                }
                other => other?,
            };
            report.iterations += iterations;
            let pulled = self.pulled_planes(&released);
            if pulled.is_empty() || released.len() >= MAX_RELEASED {
                report.released_planes = released.len();
                return Ok(report);
            }
            iterations = report.iterations;
            released.extend(pulled);
            self.particles.stress.clone_from(&start_stress);
            self.particles.state.clone_from(&start_state);
        }
    }

    /// the (node, normal) of every plane holding a node that, at the particles' current
    /// stresses, would have to pull it (its reaction along the normal below zero by more than
    /// rounding).
    fn pulled_planes(&mut self, released: &[(u32, Vector)]) -> Vec<(u32, Vector)> {
        self.p2g_internal_force();
        let g = self.config.gravity;
        let sc = &self.scratch;
        let mut pulled = Vec::new();
        for b in &sc.boundary {
            let i = b.node as usize;
            let f = sc.mass[i] * g + sc.force[i];
            let scale = (sc.mass[i] * g).length() + sc.force[i].length();
            for plane in sc.node_planes[b.planes()].iter().filter(|p| p.held) {
                let n = plane.wall.normal();
                if plane.wall.boundary().friction() != Friction::Fixed
                    && !is_released(released, b.node, n)
                    && -f.dot(n) < -PULL_TOLERANCE * scale
                {
                    pulled.push((b.node, n));
                }
            }
        }
        pulled
    }

    /// the solve (module docs) with poorly supported nodes tied to their neighbours or not; the
    /// particles are restored on failure.
    fn solve_with(
        &mut self,
        settings: &GeostaticSettings,
        tie: bool,
        released: &[(u32, Vector)],
    ) -> Result<GeostaticReport, SolverError> {
        let nodes = self.scratch.active.len();
        let (dofs, unknowns, holds, ties) = self.node_dofs(tie, released);
        let g = self.config.gravity;
        let f_grav: Vec<Vector> = self.scratch.mass.iter().map(|&m| m * g).collect();

        let reduce = |full: &[Vector], out: &mut Vec<Real>| {
            out.clear();
            out.resize(unknowns, 0.0);
            for (i, d) in dofs.iter().enumerate() {
                for &(r, c) in d.rows() {
                    out[r as usize] += c.dot(full[i]);
                }
            }
        };
        let mut scale = Vec::new();
        reduce(&f_grav, &mut scale);
        let load_norm = norm(&scale).max(Real::MIN_POSITIVE);
        let shift = self.diagonal_shift(&dofs, unknowns);

        let start_stress = self.particles.stress.clone();
        let start_state = self.particles.state.clone();
        let mut report = GeostaticReport {
            load_steps: 0,
            cutbacks: 0,
            iterations: 0,
            history: Vec::new(),
            residual: 0.0,
            unknowns,
            constrained_nodes: holds.iter().filter(|h| !matches!(h, Hold::Free)).count(),
            plastic_particles: 0,
            max_displacement: 0.0,
            slipping_nodes: 0,
            base_friction_ratio: 0.0,
            tied_nodes: ties,
            released_planes: 0,
        };
        // The stresses and states at the start of the current load step (committed ones).
        let mut base_stress = start_stress.clone();
        let mut base_state = start_state.clone();
        let mut total_u = vec![Vector::ZERO; nodes];
        let mut lambda = 0.0;
        let nominal = 1.0 / Real::from(settings.load_steps);
        let mut increment = nominal;
        let mut halvings = 0;
        let mut work = Work::new(nodes, unknowns);
        work.branches.resize(self.particles.len(), Branch::ELASTIC);
        let restore = |s: &mut Self| {
            s.particles.stress.clone_from(&start_stress);
            s.particles.state.clone_from(&start_state);
        };
        while lambda < 1.0 {
            let target = if 1.0 - (lambda + increment) < 1e-12 { 1.0 } else { lambda + increment };
            let attempt = self.newton(
                target,
                settings,
                &dofs,
                &f_grav,
                &shift,
                load_norm,
                &base_stress,
                &base_state,
                &mut work,
                &mut report,
            );
            match attempt {
                Ok(()) => {
                    lambda = target;
                    report.load_steps += 1;
                    halvings = 0;
                    for (t, u) in total_u.iter_mut().zip(&work.u_full) {
                        *t += *u;
                    }
                    base_stress.clone_from(&self.particles.stress);
                    base_state.clone_from(&self.particles.state);
                    // back towards the nominal increment after a cut, never past full gravity
                    // (a clamped target would retry the step that just failed)
                    increment = (2.0 * increment).min(nominal).min(1.0 - lambda);
                }
                Err(_) if self.interrupted() => {
                    restore(self);
                    return Err(SolverError::InitialStateInterrupted { method: "implicit" });
                }
                Err(Failed { cause }) => {
                    halvings += 1;
                    report.cutbacks += 1;
                    // Bounded work: a state that converges only in ever smaller steps, each
                    // failing once at twice its size, would otherwise creep on for ever.
                    let budget = u64::from(settings.max_iterations)
                        * (u64::from(settings.load_steps)
                            + 2 * u64::from(settings.max_cutbacks)
                            + 2);
                    if halvings > settings.max_cutbacks || u64::from(report.iterations) > budget {
                        restore(self);
                        return Err(SolverError::InitialState {
                            load_factor: lambda,
                            attempted: target,
                            iterations: report.iterations,
                            residual: report.history.last().map_or(Real::NAN, |h| h.residual),
                            cause,
                        });
                    }
                    increment *= 0.5;
                    self.particles.stress.clone_from(&base_stress);
                    self.particles.state.clone_from(&base_state);
                }
            }
        }
        report.residual = report.history.last().map_or(0.0, |h| h.residual);
        report.max_displacement = total_u.iter().map(|u| u.length()).fold(0.0, Real::max);
        report.plastic_particles = work.branches.iter().filter(|b| **b != Branch::ELASTIC).count();

        if let Err(e) = self.check_base_friction(&holds, &f_grav, &mut report) {
            restore(self);
            return Err(e);
        }

        // (velocities are the bodies' own: the solve sets stresses only)
        self.initial_stored = self.energy().stored();
        Ok(report)
    }

    /// the shift of K's diagonal (module docs, [`DIAGONAL_SHIFT`]): per unknown, the shift times
    /// the elastic stiffness scale of its node.
    fn diagonal_shift(&self, dofs: &[NodeDofs], unknowns: usize) -> Vec<Real> {
        let nodes = self.scratch.active.len();
        // each node's elastic stiffness scale
        let mut k_scale = vec![0.0; nodes];
        {
            let p = &self.particles;
            let sc = &self.scratch;
            for q in 0..p.len() {
                let gr = self.shape.gradients(&sc.factors[q]);
                let modulus = self.p_modulus[usize::from(p.material[q])];
                for k in 0..N {
                    k_scale[sc.node_index[q][k] as usize] +=
                        p.volume[q] * modulus * gr[k].length_squared();
                }
            }
        }
        let mut shift = vec![0.0; unknowns];
        for (i, d) in dofs.iter().enumerate() {
            for &(r, c) in d.entries() {
                shift[r as usize] += DIAGONAL_SHIFT * c.length_squared() * k_scale[i];
            }
        }

        shift
    }

    /// the reactions against the friction laws, into `report` (`slipping_nodes`,
    /// `base_friction_ratio`); an error where a Coulomb plane's reactions exceed its friction.
    fn check_base_friction(
        &mut self,
        holds: &[Hold],
        f_grav: &[Vector],
        report: &mut GeostaticReport,
    ) -> Result<(), SolverError> {
        // The reactions against the friction laws (module docs): R_i = −(f^ext − f^int), summed
        // per plane as vectors (a stuck base's reactions may point inwards from both ends and
        // cancel). A node held by two planes (a corner) is left out: which plane carries which
        // part of its reaction is not determined.
        self.p2g_internal_force();
        // (normal, μ, Σ tangential reaction along n⊥, Σ normal reaction) of each Coulomb plane
        let mut planes: Vec<(Vector, Real, Real, Real)> = Vec::new();
        let mut buf = Vec::new();
        for b in &self.scratch.boundary {
            let i = b.node as usize;
            let held = held_planes(&mut buf, &self.scratch.node_planes[b.planes()]);
            let (&[plane], Hold::Fixed) = (held, holds[i]) else { continue };
            let Friction::Coulomb { mu } = plane.friction() else { continue };
            if mu == 0.0 {
                continue;
            }
            let reaction = -(f_grav[i] + self.scratch.force[i]);
            let n = plane.normal();
            let (normal, tangential) = (reaction.dot(n), reaction.dot(n.perp()));
            if tangential.abs() > mu * normal.max(0.0) * (1.0 + 1e-9) {
                report.slipping_nodes += 1;
            }
            match planes.iter_mut().find(|p| p.1 == mu && 1.0 - p.0.dot(n) < SAME_NORMAL) {
                Some(p) => {
                    p.2 += tangential;
                    p.3 += normal;
                }
                None => planes.push((n, mu, tangential, normal)),
            }
        }
        let worst = planes
            .iter()
            .map(|&(_, mu, t, n)| {
                let (t, capacity) = (t.abs(), mu * n.max(0.0));
                // (no tangential load is no ratio, even on a plane that carries nothing)
                (if t == 0.0 { 0.0 } else { t / capacity }, t, capacity)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((ratio, tangential, capacity)) = worst {
            report.base_friction_ratio = ratio;
            if ratio > 1.0 {
                return Err(SolverError::SlidingBase { ratio, tangential, capacity });
            }
        }
        Ok(())
    }
}
