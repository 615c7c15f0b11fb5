//! Sparse set of active grid nodes with a deterministic dense numbering: node storage follows
//! the material, not the domain.
//!
//! # Scheme
//! Nodes are grouped in 8 × 8 blocks: block (bi, bj) = (i >> 3, j >> 3) (floor division, so
//! negative ghost indices work), local bit (j & 7)·8 + (i & 7). In 3D the blocks are
//! 4 × 4 × 4, block (bi, bj, bk) = (i >> 2, j >> 2, k >> 2), local bit
//! (k & 3)·16 + (j & 3)·4 + (i & 3), sorted by (bk, bj, bi): the same 64 nodes per block and
//! everything below holds with the third index added. A rebuild
//! 1. sets, for every node fed in (duplicates welcome), one bit in its block's 64-bit mask, the
//!    block found through an open-addressing hash table (linear probing, Fibonacci hashing, load
//!    ≤ ½) with a one-entry cache for runs of nodes in the same block;
//! 2. sorts the touched blocks by (bj, bi);
//! 3. numbers the nodes block by block, inside a block by (j, i): dense order is
//!    (bj, bi, j & 7, i & 7).
//!
//! The numbering depends only on the *set* of nodes, never on the order they were fed in or on
//! how many threads produced them. Memory and time are O(touched blocks + nodes fed in): a 10 km
//! long domain holding a 1 m² body costs what the body costs. Once warmed up (capacity reached),
//! rebuilds do not allocate. [`ActiveNodes::index_of`] is a hash probe plus a table read.

use std::fmt;
use std::ops::Range;

use crate::node::NodeId;
use crate::stencil::Stencil;

/// log2 of the block side.
#[cfg(not(feature = "dim3"))]
const BLOCK_SHIFT: u32 = 3;
/// log2 of the block side.
#[cfg(feature = "dim3")]
const BLOCK_SHIFT: u32 = 2;
/// nodes along each side of a block: block (bi, bj) holds nodes i in [8 bi, 8 bi + 8) and
/// j in [8 bj, 8 bj + 8) (in 3D 4 along each of three sides).
pub const BLOCK_SIDE: i32 = 1 << BLOCK_SHIFT;
/// block side − 1, the mask of a node's position inside its block.
const IN_BLOCK: i32 = (1 << BLOCK_SHIFT) - 1;
/// value of an empty hash slot.
const EMPTY: u32 = u32::MAX;
/// key never produced by a node (block indices are i32 >> 3, so the flipped halves stay below
/// 0x9000_0000).
const NO_KEY: u64 = u64::MAX;
/// smallest hash table, slots.
const MIN_SLOTS: usize = 64;
/// Fibonacci hashing multiplier, 2⁶⁴/φ.
const FIBONACCI: u64 = 0x9E37_79B9_7F4A_7C15;

#[derive(Clone, Copy, Debug)]
struct Slot {
    key: u64,
    /// EMPTY, or the block's position in `blocks` (insertion order while building, sorted
    /// rank once built).
    value: u32,
}

#[derive(Clone, Copy, Debug)]
struct BlockBuild {
    /// sortable block key: (bj, bi) with the sign bits flipped, bj in the high half.
    key: u64,
    /// bit per node of the block.
    mask: u64,
    /// hash slot holding this block.
    slot: u32,
}

#[derive(Clone, Copy)]
struct BlockIndex {
    mask: u64,
    /// dense index of each node of the block whose mask bit is set (others unused).
    dense: [u32; 64],
}

/// Sparse set of active nodes with deterministic dense numbering (see the module docs).
#[derive(Clone, Default)]
pub struct ActiveNodes {
    slots: Vec<Slot>,
    /// 64 − log2(slots.len()).
    shift: u32,
    blocks: Vec<BlockBuild>,
    tables: Vec<BlockIndex>,
    /// dense index of each block's first node; one extra entry = len().
    offsets: Vec<usize>,
    nodes: Vec<NodeId>,
}

#[cfg(not(feature = "dim3"))]
#[inline(always)]
fn split(node: NodeId) -> (u64, u32) {
    let bi = (node.i >> BLOCK_SHIFT) as u32 ^ 0x8000_0000;
    let bj = (node.j >> BLOCK_SHIFT) as u32 ^ 0x8000_0000;
    let bit = (((node.j & IN_BLOCK) << BLOCK_SHIFT) | (node.i & IN_BLOCK)) as u32;
    ((u64::from(bj) << 32) | u64::from(bi), bit)
}

