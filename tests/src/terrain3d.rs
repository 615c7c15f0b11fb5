//! The 3D cases on the terrain-following grid over a DEM (`mpm_grid3d::TerrainGrid`): the
//! ground is the DEM's bilinear surface, gravity is vertical, and the nodes on the ground are
//! held by the planes of the cells they are a corner of.
//!
//! - [`dem_slope`]: a block sliding down a DEM of a 30° plane whose fall line runs 30° from x
//!   towards z (oblique to the lattice): eq 22 along the fall line, nothing across it (the
//!   regular-grid case [`crate::three_d::slope`] tilts gravity instead).
//! - [`flat_dem`]: a flat DEM against the regular 3D grid: the same answer.
//! - [`no_penetration`]: sand dropped and thrown over a DEM of planar cells of many slopes and
//!   orientations; every particle's height above the ground at every step.
//! - [`spinning_block`]: an elastic block spinning and drifting in free flight under APIC, on the
//!   regular grid and over a twisted DEM: its momentum must not change, nor may it be stressed.

use mpm_constitutive::{ConstitutiveModel, LinearElastic};
use mpm_contact3d::Friction;
use mpm_grid3d::{Bilinear, RegularGrid, ShapeFunctions, TerrainGrid, TerrainGridSpec};
use mpm_solver3d::{
    Boundaries, NewParticle, Particles, STANDARD_GRAVITY, Scheme, Solver, SolverConfig, Stress,
    TimeStep, Transfer, Vector,
};

use crate::CaseError;
use crate::abe2005::{E, MU, NU, RHO};
use crate::three_d::{AZIMUTH_DEG, SLOPE_DEG, mass_mean, rigid_path, sand};

fn setup<E: std::fmt::Display>(e: E) -> CaseError {
    CaseError::Setup(e.to_string())
}

/// The heights of `g(x, z)` at the lattice nodes of a plan of `cells` cells of side `cell`
/// from (0, 0).
fn lattice(cells: [usize; 2], cell: f64, g: impl Fn(f64, f64) -> f64) -> Vec<f64> {
    let [nx, nz] = cells;
    (0..=nz)
        .flat_map(|k| (0..=nx).map(move |i| (i, k)))
        .map(|(i, k)| g(i as f64 * cell, k as f64 * cell))
        .collect()
}

/// Particles filling a box given in a frame (e1, e2, e3) from corner `base`: `size` m along
/// each, `spacing` m apart, each of volume spacing³.
fn frame_box<S: Copy>(
    base: Vector,
    frame: [Vector; 3],
    size: [f64; 3],
    spacing: f64,
    velocity: Vector,
    state: S,
) -> Particles<S> {
    let count = size.map(|s| (s / spacing).round() as usize);
    let mut p = Particles::default();
    for a in 0..count[0] {
        for b in 0..count[1] {
            for c in 0..count[2] {
                let at = [a, b, c].map(|n| (n as f64 + 0.5) * spacing);
                let x = base + at[0] * frame[0] + at[1] * frame[1] + at[2] * frame[2];
                p.push(NewParticle {
                    position: x,
                    velocity,
                    volume: spacing.powi(3),
                    density: RHO,
                    stress: Stress::ZERO,
                    state,
                    material: 0,
                    body: 0,
                });
            }
        }
    }
    p
}

/// What [`dem_slope`] measured.
#[derive(Clone, Debug, Default)]
pub struct DemSlope {
    /// (t, simulated (along, across) travel of the centre of mass, eq 22's (along, 0)), m.
    pub samples: Vec<(f64, [f64; 2], [f64; 2])>,
    /// steps taken.
    pub steps: u64,
    /// particles.
    pub particles: usize,
    /// the lowest particle height above the ground over the run, m (centres; > 0: none below).
    pub lowest: f64,
}

impl DemSlope {
    /// the largest |travel − eq 22| / eq 22 along the fall line over the samples.
    pub fn along_error(&self) -> f64 {
        self.samples.iter().map(|(_, s, r)| (s[0] - r[0]).abs() / r[0]).fold(0.0, f64::max)
    }

    /// the largest |travel across the fall line| / travel along it.
    pub fn across_drift(&self) -> f64 {
        self.samples.iter().map(|(_, s, _)| s[1].abs() / s[0].abs()).fold(0.0, f64::max)
    }
}

