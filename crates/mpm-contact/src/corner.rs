//! A node on several boundaries (a box corner, a wall meeting the ground, a kink of the ground profile).
//!
//! # Glossary
//! - n_k: unit normal of boundary k, into the material; v\* = v + a Δt the trial velocity.
//! - pressed on k: v\*·n_k < 0. Admissible: v·n_k ≥ 0 for every k (to [`FEASIBILITY_TOLERANCE`]).
//! - candidate k: the single-boundary result of `node_law.rs` on boundary k alone.
//!
//! # Treatment (deterministic, an active set)
//! 1. If any boundary is `Fixed`, the first `Fixed` one in slice order decides: the node is fixed.
//! 2. Otherwise try the candidates of the pressed boundaries, most pressed first (smallest v\*·n_k; ties
//!    by slice order), and accept the first whose end velocity is admissible for every boundary.
//! 3. If no boundary is pressed the node is untouched; if some are but no candidate is admissible, the
//!    node is pinned in the corner and stops (status `Sticking`, all removed energy is normal work).
//!    In 3D (`mpm-contact3d`) two planes meet along a line, not at a point: before pinning, the
//!    edges of two pressed boundaries are tried (pairs in slice order), the node sliding along
//!    the line with both normal velocities removed and the friction of both impulses; only a
//!    node no edge admits (a vertex of three planes) is pinned.
//!
//! Why this order: for frictionless boundaries it returns exactly the Euclidean projection of v\* onto
//! the admissible cone {v : v·n_k ≥ 0 ∀k}, i.e. the impulse solution of the two-sided contact problem.
//! When v\* presses on several boundaries, every admissible velocity is at least max_k |v\*·n_k| from v\*,
//! so only the most pressed boundary's projection can be the projection; when none is admissible the
//! multipliers of two independent normals are both active and, in 2D, the only admissible point they
//! leave is 0. Friction only shrinks the tangential component of a candidate towards 0 (a positive
//! scaling), which keeps admissibility, so with friction the same order applies and a candidate is
//! frictionally admissible exactly when its frictionless version is (or when it sticks).
//! A node that presses on two boundaries but can slide along the more pressed one without entering the
//! other (a fast node crossing a gentle kink of the ground) therefore keeps sliding rather than stopping.
//! Friction on the boundary the node ends on uses that boundary's normal impulse only.

use crate::node_law::{ContactOutcome, Face, Law, valid_dt, validate_step, work_mass};
use crate::{Boundary, Carriers, ContactError, Friction, Vector};

/// Relative slack, times |v\*|, allowed on v^L·n_k ≥ 0 when checking a candidate against the other
/// boundaries.
///
/// A candidate's end velocity is (v\*·t)t, whose component along another normal carries a few roundings
/// of size ~1e-16 |v\*|; 1e-12 leaves four orders of margin and still refuses any penetration that
/// would be visible over a whole simulation (1e6 steps × 1e-12 ≪ one cell).
pub const FEASIBILITY_TOLERANCE: f64 = 1e-12;

/// The verdict of a set of boundaries on a trial velocity.
enum Verdict {
    /// no boundary is pressed.
    Free,
    /// the node ends on the candidate of this boundary (its index).
    On(usize, Face),
    /// (3D) the node ends on the edge where two boundaries meet (their indices).
    #[cfg(feature = "dim3")]
    Edge(Edge, usize, usize),
    /// the node is pinned in a corner.
    Stop,
}

/// (3D) A node held by two boundaries at once slides along their line of intersection e = n_i ×
/// n_j (the plane has a line where, in 2D, two lines leave only their point): both normal
/// velocities are removed by impulses λ_i n_i + λ_j n_j (per unit mass, both ≥ 0: each plane
/// pushes), and the velocity along e is reduced by the friction both impulses carry,
/// μ_i λ_i + μ_j λ_j, or stops where that is enough (eqs 15–16 at an edge).
#[cfg(feature = "dim3")]
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// v^L.
    end: Vector,
    /// v\*·e.
    along_trial: f64,
    /// |v^L·e|.
    along_end: f64,
    /// the friction held it.
    stuck: bool,
}

