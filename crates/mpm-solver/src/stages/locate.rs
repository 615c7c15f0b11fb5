//! Stage 2: locate every particle on the grid.
//!
//! Evaluates every particle's stencil as its first node and the factors of its S_ip and G_ip
//! ([`ShapeFunctions::factors`]: the passes expand them), rebuilds the sparse set of active
//! nodes (only nodes whose support holds a particle exist), numbers each particle's nodes densely,
//! bins the particles by node block for the particle-to-grid sums (`p2g.rs`), and lists the active
//! nodes that lie on a declared boundary (with, under surface contact, their particles).

use std::sync::atomic::{AtomicBool, Ordering};

use mpm_constitutive::ConstitutiveModel;
use mpm_contact::{Friction, Wall};
use mpm_grid::{BLOCK_SIDE, LocateError, NodeId, ShapeFunctions, stencil_nodes};
use rayon::prelude::*;

use crate::config::{Boundaries, Contact};
use crate::error::SolverError;
use crate::math::{DIM, Vector};
use crate::par::{chunk_len, counting_sort};
use crate::scratch::{BoundaryNode, Mirror, NodePlane, PatchSums, Scratch};
use crate::solver::Solver;
use crate::stages::p2g::patch_side;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    pub(crate) fn locate(&mut self) -> Result<(), SolverError> {
        let n = self.particles.len();
        let sc = &mut self.scratch;
        // The node ids of the last located step are still in `first_node`: if no particle's stencil
        // changes its nodes (most steps: at C = 0.1 a particle needs many steps to cross a cell),
        // the active set, its numbering (a function of the set), the bins and the boundary
        // nodes are all unchanged, and only the factors of the weights and gradients are new.
        let reusable = sc.located && sc.first_node.len() == n;
        let chunk = chunk_len(n);
        sc.first_node.resize(n, NodeId::default());
        sc.factors.resize(n, S::Factors::default());

        let shape = &self.shape;
        let positions = &self.particles.position;
        let (changed, numbered) = match sc.stencils_ahead.take() {
            // The last step's final particle loop computed them (`stress.rs`).
            Some(ahead) => (ahead.changed, Some(ahead.numbered)),
            None => {
                // Fixed chunks, each run in particle order: the first chunk that fails reports
                // its first failing particle, so the error names the same particle for any
                // thread count.
                let mut failure =
                    factor_all(shape, positions, &mut sc.first_node, &mut sc.factors, chunk);
                // only where a ground holds the material: an open bottom lets it leave
                let ground = self.config.boundaries.ground.is_some();
                if failure.is_err()
                    && ground
                    && lift_onto_ground(shape, &mut self.particles.position)
                {
                    // The failed pass already stored the new nodes of the chunks it finished, so
                    // the retry cannot see what changed since the last locate: take it that
                    // something did (the active set is then checked, not trusted).
                    failure = factor_all(
                        shape,
                        &self.particles.position,
                        &mut sc.first_node,
                        &mut sc.factors,
                        chunk,
                    )
                    .map(|_| true);
                }
                let positions = &self.particles.position;
                match failure {
                    Ok(changed) => (changed, None),
                    Err((particle, cause)) => {
                        // `try_reduce` may meet any failing chunk first: name the lowest failing
                        // particle, whatever the thread count.
                        let particle = (0..particle)
                            .find(|&p| shape.factors(positions[p]).is_err())
                            .unwrap_or(particle);
                        let cause = shape.factors(positions[particle]).err().unwrap_or(cause);
                        self.scratch.located = false;
                        return Err(SolverError::OutsideGrid {
                            step: self.step + 1,
                            particle,
                            position: positions[particle],
                            cause,
                        });
                    }
                }
            }
        };
        if reusable && !changed {
            #[cfg(test)]
            {
                sc.paths[0] += 1;
            }
            return Ok(());
        }
        sc.located = true;
        // Most steps that change some particle's nodes change no node's membership of the active
        // set: every node is still in some stencil and no stencil reaches a new node. The set,
        // hence its numbering, the boundary nodes and the nodal arrays then stay, and only the
        // particles' dense indices and the bins are redone. Whether the set stayed is read off
        // the work itself: no stencil node is missing from it, and every node is in some stencil.
        // The final particle loop of the last step numbered the new nodes already (`Some(true)`)
        // or met a node outside the set (`Some(false)`: a rebuild is certain).
        let same = match numbered {
            Some(true) => bin_particles(sc),
            Some(false) => false,
            None => number_stencils(sc, chunk) && bin_particles(sc),
        };
        if same {
            #[cfg(test)]
            {
                sc.paths[1] += 1;
            }
            return Ok(());
        }
        #[cfg(test)]
        {
            sc.paths[2] += 1;
        }
        sc.active.rebuild(sc.first_node.iter().flat_map(|&f| stencil_nodes::<N>(f)));
        sc.active_generation += 1;
        let complete = number_stencils(sc, chunk);
        debug_assert!(complete, "every stencil node was inserted by the rebuild");
        index_blocks(sc);
        let active = &sc.active;
        let nodes = active.len();
        for v in [&mut sc.velocity, &mut sc.force, &mut sc.acceleration] {
            v.resize(nodes, Vector::ZERO);
        }
        sc.mass.resize(nodes, 0.0);

        boundary_nodes(
            sc,
            shape,
            self.config.boundaries,
            &self.config.walls,
            self.config.contact,
            self.config.periodic.is_some(),
            &self.particles.volume,
        );
        let active = &sc.active;
        sc.periodic_pairs.clear();
        if let Some(periodic) = self.config.periodic {
            // Node columns i and i ± columns are one column: pair each image node beyond a side
            // with its partner, when both are active.
            let columns = periodic.columns as i32;
            for (image, &node) in active.nodes().iter().enumerate() {
                let i = node.i.rem_euclid(columns);
                if i != node.i {
                    let mut partner = node.axes();
                    partner[0] = i;
                    if let Some(partner) = active.index_of(NodeId::from_axes(partner)) {
                        sc.periodic_pairs.push((image as u32, partner as u32));
                    }
                }
            }
            // Link an image's boundary entry to its partner's (`boundary` is in dense order).
            let boundary = &mut sc.boundary;
            for &(image, partner) in &sc.periodic_pairs {
                let entry = |dense: u32| boundary.binary_search_by_key(&dense, |b| b.node).ok();
                if let (Some(k), Some(j)) = (entry(image), entry(partner)) {
                    boundary[k].partner = Some(j as u32);
                }
            }
        }
        sc.boundary_of.clear();
        sc.boundary_of.resize(nodes, u32::MAX);
        if self.config.contact == Contact::Surface {
            for (k, b) in sc.boundary.iter().enumerate() {
                sc.boundary_of[b.node as usize] = k as u32;
            }
        }
        let binned = bin_particles(sc);
        debug_assert!(binned, "every active node is some stencil's node");
        Ok(())
    }
}