/// A 1 × 0.5 × 1 m elastic block (E = 1 MPa, ν = 0.3) at rest on a DEM of a 30° plane whose
/// fall line runs 30° from x towards z, μ = 0.3 on the ground, vertical gravity; the terrain
/// grid's plan cells and layers of side `cell`, 2³ particles per cell, USAVG, FLIP, C = 0.1
/// (the paper's numerics); sampled at 1 s and 2 s.
pub fn dem_slope(cell: f64) -> Result<DemSlope, CaseError> {
    let (theta, alpha) = (SLOPE_DEG.to_radians(), AZIMUTH_DEG.to_radians());
    let plan = (10.0 / cell).round() as usize;
    let ground = |x: f64, z: f64| 6.0 - theta.tan() * (x * alpha.cos() + z * alpha.sin());
    let grid = TerrainGrid::new(TerrainGridSpec {
        origin: [0.0, 0.0],
        spacing: [cell, cell],
        cells: [plan, plan],
        heights: lattice([plan, plan], cell, ground),
        layer_height: cell,
        layers: (1.5 / cell).round() as usize,
    })
    .map_err(setup)?;
    // the slope's frame: down the fall line, normal to the plane, across
    let down = Vector::new(theta.cos() * alpha.cos(), -theta.sin(), theta.cos() * alpha.sin());
    let normal = Vector::new(theta.sin() * alpha.cos(), theta.cos(), theta.sin() * alpha.sin());
    let across = Vector::new(-alpha.sin(), 0.0, alpha.cos());
    let base = Vector::new(1.5, ground(1.5, 1.0), 1.0);
    let spacing = cell / 2.0;
    let particles =
        frame_box(base, [down, normal, across], [1.0, 0.5, 1.0], spacing, Vector::ZERO, ());
    let count = particles.len();
    let c0 = mass_mean(&particles, &particles.position);
    let config = SolverConfig {
        scheme: Scheme::Usavg,
        transfer: Transfer::Flip,
        time_step: TimeStep::Courant(0.1),
        gravity: Vector::new(0.0, -STANDARD_GRAVITY, 0.0),
        boundaries: Boundaries { ground: Some(Friction::Coulomb { mu: MU }), ..Default::default() },
        ..Default::default()
    };
    let elastic = LinearElastic::from_young_poisson(E, NU).map_err(setup)?;
    let g = grid.clone();
    let mut s = Solver::new(Bilinear(grid), vec![elastic], particles, config)?;
    let mut r = DemSlope { particles: count, lowest: f64::INFINITY, ..Default::default() };
    for t in [1.0, 2.0] {
        while s.time() < t * (1.0 - 1e-12) {
            s.step_capped(t - s.time())?;
            r.lowest = r.lowest.min(lowest(&g, s.particles()));
        }
        let p = s.particles();
        let d = mass_mean(p, &p.position) - c0;
        r.samples.push((t, [d.dot(down), d.dot(across)], rigid_path(0.0, t)));
    }
    r.steps = s.step_count();
    Ok(r)
}

/// the lowest particle centre's height above the ground, m.
fn lowest<S>(g: &TerrainGrid, p: &Particles<S>) -> f64 {
    p.position.iter().map(|x| x.y - g.ground_height(x.x, x.z)).fold(f64::INFINITY, f64::min)
}

/// What [`flat_dem`] compared.
#[derive(Clone, Debug, Default)]
pub struct FlatDem {
    /// the largest difference of a particle's position between the two grids, m.
    pub position: f64,
    /// the largest difference of a particle's velocity, m/s.
    pub velocity: f64,
    /// steps taken on each.
    pub steps: [u64; 2],
    /// particles.
    pub particles: usize,
}

