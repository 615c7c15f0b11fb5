//! The fixed-size stencil of a point and the one interface over every grid + shape-function pair.

use crate::error::LocateError;
use crate::math::{DIM, Matrix, Vector};
use crate::node::{BoundaryNormals, NodeId};

/// Fixed-size stencil: the nodes whose support contains a point, with weights N_i(x) and
/// gradients ∇N_i(x) (1/m).
///
/// Weights sum to one and reproduce linear fields (Σ N_i x_i = x, Σ x_i ⊗ ∇N_i = I). A node can
/// appear with weight zero (a point on a cell edge, a point at a uGIMP support's rim); no node
/// appears twice.
///
/// Every stencil is a tensor product of w × w nodes (w × w × w in 3D), w =
/// [`stencil_side`]`(N)`: slot k holds node `nodes[0]` + (k mod w, k div w) (in 3D
/// `nodes[0]` + (k mod w, (k div w) mod w, k div w²)), so `nodes[0]` is its lowest corner. Solvers
/// rely on this to scatter a particle into a block-local patch of nodes from its first node alone.
#[derive(Clone, Copy, Debug)]
pub struct Stencil<const N: usize> {
    /// the nodes.
    pub nodes: [NodeId; N],
    /// N_i(x), dimensionless.
    pub weights: [f64; N],
    /// ∇N_i(x), 1/m.
    pub gradients: [Vector; N],
}

impl<const N: usize> Stencil<N> {
    /// (node, weight, gradient) triples in stencil order.
    pub fn iter(&self) -> impl Iterator<Item = (NodeId, f64, Vector)> + '_ {
        (0..N).map(move |k| (self.nodes[k], self.weights[k], self.gradients[k]))
    }
}

/// the side w of a w × w (w × w × w in 3D) tensor-product stencil of `n` nodes (2 for 4 nodes,
/// 3 for 9; in 3D 2 for 8, 3 for 27).
pub const fn stencil_side(n: usize) -> usize {
    let mut w: usize = 1;
    while w.pow(DIM as u32) < n {
        w += 1;
    }
    assert!(w.pow(DIM as u32) == n, "a stencil is a square (a cube in 3D) of nodes");
    w
}

/// the offset of slot `k` of a stencil of side `w` from its first node (the layout of
/// [`Stencil`]).
#[inline(always)]
pub const fn slot_offset(k: usize, w: usize) -> [i32; DIM] {
    #[cfg(not(feature = "dim3"))]
    return [(k % w) as i32, (k / w) as i32];
    #[cfg(feature = "dim3")]
    return [(k % w) as i32, ((k / w) % w) as i32, (k / (w * w)) as i32];
}

/// the nodes of the `N`-node stencil whose first (lowest) node is `first`, in slot order: slot k
/// is `first` + (k mod w, k div w), w = [`stencil_side`]`(N)` (the layout every [`Stencil`]
/// keeps). A solver may thus store a stencil's first node alone.
#[inline(always)]
pub fn stencil_nodes<const N: usize>(first: NodeId) -> [NodeId; N] {
    let w = stencil_side(N);
    std::array::from_fn(|k| first.offset(slot_offset(k, w)))
}

/// One interface over every grid + shape-function pair (no allocation, no dyn).
///
/// `N` is the stencil size: 4 for bilinear, 9 for uGIMP and quadratic B-splines (in 3D 8 and
/// 27).
pub trait ShapeFunctions<const N: usize>: Send + Sync {
    /// The few numbers a point's N weights and N gradients are computed from (its fractions
    /// across a cell, or its 1D weights along each axis). A solver may keep these per particle
    /// instead of the stencil, which is 2–4 times larger, and expand them in every pass that
    /// needs weights or gradients: the expansion is a few multiplications, cheaper than
    /// streaming the stencil through memory again.
    type Factors: Copy + Default + std::fmt::Debug + Send + Sync;

    /// whether every node's position is a tensor product of per-axis coordinates (x_i, y_j,
    /// z_k), as on the regular grids: a scatter may then factorise C (x_i − x_p) per axis. A
    /// terrain grid's node heights depend on their column, so it says false.
    const SEPARABLE_NODES: bool = true;

    /// the first (lowest) node of the stencil at `x` and the factors of its weights and
    /// gradients; a typed error for a point off the grid.
    fn factors(&self, x: Vector) -> Result<(NodeId, Self::Factors), LocateError>;

    /// N_i(x) in slot order, from the factors `factors(x)` returned: the same bits every call.
    fn weights(&self, f: &Self::Factors) -> [f64; N];