/// lists the active nodes a boundary may hold, with their planes: the grid's sides through each node
/// on one (a ghost node's plane halfway to its image), then every wall the node is near.
///
/// A wall holds the nodes of a material point that touches it ([`Wall::touches`]), so the nodes
/// watched are those within `reach` of its face, span or solid: how far a touching point can be
/// from a node of its stencil. That is at most (stencil side / 2) cell diagonals, plus the point's
/// half-size (its edge touches, not its centre) and the step's travel (≤ one cell at C ≤ 1): taken
/// as (side / 2 + 1) times the longest diagonal of an active cell plus the largest half-size,
/// computed when the active set is rebuilt. Between rebuilds particles may swell (a dilating
/// flow): the spare diagonal covers a half-size growing by up to one diagonal, far more than a
/// particle swells before its stencil changes nodes and the set is rebuilt.
#[allow(clippy::too_many_arguments)]
fn boundary_nodes<F, S: ShapeFunctions<N>, const N: usize>(
    sc: &mut Scratch<F, N>,
    shape: &S,
    sides: Boundaries,
    walls: &[Wall],
    contact: Contact,
    periodic: bool,
    volume: &[f64],
) {
    sc.boundary.clear();
    sc.node_planes.clear();
    if !sides.any() && walls.is_empty() {
        return;
    }
    let active = &sc.active;
    let reach = if walls.is_empty() { 0.0 } else { wall_reach(active, shape, volume, N) };
    let hold_always = |wall: &Wall, here: Vector| {
        (contact == Contact::Node || wall.boundary().friction() == Friction::Fixed)
            && wall.holds_node(here)
    };
    for (i, &node) in active.nodes().iter().enumerate() {
        let here = shape.node_position(node);
        let first = sc.node_planes.len();
        let normals = shape.boundary_normals(node);
        // (the source: the side's entry of `SIDE_NAMES`)
        for (source, law, normal) in [
            (0, sides.ground, normals.ground),
            (0, sides.ground, normals.ground_kink),
            #[cfg(feature = "dim3")]
            (0, sides.ground, normals.ground_more[0]),
            #[cfg(feature = "dim3")]
            (0, sides.ground, normals.ground_more[1]),
            (1, sides.left_wall, normals.left_wall),
            (2, sides.right_wall, normals.right_wall),
            #[cfg(feature = "dim3")]
            (3, sides.back_wall, normals.back_wall),
            #[cfg(feature = "dim3")]
            (4, sides.front_wall, normals.front_wall),
        ] {
            if let (Some(law), Some(normal)) = (law, normal) {
                // The grid hands out unit normals and the friction law was validated with the
                // scene, so construction cannot fail here.
                if let Ok(wall) = Wall::plane(here, normal, law) {
                    sc.node_planes.push(NodePlane { wall, always: false, held: false, source });
                }
            }
        }
        let on_sides = &mut sc.node_planes[first..];
        // (periodic sides are no mirror planes: their ghosts are image nodes)
        let across_side = |normal: Vector| periodic && normal.x != 0.0;
        let mirror = (!on_sides.is_empty()).then(|| shape.mirror(node)).flatten();
        let mirror = mirror.filter(|&(_, n)| !across_side(n));
        let mirror = mirror.and_then(|(image, normal)| {
            let fixed = on_sides.iter().any(|p| {
                p.wall.normal() == normal && p.wall.boundary().friction() == Friction::Fixed
            });
            // The mirror plane lies halfway between the ghost and its image.
            let middle = 0.5 * (here + shape.node_position(image));
            for p in on_sides.iter_mut().filter(|p| p.wall.normal() == normal) {
                if let Ok(wall) = Wall::plane(middle, normal, p.wall.boundary().friction()) {
                    p.wall = wall;
                }
            }
            active.index_of(image).map(|j| Mirror { image: j as u32, normal, fixed })
        });
        for p in &mut sc.node_planes[first..] {
            p.always = hold_always(&p.wall, here);
        }
        // (a ghost node meets its side's mirror plane; a declared wall acts on the grid's nodes)
        let walls = if mirror.is_some() { &[][..] } else { walls };
        for (k, wall) in walls.iter().enumerate().filter(|(_, w)| w.near(here, reach)) {
            sc.node_planes.push(NodePlane {
                wall: *wall,
                always: hold_always(wall, here),
                held: false,
                source: (crate::SIDES + k) as u16,
            });
        }
        let count = sc.node_planes.len() - first;
        if count > 0 {
            sc.boundary.push(BoundaryNode {
                node: i as u32,
                first: first as u32,
                count: count as u32,
                mirror,
                partner: None,
            });
        }
    }
}

