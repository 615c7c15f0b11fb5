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
use crate::{Boundary, ContactError, Friction, Vector};

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
    /// the node ends on this boundary's candidate.
    On(Face),
    /// (3D) the node ends on the edge where two boundaries meet.
    #[cfg(feature = "dim3")]
    Edge(Edge),
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
        }
    }
}

/// (3D) the first admissible edge of two pressed boundaries, pairs in slice order.
#[cfg(feature = "dim3")]
fn edge(boundaries: &[Boundary], trial: Vector, law: Law, slack: f64) -> Option<Edge> {
    for (i, a) in boundaries.iter().enumerate() {
        for b in &boundaries[i + 1..] {
            let Some(edge) = Edge::resolve(a, b, trial, law) else { continue };
            if boundaries.iter().all(|k| edge.end.dot(k.normal()) >= -slack) {
                return Some(edge);
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
    if let Some(b) = boundaries.iter().find(|b| matches!(b.friction(), Friction::Fixed)) {
        return Verdict::On(Face::resolve(b, trial, law));
    }
    let slack = FEASIBILITY_TOLERANCE * trial.length();
    let mut last = None;
    while let Some(key) = next_pressed(boundaries, trial, last) {
        last = Some(key);
        let face = Face::resolve(&boundaries[key.1], trial, law);
        let end = face.end_velocity();
        if boundaries.iter().all(|b| end.dot(b.normal()) >= -slack) {
            return Verdict::On(face);
        }
    }
    if last.is_none() {
        return Verdict::Free;
    }
    #[cfg(feature = "dim3")]
    if let Some(edge) = edge(boundaries, trial, law, slack) {
        return Verdict::Edge(edge);
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
        Verdict::On(face) => face.outcome(mass, velocity, acceleration, dt),
        #[cfg(feature = "dim3")]
        Verdict::Edge(edge) => edge.outcome(mass, velocity, acceleration, dt),
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

/// [`Boundary::constrain_velocity`] for a node on any number of boundaries: the same corner treatment
/// with every Coulomb boundary acting as a roller. A node pinned in a corner gets zero velocity.
pub fn constrain_velocity_all(boundaries: &[Boundary], velocity: Vector) -> Vector {
    match resolve_all(boundaries, velocity, Law::VelocityOnly) {
        Verdict::Free => velocity,
        Verdict::On(face) => face.end_velocity(),
        #[cfg(feature = "dim3")]
        Verdict::Edge(edge) => edge.end,
        Verdict::Stop => Vector::ZERO,
    }
}
