//! The solver's per-step memory, reused from step to step: each particle's stencil, the active
//! nodes and their bins, the nodal sums, and the boundary nodes with their planes.

use std::sync::atomic::{AtomicBool, AtomicU32};

use mpm_contact::{Boundary, Wall};
use mpm_grid::{ActiveNodes, NodeId};

use crate::consistent::ConsistentScratch;
use crate::math::{Real, Vector};

/// the blocks whose patches overlap a block's nodes, its own excluded: 2^DIM − 1.
pub(crate) const NEIGHBOURS: usize = (1 << crate::math::DIM) - 1;

/// one node's partial P2G sums in a block's patch (`p2g.rs`), side by side so that a particle's
/// share of a node touches one place in memory: in space aligned to 64 bytes, one cache line.
/// Each sum is added as the vector it is (the mass, then the momentum, then the force), as the
/// separate arrays this replaced were.
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(feature = "dim3", repr(C, align(64)))]
pub(crate) struct PatchSums {
    pub(crate) mass: Real,
    pub(crate) momentum: Vector,
    pub(crate) force: Vector,
}
/// A node that a boundary may hold: its dense index and the planes near it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoundaryNode {
    pub(crate) node: u32,
    /// Its planes are `Scratch::node_planes[first..first + count]`: the grid's sides through it
    /// first, then the walls near it.
    pub(crate) first: u32,
    pub(crate) count: u32,
    /// For a ghost node of a wide stencil: its image across the plane.
    pub(crate) mirror: Option<Mirror>,
    /// With periodic sides, for an image node beyond a side: the index in `Scratch::boundary`
    /// of its partner (the same column of nodes), which books the pair's boundary work.
    pub(crate) partner: Option<u32>,
}

impl BoundaryNode {
    /// the range of its planes in `Scratch::node_planes`.
    pub(crate) fn planes(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }
}

/// A held ghost node behind a fixed plane: it ends the grid solve as its image mirrored
/// (`stages/grid.rs`), and the particles' momentum changes by m_g times its change from the trial
/// values, which the ledger books.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FixedGhost {
    pub(crate) ghost: u32,
    pub(crate) image: u32,
    /// false for a periodic image, whose partner books the pair's impulse
    pub(crate) books: bool,
    /// the ghost's acceleration and velocity before the boundary conditions
    pub(crate) trial: (Vector, Vector),
    /// the side whose plane it is behind (its entry of `Solver::loads`), and that plane's normal
    pub(crate) source: (u16, Vector),
}

/// (image, ghost force, ghost mass, books the impulse, (side, normal)): see `Scratch::ties`.
pub(crate) type Tie = (u32, Vector, Real, bool, (u16, Vector));

/// One plane near a boundary node, placed as a [`Wall`]: a grid side passes through the node (or,
/// for a ghost node, halfway to its image), a declared wall lies wherever the scene put it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodePlane {
    pub(crate) wall: Wall,
    /// The plane holds the node whatever the material does: a `Fixed` plane, or any plane under
    /// [`crate::Contact::Node`], with the node on its face or inside its solid.
    pub(crate) always: bool,
    /// The plane holds the node during the coming step (see [`crate::Contact`]); set every step.
    pub(crate) held: bool,
    /// Which boundary it belongs to: its entry of `Solver::loads` (`loads.rs`).
    pub(crate) source: u16,
}

/// The mirror image of a ghost node (a node outside the grid, reached by wide stencils) across a
/// boundary plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mirror {
    /// Dense index of the image node.
    pub(crate) image: u32,
    /// The plane's unit normal, into the material.
    pub(crate) normal: Vector,
    /// A `Fixed` plane holds the material in both directions.
    pub(crate) fixed: bool,
}

impl Mirror {
    /// The velocity of the "wall" a ghost node meets: the velocity interpolated on the plane has
    /// the normal part (v_ghost + v_image)·n times a positive weight (the node on the plane is held
    /// by the contact law), so the ghost must not move into the plane faster than −v_image·n.
    /// Contact is applied to the ghost in the frame of a wall moving at that normal velocity:
    /// unilateral, with friction on the impulse that actually supports the material.
    pub(crate) fn wall_velocity(&self, image: Vector) -> Vector {
        -image.dot(self.normal) * self.normal
    }
}

/// What the last step's final particle loop left for the next `locate` (see
/// [`Scratch::stencils_ahead`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ahead {
    /// some particle's node ids differ from the ones the active set was built from.
    pub(crate) changed: bool,
    /// `node_index` holds every particle's new nodes in the current active set: no new node id
    /// is missing from it (the set may still have to shrink).
    pub(crate) numbered: bool,
}

