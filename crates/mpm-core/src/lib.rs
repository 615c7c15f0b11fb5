//! What both builds of the MPM solver share, compiled once (Abe, Johansson & Konagai 2005).
//!
//! The solver's source is built twice, for plane strain (`mpm-solver`) and for space
//! (`mpm-solver3d`). What does not depend on the dimension lives here, once, and both builds
//! re-export it, so that a front end driving either build handles one `Scheme`, one
//! `EnergyLedger`, one `StepReport`:
//! - [`settings`]: the update scheme (USL, MUSL, USF, USAVG), the velocity transfer, the contact
//!   rule, the mass matrix, the time-step control with its default and its bound (eq 13), the
//!   periodic sides and the side walls of plane strain;
//! - [`EnergyLedger`]: the energies of one instant (SPEC §5), and [`EnergyCheck`], the size of
//!   a run's energy error against the energy it can move around;
//! - [`StepReport`], [`BranchCounts`] and [`RunEnd`]: what a step and a run tell their observer;
//! - [`timestep`]: the stable Δt (eq 13) from the fastest signal and speed.
//!
//! Conventions: SI units, `f64`. Equation numbers refer to the paper.

mod ledger;
mod report;
pub mod settings;
pub mod timestep;

pub use ledger::{EnergyCheck, EnergyLedger};
pub use report::{BranchCounts, RunEnd, StepReport};
pub use settings::{
    BadTimeStep, Contact, DEFAULT_COURANT, DEFAULT_SMALL_MASS_RATIO, MAX_COURANT, MassMatrix,
    Periodic, PicWeighting, Real, STANDARD_GRAVITY, Scheme, SideWalls, TimeStep, Transfer,
};
pub use timestep::{StepLimit, displacement_dt, stable_dt};
