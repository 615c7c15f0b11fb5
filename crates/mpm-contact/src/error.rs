//! Typed errors of the contact layer: a bad boundary description, or a bad step handed to `try_apply`.
//!
//! Construction errors name the boundary by the normal it was given, so a scene with several boundaries
//! can tell which one is wrong; the solver adds its own name or index on top.

use crate::Vector;

/// Everything that can be wrong with a boundary or with the state of one step.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ContactError {
    /// the normal has zero length, so it has no direction.
    #[error("boundary with normal {normal}: the normal is zero and has no direction")]
    ZeroNormal {
        /// the normal as given.
        normal: Vector,
    },
    /// a component of the normal is NaN or infinite.
    #[error("boundary with normal {normal}: the normal is not finite")]
    NonFiniteNormal {
        /// the normal as given.
        normal: Vector,
    },
    /// the normal's length differs from 1 by more than [`crate::NORMAL_LENGTH_TOLERANCE`].
    #[error(
        "boundary with normal {normal}: the normal has length {length}, not 1 within 1e-9 \
         (normalise it before building the boundary)"
    )]
    NonUnitNormal {
        /// the normal as given.
        normal: Vector,
        /// its Euclidean length.
        length: f64,
    },
    /// the Coulomb friction coefficient is negative, NaN or infinite.
    #[error(
        "boundary with normal {normal}: friction coefficient mu = {mu} must be finite and >= 0 \
         (use Friction::Rough for a no-slip boundary)"
    )]
    InvalidFrictionCoefficient {
        /// the boundary's normal.
        normal: Vector,
        /// the coefficient as given.
        mu: f64,
    },
    /// the friction angle is outside [0°, 90°) or not finite.
    #[error(
        "boundary with normal {normal}: friction angle {angle_deg} degrees must lie in [0, 90) \
         (use Friction::Rough for a no-slip boundary)"
    )]
    InvalidFrictionAngle {
        /// the boundary's normal.
        normal: Vector,
        /// the angle as given, degrees.
        angle_deg: f64,
    },
    /// a point of a wall is NaN or infinite.
    #[error("wall through {point}: the point is not finite")]
    NonFinitePoint {
        /// the point as given.
        point: Vector,
    },
    /// a wall segment's two ends coincide, so it has no direction.
    #[error(
        "wall segment from {from} to {to}: the two ends coincide (or are too far apart to measure)"
    )]
    DegenerateSegment {
        /// the segment's first end.
        from: Vector,
        /// the segment's second end.
        to: Vector,
    },
    /// the thickness of a wall's solid is zero, negative or NaN.
    #[error("wall segment from {from} to {to}: thickness {thickness} m must be positive")]
    InvalidThickness {
        /// the segment's first end.
        from: Vector,
        /// the segment's second end.
        to: Vector,
        /// the thickness as given, m.
        thickness: f64,
    },
    /// the time step is zero, negative, NaN or infinite.
    #[error("contact step: time step dt = {dt} s must be finite and positive")]
    InvalidTimeStep {
        /// the time step as given, s.
        dt: f64,
    },
    /// the nodal mass is negative, NaN or infinite.
    #[error("contact step: nodal mass {mass} kg must be finite and >= 0")]
    InvalidMass {
        /// the mass as given, kg.
        mass: f64,
    },
    /// the nodal velocity or acceleration has a NaN or infinite component.
    #[error(
        "contact step: nodal velocity {velocity} m/s or acceleration {acceleration} m/s^2 is not finite"
    )]
    NonFiniteState {
        /// the start-of-step velocity as given, m/s.
        velocity: Vector,
        /// the trial acceleration as given, m/s².
        acceleration: Vector,
    },
}