/// how far a material point touching a wall can be from a node of its stencil, for a stencil of
/// `n` nodes (see [`boundary_nodes`]): over the active cells, whose nodes are all active.
fn wall_reach<S: ShapeFunctions<N>, const N: usize>(
    active: &mpm_grid::ActiveNodes,
    shape: &S,
    volume: &[f64],
    n: usize,
) -> f64 {
    let mut diagonal: f64 = 0.0;
    for &node in active.nodes() {
        // (in 3D both diagonals across z: on a terrain grid whose ground falls along x and
        // rises along z, the (1, ±1, −1) one is the longer)
        #[cfg(not(feature = "dim3"))]
        let corners = [node.offset([1, -1]), node.offset([1, 1])];
        #[cfg(feature = "dim3")]
        let corners = [-1, 1].map(|dk| [-1, 1].map(|dj| node.offset([1, dj, dk])));
        #[cfg(feature = "dim3")]
        let corners = corners.as_flattened();
        for &corner in corners.iter() {
            if active.index_of(corner).is_some() {
                let d = shape.node_position(corner) - shape.node_position(node);
                diagonal = diagonal.max(d.length());
            }
        }
    }
    let half_size = volume.par_iter().map(|&v| crate::math::half_size(v)).reduce(|| 0.0, f64::max);
    let side = mpm_grid::stencil_side(n) as f64;
    (0.5 * side + 1.0) * diagonal + half_size
}