#[cfg(not(feature = "dim3"))]
#[inline(always)]
fn block_origin(key: u64) -> NodeId {
    let bi = (key as u32 ^ 0x8000_0000) as i32;
    let bj = ((key >> 32) as u32 ^ 0x8000_0000) as i32;
    NodeId::new(bi << BLOCK_SHIFT, bj << BLOCK_SHIFT)
}

/// the node at bit `bit` of the block whose lowest node is `origin`.
#[cfg(not(feature = "dim3"))]
#[inline(always)]
fn node_at(origin: NodeId, bit: u32) -> NodeId {
    let bit = bit as i32;
    NodeId::new(origin.i + (bit & IN_BLOCK), origin.j + (bit >> BLOCK_SHIFT))
}

/// bits of each block index in a 3D key: 21, so that three fit 63 bits (nodes within ±2²²
/// along each axis, which [`MAX_CELLS_PER_AXIS`](crate::MAX_CELLS_PER_AXIS) keeps).
#[cfg(feature = "dim3")]
const KEY_BITS: u32 = 21;
/// added to a block index to make it non-negative in a 3D key.
#[cfg(feature = "dim3")]
const KEY_BIAS: i64 = 1 << (KEY_BITS - 1);

/// a node's block key, (bk, bj, bi) biased to be non-negative and packed with bk highest,
/// and its bit in the block.
#[cfg(feature = "dim3")]
#[inline(always)]
fn split(node: NodeId) -> (u64, u32) {
    let field = |n: i32| ((i64::from(n >> BLOCK_SHIFT) + KEY_BIAS) as u64) & ((1 << KEY_BITS) - 1);
    let key = (field(node.k) << (2 * KEY_BITS)) | (field(node.j) << KEY_BITS) | field(node.i);
    let bit = ((node.k & IN_BLOCK) << (2 * BLOCK_SHIFT))
        | ((node.j & IN_BLOCK) << BLOCK_SHIFT)
        | (node.i & IN_BLOCK);
    (key, bit as u32)
}

#[cfg(feature = "dim3")]
#[inline(always)]
fn block_origin(key: u64) -> NodeId {
    let index = |shift: u32| (((key >> shift) & ((1 << KEY_BITS) - 1)) as i64 - KEY_BIAS) as i32;
    NodeId::new(
        index(0) << BLOCK_SHIFT,
        index(KEY_BITS) << BLOCK_SHIFT,
        index(2 * KEY_BITS) << BLOCK_SHIFT,
    )
}

/// the node at bit `bit` of the block whose lowest node is `origin`.
#[cfg(feature = "dim3")]
#[inline(always)]
fn node_at(origin: NodeId, bit: u32) -> NodeId {
    let bit = bit as i32;
    origin.offset([bit & IN_BLOCK, (bit >> BLOCK_SHIFT) & IN_BLOCK, bit >> (2 * BLOCK_SHIFT)])
}

impl ActiveNodes {
    /// an empty set (allocates nothing until the first rebuild).
    pub fn new() -> Self {
        Self::default()
    }

    #[inline(always)]
    fn home(&self, key: u64) -> usize {
        (key.wrapping_mul(FIBONACCI) >> self.shift) as usize
    }

    fn allocate_slots(&mut self, n: usize) {
        self.slots.clear();
        self.slots.resize(n, Slot { key: NO_KEY, value: EMPTY });
        self.shift = 64 - n.trailing_zeros();
    }

    /// doubles the hash table and re-inserts the blocks gathered so far.
    fn grow(&mut self) {
        let n = (2 * self.slots.len()).max(MIN_SLOTS);
        self.allocate_slots(n);
        let mask = n - 1;
        for k in 0..self.blocks.len() {
            let key = self.blocks[k].key;
            let mut s = self.home(key);
            while self.slots[s].value != EMPTY {
                s = (s + 1) & mask;
            }
            self.slots[s] = Slot { key, value: k as u32 };
            self.blocks[k].slot = s as u32;
        }
    }

    /// position in `blocks` of the block with `key`, inserting it if new.
    #[inline]
    fn find_or_insert(&mut self, key: u64) -> usize {
        loop {
            let mask = self.slots.len() - 1;
            let mut s = self.home(key);
            loop {
                let slot = self.slots[s];
                if slot.value == EMPTY {
                    break;
                }
                if slot.key == key {
                    return slot.value as usize;
                }
                s = (s + 1) & mask;
            }
            if 2 * (self.blocks.len() + 1) > self.slots.len() {
                self.grow();
                continue;
            }
            let k = self.blocks.len();
            self.slots[s] = Slot { key, value: k as u32 };
            self.blocks.push(BlockBuild { key, mask: 0, slot: s as u32 });
            return k;
        }
    }

