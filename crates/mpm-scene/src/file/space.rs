//! The 3D scene file (`[grid] dimension = 3`): the same TOML format with 3-vectors, a regular
//! grid, bodies as boxes, cylinders and prisms, and the grid's faces as boundaries (not its top). The
//! materials, `[solver]` and `[output]` tables are the 2D ones (`gravity` has three
//! components).
//!
//! Axes: x, y up (gravity along −y by default), z. The grid's faces: `ground` (y = y₀, or the
//! DEM's surface on a terrain grid), `left_wall` and `right_wall` (x = x₀, x₁), `back_wall` and
//! `front_wall` (z = z₀, z₁); the top is open.

use serde::{Deserialize, Serialize};

use super::{BoundarySpec, GridKind, SceneFileOf, Tables, exact};

/// A 3D scene's tables.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpaceTables;

impl Tables for SpaceTables {
    type Grid = SpaceGridSpec;
    type Body = SpaceBodySpec;
    type Boundaries = SpaceBoundariesSpec;
}

/// A whole 3D scene file: the materials, `[solver]` (`gravity` with three components) and
/// `[output]` tables are the 2D ones; `[initial_state]` is refused by validation (2D only).
pub type SpaceFile = SceneFileOf<SpaceTables>;

/// `[grid]` of a 3D scene: a regular grid (`origin`, `cell`, `cells`) or the terrain-following
/// grid over a DEM (`dem`, `from`, `to`, `plan_cell`, `layer_height`, `layers`).
///
/// On a terrain grid, model coordinates are map coordinates: x = map x (east), y = height,
/// z = −map y (north is −z, as in the hazard maps).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceGridSpec {
    /// 3.
    pub dimension: i64,
    /// `"regular"` or `"terrain"`.
    pub kind: GridKind,
    /// regular: the lowest node `[x, y, z]` (m).
    #[serde(default, deserialize_with = "exact::triple", skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// regular: cell size `[dx, dy, dz]` (m).
    #[serde(default, deserialize_with = "exact::triple", skip_serializing_if = "Option::is_none")]
    pub cell: Option<[f64; 3]>,
    /// regular: number of cells `[nx, ny, nz]`.
    #[serde(default, deserialize_with = "exact::triple", skip_serializing_if = "Option::is_none")]
    pub cells: Option<[i64; 3]>,
    /// terrain: the DEM (ESRI ASCII `.asc` or GeoTIFF `.tif`), relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dem: Option<String>,
    /// terrain: the plan's south-west corner, map coordinates `[x, y]` (m).
    #[serde(default, deserialize_with = "exact::pair", skip_serializing_if = "Option::is_none")]
    pub from: Option<[f64; 2]>,
    /// terrain: the plan's north-east corner, map coordinates `[x, y]` (m).
    #[serde(default, deserialize_with = "exact::pair", skip_serializing_if = "Option::is_none")]
    pub to: Option<[f64; 2]>,
    /// terrain: the plan cells' side (m); `to − from` is a whole number of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan_cell: Option<f64>,
    /// terrain: the node layers' spacing, measured vertically (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_height: Option<f64>,
    /// terrain: cell layers above the ground.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers: Option<i64>,
    /// terrain: a rupture-surface raster (as `dem`): the ground is the lower of the DEM and
    /// it wherever it has a height; a `shape = "release"` body fills what lies between.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rupture: Option<String>,
    /// terrain: a release area, a polygon in map coordinates `[[x, y], ...]` (m): the ground
    /// at the lattice nodes inside it is cut `release_depth` below the DEM.
    #[serde(default, deserialize_with = "exact::pairs", skip_serializing_if = "Option::is_none")]
    pub release_polygon: Option<Vec<[f64; 2]>>,
    /// terrain: the release area's depth, measured vertically (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release_depth: Option<f64>,
}