/// the stencil (first node and factors) of every particle, in fixed chunks; whether some
/// stencil changed its nodes, or the first failing particle of some chunk. Generic over the
/// shape functions alone.
#[allow(clippy::type_complexity)]
fn factor_all<S: ShapeFunctions<N>, const N: usize>(
    shape: &S,
    positions: &[Vector],
    first: &mut [NodeId],
    factors: &mut [S::Factors],
    chunk: usize,
) -> Result<bool, (usize, LocateError)> {
    first
        .par_chunks_mut(chunk)
        .zip(factors.par_chunks_mut(chunk))
        .enumerate()
        .map(|(c, (first, factors))| {
            let mut changed = false;
            for j in 0..first.len() {
                let p = c * chunk + j;
                match shape.factors(positions[p]) {
                    Ok((node, f)) => changed |= store(node, f, &mut first[j], &mut factors[j]),
                    Err(cause) => return Err((p, cause)),
                }
            }
            Ok(changed)
        })
        .try_reduce(|| false, |a, b| Ok(a | b))
}

/// How far below the ground, in smallest cells, a particle is put back on it rather than
/// stopping the run: 1e-3 of a cell. The contact holds the ground's nodes, but between them a
/// 3D terrain's ground is a bilinear (curved) surface that particles moving with the nodes'
/// velocities may cross by a sliver: 4 µm on 1 m cells beside a release cut's step ended a
/// documented slide at 7 s (R3-05). A particle deeper than this went through the ground, and the
/// run stops there as before.
pub const GROUND_LIFT: f64 = 1e-3;

/// Puts every particle that lies below the ground by at most [`GROUND_LIFT`] smallest cells back
/// on it (the ground's height at its plan position); true when one was, and no particle is off
/// the grid for another reason. Called only where the ground is a boundary, and only after a
/// failed locate (serial: the common step pays nothing).
#[cold]
fn lift_onto_ground<S: ShapeFunctions<N>, const N: usize>(
    shape: &S,
    positions: &mut [Vector],
) -> bool {
    let tolerance = GROUND_LIFT * shape.min_cell_size();
    let mut lifted = false;
    for x in positions.iter_mut() {
        match shape.factors(*x) {
            Ok(_) => {}
            Err(LocateError::BelowGround { y, ground_y, .. }) if ground_y - y <= tolerance => {
                x.y = ground_y;
                lifted = true;
            }
            Err(_) => return false,
        }
    }
    lifted
}