    /// clears and rebuilds from `nodes` (duplicates welcome). Dense indices are sorted by
    /// (bj, bi, j & 7, i & 7), independent of input order. Reuses capacity: no allocation once
    /// warmed up.
    pub fn rebuild(&mut self, nodes: impl IntoIterator<Item = NodeId>) {
        for b in &self.blocks {
            self.slots[b.slot as usize].value = EMPTY;
        }
        self.blocks.clear();
        self.tables.clear();
        self.offsets.clear();
        self.nodes.clear();
        if self.slots.is_empty() {
            self.allocate_slots(MIN_SLOTS);
        }

        let mut last_key = NO_KEY;
        let mut last_block = 0;
        for node in nodes {
            let (key, bit) = split(node);
            if key != last_key {
                last_block = self.find_or_insert(key);
                last_key = key;
            }
            self.blocks[last_block].mask |= 1 << bit;
        }

        self.blocks.sort_unstable_by_key(|b| b.key);
        for (rank, b) in self.blocks.iter().enumerate() {
            self.slots[b.slot as usize].value = rank as u32;
            let origin = block_origin(b.key);
            let mut table = BlockIndex { mask: b.mask, dense: [0; 64] };
            self.offsets.push(self.nodes.len());
            let mut m = b.mask;
            while m != 0 {
                let bit = m.trailing_zeros();
                // dense indices fit u32: 2³² nodes would need 32 GiB of NodeIds alone.
                table.dense[bit as usize] = self.nodes.len() as u32;
                self.nodes.push(node_at(origin, bit));
                m &= m - 1;
            }
            self.tables.push(table);
        }
        self.offsets.push(self.nodes.len());
    }

    /// rebuilds from the nodes of `stencils` (every node listed, whatever its weight).
    pub fn rebuild_from_stencils<const N: usize>(&mut self, stencils: &[Stencil<N>]) {
        self.rebuild(stencils.iter().flat_map(|s| s.nodes));
    }

    /// number of active nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// true when no node is active.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// dense indices of a stencil's nodes, `u32::MAX` for a node that is not active. One hash
    /// probe per distinct block among the nodes (a 2 × 2 or 3 × 3 stencil usually lies in one
    /// 8 × 8 block), instead of one per node.
    #[inline]
    pub fn indices_of<const N: usize>(&self, nodes: &[NodeId; N]) -> [u32; N] {
        let mut out = [u32::MAX; N];
        let mut last_key = NO_KEY;
        let mut table: Option<&BlockIndex> = None;
        for (o, &node) in out.iter_mut().zip(nodes) {
            let (key, bit) = split(node);
            if key != last_key {
                table = self.block_of(key);
                last_key = key;
            }
            if let Some(t) = table {
                if (t.mask >> bit) & 1 == 1 {
                    *o = t.dense[bit as usize];
                }
            }
        }
        out
    }

    /// the rank of the block with `key`, if that block is active: one hash probe.
    #[inline]
    fn probe(&self, key: u64) -> Option<usize> {
        if self.tables.is_empty() {
            return None;
        }
        let mask = self.slots.len() - 1;
        let mut s = self.home(key);
        loop {
            let slot = self.slots[s];
            if slot.value == EMPTY {
                return None;
            }
            if slot.key == key {
                return Some(slot.value as usize);
            }
            s = (s + 1) & mask;
        }
    }

    /// the index table of the block with `key`, if that block is active.
    #[inline]
    fn block_of(&self, key: u64) -> Option<&BlockIndex> {
        self.probe(key).map(|rank| &self.tables[rank])
    }

    /// dense index of `node`, `None` if it is not active. O(1): one hash probe, one table read.
    #[inline]
    pub fn index_of(&self, node: NodeId) -> Option<usize> {
        let (key, bit) = split(node);
        let t = self.block_of(key)?;
        ((t.mask >> bit) & 1 == 1).then(|| t.dense[bit as usize] as usize)
    }

    /// true when `node` is active.
    pub fn contains(&self, node: NodeId) -> bool {
        self.index_of(node).is_some()
    }

    /// the active nodes in dense order.
    pub fn nodes(&self) -> &[NodeId] {
        &self.nodes
    }