    /// ∇N_i(x) (1/m) in slot order, from the factors `factors(x)` returned.
    fn gradients(&self, f: &Self::Factors) -> [Vector; N];

    /// Σ_k N_k v_k and Σ_k v_k ⊗ ∇N_k over the stencil, v_k = `value(k)` in slot order: the
    /// value and the gradient (1/m) of the field the nodes carry, at the point. The default
    /// forms the N weights and gradients and sums node by node; tensor-product functions in
    /// space override it with sums factorised per axis (the same terms, fewer products, other
    /// round-off). Every implementation calls `value` exactly once per slot, whatever its
    /// weight: a caller may observe the nodes it reads through it (APIC's G2P notes a light
    /// node there).
    #[inline(always)]
    fn interpolate(&self, f: &Self::Factors, value: impl Fn(usize) -> Vector) -> (Vector, Matrix) {
        let (w, g) = (self.weights(f), self.gradients(f));
        let (mut v, mut l) = (Vector::ZERO, Matrix::ZERO);
        for k in 0..N {
            let value = value(k);
            v += w[k] * value;
            l += outer(value, g[k]);
        }
        (v, l)
    }

    /// Σ_k v_k ⊗ ∇N_k alone (1/m): the gradient of [`ShapeFunctions::interpolate`].
    #[inline(always)]
    fn gradient(&self, f: &Self::Factors, value: impl Fn(usize) -> Vector) -> Matrix {
        let g = self.gradients(f);
        let mut l = Matrix::ZERO;
        for (k, g) in g.into_iter().enumerate() {
            l += outer(value(k), g);
        }
        l
    }

    /// one particle's share of every stencil node's force, (m N_k) b − V σ·∇N_k (N), slot by
    /// slot: its weight of its body force m b and its internal force (eqs 2–3), the stress
    /// given by its in-plane columns σ e_a (Pa, tension positive) and `weights` its N_k. The
    /// default sums node by node; tensor-product functions in space override it with sums
    /// factorised per axis.
    #[inline(always)]
    fn nodal_forces(
        &self,
        f: &Self::Factors,
        weights: &[f64; N],
        (mass, body): (f64, Vector),
        volume: f64,
        stress: [Vector; DIM],
    ) -> [Vector; N] {
        let g = self.gradients(f);
        std::array::from_fn(|k| {
            let mut sg = stress[0] * g[k][0];
            for (a, column) in stress.iter().enumerate().skip(1) {
                sg += *column * g[k][a];
            }
            (mass * weights[k]) * body - volume * sg
        })
    }

    /// nodes, weights and gradients at `x`; a typed error for a point off the grid.
    #[inline(always)]
    fn stencil(&self, x: Vector) -> Result<Stencil<N>, LocateError> {
        let (first, f) = self.factors(x)?;
        Ok(Stencil {
            nodes: stencil_nodes(first),
            weights: self.weights(&f),
            gradients: self.gradients(&f),
        })
    }

    /// position of a node, m. Defined for every node id, including ghost nodes outside the grid
    /// (extrapolating the grid's geometry), so it never fails.
    fn node_position(&self, node: NodeId) -> Vector;

    /// smallest cell dimension L used by the time-step (Courant) limit, m: for skewed cells the
    /// smallest distance between opposite edges.
    fn min_cell_size(&self) -> f64;

    /// boundary planes a node lies on (ground/floor j ≤ 0, left wall i ≤ 0, right wall
    /// i ≥ last column), as unit normals pointing into the material.
    fn boundary_normals(&self, node: NodeId) -> BoundaryNormals;

    /// For a ghost node (outside the grid across a boundary plane, reached only by the wide
    /// stencils of uGIMP and B-splines): its mirror image inside the grid across that plane and
    /// the plane's unit normal (pointing into the material). A solver that gives the ghost the
    /// mirrored normal velocity of its image makes the interpolated normal velocity vanish on the
    /// plane, so material cannot be carried through it. `None` for every other node, and for grids
    /// without ghost nodes (the default).
    fn mirror(&self, node: NodeId) -> Option<(NodeId, Vector)> {
        let _ = node;
        None
    }
}

/// a ⊗ b: the matrix whose column j is a b_j.
#[inline(always)]
fn outer(a: Vector, b: Vector) -> Matrix {
    #[cfg(not(feature = "dim3"))]
    return Matrix::from_cols(a * b.x, a * b.y);
    #[cfg(feature = "dim3")]
    return Matrix::from_cols(a * b.x, a * b.y, a * b.z);
}