/// Per-step memory, reused between steps (no allocation once the material stops growing).
#[derive(Debug)]
pub(crate) struct Scratch<F, const N: usize> {
    /// Grid node id of each particle's stencil's first node: the others follow from it
    /// ([`mpm_grid::stencil_nodes`]).
    pub(crate) first_node: Vec<NodeId>,
    /// Dense active-node indices of each particle's stencil.
    pub(crate) node_index: Vec<[u32; N]>,
    /// The factors S_ip and G_ip are computed from ([`mpm_grid::ShapeFunctions::Factors`]): each pass
    /// that needs them expands them again, cheaper than keeping the N weights and gradients.
    pub(crate) factors: Vec<F>,
    /// The active nodes.
    pub(crate) active: ActiveNodes,
    /// Particles binned by the 8 × 8 node block holding their stencil's first node, in
    /// increasing particle order: bin b is `bin_particle[bin_start[b]..bin_start[b + 1]]`.
    pub(crate) bin_start: Vec<u32>,
    pub(crate) bin_particle: Vec<AtomicU32>,
    /// Each particle's first stencil node, as a place in its block's patch (`p2g.rs`).
    pub(crate) base: Vec<u8>,
    /// Each active node's block rank and place in that block's patch.
    pub(crate) node_block: Vec<u32>,
    pub(crate) node_local: Vec<u8>,
    /// Each block's neighbours below-left, below and left (`u32::MAX` where inactive): the
    /// blocks whose patches overlap it (in 3D the seven blocks at offsets in {−1, 0}³ other
    /// than its own; `stages/locate.rs` `index_blocks` gives the order).
    pub(crate) neighbours: Vec<[u32; NEIGHBOURS]>,
    /// Per-block patches of partial particle-to-grid sums, one [`PatchSums`] per node
    /// (`p2g.rs`).
    pub(crate) patch: Vec<PatchSums>,
    /// Per-block patches of the side walls' normal force (`stages/side_walls.rs`; empty
    /// without side walls).
    pub(crate) wall_patch: Vec<Real>,
    /// N_i, the side walls' normal force on each active node (empty without side walls).
    pub(crate) wall_normal: Vec<Real>,
    /// The nodes whose side-wall friction another node books (reused).
    pub(crate) wall_skip: Vec<u32>,
    /// (ghost, image) of the ghosts behind slip planes, for the side walls (reused).
    pub(crate) wall_ghosts: Vec<(u32, u32)>,
    /// Each node's factor on v^L from the side walls' friction (reused).
    pub(crate) wall_scale: Vec<Real>,
    /// Which active nodes some stencil holds (the binning's check that the set is unchanged).
    pub(crate) referenced: Vec<AtomicBool>,
    /// Scratch of the counting sorts (`par::counting_sort`).
    pub(crate) sort_counts: Vec<u32>,
    /// Under surface contact, the (particle, slot) entries `p * N + k` of each boundary node
    /// in increasing particle order: those of `boundary[b]` are
    /// `contact_entry[contact_start[b]..contact_start[b + 1]]`.
    pub(crate) contact_start: Vec<u32>,
    pub(crate) contact_entry: Vec<AtomicU32>,
    /// Position in `boundary` of each active node under surface contact, else `u32::MAX`.
    pub(crate) boundary_of: Vec<u32>,
    /// With periodic sides: (image, partner) dense indices of each active node beyond a side
    /// whose partner column node is active too (built with the active set).
    pub(crate) periodic_pairs: Vec<(u32, u32)>,
    /// m_i.
    pub(crate) mass: Vec<Real>,
    /// v_i (from P2G, then the MUSL remap).
    pub(crate) velocity: Vec<Vector>,
    /// f_i = f_i^int + f_i^ext.
    pub(crate) force: Vec<Vector>,
    /// a_i after boundary conditions. The end-of-step velocity is never stored: it is
    /// v_i^L = v_i + a_i Δt (eq 5), an identity the contact layer keeps at boundary nodes too.
    pub(crate) acceleration: Vec<Vector>,
    /// v_i^L = v_i + a_i Δt (eq 5) per active node, formed once for APIC's grid to particle.
    pub(crate) end_velocity: Vec<Vector>,
    /// APIC's light-node mass of this step, C² m_cell (`stages/g2p.rs`): a node lighter than
    /// this gives the affine matrix no acceleration of its own.
    pub(crate) light_mass: Real,
    /// Per active node, whether APIC's grid to particle counts it light (`stages/g2p.rs`).
    pub(crate) light: Vec<bool>,
    /// Nodes on a declared boundary or near a wall.
    pub(crate) boundary: Vec<BoundaryNode>,
    /// The planes of the boundary nodes (`BoundaryNode::planes`).
    pub(crate) node_planes: Vec<NodePlane>,
    /// The planes holding one node, gathered for the contact law (reused).
    pub(crate) plane_buf: Vec<Boundary>,
    /// (image, ghost force, ghost mass, books the impulse, its side and normal) of the ghosts
    /// behind fixed planes that the lumped grid solve ties to their images (`stages/grid.rs`,
    /// reused).
    pub(crate) ties: Vec<Tie>,
    /// Each held plane's share of a node's contact impulse, for the loads (`stages/grid.rs`).
    pub(crate) shares: Vec<Vector>,
    /// The held ghost nodes behind fixed planes in this step's grid solve (either matrix).
    pub(crate) fixed_ghosts: Vec<FixedGhost>,
    /// The arrays below `first_node` describe the current `first_node` (false before the first
    /// locate, after a failed one, and after a stress update that changed some node ids).
    pub(crate) located: bool,
    /// `Some` when the last step's final particle loop already put every particle's stencil at
    /// its current position into `first_node` and `factors`; `None` makes `locate`
    /// compute them.
    pub(crate) stencils_ahead: Option<Ahead>,
    /// Unconstrained velocities of the boundary nodes while a strain update uses constrained ones.
    pub(crate) saved: Vec<Vector>,
    /// (node, plane normal) of every plane that pushed on a node in this step's grid solve
    /// (surface contact only): their particles take the normal velocity as in PIC.
    pub(crate) held: Vec<(u32, Vector)>,
    /// (particle, velocity change) of the PIC normal correction, gathered before it is applied.
    pub(crate) corrections: Vec<(u32, Vector)>,
    /// Counts rebuilds of the active set (tables keyed on the set's numbering compare it).
    pub(crate) active_generation: u64,
    /// The consistent mass matrix and its solver's vectors (`stages/mass.rs`); empty when lumped.
    pub(crate) consistent: ConsistentScratch,
    /// How often `locate` kept everything, kept the active set, rebuilt it (tests only).
    #[cfg(test)]
    pub(crate) paths: [usize; 3],
}