/// For the block scatter (`p2g.rs`): each active node's block rank and place in its block's patch,
/// and each block's neighbours below-left, below and left (in 3D the seven at offsets in
/// {−1, 0}³; `u32::MAX` where inactive); the patches sized to the blocks.
fn index_blocks<F, const N: usize>(sc: &mut Scratch<F, N>) {
    let side = patch_side(N);
    let active = &sc.active;
    sc.node_block.clear();
    sc.node_local.clear();
    sc.neighbours.clear();
    for (b, range) in active.block_ranges().enumerate() {
        let o = active.block_origin(b);
        for node in &active.nodes()[range] {
            sc.node_block.push(b as u32);
            // ci + side·cj (+ side²·ck) < MAX_PATCH ≤ 216 (`p2g.rs`): fits a byte.
            let (local, o) = (node.axes(), o.axes());
            let place = (0..DIM).rev().fold(0, |p, a| p * side + (local[a] - o[a]) as usize);
            sc.node_local.push(place as u8);
        }
        // neighbour m sits at offset ((m >> a) & 1) − 1 along axis a: below-left, below, left
        // in the plane; the own block (all offsets 0) is not listed.
        let rank = |m: usize| {
            let n = o.offset(std::array::from_fn(|a| (((m >> a) & 1) as i32 - 1) * BLOCK_SIDE));
            active.block_rank(n).map_or(u32::MAX, |r| r as u32)
        };
        sc.neighbours.push(std::array::from_fn(rank));
    }
    let cells = active.block_count() * side.pow(DIM as u32);
    sc.patch.resize(cells, PatchSums::default());
}

/// puts the dense index of every stencil node into `node_index`; false when some node is not in
/// the active set (its index is then `u32::MAX`).
fn number_stencils<F, const N: usize>(sc: &mut Scratch<F, N>, chunk: usize) -> bool {
    let active = &sc.active;
    sc.node_index.resize(sc.first_node.len(), [0; N]);
    sc.node_index
        .par_chunks_mut(chunk)
        .zip(sc.first_node.par_chunks(chunk))
        .map(|(idx, first)| {
            let mut complete = true;
            for (idx, &first) in idx.iter_mut().zip(first) {
                *idx = active.indices_of(&stencil_nodes::<N>(first));
                complete &= !idx.contains(&u32::MAX);
            }
            complete
        })
        .reduce(|| true, |a, b| a & b)
}

/// Bins the particles by the block of their stencil's first node, in increasing particle order
/// (a counting sort: deterministic), records where each particle's first node lies in its block's
/// patch, and under surface contact lists the (particle, slot) entries of every boundary node, in
/// particle order. False, with the bins left incomplete, when some active node is in no stencil.
fn bin_particles<F, const N: usize>(sc: &mut Scratch<F, N>) -> bool {
    let (n, nodes) = (sc.node_index.len(), sc.active.len());
    let chunk = chunk_len(n);
    sc.referenced.resize_with(nodes, || AtomicBool::new(false));
    sc.referenced.par_iter().with_min_len(4096).for_each(|r| r.store(false, Ordering::Relaxed));
    let (referenced, node_local) = (&sc.referenced, &sc.node_local);
    sc.base.resize(n, 0);
    sc.base.par_chunks_mut(chunk).zip(sc.node_index.par_chunks(chunk)).for_each(|(base, ids)| {
        for (base, idx) in base.iter_mut().zip(ids) {
            for &i in idx {
                referenced[i as usize].store(true, Ordering::Relaxed);
            }
            *base = node_local[idx[0] as usize];
        }
    });
    if !sc.referenced.par_iter().with_min_len(4096).all(|r| r.load(Ordering::Relaxed)) {
        return false;
    }
    let (index, block) = (&sc.node_index, &sc.node_block);
    counting_sort::<1>(
        n,
        sc.active.block_count(),
        |p| [(block[index[p][0] as usize], p as u32)],
        &mut sc.bin_start,
        &mut sc.bin_particle,
        &mut sc.sort_counts,
    );
    // Under surface contact: the (particle, slot) entries `p * N + k` of each boundary node, for
    // contact detection and the PIC normal correction (`boundary_of` marks boundary nodes only
    // under surface contact).
    if sc.boundary.first().is_none_or(|b| sc.boundary_of[b.node as usize] == u32::MAX) {
        sc.contact_start.clear();
        sc.contact_entry.clear();
        return true;
    }
    let of = &sc.boundary_of;
    counting_sort::<N>(
        n,
        sc.boundary.len(),
        |p| std::array::from_fn(|k| (of[index[p][k] as usize], (p * N + k) as u32)),
        &mut sc.contact_start,
        &mut sc.contact_entry,
        &mut sc.sort_counts,
    );
    true
}

