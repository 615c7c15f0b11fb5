//! The single-boundary law of one explicit step (eqs 14–18), in impulse (velocity) form.
//!
//! # Glossary
//! - n: unit normal of the boundary, pointing from the boundary into the material.
//! - t = (n_y, −n_x): unit tangent, (t, n) right-handed.
//! - m (kg), v (m/s), a (m/s²), Δt (s): nodal mass, start-of-step velocity, trial acceleration f/m.
//! - v\* = v + a Δt: trial (unconstrained) end-of-step velocity; v\*_n = v\*·n, v\*_t = v\*·t.
//! - a_n = a·n, a_t = a·t; v_n = v·n, v_t = v·t.
//! - v^L: constrained end-of-step velocity (eq 5's v_i^L); a^c: constrained acceleration, v^L = v + a^c Δt.
//! - r = −(v_n/Δt + a_n) = −v\*_n/Δt: normal reaction per unit mass (m/s², ≥ 0 in contact); |a_n| of
//!   the paper when v_n = 0.
//! - μ: Coulomb coefficient; μ = ∞ for `Rough` and `Fixed`.
//!
//! # The law
//! 1. Contact (eq 14): the node presses on the boundary when v\*_n < 0. A `Fixed` node is always engaged.
//!    A node not engaged is returned untouched.
//! 2. Normal (eqs 17, 18): v^L_n = 0, hence a^c_n = −v_n/Δt (= 0, eq 17, for a node already at rest
//!    normally; otherwise the acceleration also carries the impulse that stops the approach).
//! 3. Tangent (eqs 15, 16): the friction impulse per unit mass is at most μ|v\*_n| = μ r Δt.
//!    - stick if |v\*_t| ≤ μ|v\*_n|: v^L_t = 0, a^c_t = −v_t/Δt;
//!    - slide otherwise: a^c_t = a_t − sign(v\*_t) μ r and v^L_t = sign(v\*_t)(|v\*_t| − μ|v\*_n|), which
//!      keeps the sign of v\*_t: friction never reverses the tangential velocity.

#[cfg(not(feature = "dim3"))]
use crate::boundary::tangent_of;
use crate::{Boundary, ContactError, Friction, Vector};

/// A tangential quantity: in the plane its coordinate along the tangent t (a signed scalar), in
/// space the vector itself, lying in the tangent plane. The law below is written once over the
/// few operations both provide.
#[cfg(not(feature = "dim3"))]
type Tangential = f64;
/// A tangential quantity: in the plane its coordinate along the tangent t (a signed scalar), in
/// space the vector itself, lying in the tangent plane.
#[cfg(feature = "dim3")]
type Tangential = Vector;

/// the tangential part of `v` on a boundary with normal `n` and (2D) tangent `t`.
#[inline(always)]
fn tangential(v: Vector, n: Vector, t: Vector) -> Tangential {
    #[cfg(not(feature = "dim3"))]
    return {
        let _ = n;
        v.dot(t)
    };
    #[cfg(feature = "dim3")]
    return {
        let _ = t;
        v - v.dot(n) * n
    };
}

/// |x|.
#[inline(always)]
fn magnitude(x: Tangential) -> f64 {
    #[cfg(not(feature = "dim3"))]
    return x.abs();
    #[cfg(feature = "dim3")]
    return x.length();
}

/// the direction of x (sign(x) in the plane, x/|x| in space; x ≠ 0).
#[inline(always)]
fn direction(x: Tangential) -> Tangential {
    #[cfg(not(feature = "dim3"))]
    return x.signum();
    #[cfg(feature = "dim3")]
    return x / x.length();
}

/// a tangential quantity as a vector (x·t in the plane).
#[inline(always)]
fn as_vector(x: Tangential, t: Vector) -> Vector {
    #[cfg(not(feature = "dim3"))]
    return x * t;
    #[cfg(feature = "dim3")]
    return {
        let _ = t;
        x
    };
}

