//! `[output]` of a scene file: frames and their fields, probes, reference curves, observed
//! deposits and their polylines.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::exact;

/// A point-data field of the VTK output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtkField {
    /// Cauchy stress, full 3×3 tensor (Pa).
    Stress,
    /// mean stress p = tr σ / 3 (Pa, tension positive).
    Pressure,
    /// velocity (m/s).
    Velocity,
    /// displacement from the initial position (m).
    Displacement,
    /// equivalent plastic strain ε̄ᵖ.
    PlasticStrain,
    /// body index.
    Body,
    /// material index.
    Material,
    /// density (kg/m³).
    Density,
}

impl VtkField {
    /// every field, in output order.
    pub const ALL: [VtkField; 8] = [
        VtkField::Stress,
        VtkField::Pressure,
        VtkField::Velocity,
        VtkField::Displacement,
        VtkField::PlasticStrain,
        VtkField::Body,
        VtkField::Material,
        VtkField::Density,
    ];

    /// (VTK type size in bytes, components) of the field's point-data array.
    pub fn layout(self) -> (usize, usize) {
        match self {
            VtkField::Stress => (8, 9),
            VtkField::Velocity | VtkField::Displacement => (8, 3),
            VtkField::Pressure | VtkField::PlasticStrain | VtkField::Density => (8, 1),
            VtkField::Body | VtkField::Material => (4, 1),
        }
    }
}

/// How the VTK frames store their arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtkFormat {
    /// raw little-endian values appended after the XML (the default: fast and exact).
    #[default]
    Binary,
    /// the raw values compressed with zlib in blocks (smaller files, slower to write).
    Compressed,
    /// decimal text, one array per element (for reading or diffing frames as text).
    Ascii,
}

impl VtkFormat {
    /// the name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            VtkFormat::Binary => "binary",
            VtkFormat::Compressed => "compressed",
            VtkFormat::Ascii => "ascii",
        }
    }

    /// approximate size (bytes) of one frame of `particles` particles with `fields`: what the
    /// memory check before a run charges for the frame being written.
    pub fn frame_bytes(self, particles: usize, fields: &[VtkField]) -> u64 {
        let n = particles as u64;
        // points (3 × Float64), connectivity and offsets (Int64)
        let geometry = 24 + 8 + 8;
        let point_data: u64 = fields
            .iter()
            .map(|&f| {
                let (size, components) = f.layout();
                (size * components) as u64
            })
            .sum();
        match self {
            // about 60 bytes of points and cells plus 35 per field value group
            VtkFormat::Ascii => 400 + (60 + 35 * fields.len() as u64) * n,
            VtkFormat::Binary => 2000 + (geometry + point_data) * n,
            // measured: a frame of the flowing flume compresses to 0.6 of the raw size, a body
            // near rest (regular positions, uniform stress) to far less.
            VtkFormat::Compressed => 2000 + (geometry + point_data) * n * 6 / 10,
        }
    }
}

/// A probe: a particle index, or the particle nearest to a point at t = 0.
#[derive(Clone, Debug, PartialEq)]
pub enum ProbeSpec {
    /// particle index (generation order: bodies in file order, each row by row).
    Index(i64),
    /// the particle nearest to `[x, y]` (`[x, y, z]` in a 3D scene) at t = 0.
    Nearest(Vec<f64>),
}

impl<'de> Deserialize<'de> for ProbeSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ProbeSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a particle index or { nearest = [x, y] } ([x, y, z] in 3D)")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ProbeSpec, E> {
                Ok(ProbeSpec::Index(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ProbeSpec, E> {
                Ok(ProbeSpec::Index(i64::try_from(v).unwrap_or(i64::MAX)))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ProbeSpec, A::Error> {
                let mut out = None;
                while let Some(key) = map.next_key::<String>()? {
                    if key != "nearest" {
                        return Err(de::Error::unknown_field(&key, &["nearest"]));
                    }
                    let point: Vec<f64> = map.next_value()?;
                    if !(2..=3).contains(&point.len()) {
                        return Err(de::Error::custom(format!(
                            "expected 2 values [x, y] (3 in a 3D scene), found {}",
                            point.len()
                        )));
                    }
                    out = Some(ProbeSpec::Nearest(point));
                }
                out.ok_or_else(|| de::Error::missing_field("nearest"))
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for ProbeSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ProbeSpec::Index(i) => s.serialize_i64(*i),
            ProbeSpec::Nearest(p) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("nearest", p)?;
                m.end()
            }
        }
    }
}

/// An analytic curve the probes are compared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceCurve {
    /// eq 21: rigid block sliding on a horizontal boundary with initial speed v0,
    /// x = x0 + v0 t − ½ μ g t² until t = v0/(μg), then constant.
    Abe2005Eq21,
    /// eq 22: rigid block sliding from rest down a slope θ, s = ½ g (sinθ − μ cosθ) t² along
    /// the slope.
    Abe2005Eq22,
}

