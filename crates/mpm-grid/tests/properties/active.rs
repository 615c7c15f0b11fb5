//! The sparse active-node set: exact membership, deterministic numbering, and a node count that
//! follows the material, not the domain.

use std::collections::BTreeSet;

use mpm_grid::{
    ActiveNodes, Bilinear, KinkPolicy, NodeId, ShapeFunctions, TerrainGrid, TerrainGridSpec, Vector,
};
use proptest::prelude::*;

use crate::common::config;

/// the documented dense order: by block (bj, bi), then inside the 8 × 8 block by (j, i).
fn dense_key(n: &NodeId) -> (i32, i32, i32, i32) {
    (n.j.div_euclid(8), n.i.div_euclid(8), n.j.rem_euclid(8), n.i.rem_euclid(8))
}

fn nodes() -> impl Strategy<Value = Vec<NodeId>> {
    prop::collection::vec((-60i32..60, -60i32..60).prop_map(|(i, j)| NodeId::new(i, j)), 0..400)
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn membership_and_numbering_are_exact(input in nodes(), probes in nodes()) {
        let mut a = ActiveNodes::new();
        a.rebuild(input.iter().copied());
        let set: BTreeSet<NodeId> = input.iter().copied().collect();
        prop_assert_eq!(a.len(), set.len());
        prop_assert_eq!(a.is_empty(), set.is_empty());
        let mut expected: Vec<NodeId> = set.iter().copied().collect();
        expected.sort_by_key(dense_key);
        prop_assert_eq!(a.nodes(), &expected[..]);
        for (k, n) in a.nodes().iter().enumerate() {
            prop_assert_eq!(a.index_of(*n), Some(k));
        }
        for n in probes {
            prop_assert_eq!(a.index_of(n).is_some(), set.contains(&n));
        }
        let mut covered = 0;
        for r in a.block_ranges() {
            prop_assert_eq!(r.start, covered);
            let b = dense_key(&a.nodes()[r.start]);
            prop_assert!(a.nodes()[r.clone()].iter().all(|n| (dense_key(n).0, dense_key(n).1) == (b.0, b.1)));
            covered = r.end;
        }
        prop_assert_eq!(covered, a.len());
    }

    /// numbering depends on the set only: not on input order, duplicates, or what the instance
    /// held before.
    #[test]
    fn numbering_is_independent_of_order_and_history(input in nodes(), before in nodes(), seed in any::<u64>()) {
        let mut fresh = ActiveNodes::new();
        fresh.rebuild(input.iter().copied());
        let mut shuffled = input.clone();
        // deterministic Fisher–Yates from the seed, then duplicate every third node.
        let mut s = seed;
        for k in (1..shuffled.len()).rev() {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            shuffled.swap(k, (s >> 33) as usize % (k + 1));
        }
        let dup: Vec<NodeId> = shuffled.iter().step_by(3).copied().collect();
        shuffled.extend(dup);
        let mut reused = ActiveNodes::new();
        reused.rebuild(before.iter().copied());
        reused.rebuild(shuffled.iter().copied());
        prop_assert_eq!(fresh.nodes(), reused.nodes());
        for n in &before {
            prop_assert_eq!(reused.index_of(*n), fresh.index_of(*n));
        }
        // once warmed up, rebuilding reuses capacity: no reallocation.
        let warmed = reused.heap_bytes();
        reused.rebuild(before.iter().copied());
        reused.rebuild(shuffled.iter().copied());
        prop_assert_eq!(reused.heap_bytes(), warmed);
        prop_assert_eq!(fresh.nodes(), reused.nodes());
    }

    /// a 1 m × 1 m body anywhere along a 10 km slope activates exactly the nodes it activates
    /// when shifted by a whole number of columns: the count follows the body, not the domain.
    #[test]
    fn active_count_is_independent_of_domain_extent(shift in 0u32..99_000, fx in 0.0f64..1.0, ft in 0.0f64..1.0) {
        let l = 0.1;
        let t = 25f64.to_radians().tan();
        let spec = |length: f64| TerrainGridSpec {
            profile: vec![Vector::new(0.0, length * t), Vector::new(length, 0.0)],
            cell_width: l,
            row_height: l,
            rows: 30,
            kink_policy: KinkPolicy::Reject,
        };
        let long = Bilinear(TerrainGrid::new(spec(10_000.0)).unwrap());
        let short = Bilinear(TerrainGrid::new(spec(20.0)).unwrap());
        let count = |sf: &Bilinear<TerrainGrid>, x_left: f64, active: &mut ActiveNodes| {
            let g = &sf.0;
            let mut stencils = Vec::new();
            for a in 0..20 {
                for b in 0..20 {
                    // 4 particles per cell, in ground-following coordinates.
                    let x = x_left + (a as f64 + 0.5) * 0.05;
                    let y = g.ground_height(x).unwrap() + (ft + b as f64 + 0.5) * 0.05;
                    stencils.push(sf.stencil(Vector::new(x, y)).unwrap());
                }
            }
            active.rebuild_from_stencils(&stencils);
            (active.len(), active.block_count())
        };
        let (mut a_long, mut a_short) = (ActiveNodes::new(), ActiveNodes::new());
        let far = count(&long, (f64::from(shift) + 10.0 + fx) * l, &mut a_long);
        let near = count(&short, (10.0 + fx) * l, &mut a_short);
        prop_assert_eq!(far.0, near.0);
        // blocks depend on where the body sits relative to 8-node blocks, never on the extent:
        // a 1 m body (≤ 12 × 14 nodes) touches at most 3 × 3 blocks.
        prop_assert!(far.1 <= 9 && near.1 <= 9);
        prop_assert!(a_long.heap_bytes() <= 64 * 1024, "{} bytes", a_long.heap_bytes());
        prop_assert_eq!(long.0.heap_bytes(), short.0.heap_bytes());
    }
}