/// the tangent a law is written with: t = (n_y, −n_x) in the plane; unused in space, where the
/// tangential parts are vectors.
#[inline(always)]
fn tangent_for(n: Vector) -> Vector {
    #[cfg(not(feature = "dim3"))]
    return tangent_of(n);
    #[cfg(feature = "dim3")]
    return {
        let _ = n;
        Vector::ZERO
    };
}

/// How a node ended the step with respect to its boundary (or boundaries).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactStatus {
    /// the node does not press on any boundary: it was left untouched.
    Separating,
    /// the node presses and slides: the friction impulse reached its Coulomb limit.
    Sliding,
    /// the node presses and ends the step with zero tangential velocity (friction held it, it is on a
    /// `Rough` boundary, or it is pinned in a corner).
    Sticking,
    /// the node is on a `Fixed` boundary: its end-of-step velocity is zero whatever the forces.
    Fixed,
}

/// Which of the boundaries handed to the law carried a step's impulse: indices into the slice given
/// to [`crate::apply_all`] (0 for [`Boundary::apply`]). [`crate::impulse_shares`] divides the impulse
/// among them, so that a load on each boundary can be reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carriers {
    /// no boundary: the node was left untouched.
    None,
    /// one boundary carried it all: the node ended on that face.
    One(usize),
    /// (3D) the two boundaries of the edge the node ended on.
    Two(usize, usize),
    /// the pressed boundaries together: the node was pinned in a corner.
    Corner,
}

/// The result of constraining one node over one step.
///
/// "Work" is measured against the trial state v\* = v + a Δt, the velocity the node would have had
/// without the boundary: `normal_work + friction_work = ½ m |v*|² − ½ m |v^L|²` exactly (up to rounding),
/// each term ≥ 0. With the solver counting the forces' input as ½ m |v*|² − ½ m |v|² per node
/// (= f·(v + ½ a Δt) Δt), the node's kinetic energy balance closes: ½ m |v^L|² = ½ m |v|² + input −
/// `normal_work` − `friction_work`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactOutcome {
    /// constrained nodal acceleration a^c, m/s², such that v^L = v + a^c Δt (to rounding).
    pub acceleration: Vector,
    /// constrained end-of-step velocity v^L, m/s.
    pub velocity: Vector,
    /// how the node ended the step.
    pub status: ContactStatus,
    /// energy removed by the tangential law this step, J, ≥ 0: ½ m ((v\*·t)² − (v^L·t)²).
    pub friction_work: f64,
    /// energy removed by the normal constraint this step, J, ≥ 0: ½ m (v\*·n)², the kinetic energy of
    /// the removed normal velocity.
    pub normal_work: f64,
    /// impulse the boundary gave the node this step, N·s: m (v^L − v\*). Divided by Δt it is the
    /// reaction force on the node (the negative of the load on the boundary).
    pub impulse: Vector,
    /// which boundaries carried the impulse.
    pub carriers: Carriers,
}

impl ContactOutcome {
    /// the outcome of a node the boundary does not touch: a and v + a Δt unchanged, no work.
    pub(crate) fn untouched(velocity: Vector, acceleration: Vector, dt: f64) -> Self {
        Self {
            acceleration,
            velocity: velocity + acceleration * dt,
            status: ContactStatus::Separating,
            friction_work: 0.0,
            normal_work: 0.0,
            impulse: Vector::ZERO,
            carriers: Carriers::None,
        }
    }

    /// the outcome of a node brought to rest (pinned in a corner): all removed energy is normal work.
    pub(crate) fn stopped(mass: f64, velocity: Vector, acceleration: Vector, dt: f64) -> Self {
        let trial = velocity + acceleration * dt;
        Self {
            acceleration: -velocity / dt,
            velocity: Vector::ZERO,
            status: ContactStatus::Sticking,
            friction_work: 0.0,
            normal_work: 0.5 * mass * trial.length_squared(),
            impulse: -mass * trial,
            carriers: Carriers::Corner,
        }
    }
}

/// Which tangential law a resolution uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Law {
    /// the full law of a time step: Coulomb friction as configured.
    Step,
    /// the velocity-only constraint after a MUSL remap: Coulomb boundaries act as rollers.
    VelocityOnly,
}