#[cfg(feature = "dim3")]
impl Edge {
    /// the edge of boundaries `a` and `b` under `law` for trial velocity `trial`, if both press
    /// (λ ≥ 0) and the planes are not parallel.
    fn resolve(a: &Boundary, b: &Boundary, trial: Vector, law: Law) -> Option<Self> {
        let (na, nb) = (a.normal(), b.normal());
        let e = na.cross(nb);
        let length = e.length();
        // (a NaN length is refused too)
        if length.is_nan() || length <= 1e-9 {
            return None;
        }
        let e = e / length;
        let c = na.dot(nb);
        let det = 1.0 - c * c;
        let (ta, tb) = (trial.dot(na), trial.dot(nb));
        let la = (-ta + c * tb) / det;
        let lb = (-tb + c * ta) / det;
        if !(la >= 0.0 && lb >= 0.0) {
            return None;
        }
        let mu = |boundary: &Boundary| match (boundary.friction(), law) {
            (Friction::Coulomb { mu }, Law::Step) => mu,
            (Friction::Coulomb { .. }, Law::VelocityOnly) => 0.0,
            (Friction::Rough | Friction::Fixed, _) => f64::INFINITY,
        };
        // (∞·0 avoided: an infinite coefficient with no impulse adds nothing)
        let share = |m: f64, l: f64| if l > 0.0 { m * l } else { 0.0 };
        let capacity = share(mu(a), la) + share(mu(b), lb);
        let along_trial = trial.dot(e);
        let stuck = along_trial.abs() <= capacity;
        let along_end = if stuck { 0.0 } else { along_trial.abs() - capacity };
        let end = along_trial.signum() * along_end * e;
        Some(Self { end, along_trial, along_end, stuck })
    }

    /// the outcome for a node of mass `mass` with start-of-step velocity `v` and trial
    /// acceleration `a`: the work split as at one boundary (normal: what the impulses normal to
    /// the edge took; friction: what its friction took).
    fn outcome(&self, mass: f64, v: Vector, a: Vector, dt: f64) -> ContactOutcome {
        let trial = v + a * dt;
        ContactOutcome {
            acceleration: (self.end - v) / dt,
            velocity: self.end,
            status: if self.stuck {
                crate::ContactStatus::Sticking
            } else {
                crate::ContactStatus::Sliding
            },
            friction_work: 0.5
                * mass
                * (self.along_trial * self.along_trial - self.along_end * self.along_end),
            normal_work: 0.5
                * mass
                * (trial.length_squared() - self.along_trial * self.along_trial).max(0.0),
            impulse: mass * (self.end - trial),
            carriers: crate::Carriers::None,
        }
    }
}

/// (3D) the first admissible edge of two pressed boundaries, pairs in slice order.
#[cfg(feature = "dim3")]
fn edge(
    boundaries: &[Boundary],
    trial: Vector,
    law: Law,
    slack: f64,
) -> Option<(Edge, usize, usize)> {
    for (i, a) in boundaries.iter().enumerate() {
        for (j, b) in boundaries.iter().enumerate().skip(i + 1) {
            let Some(edge) = Edge::resolve(a, b, trial, law) else { continue };
            if boundaries.iter().all(|k| edge.end.dot(k.normal()) >= -slack) {
                return Some((edge, i, j));
            }
        }
    }
    None
}

/// the pressed boundary that comes after `last` in the order (v\*·n_k ascending, then k ascending).
fn next_pressed(
    boundaries: &[Boundary],
    trial: Vector,
    last: Option<(f64, usize)>,
) -> Option<(f64, usize)> {
    let key_order = |x: (f64, usize), y: (f64, usize)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
    let mut best: Option<(f64, usize)> = None;
    for (k, b) in boundaries.iter().enumerate() {
        let vn = trial.dot(b.normal());
        // Written so that a NaN component is "not pressed".
        let pressed = vn < 0.0;
        if !pressed {
            continue;
        }
        let key = (vn, k);
        if last.is_some_and(|l| key_order(key, l).is_le()) {
            continue;
        }
        if best.is_none_or(|b| key_order(key, b).is_lt()) {
            best = Some(key);
        }
    }
    best
}

