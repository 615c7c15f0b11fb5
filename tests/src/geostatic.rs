//! Drivers of the geostatic initial state's verification cases (`Solver::solve_geostatic`): an
//! elastic layer at rest between frictionless walls (K0, exact), and cohesionless slopes below
//! and above their friction angle.

use mpm_constitutive::ConstitutiveModel;
use mpm_constitutive::{ConeMatch, DruckerPrager, DruckerPragerParams, LinearElastic};
use mpm_contact::Friction;
use mpm_grid::{Bilinear, RegularGrid};
use mpm_solver::generate::Shape;
use mpm_solver::{
    Boundaries, GeostaticReport, GeostaticSettings, Solver, SolverConfig, SolverError, Vector,
};

use crate::{CaseError, block};

/// density of the cases' materials (kg/m³).
pub const DENSITY: f64 = 2000.0;
/// gravity of the cases (m/s²).
pub const GRAVITY: f64 = 9.81;

fn between_walls(ground: Friction) -> SolverConfig {
    SolverConfig {
        boundaries: Boundaries {
            ground: Some(ground),
            left_wall: Some(Friction::Coulomb { mu: 0.0 }),
            right_wall: Some(Friction::Coulomb { mu: 0.0 }),
        },
        gravity: Vector::new(0.0, -GRAVITY),
        ..Default::default()
    }
}

/// What the K0 layer measured.
#[derive(Debug)]
pub struct LayerResult {
    /// the solve's report.
    pub report: GeostaticReport,
    /// max over the particles of |σ_yy − σ_yy,exact| / |σ_yy,exact| (exact at the particle's
    /// cell centre, module docs of the test).
    pub vertical_error: f64,
    /// max over the particles of |σ_xx − K0 σ_yy| / |σ_yy| and the same for σ_zz.
    pub lateral_error: f64,
    /// max |σ_xy| / |σ_yy|.
    pub shear: f64,
}

/// An elastic layer `depth` deep and 1 m wide (E = 50 MPa, ν = `poisson`) on a fixed base
/// between frictionless walls, 0.25 m bilinear cells with 2 × 2 particles, solved for its
/// geostatic state. Exact: σ_yy = −ρ g (H − y), σ_xx = σ_zz = ν/(1 − ν) σ_yy. Linear elements
/// whose particles integrate the shape functions exactly give the 1D solution exactly at the
/// nodes, so a cell's strain is the exact strain's mean over it, the exact value at its centre:
/// every particle of a cell carries the exact stress at the cell's centre.
pub fn k0_layer(depth: f64, poisson: f64) -> Result<LayerResult, CaseError> {
    let h = 0.25;
    let rows = (depth / h).round() as usize + 4;
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(h), [4, rows])
        .map_err(|e| CaseError::Setup(e.to_string()))?;
    let shape = Shape::Rectangle { min: Vector::ZERO, max: Vector::new(1.0, depth) };
    let elastic = LinearElastic::from_young_poisson(5e7, poisson)
        .map_err(|e| CaseError::Setup(e.to_string()))?;
    let particles = block(&shape, h, 2, DENSITY, Vector::ZERO, ());
    let mut s =
        Solver::new(Bilinear(grid), vec![elastic], particles, between_walls(Friction::Fixed))
            .map_err(CaseError::Solver)?;
    let report = s.solve_geostatic(&GeostaticSettings::default()).map_err(CaseError::Solver)?;
    let k0 = poisson / (1.0 - poisson);
    let p = s.particles();
    let (mut vertical_error, mut lateral_error, mut shear) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (x, st) in p.position.iter().zip(&p.stress) {
        let y_c = ((x.y / h).floor() + 0.5) * h;
        let exact = -DENSITY * GRAVITY * (depth - y_c);
        vertical_error = vertical_error.max(((st.yy - exact) / exact).abs());
        lateral_error = lateral_error
            .max(((st.xx - k0 * st.yy) / st.yy).abs())
            .max(((st.zz - k0 * st.yy) / st.yy).abs());
        shear = shear.max((st.xy / st.yy).abs());
    }
    Ok(LayerResult { report, vertical_error, lateral_error, shear })
}

/// What the slope case measured.
#[derive(Debug)]
pub struct SlopeResult {
    /// the solve's report, or its error.
    pub outcome: Result<GeostaticReport, SolverError>,
    /// max over the particles of the stress change a zero strain increment makes (relative to
    /// the stress): 0 to rounding for a state on or inside the yield cone.
    pub outside_cone: f64,
    /// the bits of every particle's stress (xx, yy, zz, xy), for bit-identity checks.
    pub stress_bits: Vec<[u64; 4]>,
}

/// A cohesionless Drucker-Prager slope (E = 10 MPa, ν = 0.3, friction angle `phi`, ψ = 0,
/// plane-strain cone) of angle `beta` (degrees), 1 m high, from x = 1 m to the right wall at
/// x = 4 m, on a fixed base, 0.1 m bilinear cells, 2 × 2 particles, gravity in four load steps.
pub fn sand_slope(beta: f64, phi: f64) -> Result<SlopeResult, CaseError> {
    let h = 0.1;
    let grid = RegularGrid::new(Vector::ZERO, Vector::splat(h), [40, 20])
        .map_err(|e| CaseError::Setup(e.to_string()))?;
    let (height, toe) = (1.0, 1.0);
    let crest = toe + height / beta.to_radians().tan();
    let shape = Shape::Polygon {
        vertices: vec![
            Vector::new(toe, 0.0),
            Vector::new(4.0, 0.0),
            Vector::new(4.0, height),
            Vector::new(crest, height),
        ],
    };
    let sand = DruckerPrager::new(DruckerPragerParams {
        young: 1e7,
        poisson: 0.3,
        cohesion: 0.0,
        friction_angle_deg: phi,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        mixing: 1.0,
        cone_match: ConeMatch::PlaneStrain,
    })
    .map_err(|e| CaseError::Setup(e.to_string()))?;
    let particles = block(&shape, h, 2, DENSITY, Vector::ZERO, sand.initial_state());
    let mut s = Solver::new(Bilinear(grid), vec![sand], particles, between_walls(Friction::Fixed))
        .map_err(CaseError::Solver)?;
    let outcome = s.solve_geostatic(&GeostaticSettings { load_steps: 4, ..Default::default() });
    let p = s.particles();
    let mut outside_cone = 0.0_f64;
    for (st, state) in p.stress.iter().zip(&p.state) {
        let (mut sigma, mut state) = (*st, *state);
        s.materials()[0]
            .update_plane(&mut sigma, &mut state, &mpm_constitutive::PlaneTensor::ZERO, 1.0, None)
            .map_err(|e| CaseError::Setup(e.to_string()))?;
        if st.norm() > 0.0 {
            outside_cone = outside_cone.max((sigma - *st).norm() / st.norm());
        }
    }
    let stress_bits = p.stress.iter().map(|t| [t.xx, t.yy, t.zz, t.xy].map(f64::to_bits)).collect();
    Ok(SlopeResult { outcome, outside_cone, stress_bits })
}