/// writes the first node and the factors of a particle's stencil into its slots; true when
/// the node differs from the one the slot held (the dense indices and the bins must then be
/// redone). A stencil's nodes follow from its first node (the slot layout of
/// [`mpm_grid::Stencil`]), so they change exactly when it does. Used by `locate` and, for the
/// stencils computed ahead, by the stress update.
#[inline(always)]
pub(crate) fn store<F>(node: NodeId, factors: F, first: &mut NodeId, slot: &mut F) -> bool {
    let changed = *first != node;
    if changed {
        // (most steps keep a particle's nodes: no write then)
        *first = node;
    }
    *slot = factors;
    changed
}

#[cfg(test)]
mod tests {
    use mpm_constitutive::LinearElastic;
    use mpm_contact::Friction;
    use mpm_grid::Bilinear;
    use mpm_grid::testing::{at, grid, volume};
    use mpm_grid::{ActiveNodes, RegularGrid, ShapeFunctions};

    use crate::particles::{NewParticle, Particles};
    use crate::{Boundaries, Solver, SolverConfig, Vector};

    /// R3-05: a particle a sliver below the ground (1e-5 of a cell: what a curved 3D ground
    /// lets particles cross between its nodes) is put back on it and the run goes on, to the
    /// same bits as the particle placed on the ground (the retried locate trusts nothing it
    /// stored); one a hundredth of a cell below went through the ground, and the step stops
    /// with it named; without a ground law the bottom is open and even the sliver stops the run.
    #[test]
    fn a_particle_a_sliver_below_the_ground_is_put_back_on_it() {
        let run = |y: f64, ground: Option<Friction>| {
            let grid = grid([0.0; 2], [0.25; 2], [8, 8]).unwrap();
            let mut particles = Particles::default();
            for x in [0.9, 1.0, 1.1] {
                let p = at(x, 0.0625);
                particles.push(NewParticle::unstressed(p, Vector::ZERO, volume(0.1), 1000.0, ()));
            }
            let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
            let config = SolverConfig {
                boundaries: Boundaries { ground, ..Default::default() },
                ..Default::default()
            };
            let mut s = Solver::new(Bilinear(grid), vec![material], particles, config).unwrap();
            s.step().unwrap();
            s.particles_mut().position[1].y = y;
            let result = (0..5).try_for_each(|_| s.step().map(|_| ()));
            (result, s.particles().position.clone())
        };
        let floor = Some(Friction::Coulomb { mu: 0.3 });
        let (result, lifted) = run(-1e-5 * 0.25, floor);
        assert!(result.is_ok(), "{result:?}");
        let (_, placed) = run(0.0, floor);
        assert_eq!(lifted, placed);
        assert!(lifted[1].y >= 0.0, "{:?}", lifted[1]);
        for (y, ground) in [(-1e-2 * 0.25, floor), (-1e-5 * 0.25, None)] {
            let (result, _) = run(y, ground);
            assert!(
                matches!(result, Err(crate::SolverError::OutsideGrid { particle: 1, .. })),
                "{y} {ground:?}: {result:?}"
            );
        }
    }