/// the treatment of the module documentation, in the velocity domain.
fn resolve_all(boundaries: &[Boundary], trial: Vector, law: Law) -> Verdict {
    if let Some(k) = boundaries.iter().position(|b| matches!(b.friction(), Friction::Fixed)) {
        return Verdict::On(k, Face::resolve(&boundaries[k], trial, law));
    }
    let slack = FEASIBILITY_TOLERANCE * trial.length();
    let mut last = None;
    while let Some(key) = next_pressed(boundaries, trial, last) {
        last = Some(key);
        let face = Face::resolve(&boundaries[key.1], trial, law);
        let end = face.end_velocity();
        if boundaries.iter().all(|b| end.dot(b.normal()) >= -slack) {
            return Verdict::On(key.1, face);
        }
    }
    if last.is_none() {
        return Verdict::Free;
    }
    #[cfg(feature = "dim3")]
    if let Some((edge, i, j)) = edge(boundaries, trial, law, slack) {
        return Verdict::Edge(edge, i, j);
    }
    Verdict::Stop
}

/// the step for a valid `dt` and a work mass ≥ 0.
fn step_all(
    boundaries: &[Boundary],
    mass: f64,
    velocity: Vector,
    acceleration: Vector,
    dt: f64,
) -> ContactOutcome {
    match resolve_all(boundaries, velocity + acceleration * dt, Law::Step) {
        Verdict::Free => ContactOutcome::untouched(velocity, acceleration, dt),
        Verdict::On(k, face) => ContactOutcome {
            carriers: Carriers::One(k),
            ..face.outcome(mass, velocity, acceleration, dt)
        },
        #[cfg(feature = "dim3")]
        Verdict::Edge(edge, i, j) => ContactOutcome {
            carriers: Carriers::Two(i, j),
            ..edge.outcome(mass, velocity, acceleration, dt)
        },
        Verdict::Stop => ContactOutcome::stopped(mass, velocity, acceleration, dt),
    }
}

/// [`Boundary::apply`] for a node on any number of boundaries (usually one or two).
///
/// 1. If any boundary is `Fixed`, the first `Fixed` one in slice order decides: the node is fixed.
/// 2. Otherwise the pressed boundaries (v\*·n_k < 0) are tried most pressed first (smallest v\*·n_k,
///    ties by slice order), each alone as by [`Boundary::apply`]; the first result whose end velocity
///    satisfies v^L·n_j ≥ −[`FEASIBILITY_TOLERANCE`]·|v\*| for every boundary j is returned.
/// 3. No boundary pressed: the node is untouched. Pressed but no admissible result: the node is
///    pinned and stops (v^L = 0, status `Sticking`, all removed energy reported as normal work).
///
/// The order of the slice matters only for ties and for which of several `Fixed` boundaries splits
/// the work. With one boundary it is
/// [`Boundary::apply`]; with none the node is untouched. Never panics; bad input is handled as by
/// [`Boundary::apply`].
pub fn apply_all(
    boundaries: &[Boundary],
    mass: f64,
    velocity: Vector,
    acceleration: Vector,
    dt: f64,
) -> ContactOutcome {
    if !valid_dt(dt) {
        return ContactOutcome::untouched(velocity, acceleration, dt);
    }
    step_all(boundaries, work_mass(mass), velocity, acceleration, dt)
}

