//! Helpers shared by the test binaries: seeded proptest configuration, generators of random
//! grids, and the identity checks every shape function must pass.
#![allow(dead_code)] // each binary uses a different subset.

use mpm_grid::{NodeId, ShapeFunctions, Stencil, Vector};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestCaseError};

/// partition of unity, Σ N = 1: the bound; the sums are of ≤ 9 terms in [0, 1], whose
/// round-off is ~1e-15.
pub const PARTITION_TOL: f64 = 1e-12;
/// Σ ∇N = 0 and Σ (x_i − x) ⊗ ∇N_i = I, made dimensionless by the cell size L. Terms are O(1)
/// after scaling; round-off is ε·|x|/L ≤ ~1e-13 for the coordinate ranges generated here.
pub const IDENTITY_TOL: f64 = 1e-12;
/// relative bound on Σ N_i x_i = x and on the inverse-map round trip x(ξ(x)) = x (the issue's
/// 1e-12 relative), relative to max(|x|, L).
pub const RELATIVE_TOL: f64 = 1e-12;

/// deterministic proptest configuration: a fixed seed, `cases` cases.
pub fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(0x6D70_6D2D_6772_6964),
        ..ProptestConfig::default()
    }
}

/// weight of `node` in a stencil, 0 if absent.
pub fn weight_of<const N: usize>(s: &Stencil<N>, node: NodeId) -> f64 {
    s.iter().filter(|(n, _, _)| *n == node).map(|(_, w, _)| w).sum()
}

/// the identities every stencil must satisfy at `p`: no duplicate nodes, 0 ≤ N ≤ 1, partition
/// of unity, gradients summing to zero, linear completeness Σ N_i x_i = x and
/// Σ x_i ⊗ ∇N_i = I. `cell` is the smallest cell size (for scaling). The tensor identity is
/// evaluated as Σ (x_i − x) ⊗ ∇N_i, which equals it exactly because Σ ∇N_i = 0 (checked first)
/// and avoids a cancellation of size ε|x|/L that says nothing about the shape functions.
pub fn check_identities<const N: usize, S: ShapeFunctions<N>>(
    sf: &S,
    p: Vector,
    cell: f64,
) -> Result<(), TestCaseError> {
    let s = sf.stencil(p).map_err(|e| TestCaseError::fail(format!("{e}")))?;
    // The layout solvers scatter by: slot k is node 0 shifted by (k mod w, k div w).
    let w = mpm_grid::stencil_side(N);
    for (k, n) in s.nodes.iter().enumerate() {
        let expected = NodeId::new(s.nodes[0].i + (k % w) as i32, s.nodes[0].j + (k / w) as i32);
        prop_assert_eq!(*n, expected, "slot {} out of the tensor-product layout", k);
    }
    // (`stencil` builds the nodes from the first with `stencil_nodes`, so this checks the
    // layout an implementation that overrides it must keep; that the first node is the right
    // one is what the linear completeness below checks.)
    for a in 0..N {
        for b in a + 1..N {
            prop_assert_ne!(s.nodes[a], s.nodes[b], "duplicate node");
        }
        prop_assert!(
            s.weights[a] >= -PARTITION_TOL && s.weights[a] <= 1.0 + PARTITION_TOL,
            "weight {} out of [0, 1]",
            s.weights[a]
        );
    }
    let sum: f64 = s.weights.iter().sum();
    prop_assert!((sum - 1.0).abs() <= PARTITION_TOL, "Σ N = {sum}");
    let grad_sum: Vector = s.gradients.iter().copied().sum();
    prop_assert!(grad_sum.length() * cell <= IDENTITY_TOL, "Σ ∇N = {grad_sum}");
    let x: Vector = s.iter().map(|(n, w, _)| w * sf.node_position(n)).sum();
    prop_assert!(
        (x - p).length() <= RELATIVE_TOL * p.length().max(cell),
        "Σ N x = {x}, expected {p}"
    );
    let mut m = [[0.0; 2]; 2];
    for (n, _, g) in s.iter() {
        let d = sf.node_position(n) - p;
        for (r, dr) in [d.x, d.y].into_iter().enumerate() {
            for (c, gc) in [g.x, g.y].into_iter().enumerate() {
                m[r][c] += dr * gc;
            }
        }
    }
    let err = (m[0][0] - 1.0).abs() + m[0][1].abs() + m[1][0].abs() + (m[1][1] - 1.0).abs();
    prop_assert!(err <= IDENTITY_TOL, "Σ x ⊗ ∇N = {m:?}");
    Ok(())
}

