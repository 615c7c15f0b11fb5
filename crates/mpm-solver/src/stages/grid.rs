//! Stage 4: the grid solve.
//!
//! a_i = f_i / m_i (eq 4), except at small-mass nodes (m_i below the threshold, §2(3)) where the
//! internal force is dropped and a_i = f_i^ext / m_i = b; then the boundary conditions of the contact
//! layer (eqs 14–18), which keep v_i^L = v_i + a_i Δt (eq 5) so that v^L need not be stored. The
//! work of each boundary impulse is booked in the energy ledger, split into its part normal to the
//! node's first boundary (constraint work) and the rest (friction work).
//!
//! Which planes hold a node is decided once per step by [`Solver::detect_contact`]: under
//! [`Contact::Surface`] a plane holds a node only where material touches it, under
//! [`Contact::Node`] (the paper's rule) always.

use mpm_constitutive::ConstitutiveModel;
use mpm_contact::{
    Boundary, Carriers, ContactOutcome, Friction, apply_all, constrain_velocity_all, impulse_shares,
};
use mpm_grid::ShapeFunctions;
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use crate::config::{Contact, MassMatrix};
use crate::error::SolverError;
use crate::loads::BoundaryLoad;
use crate::math::{Real, Vector};
use crate::scratch::{FixedGhost, NodePlane, Scratch};
use crate::solver::Solver;

/// the planes of `planes` that hold their node this step, gathered into `buf` for the contact law.
pub(crate) fn held_planes<'a>(buf: &'a mut Vec<Boundary>, planes: &[NodePlane]) -> &'a [Boundary] {
    buf.clear();
    buf.extend(planes.iter().filter(|p| p.held).map(|p| *p.wall.boundary()));
    buf
}

/// The method of images behind fixed planes, lumped matrix: the velocity field is odd across a
/// fixed plane, so the material's mirror image would add to the image node j of a ghost g the
/// ghost's own sums, negated: a_j = (f_j − f_g)/(m_j + m_g) (the tie a_g = −a_j applied to the
/// lumped system, TᵀMT, as the consistent re-solve applies it to its matrix). Without it the nodes
/// next to the wall feel material on one side only, and B-splines converged at first order on the
/// manufactured solution. Ghosts and images below the small-mass threshold are left alone; several
/// ghosts of one image all add. Returns the impulse the tie gives the material at the images,
/// Σ (m_j a_j − f_j) Δt (the ghost's share is booked by `mirror_fixed_ghosts`; with periodic
/// sides a pair's partner books it).
fn tie_fixed_ghosts<F, const N: usize>(
    sc: &mut Scratch<F, N>,
    loads: &mut [BoundaryLoad],
    small: Real,
    dt: Real,
) -> Vector {
    sc.ties.clear();
    for b in &sc.boundary {
        let Some(m) = b.mirror.filter(|m| m.fixed) else { continue };
        if !sc.node_planes[b.planes()].iter().any(|p| p.held) {
            continue;
        }
        let (g, j) = (b.node as usize, m.image as usize);
        if sc.mass[g] > small && sc.mass[j] > small {
            let source = mirror_source(&sc.node_planes[b.planes()], m.normal);
            sc.ties.push((m.image, sc.force[g], sc.mass[g], b.partner.is_none(), source));
        }
    }
    // stable: the ghosts of one image add in boundary order, whatever the threads
    sc.ties.sort_by_key(|t| t.0);
    let mut impulse = Vector::ZERO;
    let mut k = 0;
    while k < sc.ties.len() {
        let j = sc.ties[k].0 as usize;
        let first = sc.ties[k];
        let (mut f, mut m, book) = (sc.force[j], sc.mass[j], first.3);
        while k < sc.ties.len() && sc.ties[k].0 as usize == j {
            f -= sc.ties[k].1;
            m += sc.ties[k].2;
            k += 1;
        }
        sc.acceleration[j] = f / m;
        if book {
            let dp = (sc.mass[j] * sc.acceleration[j] - sc.force[j]) * dt;
            impulse += dp;
            // (an image tied to the ghosts of two sides, in a corner: booked to the first)
            let (source, normal) = first.4;
            loads[source as usize].add(dp, normal);
        }
    }
    impulse
}