/// [`apply_all`], refusing a bad step with a typed error instead of passing it through.
pub fn try_apply_all(
    boundaries: &[Boundary],
    mass: f64,
    velocity: Vector,
    acceleration: Vector,
    dt: f64,
) -> Result<ContactOutcome, ContactError> {
    validate_step(mass, velocity, acceleration, dt)?;
    Ok(step_all(boundaries, mass, velocity, acceleration, dt))
}

/// Each boundary's share of the impulse `outcome` (from [`apply_all`] on `boundaries` with trial
/// velocity `trial` = v + a Δt) gave the node, written to `shares[k]` for boundary k (the others
/// 0): what a solver adds up per wall to report the load each one takes. The shares sum to
/// `outcome.impulse` (the last carrier takes the rounding).
///
/// - One carrier: it takes the whole impulse.
/// - (3D) An edge of boundaries i and j: the impulse J = α n_i + β n_j + γ e, with e along the
///   edge, is split as the law made it: α n_i and β n_j are the two normal pushes, and the friction
///   γ e is divided in proportion to the friction each push carries, μ_i α : μ_j β (in proportion
///   to α : β where a boundary is rough or fixed).
/// - Pinned in a corner: J = −m v\* is the sum of pushes along the pressed boundaries' normals,
///   taken most pressed first as long as each normal adds a new direction (nearly parallel planes,
///   such as the two sides of a gentle kink, leave the later one without a share); with two
///   independent normals in 2D, or three in 3D, the decomposition is exact.
///
/// `shares` must be at least as long as `boundaries`; only its first `boundaries.len()` entries are
/// written.
pub fn impulse_shares(
    boundaries: &[Boundary],
    outcome: &ContactOutcome,
    trial: Vector,
    shares: &mut [Vector],
) {
    let shares = &mut shares[..boundaries.len()];
    shares.fill(Vector::ZERO);
    let impulse = outcome.impulse;
    match outcome.carriers {
        Carriers::None => {}
        Carriers::One(k) => shares[k] = impulse,
        Carriers::Two(i, j) => {
            let (ni, nj) = (boundaries[i].normal(), boundaries[j].normal());
            // the part along the edge (3D; in 2D two independent normals span everything)
            #[cfg(feature = "dim3")]
            let along = ni.cross(nj).try_normalize().map_or(Vector::ZERO, |e| impulse.dot(e) * e);
            #[cfg(not(feature = "dim3"))]
            let along = Vector::ZERO;
            let normal = impulse - along;
            let c = ni.dot(nj);
            let det = 1.0 - c * c;
            let (a, b) = if det > 1e-12 {
                let (pi, pj) = (normal.dot(ni), normal.dot(nj));
                ((pi - c * pj) / det, (pj - c * pi) / det)
            } else {
                (normal.dot(ni), 0.0)
            };
            let mu = |k: usize| match boundaries[k].friction() {
                Friction::Coulomb { mu } => mu,
                Friction::Rough | Friction::Fixed => f64::INFINITY,
            };
            let (mi, mj) = (mu(i), mu(j));
            let weight = if mi.is_infinite() || mj.is_infinite() {
                let w = |m: f64, l: f64| if m.is_infinite() { l.max(0.0) } else { 0.0 };
                (w(mi, a), w(mj, b))
            } else {
                ((mi * a).max(0.0), (mj * b).max(0.0))
            };
            let total = weight.0 + weight.1;
            let first = if total > 0.0 { weight.0 / total } else { 1.0 };
            shares[i] = a * ni + first * along;
            shares[j] = impulse - shares[i];
        }
        Carriers::Corner => {
            // the pressed normals, most pressed first, kept while independent
            let mut order: [(f64, usize); 8] = [(0.0, 0); 8];
            let mut count = 0;
            for (k, b) in boundaries.iter().enumerate() {
                let vn = trial.dot(b.normal());
                if vn < 0.0 && count < order.len() {
                    order[count] = (vn, k);
                    count += 1;
                }
            }
            order[..count].sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            const DIM: usize = if cfg!(feature = "dim3") { 3 } else { 2 };
            let mut basis: [Vector; DIM] = [Vector::ZERO; DIM];
            let mut chosen: [usize; DIM] = [0; DIM];
            let mut rank = 0;
            for &(_, k) in &order[..count] {
                if rank == DIM {
                    break;
                }
                let n = boundaries[k].normal();
                let mut q = n;
                for b in &basis[..rank] {
                    q -= q.dot(*b) * *b;
                }
                if let Some(q) = q.try_normalize().filter(|_| q.length() > 1e-6) {
                    basis[rank] = q;
                    chosen[rank] = k;
                    rank += 1;
                }
            }
            if rank == 0 {
                return;
            }
            // J = Σ λ_r n_r over the chosen normals: the Gram system, solved by elimination
            let mut g = [[0.0; 4]; DIM];
            for r in 0..rank {
                let nr = boundaries[chosen[r]].normal();
                for (c, &k) in chosen[..rank].iter().enumerate() {
                    g[r][c] = nr.dot(boundaries[k].normal());
                }
                g[r][3] = impulse.dot(nr);
            }
            let lambda = solve_small(&mut g, rank);
            let last = chosen[rank - 1];
            let mut rest = impulse;
            for r in 0..rank - 1 {
                let k = chosen[r];
                shares[k] = lambda[r] * boundaries[k].normal();
                rest -= shares[k];
            }
            shares[last] = rest;
        }
    }
}

