//! Explicit plane-strain Material Point Method time stepping (Abe, Johansson & Konagai 2005, §2–§4).
//!
//! This crate composes three independent layers into time steps:
//! - [`mpm_grid`]: where particles are on the grid and their shape functions S_ip, G_ip;
//! - [`mpm_constitutive`]: how stress responds to a strain increment;
//! - [`mpm_contact`]: what Coulomb-friction boundaries do to a node.
//!
//! The caller owns the scene: a grid with its shape functions, the materials, the [`Particles`] and
//! a [`SolverConfig`]. [`Solver`] owns only scratch memory and runs the stages listed in the
//! [`solver`] module, in the order its [`Scheme`] gives (USL, MUSL, USF, USAVG).
//!
//! Conventions: SI units, `f64`, plane strain in x–y with a unit thickness, **tension-positive**
//! stress and strain. Equation numbers refer to the paper.
//!
//! ```
//! use mpm_constitutive::{LinearElastic, PlaneTensor};
//! use mpm_grid::{Bilinear, RegularGrid};
//! use mpm_solver::{generate, NewParticle, Particles, Solver, SolverConfig, Vector};
//!
//! // A 1 m × 1 m elastic block in free fall on a 0.25 m grid, 2 × 2 particles per cell.
//! let grid = RegularGrid::new(Vector::new(0.0, 0.0), Vector::splat(0.25), [8, 16]).unwrap();
//! let material = LinearElastic::from_young_poisson(1e6, 0.3).unwrap();
//! let mut particles = Particles::default();
//! let block = generate::Shape::Rectangle { min: Vector::new(0.5, 2.0), max: Vector::new(1.5, 3.0) };
//! for seed in generate::fill(&block, 0.125) {
//!     particles.push(NewParticle {
//!         position: seed.position,
//!         velocity: Vector::ZERO,
//!         volume: seed.area,
//!         density: 1000.0,
//!         stress: PlaneTensor::ZERO,
//!         state: (),
//!         material: 0,
//!         body: 0,
//!     });
//! }
//! let mut solver = Solver::new(Bilinear(grid), vec![material], particles, SolverConfig::default())
//!     .unwrap();
//! solver.run_until(0.1, &mut ()).unwrap();
//! // Free flight: the momentum is m g t to rounding.
//! let p = solver.particles();
//! let expected = p.total_mass() * -9.81 * 0.1;
//! assert!((p.momentum().y - expected).abs() < 1e-10 * expected.abs());
//! ```

pub mod config;
mod consistent;
pub mod energy;
pub mod error;
#[cfg(not(feature = "dim3"))]
pub mod generate;
/// Particle generation in 3D: boxes, cylinders and prisms.
#[cfg(feature = "dim3")]
#[path = "generate3d.rs"]
pub mod generate;
#[cfg(not(feature = "dim3"))]
pub mod geostatic;
pub mod loads;
pub mod math;
mod par;
pub use par::{PARTICLES_PER_THREAD, useful_threads};
pub mod particles;
mod polygon;
mod report;
mod scratch;
mod setup;
mod signal;
pub mod solver;
mod stages;
#[cfg(test)]
mod testing;

pub use config::{
    BadTimeStep, Boundaries, Contact, DEFAULT_COURANT, DEFAULT_SMALL_MASS_RATIO, MAX_COURANT,
    MassMatrix, Outflow, Periodic, PicWeighting, STANDARD_GRAVITY, Scheme, SideWalls, SolverConfig,
    TimeStep, Transfer,
};
pub use energy::{Dissipation, EnergyCheck, EnergyLedger, Outflowed};
pub use error::{Field, SolverError};
#[cfg(not(feature = "dim3"))]
pub use geostatic::{GeostaticReport, GeostaticSettings, NewtonIteration, SettleReport};
pub use loads::{BoundaryLoad, SIDE_NAMES, SIDES};
pub use math::{DIM, Matrix, Real, Stress, Vector};
pub use particles::{NewParticle, Particles};
pub use report::{BranchCounts, Checkpoint, RunEnd, StepReport};
pub use setup::estimated_bytes;
pub use signal::{StepLimit, displacement_dt, stable_dt};
pub use solver::{END_SLACK, Observer, Solver, reached};