/// gradient check against central differences of the weights. `delta` is the step; `tol` the
/// allowed difference in units of 1/cell. Skipped (Ok) when the stencil changes within ±delta,
/// where a one-sided kink of bilinear N makes the difference quotient meaningless.
pub fn check_gradients_by_differences<const N: usize, S: ShapeFunctions<N>>(
    sf: &S,
    p: Vector,
    cell: f64,
    delta: f64,
    tol: f64,
) -> Result<(), TestCaseError> {
    let s = sf.stencil(p).map_err(|e| TestCaseError::fail(format!("{e}")))?;
    for e in [Vector::X, Vector::Y] {
        let (Ok(sp), Ok(sm)) = (sf.stencil(p + delta * e), sf.stencil(p - delta * e)) else {
            return Ok(()); // stepped off the grid
        };
        if sp.nodes != s.nodes || sm.nodes != s.nodes {
            return Ok(());
        }
        for k in 0..N {
            let fd = (sp.weights[k] - sm.weights[k]) / (2.0 * delta);
            let exact = s.gradients[k].dot(e);
            prop_assert!(
                (fd - exact).abs() * cell <= tol,
                "node {:?}: ∂N/∂{e} = {exact}, difference quotient {fd}",
                s.nodes[k]
            );
        }
    }
    Ok(())
}

/// continuity of N: weights at p − eps·dir and p + eps·dir agree node by node (nodes missing on
/// one side count as weight 0) within `tol`.
pub fn check_continuity<const N: usize, S: ShapeFunctions<N>>(
    sf: &S,
    p: Vector,
    dir: Vector,
    eps: f64,
    tol: f64,
) -> Result<(), TestCaseError> {
    let (Ok(a), Ok(b)) = (sf.stencil(p - eps * dir), sf.stencil(p + eps * dir)) else {
        return Ok(());
    };
    for n in a.nodes.iter().chain(b.nodes.iter()) {
        let (wa, wb) = (weight_of(&a, *n), weight_of(&b, *n));
        prop_assert!((wa - wb).abs() <= tol, "N of {n:?} jumps from {wa} to {wb} across {p}");
    }
    Ok(())
}

/// a random terrain: profile points exactly on column boundaries.
#[derive(Clone, Debug)]
pub struct TerrainCase {
    /// profile points x0 + c_k·l.
    pub points: Vec<Vector>,
    /// column index c_k of each point.
    pub point_columns: Vec<u32>,
    pub l: f64,
    pub h: f64,
    pub rows: usize,
}

impl TerrainCase {
    /// the reference ground y(x) by linear interpolation of the profile points.
    pub fn ground(&self, x: f64) -> f64 {
        let k = self.points.partition_point(|p| p.x <= x).clamp(1, self.points.len() - 1);
        let (a, b) = (self.points[k - 1], self.points[k]);
        a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x)
    }

    pub fn columns(&self) -> u32 {
        *self.point_columns.last().unwrap()
    }
}

/// 1–5 (or 17–30) segments of 1–12 columns each, slopes within ±50°, l ∈ [0.05, 2] m, h/l ∈ [0.2, 3],
/// 1–8 rows, starting anywhere in [−20, 20]² m.
pub fn terrain_case() -> impl Strategy<Value = TerrainCase> {
    (
        // mostly a few segments; sometimes more than 16 kinks (the binary-search path).
        prop_oneof![
            3 => prop::collection::vec((1u32..=12, -50.0f64..50.0), 1..=5),
            1 => prop::collection::vec((1u32..=12, -50.0f64..50.0), 17..=30),
        ],
        0.05f64..2.0,
        0.2f64..3.0,
        1usize..=8,
        -20.0f64..20.0,
        -20.0f64..20.0,
    )
        .prop_map(|(segments, l, h_over_l, rows, x0, y0)| {
            let mut points = vec![Vector::new(x0, y0)];
            let mut point_columns = vec![0];
            let (mut c, mut y) = (0u32, y0);
            for (n, degrees) in segments {
                c += n;
                y += f64::from(n) * l * degrees.to_radians().tan();
                points.push(Vector::new(x0 + f64::from(c) * l, y));
                point_columns.push(c);
            }
            TerrainCase { points, point_columns, l, h: h_over_l * l, rows }
        })
}

/// a fraction in [0, 1] that hits 0 and 1 exactly now and then (edges and corners matter).
pub fn fraction() -> impl Strategy<Value = f64> {
    prop_oneof![8 => 0.0f64..=1.0, 1 => Just(0.0), 1 => Just(1.0)]
}