/// the side a ghost node's mirror plane of normal `normal` belongs to, with that normal.
pub(crate) fn mirror_source(planes: &[NodePlane], normal: Vector) -> (u16, Vector) {
    // (the mirror plane is one of the node's side planes; else its first held plane's side)
    let plane = planes.iter().find(|p| p.wall.normal() == normal);
    let plane = plane.or_else(|| planes.iter().find(|p| p.held)).or(planes.first());
    (plane.map_or(0, |p| p.source), normal)
}

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// decides which planes hold each boundary node during the coming step (see [`Contact`]).
    ///
    /// A plane marked `always` (a `Fixed` plane, or any plane under [`Contact::Node`], with the
    /// node on its face or inside its solid) holds it; otherwise, under [`Contact::Surface`],
    /// plane k holds node i when some particle p of the node's support touches it
    /// ([`mpm_contact::Wall::touches`]): its edge, at half-size r_p = ½√V_p, is on the face
    /// within 0.01 r_p or would cross it within the step.
    pub(crate) fn detect_contact(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        if sc.boundary.is_empty() {
            return;
        }
        let p = &self.particles;
        let surface = self.config.contact == Contact::Surface;
        for (j, b) in sc.boundary.iter().enumerate() {
            let list = || {
                &sc.contact_entry[sc.contact_start[j] as usize..sc.contact_start[j + 1] as usize]
            };
            for plane in &mut sc.node_planes[b.planes()] {
                plane.held = plane.always
                    || surface
                        && list().iter().any(|e| {
                            let q = e.load(Ordering::Relaxed) as usize / N;
                            let r = crate::math::half_size(p.volume[q]);
                            plane.wall.touches(p.position[q], r, p.velocity[q], dt)
                        });
            }
        }
        // A periodic image and its partner are one column: held when either is.
        for j in 0..sc.boundary.len() {
            if let Some(k) = sc.boundary[j].partner {
                let (image, partner) = (sc.boundary[j].planes(), sc.boundary[k as usize].planes());
                for (a, b) in image.zip(partner) {
                    let both = sc.node_planes[a].held | sc.node_planes[b].held;
                    (sc.node_planes[a].held, sc.node_planes[b].held) = (both, both);
                }
            }
        }
    }

    /// accelerations and end-of-step velocities of every active node, boundary nodes included.
    ///
    /// With the consistent mass matrix the lumped a_i = f_i / m_i start its solve M a = f
    /// (`stages/mass.rs`), whose failure is the only error.
    pub(crate) fn grid_solve(&mut self, dt: Real) -> Result<(), SolverError> {
        let sc = &mut self.scratch;
        let small = self.small_mass;
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        lumped_acceleration(&mut sc.acceleration, &sc.force, &sc.mass, small, g);
        self.solve_acceleration()?;
        let sc = &mut self.scratch;

        let loads = &mut self.loads;

        let (mut friction, mut constraint, mut impulse) = (0.0, 0.0, Vector::ZERO);
        let surface = self.config.contact == Contact::Surface;
        let consistent = self.config.mass == MassMatrix::Consistent;
        sc.held.clear();
        sc.consistent.constrained.clear();
        sc.fixed_ghosts.clear();
        if !consistent {
            impulse += tie_fixed_ghosts(sc, loads, small, dt);
        }
        for b in &sc.boundary {
            let i = b.node as usize;
            let planes = held_planes(&mut sc.plane_buf, &sc.node_planes[b.planes()]);
            if planes.is_empty() {
                continue;
            }
            if consistent {
                // A ghost's image is prescribed too: the re-solve must not move it away from the
                // value the ghost mirrors. Not behind a fixed plane: there the image is solved
                // for (it is the wall node's neighbour, which must feel the wall) and the ghost
                // follows it afterwards (`mirror_fixed_ghosts`).
                sc.consistent.constrained.push(b.node);
                sc.consistent.constrained.extend(b.mirror.filter(|m| !m.fixed).map(|m| m.image));
            }
            // A ghost node meets a wall moving with its image's mirrored normal velocity (images
            // are interior nodes, final above); a node on the plane meets a wall at rest.
            let wall = match b.mirror {
                Some(m) if m.fixed => {
                    // A fixed plane: the ghost is its image mirrored, once every node (its image
                    // included, which may be held itself) is final: `mirror_fixed_ghosts`.
                    sc.fixed_ghosts.push(FixedGhost {
                        ghost: b.node,
                        image: m.image,
                        books: b.partner.is_none(),
                        trial: (sc.acceleration[i], sc.velocity[i]),
                        source: mirror_source(&sc.node_planes[b.planes()], m.normal),
                    });
                    continue;
                }
                Some(m) => {
                    let j = m.image as usize;
                    m.wall_velocity(sc.velocity[j] + sc.acceleration[j] * dt)
                }
                None => Vector::ZERO,
            };
            let v_rel = sc.velocity[i] - wall;
            let trial = v_rel + sc.acceleration[i] * dt;
            let out = apply_all(planes, sc.mass[i], v_rel, sc.acceleration[i], dt);
            // v^L = v_rel + a Δt + wall = v + a Δt: the identity still holds.
            sc.acceleration[i] = out.acceleration;
            if surface {
                // The PIC correction removes the normal velocity of the face the node ends on
                // (its end velocity has no part along that normal), once: the two nearly parallel
                // planes of a kink would otherwise both correct the same velocity. A node pinned
                // in a corner (pressed on two planes, stopped) loses its whole relative velocity.
                // Fixed planes glue the material, as in the paper: no PIC correction there.
                let pushing = |p: &&Boundary| {
                    p.friction() != Friction::Fixed && out.impulse.dot(p.normal()) > 0.0
                };
                let along = |p: &Boundary| out.velocity.dot(p.normal()).abs();
                if let Some(face) =
                    planes.iter().filter(pushing).min_by(|p, q| along(p).total_cmp(&along(q)))
                {
                    let n = face.normal();
                    sc.held.push((b.node, n));
                    // (3D) a node sliding along the edge of two planes ends with no velocity
                    // along either normal: the second normal's part orthogonal to the first is
                    // corrected too.
                    #[cfg(feature = "dim3")]
                    if out.velocity != Vector::ZERO {
                        let scale = 1e-9 * out.velocity.length();
                        let second = planes
                            .iter()
                            .filter(pushing)
                            .filter(|p| out.velocity.dot(p.normal()).abs() <= scale)
                            .find_map(|p| (p.normal() - p.normal().dot(n) * n).try_normalize());
                        if let Some(m) = second {
                            sc.held.push((b.node, m));
                        }
                    }
                    let pressed = planes.iter().filter(|p| trial.dot(p.normal()) < 0.0).count();
                    if out.velocity == Vector::ZERO && pressed >= 2 {
                        for t in crate::math::tangents(n) {
                            sc.held.push((b.node, t));
                        }
                    }
                }
            }
            // Work the boundary impulse J does over the step at the mean nodal velocity relative
            // to the wall: for a node at rest on the ground it is zero (the reaction does no
            // work), for a sliding node it is the friction force times the distance slid. Their
            // sum is the kinetic energy the impulse takes from the node (midpoint rule), which is
            // what closes the ledger; the split along the first held plane's normal is indicative
            // only, and either part can be negative in a step where a pressed node was moving
            // away from the wall.
            if b.partner.is_some() || consistent {
                // a periodic image: its partner, holding the same sums, books the pair's work;
                // with the consistent matrix `book_reactions` books every node's once final.
                continue;
            }
            impulse += out.impulse;
            book_load(loads, &sc.node_planes[b.planes()], planes, &out, trial, &mut sc.shares);
            let mean_v = 0.5 * (v_rel + out.velocity);
            let n = planes[0].normal();
            let (jn, vn) = (out.impulse.dot(n), mean_v.dot(n));
            constraint -= jn * vn;
            friction -= out.impulse.dot(mean_v) - jn * vn;
        }
        self.dissipation.friction += friction;
        self.dissipation.constraint += constraint;
        self.dissipation.impulse += impulse;
        self.resolve_constrained()?;
        if let Some(walls) = self.config.side_walls() {
            // after the contact law: the friction opposes the velocity the boundaries leave
            // (scaling it keeps what they imposed), before the ghosts mirror their images.
            self.side_wall_friction(walls, dt);
        }
        self.mirror_fixed_ghosts(dt);
        self.book_reactions(dt);
        Ok(())
    }

    /// every held ghost behind a fixed plane becomes its image mirrored: the velocity field is
    /// antisymmetric across the plane, so v_g = −v_j and a_g = −a_j (the image's acceleration
    /// tied to the ghost already: `tie_fixed_ghosts`, or the consistent re-solve). Setting only
    /// a_g = (−v_j^L − v_g)/Δt, as before, handed the particles near the wall, through FLIP
    /// (eq 7), the whole gap between the one-sided P2G velocity at the ghost and the mirrored one
    /// at every step: a kick that does not shrink with Δt (B-spline manufactured solution,
    /// 8 cells: error 0.15 of A, 1.84 with Δt/32). Two passes: a corner ghost's image can be a
    /// ghost itself. With the lumped matrix the ledger books the impulse this gives the
    /// particles, m_g Δa_g Δt from the trial values, and under APIC (whose particles take v^L)
    /// also m_g Δv_g; the consistent matrix's `book_reactions` books it with every reaction.
    fn mirror_fixed_ghosts(&mut self, dt: Real) {
        let apic = self.config.transfer == crate::config::Transfer::Apic;
        let sc = &mut self.scratch;
        for _ in 0..2 {
            for f in &sc.fixed_ghosts {
                let (g, j) = (f.ghost as usize, f.image as usize);
                (sc.acceleration[g], sc.velocity[g]) = (-sc.acceleration[j], -sc.velocity[j]);
            }
        }
        if self.config.mass == MassMatrix::Consistent {
            return; // `book_reactions` books them
        }
        for f in sc.fixed_ghosts.iter().filter(|f| f.books) {
            let (g, (a, v)) = (f.ghost as usize, f.trial);
            let mut dp = sc.mass[g] * (sc.acceleration[g] - a) * dt;
            if apic {
                dp += sc.mass[g] * (sc.velocity[g] - v);
            }
            self.dissipation.impulse += dp;
            let (source, normal) = f.source;
            self.loads[source as usize].add(dp, normal);
        }
    }

    /// v_i ← v_i^L = v_i + a_i Δt (eq 5), for USL's strain increment.
    pub(crate) fn advance_velocity(&mut self, dt: Real) {
        let sc = &mut self.scratch;
        add_scaled(&mut sc.velocity, &sc.acceleration, dt);
    }

    /// the velocity constraint (eq 18) on `scratch.velocity` at boundary nodes, for a strain
    /// update. The unconstrained velocities are kept in `scratch.saved` so that
    /// [`Self::unconstrain_velocity`] can put them back before the grid solve: the grid solve must
    /// start from the velocity the particles actually carry, so that the contact's removal of an
    /// approach velocity reaches the particles through the FLIP update (eq 7). Otherwise the same
    /// approach velocity is stopped again at every step, and turned into strain energy each time.
    pub(crate) fn constrain_velocity(&mut self) {
        let sc = &mut self.scratch;
        sc.saved.clear();
        for b in &sc.boundary {
            let i = b.node as usize;
            sc.saved.push(sc.velocity[i]);
        }
        for b in &sc.boundary {
            let i = b.node as usize;
            let planes = held_planes(&mut sc.plane_buf, &sc.node_planes[b.planes()]);
            if planes.is_empty() {
                continue;
            }
            let wall = match b.mirror {
                Some(m) if m.fixed => {
                    sc.velocity[i] = -sc.velocity[m.image as usize];
                    continue;
                }
                Some(m) => m.wall_velocity(sc.velocity[m.image as usize]),
                None => Vector::ZERO,
            };
            sc.velocity[i] = constrain_velocity_all(planes, sc.velocity[i] - wall) + wall;
        }
    }

    /// restores the boundary nodes' velocities saved by [`Self::constrain_velocity`].
    pub(crate) fn unconstrain_velocity(&mut self) {
        let sc = &mut self.scratch;
        for (b, &v) in sc.boundary.iter().zip(&sc.saved) {
            sc.velocity[b.node as usize] = v;
        }
    }
}

