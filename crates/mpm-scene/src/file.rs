//! The scene file's data model: what a user writes in TOML, before validation.
//!
//! Every table refuses unknown fields. Kind-dependent fields (a terrain grid's `profile`, a
//! Drucker-Prager material's `cohesion`, a rectangle's `min`) are optional here and checked
//! against their `kind` or `shape` in `validate/`, which can then say which field is
//! missing or does not belong, with its line and column. `docs/scene-format.md` documents each
//! field with its unit, default and admissible range.
//!
//! Units: SI (m, s, kg, Pa), angles in degrees.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use mpm_solver::{Contact, MassMatrix, Scheme, Transfer};

mod boundary;
mod space;
pub use boundary::BoundarySpec;
pub use space::{
    Axis, SpaceBodySpec, SpaceBoundariesSpec, SpaceFile, SpaceGridSpec, SpaceShapeKind,
    SpaceTables, SpaceWallSpec,
};

mod output;
pub use output::{
    ObservedSpec, OutputSpec, PolylineFile, PolylineSpec, ProbeSpec, ReferenceCurve, VtkField,
    VtkFormat,
};

/// A whole scene file, of either dimension: the tables every scene has and the three whose
/// form depends on its dimension (`D`: the grid, the bodies, the boundaries). [`SceneFile`] is
/// a plane-strain scene's, [`SpaceFile`] a 3D scene's (`[grid] dimension = 3`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, bound = "")]
pub struct SceneFileOf<D: Tables> {
    /// one-line description, shown by `mpm scenes` and `mpm check`.
    #[serde(default)]
    pub title: Option<String>,
    /// the background grid.
    pub grid: D::Grid,
    /// named materials, referred to by `bodies[].material`.
    pub materials: BTreeMap<String, MaterialSpec>,
    /// bodies filled with material points.
    pub bodies: Vec<D::Body>,
    /// boundary friction laws.
    #[serde(default)]
    pub boundaries: D::Boundaries,
    /// time stepping (`gravity` has a component per axis).
    pub solver: SolverSpec,
    /// what to write.
    #[serde(default)]
    pub output: OutputSpec,
    /// the stresses the run starts from (stress-free by default; 2D only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_state: Option<InitialStateSpec>,
    /// plausibility warnings this scene means to have, by name (`mpm check` prints the names).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub silence: Vec<String>,
}

/// The tables of a scene file whose form depends on its dimension.
pub trait Tables {
    /// `[grid]`.
    type Grid: Clone + std::fmt::Debug + PartialEq + Serialize + serde::de::DeserializeOwned;
    /// one `[[bodies]]` entry.
    type Body: Clone + std::fmt::Debug + PartialEq + Serialize + serde::de::DeserializeOwned;
    /// `[boundaries]`.
    type Boundaries: Clone
        + std::fmt::Debug
        + PartialEq
        + Default
        + Serialize
        + serde::de::DeserializeOwned;
}

/// The plane-strain scene's tables.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlaneTables;

impl Tables for PlaneTables {
    type Grid = GridSpec;
    type Body = BodySpec;
    type Boundaries = BoundariesSpec;
}

/// A plane-strain scene file.
pub type SceneFile = SceneFileOf<PlaneTables>;

/// How the initial stresses are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitialStateMethod {
    /// stress-free, gravity at once (the paper's start).
    #[default]
    None,
    /// one implicit quasi-static solve for equilibrium under gravity (`mpm_solver::geostatic`).
    Implicit,
    /// explicit steps from rest with gravity ramped up and held; then the bodies get their own
    /// velocities back.
    GravityRamp,
}

/// `[initial_state]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialStateSpec {
    /// `"none"` (default), `"implicit"` or `"gravity_ramp"`.
    #[serde(default)]
    pub method: InitialStateMethod,
    /// implicit: load steps sharing gravity (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_steps: Option<i64>,
    /// implicit: Newton iterations per load step (default 50).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<i64>,
    /// implicit: equilibrium tolerance ‖R‖/‖f_gravity‖ (default 1e-10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// gravity_ramp: time over which gravity grows from zero (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_time: Option<f64>,
    /// gravity_ramp: time gravity is then held before the run starts (s, default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_time: Option<f64>,
}