/// An elastic block thrown at (1, 0, 0.5) m/s across a flat floor with μ = 0.3 for 0.5 s, on a
/// flat DEM and on the regular grid with the same cells (0.1 m, trilinear, USAVG, FLIP): the
/// terrain grid is the regular grid's generalisation, so the two runs must agree to
/// round-off.
pub fn flat_dem() -> Result<FlatDem, CaseError> {
    let cell = 0.1;
    let terrain = TerrainGrid::new(TerrainGridSpec {
        origin: [0.0, 0.0],
        spacing: [cell, cell],
        cells: [30, 20],
        heights: vec![0.0; 31 * 21],
        layer_height: cell,
        layers: 10,
    })
    .map_err(setup)?;
    let regular =
        RegularGrid::new(Vector::ZERO, Vector::splat(cell), [30, 10, 20]).map_err(setup)?;
    let velocity = Vector::new(1.0, 0.0, 0.5);
    let frame = [Vector::X, Vector::Y, Vector::Z];
    let make =
        || frame_box(Vector::new(0.5, 0.0, 0.5), frame, [0.4, 0.3, 0.4], cell / 2.0, velocity, ());
    let config = SolverConfig {
        scheme: Scheme::Usavg,
        transfer: Transfer::Flip,
        time_step: TimeStep::Courant(0.1),
        gravity: Vector::new(0.0, -STANDARD_GRAVITY, 0.0),
        boundaries: Boundaries { ground: Some(Friction::Coulomb { mu: MU }), ..Default::default() },
        ..Default::default()
    };
    let elastic = LinearElastic::from_young_poisson(E, NU).map_err(setup)?;
    fn go<S: ShapeFunctions<8>, M: ConstitutiveModel>(
        shape: S,
        m: M,
        p: Particles<M::State>,
        config: SolverConfig,
    ) -> Result<(Particles<M::State>, u64), CaseError> {
        let mut s = Solver::new(shape, vec![m], p, config)?;
        s.run_until(0.5, &mut ())?;
        Ok((s.particles().clone(), s.step_count()))
    }
    let (a, sa) = go(Bilinear(terrain), elastic, make(), config.clone())?;
    let (b, sb) = go(Bilinear(regular), elastic, make(), config)?;
    let mut r = FlatDem { steps: [sa, sb], particles: a.len(), ..Default::default() };
    for i in 0..a.len() {
        r.position = r.position.max((a.position[i] - b.position[i]).length());
        r.velocity = r.velocity.max((a.velocity[i] - b.velocity[i]).length());
    }
    Ok(r)
}

/// What [`no_penetration`] swept.
#[derive(Clone, Debug, Default)]
pub struct NoPenetration {
    /// the lowest particle centre's height above the ground at any step, m.
    pub lowest: f64,
    /// distinct ground-plane normals the grid's ground nodes carry.
    pub planes: usize,
    /// the largest and smallest slope of those planes (deg).
    pub slopes_deg: [f64; 2],
    /// steps taken.
    pub steps: u64,
    /// particles.
    pub particles: usize,
    /// the centre of mass's horizontal travel, m (that the sand did flow over the kinks).
    pub travel: f64,
}