/// books a boundary node's contact impulse `out` (from `held`, the planes of `planes` that held it,
/// in order) to the boundaries that carried it (`loads.rs`), each part with its plane's normal.
fn book_load(
    loads: &mut [BoundaryLoad],
    planes: &[NodePlane],
    held: &[Boundary],
    out: &ContactOutcome,
    trial: Vector,
    shares: &mut Vec<Vector>,
) {
    let mut carriers = planes.iter().filter(|p| p.held);
    match out.carriers {
        Carriers::None => {}
        Carriers::One(k) => {
            if let Some(p) = carriers.nth(k) {
                loads[p.source as usize].add(out.impulse, p.wall.normal());
            }
        }
        Carriers::Two(..) | Carriers::Corner => {
            shares.resize(held.len(), Vector::ZERO);
            impulse_shares(held, out, trial, shares);
            for (p, &j) in carriers.zip(shares.iter()) {
                loads[p.source as usize].add(j, p.wall.normal());
            }
        }
    }
}

/// a_i = f_i / m_i at every node, g where the mass is below `small` (a node no material
/// reaches holds none). Not generic over the model or shape functions: one copy.
fn lumped_acceleration(
    acc: &mut [Vector],
    force: &[Vector],
    mass: &[Real],
    small: Real,
    g: Vector,
) {
    acc.par_iter_mut().zip(force.par_iter().zip(mass.par_iter())).with_min_len(1024).for_each(
        |(a, (&f, &m))| {
            *a = if m > small { f / m } else { g };
        },
    );
}