/// Kind of background grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GridKind {
    /// terrain-following skewed rectangles over a ground polyline (eqs 19–20).
    Terrain,
    /// regular Cartesian cells.
    Regular,
}

/// What to do with a terrain profile point that is not on a column boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KinkPolicySpec {
    /// move it horizontally to the nearest column boundary.
    Snap,
    /// refuse the scene.
    Reject,
}

/// `[grid]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// `"terrain"` or `"regular"`.
    pub kind: GridKind,
    /// terrain: column width l (m).
    #[serde(default)]
    pub cell_width: Option<f64>,
    /// terrain: row spacing h, measured vertically (m).
    #[serde(default)]
    pub row_height: Option<f64>,
    /// terrain: cell rows above the ground.
    #[serde(default)]
    pub rows: Option<i64>,
    /// terrain: ground polyline `[[x, y], ...]`, x strictly increasing (m), or the section of
    /// a DEM (`{ dem = "slope.asc", from = [x, y], to = [x, y] }`) or a CSV of points.
    #[serde(default)]
    pub profile: Option<PolylineSpec>,
    /// terrain: a rupture surface cut into the profile: the grid's ground is the lower of the
    /// two where this polyline is defined, so that a release mass between the pre-failure
    /// surface and the rupture surface (a `between_profiles` body) rests on the ground.
    #[serde(default)]
    pub rupture_surface: Option<PolylineSpec>,
    /// terrain: `"snap"` (default) or `"reject"`.
    #[serde(default)]
    pub kink_policy: Option<KinkPolicySpec>,
    /// regular: lower-left node `[x, y]` (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub origin: Option<[f64; 2]>,
    /// regular: cell size `[dx, dy]` (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub cell: Option<[f64; 2]>,
    /// regular: number of cells `[nx, ny]`.
    #[serde(default, deserialize_with = "exact::pair")]
    pub cells: Option<[i64; 2]>,
    /// 2 (the default: plane strain in x–y) or 3 (x, y up, z: the scene is read as
    /// [`SpaceFile`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dimension: Option<i64>,
}

/// `[materials.NAME]`: `kind` (a model of the registry, [`crate::materials::KINDS`]),
/// `density` (kg/m³) and the model's parameters, kept as written: the registry reads them
/// as the model's own table, so a new model needs no change here.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MaterialSpec(pub toml::Table);

impl MaterialSpec {
    /// the `kind` as written (`None` when absent or not a string).
    pub fn kind(&self) -> Option<&str> {
        self.0.get("kind").and_then(toml::Value::as_str)
    }

    /// a numeric field (integer or float) as written.
    pub fn number(&self, field: &str) -> Option<f64> {
        match self.0.get(field)? {
            toml::Value::Float(x) => Some(*x),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        }
    }

    /// sets `field` (for studies and tests that vary a material).
    pub fn set(&mut self, field: &str, value: impl Into<toml::Value>) {
        self.0.insert(field.to_string(), value.into());
    }
}

/// Shape of a body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// axis-aligned rectangle `min`–`max`.
    Rectangle,
    /// simple polygon `vertices`.
    Polygon,
    /// rectangle resting on the ground (or any inclined base).
    OnSlope,
    /// a release mass between a `top` and a `bottom` polyline.
    BetweenProfiles,
}