    /// A block of slightly jittered particles sliding across cells on a frictional floor:
    /// stencils change nodes on some steps and not on others, and the active set changes on some
    /// of the former, so all three locate paths are taken (asserted); `force_full_locate` makes
    /// every step recompute the stencils and rebuild the active set and its numbering instead.
    fn sliding(force_full_locate: bool) -> Vec<u64> {
        sliding_with(force_full_locate, false)
    }

    /// `touch`: take `particles_mut()` before every step without changing anything, as scripted
    /// loading does; the stencils computed ahead must then be recomputed, never trusted stale.
    fn sliding_with(force_full_locate: bool, touch: bool) -> Vec<u64> {
        sliding_on(Bilinear(sliding_grid()), force_full_locate, touch)
    }

    fn sliding_grid() -> RegularGrid {
        grid([0.0; 2], [0.25; 2], [24, 8]).unwrap()
    }

    /// `sliding_with` for any shape functions on `sliding_grid`.
    fn sliding_on<S: ShapeFunctions<N>, const N: usize>(
        shape: S,
        force_full_locate: bool,
        touch: bool,
    ) -> Vec<u64> {
        let mut particles = Particles::default();
        let block = crate::testing::block([0.5, 0.0], [1.5, 1.0], 0.125);
        for (i, (position, volume)) in block.into_iter().enumerate() {
            // up to ±0.018 m, so that particles of one column cross a cell edge on different steps
            let jitter = 0.003 * ((i * 7919 % 13) as f64 - 6.0);
            let velocity = at(4.0, 0.0);
            let x = position + at(jitter, 0.0);
            particles.push(NewParticle::unstressed(x, velocity, volume, 1000.0, ()));
        }
        let config = SolverConfig {
            boundaries: Boundaries {
                ground: Some(Friction::Coulomb { mu: 0.3 }),
                ..Default::default()
            },
            ..Default::default()
        };
        let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
        let mut s = Solver::new(shape, vec![material], particles, config).unwrap();
        for _ in 0..400 {
            if force_full_locate {
                s.scratch.located = false;
                s.scratch.stencils_ahead = None;
                s.scratch.active = ActiveNodes::new();
            }
            if touch {
                let _ = s.particles_mut();
            }
            s.step().unwrap();
        }
        let [kept, same_set, rebuilt] = s.scratch.paths;
        if force_full_locate {
            assert_eq!((kept, same_set), (0, 0));
        } else {
            assert!(kept > 0 && same_set > 0 && rebuilt > 1, "paths {:?}", s.scratch.paths);
        }
        s.particles().position.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect()
    }

    #[test]
    fn reusing_an_unchanged_stencil_set_gives_the_same_bits_as_a_full_locate() {
        assert_eq!(sliding(false), sliding(true));
    }

    /// Regression: after a step whose particles changed nodes, `particles_mut` dropped the
    /// stencils computed ahead but left the stale numbering marked as valid, so the next step
    /// put mass and force on the wrong nodes.
    #[test]
    fn taking_the_particles_mutably_between_steps_changes_nothing() {
        assert_eq!(sliding_with(false, true), sliding(false));
    }

    /// The same for the 3 × 3 stencils, whose first node lies one node below and left of the
    /// point's nearest node: ghost nodes at j = −1 under the floor, and a first node that
    /// changes at the half-cell lines rather than at the cell edges.
    #[test]
    fn wide_stencils_reuse_what_a_full_locate_would_compute() {
        use mpm_grid::{Gimp, QuadraticBSpline};
        let spline = || QuadraticBSpline::new(sliding_grid());
        assert_eq!(sliding_on(spline(), false, false), sliding_on(spline(), true, false));
        let gimp = || Gimp::with_particles_per_cell(sliding_grid(), [2; mpm_grid::DIM]).unwrap();
        assert_eq!(sliding_on(gimp(), false, false), sliding_on(gimp(), true, false));
    }
}