impl<F, const N: usize> Scratch<F, N> {
    pub(crate) fn new() -> Self {
        Self {
            first_node: Vec::new(),
            node_index: Vec::new(),
            factors: Vec::new(),
            active: ActiveNodes::new(),
            bin_start: Vec::new(),
            bin_particle: Vec::new(),
            base: Vec::new(),
            node_block: Vec::new(),
            node_local: Vec::new(),
            neighbours: Vec::new(),
            patch: Vec::new(),
            wall_patch: Vec::new(),
            wall_normal: Vec::new(),
            wall_skip: Vec::new(),
            wall_ghosts: Vec::new(),
            wall_scale: Vec::new(),
            referenced: Vec::new(),
            sort_counts: Vec::new(),
            contact_start: Vec::new(),
            contact_entry: Vec::new(),
            boundary_of: Vec::new(),
            periodic_pairs: Vec::new(),
            mass: Vec::new(),
            velocity: Vec::new(),
            force: Vec::new(),
            acceleration: Vec::new(),
            end_velocity: Vec::new(),
            light_mass: 0.0,
            light: Vec::new(),
            boundary: Vec::new(),
            node_planes: Vec::new(),
            plane_buf: Vec::new(),
            ties: Vec::new(),
            shares: Vec::new(),
            fixed_ghosts: Vec::new(),
            located: false,
            stencils_ahead: None,
            saved: Vec::new(),
            held: Vec::new(),
            corrections: Vec::new(),
            active_generation: 0,
            consistent: ConsistentScratch::new(),
            #[cfg(test)]
            paths: [0; 3],
        }
    }

    /// heap bytes held (for memory reports).
    pub(crate) fn heap_bytes(&self) -> usize {
        self.first_node.capacity() * size_of::<NodeId>()
            + self.node_index.capacity() * size_of::<[u32; N]>()
            + self.factors.capacity() * size_of::<F>()
            + self.active.len() * (size_of::<NodeId>() + 8)
            + (self.bin_start.capacity()
                + self.bin_particle.capacity()
                + self.sort_counts.capacity()
                + self.node_block.capacity()
                + self.contact_start.capacity()
                + self.contact_entry.capacity()
                + self.boundary_of.capacity()
                + 2 * self.periodic_pairs.capacity()
                + self.wall_skip.capacity()
                + 2 * self.wall_ghosts.capacity())
                * size_of::<u32>()
            + self.base.capacity()
            + self.light.capacity()
            + self.node_local.capacity()
            + self.referenced.capacity()
            + self.neighbours.capacity() * size_of::<[u32; NEIGHBOURS]>()
            + self.patch.capacity() * size_of::<PatchSums>()
            + (self.mass.capacity()
                + self.wall_patch.capacity()
                + self.wall_normal.capacity()
                + self.wall_scale.capacity())
                * size_of::<Real>()
            + (self.velocity.capacity()
                + self.force.capacity()
                + self.acceleration.capacity()
                + self.end_velocity.capacity()
                + self.saved.capacity())
                * size_of::<Vector>()
            + self.boundary.capacity() * size_of::<BoundaryNode>()
            + self.node_planes.capacity() * size_of::<NodePlane>()
            + self.plane_buf.capacity() * size_of::<Boundary>()
            + self.ties.capacity() * size_of::<Tie>()
            + self.shares.capacity() * size_of::<Vector>()
            + self.fixed_ghosts.capacity() * size_of::<FixedGhost>()
            + (self.held.capacity() + self.corrections.capacity()) * size_of::<(u32, Vector)>()
            + self.consistent.heap_bytes()
    }
}