/// Drucker-Prager sand (the 3D collapse's) dropped from 0.1 m and thrown at 3 m/s along x
/// and 1 m/s along z over a DEM g = f(x) + p(z) + a tilt, f and p piecewise linear with a kink
/// at every lattice line: planar cells of slopes from 17° to 50° in every orientation,
/// ridges and valleys, between frictionless sides. Trilinear, MUSL, FLIP, C = 0.3, μ = 0.4 on
/// the ground, 1.5 s.
pub fn no_penetration() -> Result<NoPenetration, CaseError> {
    let cell = 0.2;
    let [nx, nz] = [30, 20];
    let f = |i: usize| [0.0, 0.12, 0.02, 0.16, 0.05, 0.1][i % 6];
    let p = |k: usize| [0.0, -0.08, 0.1, 0.03, 0.15, 0.06, 0.12][k % 7];
    let heights: Vec<f64> = (0..=nz)
        .flat_map(|k| (0..=nx).map(move |i| f(i) + p(k) - 0.04 * i as f64 + 0.01 * k as f64))
        .collect();
    let grid = TerrainGrid::new(TerrainGridSpec {
        origin: [0.0, 0.0],
        spacing: [cell, cell],
        cells: [nx, nz],
        heights: heights.clone(),
        layer_height: cell,
        layers: 12,
    })
    .map_err(setup)?;
    let mut planes: Vec<Vector> = Vec::new();
    for k in 0..=nz as i64 {
        for i in 0..=nx as i64 {
            for n in grid.ground_planes(i, k).into_iter().flatten() {
                if !planes.iter().any(|q| (*q - n).length() < 1e-12) {
                    planes.push(n);
                }
            }
        }
    }
    let slope = |n: &Vector| n.y.acos().to_degrees();
    let slopes_deg = [
        planes.iter().map(slope).fold(0.0, f64::max),
        planes.iter().map(slope).fold(f64::INFINITY, f64::min),
    ];
    let top = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let material = sand().map_err(setup)?;
    let base = Vector::new(0.6, top + 0.1, 0.8);
    let frame = [Vector::X, Vector::Y, Vector::Z];
    let v0 = Vector::new(3.0, 0.0, 1.0);
    let particles =
        frame_box(base, frame, [1.0, 0.6, 1.0], cell / 2.0, v0, material.initial_state());
    let count = particles.len();
    let c0 = mass_mean(&particles, &particles.position);
    let config = SolverConfig {
        scheme: Scheme::Musl,
        transfer: Transfer::Flip,
        time_step: TimeStep::Courant(0.3),
        gravity: Vector::new(0.0, -STANDARD_GRAVITY, 0.0),
        boundaries: Boundaries {
            ground: Some(Friction::Coulomb { mu: 0.4 }),
            ..Boundaries::all(Friction::Coulomb { mu: 0.0 })
        },
        ..Default::default()
    };
    let g = grid.clone();
    let mut s = Solver::new(Bilinear(grid), vec![material], particles, config)?;
    let mut r = NoPenetration {
        planes: planes.len(),
        slopes_deg,
        particles: count,
        lowest: f64::INFINITY,
        ..Default::default()
    };
    let end = 1.5;
    while s.time() < end * (1.0 - 1e-12) {
        s.step_capped(end - s.time())?;
        r.lowest = r.lowest.min(lowest(&g, s.particles()));
    }
    let p = s.particles();
    let d = mass_mean(p, &p.position) - c0;
    r.travel = (d.x * d.x + d.z * d.z).sqrt();
    r.steps = s.step_count();
    Ok(r)
}

/// The 3D grid a spinning block flies over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpinGrid {
    /// the regular grid (separable sums, trilinear functions)
    Regular,
    /// a terrain grid over a twisted DEM (bilinear cells of slopes up to ~35°, node-by-node sums)
    Twisted,
}

/// What a spinning block did (see [`spinning_block`]).
#[derive(Clone, Copy, Debug)]
pub struct Spin {
    /// steps taken
    pub steps: u64,
    /// the largest |P − P₀| / |P₀| of the linear momentum over the run
    pub momentum: f64,
    /// |H − H₀| / |H₀| of the angular momentum about the centre of mass at the end
    pub angular: f64,
    /// the largest |σ| (Pa) any particle reached over the run
    pub stress: f64,
    /// the impedance stress scale ρ c Ω R (Pa) the stress must stay below
    pub scale: f64,
    /// the final kinetic energy over the initial one
    pub kinetic: f64,
}

/// runs a spinning block's 600 steps and measures them (`spinning_block`).
fn fly<S: ShapeFunctions<8>>(
    mut s: Solver<LinearElastic, S, 8>,
    scale: f64,
) -> Result<Spin, CaseError> {
    let angular = |p: &Particles<()>| {
        let c = mass_mean(p, &p.position);
        (0..p.len()).map(|q| p.mass[q] * (p.position[q] - c).cross(p.velocity[q])).sum()
    };
    let kinetic = |p: &Particles<()>| -> f64 {
        (0..p.len()).map(|q| 0.5 * p.mass[q] * p.velocity[q].length_squared()).sum()
    };
    let (p0, h0, k0): (Vector, Vector, f64) =
        (s.particles().momentum(), angular(s.particles()), kinetic(s.particles()));
    let (mut momentum, mut stress): (f64, f64) = (0.0, 0.0);
    for _ in 0..600 {
        s.step()?;
        let p = s.particles();
        momentum = momentum.max((p.momentum() - p0).length() / p0.length());
        stress = p.stress.iter().map(Stress::norm).fold(stress, f64::max);
    }
    let p = s.particles();
    Ok(Spin {
        steps: s.step_count(),
        momentum,
        angular: (angular(p) - h0).length() / h0.length(),
        stress,
        scale,
        kinetic: kinetic(p) / k0,
    })
}

