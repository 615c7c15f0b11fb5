//! A boundary's friction law as written in a scene (`[boundaries]`, `[[boundaries.walls]]`):
//! a name or a one-field table, read and written by hand so that messages list every form.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// One boundary's law: `{ friction = μ }`, `{ friction_angle_deg = φ_b }`, `"rough"`, `"fixed"`
/// or `"frictionless"`; or, on a side face of the grid, `"outflow"` (material leaves the run
/// through it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundarySpec {
    /// Coulomb friction with coefficient μ.
    Friction(f64),
    /// Coulomb friction with μ = tan φ_b (degrees).
    FrictionAngleDeg(f64),
    /// no slip while pressed.
    Rough,
    /// fixed in both directions.
    Fixed,
    /// μ = 0 (a roller).
    Frictionless,
    /// no boundary: material that crosses the face leaves the run (side faces of the grid only).
    Outflow,
}

const BOUNDARY_NAMES: &[&str] = &["rough", "fixed", "frictionless", "outflow"];
const BOUNDARY_KEYS: &[&str] = &["friction", "friction_angle_deg"];

impl<'de> Deserialize<'de> for BoundarySpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = BoundarySpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "\"rough\", \"fixed\", \"frictionless\", { friction = μ }, \
                     { friction_angle_deg = φ } or (a side face) \"outflow\"",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<BoundarySpec, E> {
                match v {
                    "rough" => Ok(BoundarySpec::Rough),
                    "fixed" => Ok(BoundarySpec::Fixed),
                    "frictionless" => Ok(BoundarySpec::Frictionless),
                    "outflow" => Ok(BoundarySpec::Outflow),
                    other => Err(E::unknown_variant(other, BOUNDARY_NAMES)),
                }
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<BoundarySpec, A::Error> {
                let mut out = None;
                while let Some(key) = map.next_key::<String>()? {
                    let value: f64 = match key.as_str() {
                        "friction" | "friction_angle_deg" => map.next_value()?,
                        other => return Err(de::Error::unknown_field(other, BOUNDARY_KEYS)),
                    };
                    if out.is_some() {
                        return Err(de::Error::custom(
                            "give either `friction` or `friction_angle_deg`, not both",
                        ));
                    }
                    out = Some(if key == "friction" {
                        BoundarySpec::Friction(value)
                    } else {
                        BoundarySpec::FrictionAngleDeg(value)
                    });
                }
                out.ok_or_else(|| de::Error::missing_field("friction"))
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for BoundarySpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let single = |s: S, key: &str, v: f64| {
            let mut m = s.serialize_map(Some(1))?;
            m.serialize_entry(key, &v)?;
            m.end()
        };
        match *self {
            BoundarySpec::Friction(mu) => single(s, "friction", mu),
            BoundarySpec::FrictionAngleDeg(a) => single(s, "friction_angle_deg", a),
            BoundarySpec::Rough => s.serialize_str("rough"),
            BoundarySpec::Fixed => s.serialize_str("fixed"),
            BoundarySpec::Frictionless => s.serialize_str("frictionless"),
            BoundarySpec::Outflow => s.serialize_str("outflow"),
        }
    }
}