    /// number of touched 8 × 8 blocks.
    pub fn block_count(&self) -> usize {
        self.tables.len()
    }

    /// dense index range of each block, in dense order: disjoint, contiguous, covering
    /// 0..len(). Handy for deterministic block-parallel work on nodes.
    pub fn block_ranges(&self) -> impl ExactSizeIterator<Item = Range<usize>> + '_ {
        self.offsets.windows(2).map(|w| w[0]..w[1])
    }

    /// the lowest node (8 bi, 8 bj) of block `rank` (ranks follow [`Self::block_ranges`]).
    pub fn block_origin(&self, rank: usize) -> NodeId {
        block_origin(self.blocks[rank].key)
    }

    /// the rank of the block holding `node`, if that block is active (it has some active
    /// node, not necessarily this one).
    #[inline]
    pub fn block_rank(&self, node: NodeId) -> Option<usize> {
        self.probe(split(node).0)
    }

    /// heap bytes reserved (capacity, not length): follows the largest material footprint seen,
    /// never the domain.
    pub fn heap_bytes(&self) -> usize {
        self.slots.capacity() * size_of::<Slot>()
            + self.blocks.capacity() * size_of::<BlockBuild>()
            + self.tables.capacity() * size_of::<BlockIndex>()
            + self.offsets.capacity() * size_of::<usize>()
            + self.nodes.capacity() * size_of::<NodeId>()
    }
}

impl fmt::Debug for ActiveNodes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ActiveNodes")
            .field("len", &self.len())
            .field("blocks", &self.block_count())
            .field("hash_slots", &self.slots.len())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::node;

    #[test]
    fn split_and_block_origin_round_trip_including_negative_ghosts() {
        // the farthest nodes a key holds: i32's range in the plane, ±2²² in space.
        let far = if crate::DIM == 3 { (1 << 22) - 1 } else { i32::MAX };
        for (i, j) in [(0, 0), (-1, -1), (7, 8), (-9, 17), (far, -far - 1), (-far - 1, 5)] {
            let (key, bit) = split(node(i, j));
            assert_ne!(key, NO_KEY);
            assert_eq!(node_at(block_origin(key), bit), node(i, j));
        }
    }

    #[test]
    fn indices_of_agrees_with_index_of_across_block_edges() {
        let mut a = ActiveNodes::new();
        // 2 × 2 and 3 × 3 stencils placed so that some straddle block edges (8k − 1 | 8k).
        let stencils: Vec<[NodeId; 4]> = (-10..20)
            .flat_map(|j| (-10..20).map(move |i| (i, j)))
            .filter(|(i, j)| (i + 3 * j) % 7 == 0)
            .map(|(i, j)| [node(i, j), node(i + 1, j), node(i, j + 1), node(i + 1, j + 1)])
            .collect();
        a.rebuild(stencils.iter().flatten().copied());
        for s in &stencils {
            let got = a.indices_of(s);
            for k in 0..4 {
                assert_eq!(got[k] as usize, a.index_of(s[k]).unwrap());
            }
        }
        // A node outside the set is reported as u32::MAX, its neighbours still found.
        let probe = [stencils[0][0], node(1000, 1000)];
        let got = a.indices_of(&probe);
        assert_eq!(got[0] as usize, a.index_of(probe[0]).unwrap());
        assert_eq!(got[1], u32::MAX);
    }

    #[test]
    fn empty_set_answers_none() {
        let mut a = ActiveNodes::new();
        assert_eq!(a.index_of(node(0, 0)), None);
        a.rebuild([]);
        assert!(a.is_empty());
        assert_eq!(a.index_of(node(0, 0)), None);
        assert_eq!(a.block_ranges().count(), 0);
    }

    #[test]
    fn growth_keeps_every_block_reachable() {
        let mut a = ActiveNodes::new();
        // 40 × 40 blocks force several doublings of the 64-slot table.
        let nodes: Vec<_> =
            (0..40).flat_map(|bj| (0..40).map(move |bi| node(8 * bi - 100, 8 * bj + 3))).collect();
        a.rebuild(nodes.iter().copied());
        assert_eq!(a.len(), 1600);
        assert_eq!(a.block_count(), 1600);
        for (k, n) in a.nodes().iter().enumerate() {
            assert_eq!(a.index_of(*n), Some(k));
        }
        for n in &nodes {
            assert_eq!(a.nodes()[a.index_of(*n).unwrap()], *n);
        }
        assert_eq!(a.index_of(node(-99, 3)), None);
    }
}