/// v_i += a_i Δt at every node (not generic: one copy).
fn add_scaled(v: &mut [Vector], a: &[Vector], dt: Real) {
    v.par_iter_mut().zip(a.par_iter()).with_min_len(1024).for_each(|(v, &a)| {
        *v += a * dt;
    });
}

#[cfg(test)]
mod tests {
    use mpm_constitutive::LinearElastic;
    use mpm_contact::Friction;
    use mpm_grid::testing::{LINEAR, at, grid, volume};
    use mpm_grid::{Bilinear, RegularGrid};

    use crate::particles::{NewParticle, Particles};
    use crate::{Boundaries, Contact, Solver, SolverConfig, Vector};

    /// 0.125 m particles (half-size r = 0.0625 m) given as (position, velocity, density) over a
    /// frictionless floor of 0.25 m cells.
    fn on_floor(
        seeds: &[(Vector, Vector, f64)],
        contact: Contact,
    ) -> Solver<LinearElastic, Bilinear<RegularGrid>, LINEAR> {
        let grid = grid([0.0; 2], [0.25; 2], [4, 4]).unwrap();
        let mut particles = Particles::default();
        for &(position, velocity, density) in seeds {
            particles.push(NewParticle::unstressed(position, velocity, volume(0.125), density, ()));
        }
        let config = SolverConfig {
            boundaries: Boundaries {
                ground: Some(Friction::Coulomb { mu: 0.0 }),
                ..Default::default()
            },
            contact,
            ..Default::default()
        };
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        Solver::new(Bilinear(grid), vec![material], particles, config).unwrap()
    }