/// Shape of a 3D body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpaceShapeKind {
    /// axis-aligned box `min`–`max`.
    Box,
    /// circular cylinder: `base` (centre of one end), `direction` (of its axis), `radius`,
    /// `height`.
    Cylinder,
    /// a polygon `vertices` extruded along `axis` from `from` to `to`.
    Prism,
    /// (terrain grids) the release volume: everything between the grid's ground, cut into the
    /// DEM by `[grid] rupture` or `release_polygon` and `release_depth`, and the DEM's surface.
    Release,
}

/// A coordinate axis (`"x"`, `"y"`, `"z"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// x.
    X,
    /// y (up).
    Y,
    /// z.
    Z,
}

/// `[[bodies]]` of a 3D scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceBodySpec {
    /// optional label.
    #[serde(default)]
    pub name: Option<String>,
    /// name of a `[materials.NAME]` table.
    pub material: String,
    /// `"box"`, `"cylinder"` or `"prism"`.
    pub shape: SpaceShapeKind,
    /// box: lowest corner `[x, y, z]` (m).
    #[serde(default, deserialize_with = "exact::triple")]
    pub min: Option<[f64; 3]>,
    /// box: highest corner (m).
    #[serde(default, deserialize_with = "exact::triple")]
    pub max: Option<[f64; 3]>,
    /// cylinder: centre of its base disc (m).
    #[serde(default, deserialize_with = "exact::triple")]
    pub base: Option<[f64; 3]>,
    /// cylinder: direction of its axis (any length but zero), default `[0, 1, 0]` (upright).
    #[serde(default, deserialize_with = "exact::triple")]
    pub direction: Option<[f64; 3]>,
    /// cylinder: radius (m).
    #[serde(default)]
    pub radius: Option<f64>,
    /// cylinder: length along its axis (m).
    #[serde(default)]
    pub height: Option<f64>,
    /// prism: the polygon's vertices in the other two coordinates, in axis order (`[y, z]` for
    /// `axis = "x"`, `[x, z]` for `"y"`, `[x, y]` for `"z"`) (m).
    #[serde(default, deserialize_with = "exact::pairs")]
    pub vertices: Option<Vec<[f64; 2]>>,
    /// prism: the axis it is extruded along.
    #[serde(default)]
    pub axis: Option<Axis>,
    /// prism: where it starts along `axis` (m).
    #[serde(default)]
    pub from: Option<f64>,
    /// prism: where it ends along `axis` (m).
    #[serde(default)]
    pub to: Option<f64>,
    /// particles per cell along each axis (n × n × n per cell), default 2.
    #[serde(default)]
    pub particles_per_cell: Option<i64>,
    /// initial velocity `[vx, vy, vz]` (m/s), default zero.
    #[serde(default, deserialize_with = "exact::triple")]
    pub velocity: Option<[f64; 3]>,
}

/// `[boundaries]` of a 3D scene: absent faces are open.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceBoundariesSpec {
    /// the floor (y = y₀).
    #[serde(default)]
    pub ground: Option<BoundarySpec>,
    /// the face x = x₀.
    #[serde(default)]
    pub left_wall: Option<BoundarySpec>,
    /// the face x = x₁.
    #[serde(default)]
    pub right_wall: Option<BoundarySpec>,
    /// the face z = z₀.
    #[serde(default)]
    pub back_wall: Option<BoundarySpec>,
    /// the face z = z₁.
    #[serde(default)]
    pub front_wall: Option<BoundarySpec>,
    /// the faces x = x₀ and x = x₁ are a periodic pair (no left or right wall). Default false.
    #[serde(default)]
    pub periodic: bool,
    /// `[[boundaries.walls]]`: planes anywhere, beside the grid's faces.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<SpaceWallSpec>,
}

/// One `[[boundaries.walls]]` entry of a 3D scene: the plane through `point` with normal
/// `normal` (pointing into the material; normalised), the solid filling everything behind it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceWallSpec {
    /// a point of the plane `[x, y, z]` (m).
    #[serde(deserialize_with = "exact::required_triple")]
    pub point: [f64; 3],
    /// its normal, into the material (any length but zero).
    #[serde(deserialize_with = "exact::required_triple")]
    pub normal: [f64; 3],
    /// the friction law, as for the ground.
    pub law: BoundarySpec,
}