/// One boundary's verdict on a trial velocity. Works in the velocity domain only, so needs no Δt.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Face {
    n: Vector,
    t: Vector,
    /// v\*·n.
    vn_trial: f64,
    /// v\*·t (in 3D the tangential vector v\* − (v\*·n) n).
    vt_trial: Tangential,
    /// the effective coefficient: μ, 0 (roller) or ∞ (rough, fixed).
    mu: f64,
    fixed: bool,
    /// pressed, or fixed.
    pub(crate) engaged: bool,
    /// tangential impulse capacity per unit mass, μ|v\*_n| (∞ for rough and fixed), m/s.
    capacity: f64,
    /// |v\*_t| within the friction capacity.
    stuck: bool,
    /// v^L·t (in 3D the tangential vector of v^L).
    vt_end: Tangential,
    /// |v^L_t|, kept from the arithmetic that made it (the friction work's ≥ 0 rests on it).
    vt_end_magnitude: f64,
}

impl Face {
    /// the verdict of boundary `b` on trial velocity `trial` under `law`.
    pub(crate) fn resolve(b: &Boundary, trial: Vector, law: Law) -> Self {
        let n = b.normal();
        let t = tangent_for(n);
        let vn_trial = trial.dot(n);
        let vt_trial = tangential(trial, n, t);
        let (mu, fixed) = match (b.friction(), law) {
            (Friction::Coulomb { mu }, Law::Step) => (mu, false),
            (Friction::Coulomb { .. }, Law::VelocityOnly) => (0.0, false),
            (Friction::Rough, _) => (f64::INFINITY, false),
            (Friction::Fixed, _) => (f64::INFINITY, true),
        };
        let engaged = fixed || vn_trial < 0.0;
        // Tangential impulse capacity per unit mass; ∞·0 is avoided by testing μ first.
        let capacity = if mu == f64::INFINITY { f64::INFINITY } else { mu * -vn_trial };
        let stuck = engaged && magnitude(vt_trial) <= capacity;
        let (vt_end, vt_end_magnitude) = if !engaged {
            (vt_trial, magnitude(vt_trial))
        } else if stuck {
            (Tangential::default(), 0.0)
        } else {
            // |v*_t| > capacity here, so the difference is > 0 in floating point too: no reversal.
            let left = magnitude(vt_trial) - capacity;
            (direction(vt_trial) * left, left)
        };
        Self {
            n,
            t,
            vn_trial,
            vt_trial,
            mu,
            fixed,
            engaged,
            capacity,
            stuck,
            vt_end,
            vt_end_magnitude,
        }
    }

    /// v^L for an engaged face: the normal component is exactly zero.
    pub(crate) fn end_velocity(&self) -> Vector {
        as_vector(self.vt_end, self.t)
    }

    /// the status of an engaged face.
    fn status(&self) -> ContactStatus {
        if self.fixed {
            ContactStatus::Fixed
        } else if self.stuck {
            ContactStatus::Sticking
        } else {
            ContactStatus::Sliding
        }
    }

    /// the full outcome of an engaged face for a node of mass `mass` (≥ 0) with start-of-step velocity
    /// `v` and trial acceleration `a` over a valid `dt`.
    pub(crate) fn outcome(&self, mass: f64, v: Vector, a: Vector, dt: f64) -> ContactOutcome {
        let (vn, vt) = (v.dot(self.n), tangential(v, self.n, self.t));
        let (an, at) = (a.dot(self.n), tangential(a, self.n, self.t));
        // Eq 17 (and 18 through v^L = v + a^c Δt): the normal velocity ends at zero.
        let an_end = -vn / dt;
        let at_end = if self.stuck {
            -vt / dt
        } else {
            // Eq 16 with the reaction rate r; r = −a_n exactly when v_n = 0.
            let reaction = -(vn / dt + an);
            at - direction(self.vt_trial) * self.mu * reaction
        };
        let velocity = self.end_velocity();
        // v^L − v* from its components, free of the cancellation of subtracting two nearly equal speeds.
        let dvt =
            if self.stuck { -self.vt_trial } else { -direction(self.vt_trial) * self.capacity };
        let vt_trial = magnitude(self.vt_trial);
        let vt_end = self.vt_end_magnitude;
        ContactOutcome {
            acceleration: an_end * self.n + as_vector(at_end, self.t),
            velocity,
            status: self.status(),
            // |v^L_t| ≤ |v*_t| holds in floating point, and squaring is monotone, so this is ≥ 0.
            friction_work: 0.5 * mass * (vt_trial * vt_trial - vt_end * vt_end),
            normal_work: 0.5 * mass * self.vn_trial * self.vn_trial,
            impulse: mass * (-self.vn_trial * self.n + as_vector(dvt, self.t)),
            carriers: Carriers::One(0),
        }
    }
}