    /// the floor nodes a particle's linear stencil reaches: 2 in the plane, 2 × 2 in space.
    const FLOOR: usize = LINEAR / 2;

    /// how many of the floor nodes the particle reaches are held.
    fn held(y: f64, vy: f64, dt: f64, contact: Contact) -> usize {
        let mut s = on_floor(&[(at(0.5, y), at(0.0, vy), 1000.0)], contact);
        s.detect_contact(dt);
        assert_eq!(s.scratch.boundary.len(), FLOOR, "the particle's floor nodes");
        s.scratch.node_planes.iter().filter(|p| p.held).count()
    }

    #[test]
    fn surface_contact_holds_floor_nodes_only_where_the_particle_touches_the_floor() {
        let r = 0.0625;
        // Resting on the floor (edge at y = 0): held.
        assert_eq!(held(r, 0.0, 1e-3, Contact::Surface), FLOOR);
        // Within the 1 % tolerance of r above it: held; beyond it: free.
        assert_eq!(held(r + 0.005 * r, 0.0, 1e-3, Contact::Surface), FLOOR);
        assert_eq!(held(r + 0.02 * r, 0.0, 1e-3, Contact::Surface), 0);
        // 1 cm above the floor, falling at 1 m/s: reaches it within a 0.02 s step, not 0.005 s.
        assert_eq!(held(r + 0.01, -1.0, 0.02, Contact::Surface), FLOOR);
        assert_eq!(held(r + 0.01, -1.0, 0.005, Contact::Surface), 0);
        // Rising: the gap is what it is now.
        assert_eq!(held(r + 0.01, 1.0, 0.02, Contact::Surface), 0);
        // The paper's rule holds every floor node, however far the particle is in its cell.
        assert_eq!(held(0.2, 0.0, 1e-3, Contact::Node), FLOOR);
    }