/// the solution of the `n`×`n` system whose augmented rows (right-hand side in column 3) are
/// `g`, by Gaussian elimination with partial pivoting; a zero pivot gives that unknown 0.
fn solve_small<const D: usize>(g: &mut [[f64; 4]; D], n: usize) -> [f64; D] {
    for col in 0..n {
        let pivot = (col..n).max_by(|&a, &b| g[a][col].abs().total_cmp(&g[b][col].abs()));
        let pivot = pivot.unwrap_or(col);
        g.swap(col, pivot);
        if g[col][col] == 0.0 {
            continue;
        }
        let pivot_row = g[col];
        for row in &mut g[col + 1..n] {
            let f = row[col] / pivot_row[col];
            for (a, b) in row.iter_mut().zip(pivot_row).skip(col) {
                *a -= f * b;
            }
        }
    }
    let mut x = [0.0; D];
    for row in (0..n).rev() {
        let mut v = g[row][3];
        for c in row + 1..n {
            v -= g[row][c] * x[c];
        }
        x[row] = if g[row][row] == 0.0 { 0.0 } else { v / g[row][row] };
    }
    x
}

/// [`Boundary::constrain_velocity`] for a node on any number of boundaries: the same corner treatment
/// with every Coulomb boundary acting as a roller. A node pinned in a corner gets zero velocity.
pub fn constrain_velocity_all(boundaries: &[Boundary], velocity: Vector) -> Vector {
    match resolve_all(boundaries, velocity, Law::VelocityOnly) {
        Verdict::Free => velocity,
        Verdict::On(_, face) => face.end_velocity(),
        #[cfg(feature = "dim3")]
        Verdict::Edge(edge, ..) => edge.end,
        Verdict::Stop => Vector::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn coulomb(mu: f64) -> Friction {
        Friction::Coulomb { mu }
    }

    /// a node pushed into the corner of a wall (n = x) and the ground (n = y): the pinned node's
    /// impulse −m v* splits exactly into the wall's push along x and the ground's along y.
    #[cfg(not(feature = "dim3"))]
    #[test]
    fn a_pinned_corner_node_splits_its_impulse_along_the_two_normals() {
        let wall = Boundary::new(Vector::X, coulomb(0.3)).unwrap();
        let ground = Boundary::new(Vector::Y, coulomb(0.3)).unwrap();
        let planes = [ground, wall];
        let (m, v, a, dt) = (2.0, Vector::new(-1.0, -2.0), Vector::ZERO, 1e-3);
        let out = apply_all(&planes, m, v, a, dt);
        assert_eq!(out.carriers, Carriers::Corner);
        let mut shares = [Vector::ZERO; 2];
        impulse_shares(&planes, &out, v + a * dt, &mut shares);
        assert!((shares[0] - Vector::new(0.0, 4.0)).length() < 1e-15, "{shares:?}");
        assert!((shares[1] - Vector::new(2.0, 0.0)).length() < 1e-15, "{shares:?}");
        // sliding along the ground away from the wall: the ground carries it all
        let v = Vector::new(1.0, -2.0);
        let out = apply_all(&planes, m, v, a, dt);
        assert_eq!(out.carriers, Carriers::One(0));
        impulse_shares(&planes, &out, v, &mut shares);
        assert_eq!(shares, [out.impulse, Vector::ZERO]);
        // moving away from both: nothing
        let out = apply_all(&planes, m, Vector::new(1.0, 1.0), a, dt);
        impulse_shares(&planes, &out, Vector::new(1.0, 1.0), &mut shares);
        assert_eq!(shares, [Vector::ZERO; 2]);
    }

    /// (3D) a node sliding along the edge of a wall (n = x) and the ground (n = y): each takes its
    /// own normal push, and the friction along the edge in proportion μ_i α_i.
    #[cfg(feature = "dim3")]
    #[test]
    fn an_edge_node_splits_pushes_and_friction_between_its_two_planes() {
        let wall = Boundary::new(Vector::X, coulomb(0.1)).unwrap();
        let ground = Boundary::new(Vector::Y, coulomb(0.2)).unwrap();
        let planes = [ground, wall];
        let (m, v, a, dt) = (2.0, Vector::new(-1.0, -2.0, 3.0), Vector::ZERO, 1e-3);
        let out = apply_all(&planes, m, v, a, dt);
        assert!(matches!(out.carriers, Carriers::Two(..)), "{:?}", out.carriers);
        let mut shares = [Vector::ZERO; 2];
        impulse_shares(&planes, &out, v, &mut shares);
        // pushes m·2 (ground) and m·1 (wall); friction m (0.2·2 + 0.1·1) = 1.0 against +z,
        // split 0.8 : 0.2
        assert!((shares[0] - Vector::new(0.0, 4.0, -0.8)).length() < 1e-14, "{shares:?}");
        assert!((shares[1] - Vector::new(2.0, 0.0, -0.2)).length() < 1e-14, "{shares:?}");
    }

    /// the shares add up to the impulse whatever the planes and the trial velocity: random
    /// corners of up to four planes (kinks, walls, a fixed plane now and then).
    #[test]
    fn the_shares_sum_to_the_impulse() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut carried = 0;
        for _ in 0..2000 {
            let count = 1 + (uniform().abs() * 4.0) as usize;
            let mut planes = Vec::new();
            for k in 0..count {
                #[cfg(feature = "dim3")]
                let n = Vector::new(uniform(), uniform(), uniform());
                #[cfg(not(feature = "dim3"))]
                let n = Vector::new(uniform(), uniform());
                let Some(n) = n.try_normalize() else { continue };
                let law = if k == 3 && uniform() > 0.5 { Friction::Fixed } else { coulomb(0.5) };
                planes.push(Boundary::new(n, law).unwrap());
            }
            #[cfg(feature = "dim3")]
            let v = Vector::new(uniform(), uniform(), uniform());
            #[cfg(not(feature = "dim3"))]
            let v = Vector::new(uniform(), uniform());
            let out = apply_all(&planes, 1.5, v, Vector::ZERO, 1e-3);
            let mut shares = [Vector::ZERO; 4];
            impulse_shares(&planes, &out, v, &mut shares);
            let sum: Vector = shares.iter().copied().sum();
            assert!((sum - out.impulse).length() <= 1e-13, "{sum:?} vs {:?}", out.impulse);
            carried += usize::from(out.carriers != Carriers::None);
        }
        assert!(carried > 500, "the random corners pressed too rarely: {carried}");
    }
}