/// `[[bodies]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// optional label.
    #[serde(default)]
    pub name: Option<String>,
    /// name of a `[materials.NAME]` table.
    pub material: String,
    /// `"rectangle"`, `"polygon"`, `"on_slope"` or `"between_profiles"`.
    pub shape: ShapeKind,
    /// rectangle: lower-left corner (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub min: Option<[f64; 2]>,
    /// rectangle: upper-right corner (m).
    #[serde(default, deserialize_with = "exact::pair")]
    pub max: Option<[f64; 2]>,
    /// polygon: vertices in order (m).
    #[serde(default, deserialize_with = "exact::pairs")]
    pub vertices: Option<Vec<[f64; 2]>>,
    /// on_slope: lower corner of the base (m); or give `base_x` to put it on the ground.
    #[serde(default, deserialize_with = "exact::pair")]
    pub base_start: Option<[f64; 2]>,
    /// on_slope: x of the base's lower corner, placed on the ground (m).
    #[serde(default)]
    pub base_x: Option<f64>,
    /// on_slope: inclination of the base from +x (degrees, negative descending to the right);
    /// default: the ground's slope at the base's lower corner.
    #[serde(default)]
    pub angle_deg: Option<f64>,
    /// on_slope: length along the base (m).
    #[serde(default)]
    pub length: Option<f64>,
    /// on_slope: thickness normal to the base (m).
    #[serde(default)]
    pub thickness: Option<f64>,
    /// between_profiles: the upper surface (e.g. the pre-failure ground), x increasing.
    #[serde(default)]
    pub top: Option<PolylineSpec>,
    /// between_profiles: the lower surface (e.g. the rupture surface), x increasing.
    #[serde(default)]
    pub bottom: Option<PolylineSpec>,
    /// particles per cell along each axis (n × n per cell), default 2.
    #[serde(default)]
    pub particles_per_cell: Option<i64>,
    /// initial velocity `[vx, vy]` (m/s), default `[0, 0]`.
    #[serde(default, deserialize_with = "exact::pair")]
    pub velocity: Option<[f64; 2]>,
}

/// `[boundaries]`: absent entries are open (no boundary condition).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundariesSpec {
    /// the ground (terrain) or floor (regular grid).
    #[serde(default)]
    pub ground: Option<BoundarySpec>,
    /// the wall at the grid's first column.
    #[serde(default)]
    pub left_wall: Option<BoundarySpec>,
    /// the wall at the grid's last column.
    #[serde(default)]
    pub right_wall: Option<BoundarySpec>,
    /// the grid's first and last columns are a periodic pair (regular grid, no side walls):
    /// material leaving through one side enters through the other. Default false.
    #[serde(default)]
    pub periodic: bool,
    /// `[[boundaries.walls]]`: walls anywhere (inclined, inside the domain), beside the grid's sides.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallSpec>,
    /// the side walls of a channel across the plane (plane strain only): their width apart and
    /// their friction, which acts through the out-of-plane stress σ_zz.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side_walls: Option<SideWallsSpec>,
}

/// `side_walls = { width = W, friction_angle_deg = δ }` (or `friction = μ_w`): two parallel
/// walls W apart across the plane of the section, each rubbing the material with μ_w |σ_zz|.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideWallsSpec {
    /// the channel's width between the walls (m).
    pub width: f64,
    /// the walls' friction coefficient μ_w.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// the walls' friction angle δ (degrees), μ_w = tan δ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_deg: Option<f64>,
}

/// One `[[boundaries.walls]]` entry: a straight wall from `from` to `to`, the material on its left
/// (walking from `from` to `to`), with a friction law and an optional solid thickness behind it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// one end `[x, y]` (m).
    #[serde(deserialize_with = "exact::required_pair")]
    pub from: [f64; 2],
    /// the other end `[x, y]` (m).
    #[serde(deserialize_with = "exact::required_pair")]
    pub to: [f64; 2],
    /// the friction law, as for the ground.
    pub law: BoundarySpec,
    /// depth of the solid behind the face (m); default: the whole half-plane behind the segment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
}

/// Shape functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeFunctionKind {
    /// bilinear (either grid; the only choice on the terrain grid).
    Bilinear,
    /// uGIMP (regular grid).
    Gimp,
    /// quadratic B-splines (regular grid).
    Bspline,
}