/// An elastic block (0.6 × 0.4 × 0.6 m, 0.1 m cells, 2³ particles per cell, E = 1 MPa,
/// ρ = 1000 kg/m³) in free flight without gravity, translating at (1, 0.2, −0.5) m/s and spinning
/// at Ω = (0.1, 0.4, 0.2) rad/s, its affine matrices started at the rigid spin, under APIC, the
/// elastic default (no objective rate), Courant 0.3 and no small-mass rule, for 600 steps
/// (0.47 s, about 0.2 rad of turn and 0.56 m of travel: its faces cross node planes many
/// times). Until the light-node rule of APIC's grid to particle (`mpm-solver`, `stages/g2p.rs`)
/// this block inverted a particle at step 33–37 under every scheme, on both grids: the
/// acceleration of a node the block had just reached (f_i / m_i ~ 1/ξ) came back through the
/// affine matrix.
pub fn spinning_block(on: SpinGrid, scheme: Scheme) -> Result<Spin, CaseError> {
    let cell = 0.1;
    let [nx, nz] = [24, 24];
    let heights: Vec<f64> = (0..=nz)
        .flat_map(|k| (0..=nx).map(move |i| (i, k)))
        .map(|(i, k)| {
            let (x, z) = (i as f64 * cell, k as f64 * cell);
            0.3 * x - 0.2 * z + 0.4 * (x - 1.2) * (z - 1.2) + 0.1 * ((i * 7 + k * 3) % 4) as f64
        })
        .collect();
    let grid = TerrainGrid::new(TerrainGridSpec {
        origin: [0.0, 0.0],
        spacing: [cell, cell],
        cells: [nx, nz],
        heights,
        layer_height: cell,
        layers: 30,
    })
    .map_err(setup)?;
    let top = (0..=nz)
        .flat_map(|k| (0..=nx).map(move |i| (i, k)))
        .map(|(i, k)| grid.node_position(mpm_grid3d::NodeId::new(i as i32, 0, k as i32)).y)
        .fold(f64::NEG_INFINITY, f64::max);
    let base = match on {
        SpinGrid::Twisted => Vector::new(0.6, top + 0.4, 0.9),
        SpinGrid::Regular => Vector::new(0.6, 1.0, 0.9),
    };
    let frame = [Vector::X, Vector::Y, Vector::Z];
    let (v0, omega) = (Vector::new(1.0, 0.2, -0.5), Vector::new(0.1, 0.4, 0.2));
    let mut particles = frame_box(base, frame, [0.6, 0.4, 0.6], cell / 2.0, v0, ());
    let centre = mass_mean(&particles, &particles.position);
    // C r = Ω × r
    let spin = mpm_solver3d::Matrix::from_cols(
        omega.cross(Vector::X),
        omega.cross(Vector::Y),
        omega.cross(Vector::Z),
    );
    let mut radius: f64 = 0.0;
    for q in 0..particles.len() {
        let r = particles.position[q] - centre;
        particles.velocity[q] = v0 + omega.cross(r);
        radius = radius.max(r.length());
    }
    particles.affine = vec![spin; particles.len()];
    let config = SolverConfig {
        scheme,
        transfer: Transfer::Apic,
        time_step: TimeStep::Courant(0.3),
        gravity: Vector::ZERO,
        // (the small-mass rule drops momentum at nearly empty nodes: off, to see the scatter's)
        small_mass_ratio: 0.0,
        objective_stress: false,
        ..Default::default()
    };
    let elastic = LinearElastic::from_young_poisson(E, NU).map_err(setup)?;
    let scale = RHO * elastic.dilatational_wave_speed(RHO) * omega.length() * radius;
    match on {
        SpinGrid::Twisted => {
            fly(Solver::new(Bilinear(grid), vec![elastic], particles, config)?, scale)
        }
        SpinGrid::Regular => {
            let grid =
                RegularGrid::new(Vector::ZERO, Vector::splat(cell), [24, 30, 24]).map_err(setup)?;
            fly(Solver::new(Bilinear(grid), vec![elastic], particles, config)?, scale)
        }
    }
}