    /// The PIC normal correction conserves momentum and never adds kinetic energy (module docs of
    /// `g2p`): checked on particles of random velocities over two held floor nodes.
    #[test]
    fn pic_normal_correction_conserves_momentum_and_takes_energy() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut seeds = vec![(at(0.5, 0.0625), Vector::ZERO, 1000.0)];
        for _ in 0..7 {
            let position = at(0.3 + 0.4 * uniform(), 0.05 + 0.15 * uniform());
            let velocity = at(2.0 * uniform() - 1.0, 2.0 * uniform() - 1.0);
            seeds.push((position, velocity, 1000.0 + 500.0 * uniform()));
        }
        let mut s = on_floor(&seeds, Contact::Surface);
        s.p2g_mass_velocity();
        let floor: Vec<u32> = s.scratch.boundary.iter().map(|b| b.node).collect();
        assert!(!floor.is_empty());
        s.scratch.held = floor.iter().map(|&i| (i, Vector::Y)).collect();
        let before = (s.particles.momentum(), kinetic(&s.particles));
        s.correct_held_normals();
        let after = (s.particles.momentum(), kinetic(&s.particles));
        // Σ_p m_p S_ip (v_i − v_p) = 0 for each node: rounding only.
        assert!((after.0 - before.0).length() < 1e-12 * before.0.length().max(1.0));
        assert!(after.1 <= before.1, "kinetic energy grew from {} to {}", before.1, after.1);
        assert!(after.1 < 0.999 * before.1, "the correction did nothing");
    }

    /// A node at a kink of the ground carries both segments' planes, nearly parallel; the PIC
    /// correction must remove its normal velocity once, not once per plane (which would reflect
    /// the particles' normal velocity instead of removing it). A row of particles falls at
    /// 1 m/s onto a ground that turns up by 2.3° at x = 0.5 m: every held node has one entry.
    #[cfg(not(feature = "dim3"))] // the plane terrain grid
    #[test]
    fn a_kink_node_gets_one_pic_normal_correction() {
        use mpm_grid::{KinkPolicy, TerrainGrid, TerrainGridSpec};
        let grid = TerrainGrid::new(TerrainGridSpec {
            profile: vec![Vector::ZERO, at(0.5, 0.0), at(1.0, 0.02)],
            cell_width: 0.25,
            row_height: 0.25,
            rows: 4,
            kink_policy: KinkPolicy::Reject,
        })
        .unwrap();
        let mut particles = Particles::default();
        for k in 0..8 {
            let x = 0.0625 + 0.125 * f64::from(k);
            let y = grid.ground_height(x).unwrap() + 0.0625;
            let v = at(0.0, -1.0);
            particles.push(NewParticle::unstressed(at(x, y), v, volume(0.125), 1000.0, ()));
        }
        let config = SolverConfig {
            boundaries: Boundaries {
                ground: Some(Friction::Coulomb { mu: 0.0 }),
                ..Default::default()
            },
            contact: Contact::Surface,
            ..Default::default()
        };
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        let mut s = Solver::new(Bilinear(grid), vec![material], particles, config).unwrap();
        s.step().unwrap();
        let mut nodes: Vec<u32> = s.scratch.held.iter().map(|h| h.0).collect();
        assert!(nodes.len() >= 3, "the falling row presses on the ground: {nodes:?}");
        let n = nodes.len();
        nodes.dedup();
        assert_eq!(nodes.len(), n, "a node corrected twice: {:?}", s.scratch.held);
    }

    fn kinetic<S>(p: &Particles<S>) -> f64 {
        p.mass.iter().zip(&p.velocity).map(|(m, v)| 0.5 * m * v.length_squared()).sum()
    }
}
