//! What a node boundary is: a unit normal pointing into the material and a tangential law.
//!
//! Construction validates everything once, so the per-node law in `node_law.rs` never has to.
//! Deserialising a [`Boundary`] goes through the same validation as [`Boundary::new`].

use serde::{Deserialize, Serialize};

use crate::{ContactError, Vector};

/// How far the length of a boundary normal may be from 1 before [`Boundary::new`] refuses it.
///
/// Normals come from geometry (a slope angle, a segment of the ground profile) computed in f64, which
/// is exact to ~1e-16; 1e-9 accepts any normal normalised in f64 or typed with nine digits, and refuses
/// an unnormalised direction such as (1, 1).
pub const NORMAL_LENGTH_TOLERANCE: f64 = 1e-9;

/// Tangential law of a boundary. Frictionless is `Coulomb { mu: 0.0 }` (a roller).
///
/// The three laws are settings of one algorithm, not three code paths: `Rough` is Coulomb friction with
/// an unbounded coefficient, and `Fixed` is `Rough` with the normal constraint made two-sided.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Friction {
    /// Coulomb friction with coefficient μ ≥ 0: the tangential impulse is at most μ times the normal one.
    Coulomb {
        /// friction coefficient μ, dimensionless, finite and ≥ 0.
        mu: f64,
    },
    /// no slip while pressed: a node pressing on the boundary stops; a separating node is free.
    Rough,
    /// the node is fixed in both directions whatever the sign of the normal force.
    Fixed,
}

/// A plane boundary seen by one grid node: unit normal n pointing from the boundary into the material,
/// and the tangential law.
///
/// Only the normal's direction matters: the node is assumed to lie on the boundary (the terrain-following
/// grid puts its bottom row of nodes exactly on the ground, SPEC §2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Boundary {
    normal: Vector,
    friction: Friction,
}

impl Boundary {
    /// a boundary with unit normal `normal` (pointing into the material) and tangential law `friction`.
    ///
    /// The normal must be finite, non-zero and of length 1 within [`NORMAL_LENGTH_TOLERANCE`]; it is
    /// then renormalised to full f64 precision. A Coulomb coefficient must be finite and ≥ 0.
    pub fn new(normal: Vector, friction: Friction) -> Result<Self, ContactError> {
        if !normal.is_finite() {
            return Err(ContactError::NonFiniteNormal { normal });
        }
        let length = normal.length();
        if length == 0.0 {
            return Err(ContactError::ZeroNormal { normal });
        }
        if (length - 1.0).abs() > NORMAL_LENGTH_TOLERANCE {
            return Err(ContactError::NonUnitNormal { normal, length });
        }
        let friction = match friction {
            Friction::Coulomb { mu } if !(mu.is_finite() && mu >= 0.0) => {
                return Err(ContactError::InvalidFrictionCoefficient { normal, mu });
            }
            // -0.0 passes the test above; store +0.0 so that equal boundaries compare and print equal.
            Friction::Coulomb { mu } => Friction::Coulomb { mu: mu + 0.0 },
            other => other,
        };
        Ok(Self { normal: normal / length, friction })
    }

    /// a Coulomb boundary with μ = tan(`angle_deg`), the friction angle in degrees, in [0°, 90°).
    pub fn with_friction_angle_deg(normal: Vector, angle_deg: f64) -> Result<Self, ContactError> {
        if !(angle_deg.is_finite() && (0.0..90.0).contains(&angle_deg)) {
            return Err(ContactError::InvalidFrictionAngle { normal, angle_deg });
        }
        Self::new(normal, Friction::Coulomb { mu: angle_deg.to_radians().tan() })
    }

    /// the unit normal n, pointing from the boundary into the material.
    pub fn normal(&self) -> Vector {
        self.normal
    }

    #[cfg(not(feature = "dim3"))]
    /// the unit tangent t = (n_y, −n_x): n turned by −90°, so that (t, n) is right-handed like (x, y).
    ///
    /// For the ground (n = +y) the tangent is +x; on a slope rising to the right it points up-slope.
    pub fn tangent(&self) -> Vector {
        tangent_of(self.normal)
    }

    /// the tangential law.
    pub fn friction(&self) -> Friction {
        self.friction
    }
}

#[cfg(not(feature = "dim3"))]
/// the tangent convention of [`Boundary::tangent`] for a unit normal `n`.
pub(crate) fn tangent_of(n: Vector) -> Vector {
    Vector::new(n.y, -n.x)
}

/// the serialised form of a boundary, validated on the way in.
#[derive(Deserialize)]
struct BoundaryDef {
    normal: Vector,
    friction: Friction,
}

impl<'de> Deserialize<'de> for Boundary {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let def = BoundaryDef::deserialize(deserializer)?;
        Boundary::new(def.normal, def.friction).map_err(serde::de::Error::custom)
    }
}