/// whether `dt` is a usable time step.
pub(crate) fn valid_dt(dt: f64) -> bool {
    dt.is_finite() && dt > 0.0
}

/// the mass used for work: a negative, NaN or infinite mass reports zero work instead of nonsense.
pub(crate) fn work_mass(mass: f64) -> f64 {
    if mass.is_finite() && mass > 0.0 { mass } else { 0.0 }
}

/// the checks of the `try_apply` functions.
pub(crate) fn validate_step(
    mass: f64,
    velocity: Vector,
    acceleration: Vector,
    dt: f64,
) -> Result<(), ContactError> {
    if !valid_dt(dt) {
        return Err(ContactError::InvalidTimeStep { dt });
    }
    if !(mass.is_finite() && mass >= 0.0) {
        return Err(ContactError::InvalidMass { mass });
    }
    if !(velocity.is_finite() && acceleration.is_finite()) {
        return Err(ContactError::NonFiniteState { velocity, acceleration });
    }
    Ok(())
}

impl Boundary {
    /// The grid-update constraint of one explicit step (eqs 14–17, and 18 for the end-of-step velocity):
    /// node of mass `mass` (kg) with start-of-step velocity `velocity` (m/s) and trial acceleration
    /// `acceleration` (m/s², from f/m) over `dt` (s).
    ///
    /// See the module documentation of this crate for the law. Never panics: a zero, negative or
    /// non-finite `dt` is not a step and leaves the node untouched (use [`Boundary::try_apply`] to have
    /// it reported); a negative or non-finite `mass` reports zero work; non-finite velocity or
    /// acceleration propagate into the outcome.
    pub fn apply(
        &self,
        mass: f64,
        velocity: Vector,
        acceleration: Vector,
        dt: f64,
    ) -> ContactOutcome {
        if !valid_dt(dt) {
            return ContactOutcome::untouched(velocity, acceleration, dt);
        }
        self.step(work_mass(mass), velocity, acceleration, dt)
    }

    /// [`Boundary::apply`], refusing a bad step with a typed error instead of passing it through.
    pub fn try_apply(
        &self,
        mass: f64,
        velocity: Vector,
        acceleration: Vector,
        dt: f64,
    ) -> Result<ContactOutcome, ContactError> {
        validate_step(mass, velocity, acceleration, dt)?;
        Ok(self.step(mass, velocity, acceleration, dt))
    }

    /// the law for a valid `dt` and a work mass ≥ 0.
    fn step(&self, mass: f64, velocity: Vector, acceleration: Vector, dt: f64) -> ContactOutcome {
        let face = Face::resolve(self, velocity + acceleration * dt, Law::Step);
        if face.engaged {
            face.outcome(mass, velocity, acceleration, dt)
        } else {
            ContactOutcome::untouched(velocity, acceleration, dt)
        }
    }

    /// The velocity-only constraint used after a MUSL remap (eq 18): removes an inward normal velocity
    /// (and the tangential one for `Rough`, and everything for `Fixed`); leaves a separating node
    /// untouched. No friction is applied: the step's friction was already applied by
    /// [`Boundary::apply`], and applying it again to the remapped velocity would count it twice.
    pub fn constrain_velocity(&self, velocity: Vector) -> Vector {
        let face = Face::resolve(self, velocity, Law::VelocityOnly);
        if face.engaged { face.end_velocity() } else { velocity }
    }
}