impl ShapeFunctionKind {
    /// the name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ShapeFunctionKind::Bilinear => "bilinear",
            ShapeFunctionKind::Gimp => "gimp",
            ShapeFunctionKind::Bspline => "bspline",
        }
    }

    /// the name in a scene of `dimension` dimensions: `bilinear` is `trilinear` in 3D.
    pub fn name_in(self, dimension: usize) -> &'static str {
        match self {
            ShapeFunctionKind::Bilinear if dimension == 3 => "trilinear",
            other => other.name(),
        }
    }
}

/// Named speed/accuracy settings (see [`crate::presets`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// fastest settings of the table.
    Fast,
    /// the middle ground.
    Balanced,
    /// most accurate settings of the table.
    Accurate,
}

/// `[solver]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// named settings for scheme, shape function and Courant number; explicit fields win.
    #[serde(default)]
    pub preset: Option<Preset>,
    /// `"usl"`, `"musl"`, `"usf"` or `"usavg"` (default).
    #[serde(default)]
    pub scheme: Option<Scheme>,
    /// `"bilinear"` (default), `"gimp"` or `"bspline"`.
    #[serde(default)]
    pub shape_function: Option<ShapeFunctionKind>,
    /// Courant number C in (0, 1], default 0.1; exclusive with `dt`.
    #[serde(default)]
    pub courant: Option<f64>,
    /// fixed time step (s); exclusive with `courant`.
    #[serde(default)]
    pub dt: Option<f64>,
    /// simulated end time (s).
    pub end_time: f64,
    /// gravity `[gx, gy]` (m/s²), default `[0, -9.81]`; `[gx, gy, gz]` in a 3D scene, default
    /// `[0, -9.81, 0]`.
    #[serde(default, deserialize_with = "exact::pair_or_triple")]
    pub gravity: Option<Vec<f64>>,
    /// gravity ramp time (s), default 0.
    #[serde(default)]
    pub gravity_ramp: Option<f64>,
    /// small nodal mass ratio, default 1e-4.
    #[serde(default)]
    pub small_mass_ratio: Option<f64>,
    /// Jaumann stress rate; default on for Drucker-Prager scenes, off for elastic ones.
    #[serde(default)]
    pub objective_stress: Option<bool>,
    /// velocity transfer: `"flip"` (default, the paper's) or `"apic"` (affine; keeps rotation).
    #[serde(default)]
    pub transfer: Option<Transfer>,
    /// the PIC share of a FLIP transfer per step, 0 ≤ β ≤ 1
    /// (`mpm_solver::SolverConfig::pic_fraction`): default 0.001 for granular materials (their
    /// deposits come to rest), 0 for elastic ones and with APIC; not with `pic_relaxation`.
    #[serde(default)]
    pub pic_fraction: Option<f64>,
    /// the PIC share of a FLIP transfer as a relaxation time τ (s): β = 1 − exp(−Δt/τ) each step,
    /// the same damping per second whatever Δt (`mpm_solver::SolverConfig::pic_relaxation`); not
    /// with `pic_fraction`. Default none.
    #[serde(default)]
    pub pic_relaxation: Option<f64>,
    /// how the PIC share is spread over the particles: `"uniform"` (each the same share) or
    /// `"noise"` (each in proportion to the part of its velocity the grid does not see;
    /// `mpm_solver::PicWeighting`). Default `"uniform"`; not with APIC.
    #[serde(default)]
    pub pic_weighting: Option<mpm_solver::PicWeighting>,
    /// below this fraction of its material's reference density a particle is a separated grain
    /// and carries no stress (`mpm_solver::SolverConfig::separation_density`): default 0.5 for
    /// Drucker-Prager, 0 (off) for elastic materials, μ(I) (its own opening) and APIC.
    #[serde(default)]
    pub separation_density: Option<f64>,
    /// end the run early, with status `at_rest`, once the material has come to rest.
    #[serde(default)]
    pub stop_at_rest: Option<StopAtRestSpec>,
    /// when boundary planes hold their nodes: `"surface"` (default: where material touches them)
    /// or `"node"` (the paper's: always).
    #[serde(default)]
    pub contact: Option<Contact>,
    /// the grid's mass matrix: `"lumped"` (default, the paper's) or `"consistent"` (less
    /// numerical dissipation, a linear solve per transfer).
    #[serde(default)]
    pub mass: Option<MassMatrix>,
    /// energy alarm: largest admissible |energy residual| as a fraction of the run's energy scale
    /// (`mpm_solver::EnergyCheck`), default 0.2.
    #[serde(default)]
    pub energy_alarm: Option<f64>,
    /// stop the run when the energy alarm trips (default false: run on, end with status
    /// `energy_alarm`).
    #[serde(default)]
    pub energy_alarm_stop: Option<bool>,
    /// most steps a run may take (default 100 000 000): `mpm check` and `mpm run` refuse a scene
    /// whose initial Δt needs more, and a run that reaches it stops with status `step_limit`.
    #[serde(default)]
    pub max_steps: Option<i64>,
}