impl ReferenceCurve {
    /// the name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceCurve::Abe2005Eq21 => "abe2005_eq21",
            ReferenceCurve::Abe2005Eq22 => "abe2005_eq22",
        }
    }
}

/// `[output]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// time between particle frames (s), default end_time / 50.
    #[serde(default)]
    pub interval: Option<f64>,
    /// time between rows of the CSV time series (s), default min(interval, end_time / 200).
    #[serde(default)]
    pub series_interval: Option<f64>,
    /// shorten the steps that would pass an output time (a series row, a frame, a checkpoint)
    /// to end on it, so every record falls on its k·interval mark; default false (records at
    /// the first step on or after each mark).
    #[serde(default)]
    pub exact_times: Option<bool>,
    /// VTK point-data fields, default all.
    #[serde(default)]
    pub fields: Option<Vec<VtkField>>,
    /// write VTK frames, default true.
    #[serde(default)]
    pub vtk: Option<bool>,
    /// `"binary"` (default), `"compressed"` or `"ascii"`.
    #[serde(default)]
    pub vtk_format: Option<VtkFormat>,
    /// write PNG plots, default true.
    #[serde(default)]
    pub plots: Option<bool>,
    /// probe particles.
    #[serde(default)]
    pub probes: Option<Vec<ProbeSpec>>,
    /// analytic curve for the probes.
    #[serde(default)]
    pub reference: Option<ReferenceCurve>,
    /// simulated time between checkpoints (s); none by default (a checkpoint is still written on
    /// Ctrl-C).
    #[serde(default)]
    pub checkpoint_interval: Option<f64>,
    /// write hazard envelopes along the path (`envelope.csv`, `deposit.csv`,
    /// `plots/envelope.png`), default false.
    #[serde(default)]
    pub envelope: Option<bool>,
    /// an observed deposit to compare the run's with (`summary.json` `observed`, the end-of-run
    /// line, `plots/deposit.png`).
    #[serde(default)]
    pub observed: Option<ObservedSpec>,
    /// 3D only: the horizontal direction `[x, y, z]` the runout is measured along (its
    /// vertical component is dropped); default the horizontal part of gravity, else +x.
    #[serde(default, deserialize_with = "exact::triple", skip_serializing_if = "Option::is_none")]
    pub runout_direction: Option<[f64; 3]>,
    /// 3D only: hazard maps per plan cell (`maps/*.asc` and `maps/*.tif`), default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hazard_maps: Option<bool>,
}

/// `[output] observed = { deposit = "observed.csv" }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObservedSpec {
    /// CSV of the observed deposit, relative to the scene file: a header naming `x` and
    /// `thickness` (vertical, m) or `x` and `surface` (the deposit's top elevation, m).
    pub deposit: String,
}

/// A polyline `[[x, y], ...]` (m), written inline or read from a file ([`PolylineFile`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum PolylineSpec {
    /// the points, in order.
    Points(Vec<[f64; 2]>),
    /// a DEM section or a CSV of points.
    File(PolylineFile),
}

impl PolylineSpec {
    /// the inline points, if the polyline is written inline.
    pub fn points(&self) -> Option<&[[f64; 2]]> {
        match self {
            PolylineSpec::Points(p) => Some(p),
            PolylineSpec::File(_) => None,
        }
    }
}

impl From<Vec<[f64; 2]>> for PolylineSpec {
    fn from(p: Vec<[f64; 2]>) -> Self {
        PolylineSpec::Points(p)
    }
}

impl<'de> Deserialize<'de> for PolylineSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = PolylineSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a list of [x, y] points, or a table `{ dem = \"FILE\", from = [x, y], \
                     to = [x, y] }` or `{ csv = \"FILE\" }`",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<Self::Value, A::Error> {
                let v = Vec::<exact::Two<f64>>::deserialize(SeqAccessDeserializer::new(seq))?;
                Ok(PolylineSpec::Points(v.into_iter().map(|t| t.0).collect()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Self::Value, A::Error> {
                PolylineFile::deserialize(MapAccessDeserializer::new(map)).map(PolylineSpec::File)
            }
        }
        d.deserialize_any(V)
    }
}

/// A polyline read from a file, relative to the scene file's directory: either the section of a
/// DEM (`dem`, `from`, `to`, optional `spacing`; x is the distance along the line from `from`,
/// y the ground height) or a CSV of points (`csv`: columns `station` and `z` if its header has
/// them, as `mpm section` writes, else its first two columns as x and y).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolylineFile {
    /// an ESRI ASCII grid (`.asc`) or GeoTIFF (`.tif`) of ground heights.
    #[serde(default)]
    pub dem: Option<String>,
    /// a CSV file of points.
    #[serde(default)]
    pub csv: Option<String>,
    /// dem: the section's start, map coordinates (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub from: Option<[f64; 2]>,
    /// dem: the section's end, map coordinates (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub to: Option<[f64; 2]>,
    /// dem: station spacing (m); default the grid's column width.
    #[serde(default)]
    pub spacing: Option<f64>,
}
