//! Coulomb-friction node boundaries for MPM grids on planes of any inclination (Abe, Johansson &
//! Konagai 2005, §3(1), eqs 14–18; SPEC §3).
//!
//! The crate works on one grid node at a time: its mass, its start-of-step velocity, its trial
//! acceleration f/m, and the boundaries it lies on. It knows nothing of particles, materials or the
//! grid's geometry.
//! A [`Wall`] places a boundary: a plane through a point or a segment of one, at any position and
//! angle, with the rule that says which material points touch it.
//! [`RigidSlide`] is the law's analytic reference: a rigid block sliding on one plane (eqs 21–22).
//!
//! ```
//! use mpm_contact::{Boundary, ContactStatus, Friction, Vector};
//!
//! // A node sliding at 10 m/s on the ground (μ = 0.3) under gravity decelerates at exactly μg.
//! let ground = Boundary::new(Vector::Y, Friction::Coulomb { mu: 0.3 })?;
//! let out = ground.apply(1.0, Vector::new(10.0, 0.0), Vector::new(0.0, -9.81), 1e-3);
//! assert_eq!(out.status, ContactStatus::Sliding);
//! assert_eq!(out.acceleration, Vector::new(-0.3 * 9.81, 0.0));
//! assert_eq!(out.velocity.y, 0.0);
//! # Ok::<(), mpm_contact::ContactError>(())
//! ```
//!
//! # Glossary
//! - n: unit normal of a boundary, pointing **from the boundary into the material** (the paper's eq 14
//!   is written with the opposite sign convention; the physics, "the node presses on the wall", is the
//!   same). t = (n_y, −n_x): unit tangent, (t, n) right-handed; for the ground (n = +y) t = +x.
//!   In 3D (the `dim3` build, `mpm-contact3d`) a boundary has a tangent *plane*, and every
//!   tangential quantity below is the vector in that plane (v_t = v − (v·n) n), its magnitude
//!   taking the place of |v_t| and its direction that of sign(v_t): the same law, eqs 15–16
//!   written for a vector.
//! - μ: Coulomb friction coefficient, dimensionless; `Rough` and `Fixed` behave as μ = ∞.
//! - m (kg), v (m/s), a (m/s²), Δt (s): nodal mass, start-of-step velocity, trial acceleration
//!   (f_int + f_ext)/m (eq 4), time step.
//! - a_n = a·n, a_t = a·t (and likewise v_n, v_t): normal and tangential components. a_n < 0 means the
//!   material pushes into the boundary.
//! - v\* = v + a Δt: the trial end-of-step velocity, what eq 5 gives without the boundary.
//! - v^L: the constrained end-of-step velocity (eq 5's v_i^L); a^c the constrained acceleration, with
//!   v^L = v + a^c Δt, so the solver moves particles with v^L (eq 6) and updates their velocity with
//!   a^c (eq 7) consistently.
//! - Units SI throughout; work in J.
//!
//! # The law (one boundary)
//! This crate implements the **impulse (velocity) form**: the boundary acts on v\*.
//! 1. Contact (eq 14): the node presses when v\*_n < 0. For a node already at rest normally (v_n = 0,
//!    which every node that was in contact the step before is) v\*_n = a_n Δt, so this is the paper's
//!    acceleration criterion a_n < 0; for a node arriving at the boundary (v_n < 0 after particle-to-grid)
//!    it also catches the approach that a trial acceleration alone would miss. A separating node is
//!    returned untouched.
//! 2. Normal (eqs 17, 18): v^L_n = 0 and a^c_n = −v_n/Δt, which is eq 17's a^c_n = 0 when v_n = 0.
//! 3. Tangent (eqs 15, 16): the friction impulse per unit mass is at most μ|v\*_n|, which is μ|a_n|Δt when
//!    v_n = 0. If |v\*_t| ≤ μ|v\*_n| the node sticks exactly (v^L_t = 0); otherwise it slides with
//!    a^c_t = a_t − sign(v\*_t) μ|a_n| and |v^L_t| = |v\*_t| − μ|v\*_n| > 0 with the sign of v\*_t: friction
//!    never reverses the tangential velocity, and a sticking node stays stuck while |a_t| ≤ μ|a_n|.
//! 4. `Rough` is μ = ∞ (a pressing node stops); `Fixed` is `Rough` engaged whatever the sign of v\*_n.
//!
//! # Relation to the paper's acceleration form
//! Eqs 15–16 decide sliding from the start-of-step v_t and decelerate by μ|a_n| along −sign(v_t),
//! sticking the node if that would reverse v_t (as CB-Geo and NairnMPM do). When v_n = 0 and either
//! v_t = 0 or sign(v\*_t) = sign(v_t), the two forms give identical a^c and v^L (the tests check this on
//! the analytic cases and on random inputs). They differ only when the applied tangential acceleration
//! alone reverses v_t within one step: the acceleration form then stops the node, the impulse form lets
//! it start back at the reduced rate; both are first-order accurate in Δt there, and the impulse form is
//! the one whose friction can be shown never to add kinetic energy relative to v\*.
//!
//! # Work
//! Measured against the trial state v\*: `normal_work` = ½ m (v\*·n)² is the kinetic energy of the removed
//! normal velocity and `friction_work` = ½ m ((v\*·t)² − (v^L·t)²) that of the removed tangential
//! velocity; both are ≥ 0 and they sum to ½ m |v\*|² − ½ m |v^L|². A node resting on the ground under
//! gravity therefore reports `normal_work` = ½ m (g_n Δt)² per step, balanced by the same trial input
//! ½ m |v\*|² − ½ m |v|² that the solver's ledger must count for it.
//!
//! # Corners
//! [`apply_all`] and [`constrain_velocity_all`] handle a node on several boundaries (a box corner, a
//! wall meeting the ground, a kink of the ground profile) by an active set, deterministically:
//! a `Fixed` boundary decides alone; otherwise the single-boundary results of the pressed boundaries
//! are tried, most pressed first, and the first one that does not enter any other boundary is taken;
//! if none qualifies the node is pinned and stops. For frictionless boundaries this is exactly the
//! Euclidean projection of v\* onto the admissible cone {v : v·n_k ≥ 0}, so a fast node crossing a
//! gentle kink keeps sliding instead of stopping merely because it presses on both sides.

mod boundary;
mod corner;
mod error;
mod node_law;
mod sliding;
mod wall;

/// The vector type of the crate: a 2D f64 vector (x, y), SI units.
#[cfg(not(feature = "dim3"))]
pub type Vector = glam::DVec2;
/// The vector type of the crate's 3D build (`mpm-contact3d`): a 3D f64 vector (x, y, z), SI units.
#[cfg(feature = "dim3")]
pub type Vector = glam::DVec3;

pub use boundary::{Boundary, Friction, NORMAL_LENGTH_TOLERANCE};
pub use corner::{
    FEASIBILITY_TOLERANCE, apply_all, constrain_velocity_all, impulse_shares, try_apply_all,
};
pub use error::ContactError;
pub use node_law::{Carriers, ContactOutcome, ContactStatus};
pub use sliding::RigidSlide;
pub use wall::{TOUCH_TOLERANCE, Wall};