/// `[solver] stop_at_rest`: the run ends once the kinetic energy has stayed below
/// `kinetic_fraction` of its peak for `duration` seconds (sampled at every output row).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopAtRestSpec {
    /// largest kinetic energy, as a fraction of the run's peak, that counts as at rest
    /// (default 1e-6).
    #[serde(default)]
    pub kinetic_fraction: Option<f64>,
    /// how long (s) the kinetic energy must stay below it (default 1 s).
    #[serde(default)]
    pub duration: Option<f64>,
}

/// 2-vectors that are exactly two values: serde's arrays read the first two elements of a longer
/// TOML array and ignore the rest (`cell = [0.25, 0.25, 0.25]` was accepted).
mod exact {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer};

    /// `[a, b]` and nothing else.
    pub struct Two<T>(pub [T; 2]);

    impl<'de, T: Deserialize<'de>> Deserialize<'de> for Two<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            let v = Vec::<T>::deserialize(d)?;
            let n = v.len();
            <[T; 2]>::try_from(v).map(Two).map_err(|_| {
                D::Error::custom(format!("expected exactly 2 values [x, y], found {n}"))
            })
        }
    }

    /// an optional `[a, b]`.
    pub fn pair<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<[T; 2]>, D::Error> {
        Ok(Option::<Two<T>>::deserialize(d)?.map(|t| t.0))
    }

    /// a required `[a, b]`.
    pub fn required_pair<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<[T; 2], D::Error> {
        Ok(Two::<T>::deserialize(d)?.0)
    }

    /// `[a, b, c]` and nothing else.
    pub struct Three<T>(pub [T; 3]);

    impl<'de, T: Deserialize<'de>> Deserialize<'de> for Three<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            let v = Vec::<T>::deserialize(d)?;
            let n = v.len();
            <[T; 3]>::try_from(v).map(Three).map_err(|_| {
                D::Error::custom(format!("expected exactly 3 values [x, y, z], found {n}"))
            })
        }
    }

    /// an optional `[a, b, c]`.
    pub fn triple<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<[T; 3]>, D::Error> {
        Ok(Option::<Three<T>>::deserialize(d)?.map(|t| t.0))
    }

    /// a required `[a, b, c]`.
    pub fn required_triple<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<[T; 3], D::Error> {
        Ok(Three::<T>::deserialize(d)?.0)
    }

    /// an optional `[a, b]` or `[a, b, c]` (a vector of the scene's dimension, checked with it).
    pub fn pair_or_triple<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<f64>>, D::Error> {
        let v = Option::<Vec<f64>>::deserialize(d)?;
        match v {
            Some(v) if !(2..=3).contains(&v.len()) => Err(D::Error::custom(format!(
                "expected 2 values [x, y] (3 in a 3D scene), found {}",
                v.len()
            ))),
            other => Ok(other),
        }
    }

    /// an optional list of `[a, b]`.
    pub fn pairs<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<Vec<[T; 2]>>, D::Error> {
        Ok(Option::<Vec<Two<T>>>::deserialize(d)?.map(|v| v.into_iter().map(|t| t.0).collect()))
    }
}
