//! What the run driver reads of a solver, in either dimension: [`Stepper`], implemented once by
//! the plane-strain build (`mpm-solver`) and once by the 3D build (`mpm-solver3d`), so that one
//! driver ([`super::Driver`]) records, checkpoints and ends the runs of both. The build is chosen
//! once, when a scene is dispatched; nothing here is called per particle.

use std::borrow::Cow;
use std::ops::Sub;

use mpm_output::loads::LoadSample;
use mpm_output::vtk;
use mpm_scene::dispatch::{SavedState, SceneModel};
use mpm_scene::file::{VtkField, VtkFormat};
use mpm_solver::{EnergyLedger, RunEnd, StepReport};

use super::{Driver, Wing};

/// a solver error as the run reports it: a particle out of the grid with what to do.
pub(crate) fn describe<Sv: Stepper>(e: &Sv::Error) -> String {
    let hint = if Sv::outside_grid(e) { crate::common::OUTSIDE_HINT } else { "" };
    format!("{e}{hint}")
}

/// A point or vector of the plane or of space, as the driver reads it.
pub(crate) trait Point: Copy + Sub<Output = Self> {
    /// its components, z = 0 in the plane.
    fn xyz(self) -> [f64; 3];
    /// the dot product.
    fn dot_with(self, other: Self) -> f64;
    /// the point moved by `dx` along x (the unwrapping of a periodic pair of sides).
    fn shifted_x(self, dx: f64) -> Self;
}

impl Point for glam::DVec2 {
    fn xyz(self) -> [f64; 3] {
        [self.x, self.y, 0.0]
    }
    fn dot_with(self, other: Self) -> f64 {
        self.dot(other)
    }
    fn shifted_x(mut self, dx: f64) -> Self {
        self.x += dx;
        self
    }
}

impl Point for glam::DVec3 {
    fn xyz(self) -> [f64; 3] {
        self.to_array()
    }
    fn dot_with(self, other: Self) -> f64 {
        self.dot(other)
    }
    fn shifted_x(mut self, dx: f64) -> Self {
        self.x += dx;
        self
    }
}

/// The particles' fields the driver reads (struct of arrays, one entry per particle).
pub(crate) struct View<'a, V> {
    pub(crate) position: &'a [V],
    pub(crate) velocity: &'a [V],
    pub(crate) mass: &'a [f64],
    pub(crate) volume: &'a [f64],
    pub(crate) initial_position: &'a [V],
    pub(crate) material: &'a [u16],
    /// the x shift of each particle through periodic sides (empty without them).
    pub(crate) unwrap: &'a [f64],
}

impl<'a, V: Point> View<'a, V> {
    pub(crate) fn len(&self) -> usize {
        self.position.len()
    }

    /// particle `q`'s position had it never wrapped through periodic sides.
    pub(crate) fn unwrapped_position(&self, q: usize) -> V {
        let x = self.position[q];
        self.unwrap.get(q).map_or(x, |&u| x.shifted_x(u))
    }

    /// every particle's position had it never wrapped (borrowed without periodic sides).
    pub(crate) fn unwrapped(&self) -> Cow<'a, [V]> {
        if self.unwrap.is_empty() {
            Cow::Borrowed(self.position)
        } else {
            Cow::Owned((0..self.len()).map(|q| self.unwrapped_position(q)).collect())
        }
    }
}

/// What one build of the solver offers the driver: its clock, ledger, particles, loads and
/// state, and the run to a time with the driver observing each step.
pub(crate) trait Stepper {
    /// the build's vector (`DVec2` in the plane, `DVec3` in space).
    type Vector: Point;
    /// the build's solver error.
    type Error: std::error::Error;

    fn time(&self) -> f64;
    fn step_count(&self) -> u64;
    fn energy(&self) -> EnergyLedger;
    /// the last step's Δt (s).
    fn last_dt(&self) -> f64;
    fn particles(&self) -> View<'_, Self::Vector>;
    /// the boundaries' loads so far, in the solver's order (`walls.csv`).
    fn loads(&self) -> Vec<LoadSample>;
    /// the solver's state, for a checkpoint.
    fn saved(&self) -> SavedState;
    /// the hash of the solver's state (`summary.json` `state_hash`).
    fn state_hash(&self) -> String;
    /// what left through outflow faces: particles, mass, momentum, energy, when the first left.
    fn outflowed(&self) -> (u64, f64, Vec<f64>, f64, Option<f64>);
    /// a VTK frame of the particles now.
    fn frame(&self, fields: &[VtkField], format: VtkFormat) -> std::io::Result<vtk::Frame>;
    /// whether `e` is a particle leaving the grid (the run's message adds what to do).
    fn outside_grid(e: &Self::Error) -> bool;
    /// whether `e` is an interrupt during the initial state (2D only: the run has not started).
    fn interrupted_initial_state(e: &Self::Error) -> bool;
    /// steps to `end` with `d` observing.
    fn run_to<W: Wing<Vector = Self::Vector>>(
        &mut self,
        end: f64,
        d: &mut Driver<'_, W>,
    ) -> Result<RunEnd, Self::Error>;
    /// one step of at most `cap` (s).
    fn step_within(&mut self, cap: f64) -> Result<StepReport, Self::Error>;
}

/// (the two builds' implementations differ only in their types: one source for both)
macro_rules! stepper {
    ($solver:ident, $grid:ident, $wrap:ident, $frame:ident, $initial_interrupt:expr) => {
        impl<M: SceneModel, S: $grid::ShapeFunctions<N>, const N: usize> Stepper
            for $solver::Solver<M, S, N>
        {
            type Vector = $solver::Vector;
            type Error = $solver::SolverError;

            fn time(&self) -> f64 {
                $solver::Solver::time(self)
            }
            fn step_count(&self) -> u64 {
                $solver::Solver::step_count(self)
            }
            fn energy(&self) -> EnergyLedger {
                $solver::Solver::energy(self)
            }
            fn last_dt(&self) -> f64 {
                self.last_report().dt
            }
            fn particles(&self) -> View<'_, Self::Vector> {
                let p = $solver::Solver::particles(self);
                View {
                    position: &p.position,
                    velocity: &p.velocity,
                    mass: &p.mass,
                    volume: &p.volume,
                    initial_position: &p.initial_position,
                    material: &p.material,
                    unwrap: &p.unwrap,
                }
            }
            fn loads(&self) -> Vec<LoadSample> {
                let v = |v: Self::Vector| v.xyz();
                self.boundary_loads()
                    .iter()
                    .map(|l| LoadSample {
                        impulse: v(l.impulse),
                        normal: l.normal,
                        tangential: v(l.tangential),
                    })
                    .collect()
            }
            fn saved(&self) -> SavedState {
                M::$wrap(self.checkpoint())
            }
            fn state_hash(&self) -> String {
                mpm_output::checkpoint::state_hash(&self.checkpoint())
            }
            fn outflowed(&self) -> (u64, f64, Vec<f64>, f64, Option<f64>) {
                let g = $solver::Solver::outflowed(self);
                (g.particles, g.mass, g.momentum.to_array().to_vec(), g.energy, g.first_time)
            }
            fn frame(&self, fields: &[VtkField], format: VtkFormat) -> std::io::Result<vtk::Frame> {
                let p = $solver::Solver::particles(self);
                vtk::$frame(p, self.materials(), fields, format, $solver::Solver::time(self))
            }
            fn outside_grid(e: &Self::Error) -> bool {
                matches!(e, $solver::SolverError::OutsideGrid { .. })
            }
            fn interrupted_initial_state(e: &Self::Error) -> bool {
                $initial_interrupt(e)
            }
            fn run_to<W: Wing<Vector = Self::Vector>>(
                &mut self,
                end: f64,
                d: &mut Driver<'_, W>,
            ) -> Result<RunEnd, Self::Error> {
                self.run_until(end, d)
            }
            fn step_within(&mut self, cap: f64) -> Result<StepReport, Self::Error> {
                self.step_capped(cap)
            }
        }

        impl<M, S, const N: usize, W> $solver::Observer<M, S, N> for Driver<'_, W>
        where
            M: SceneModel,
            S: $grid::ShapeFunctions<N>,
            W: Wing<Vector = $solver::Vector>,
        {
            fn after_step(
                &mut self,
                solver: &$solver::Solver<M, S, N>,
                report: &StepReport,
            ) -> std::ops::ControlFlow<()> {
                self.stepped(solver, report)
            }

            fn landing(&self, time: f64) -> f64 {
                self.next_landing(time)
            }
        }
    };
}

stepper!(mpm_solver, mpm_grid, wrap, frame, |e: &mpm_solver::SolverError| matches!(
    e,
    mpm_solver::SolverError::InitialStateInterrupted { .. }
));
stepper!(mpm_solver3d, mpm_grid3d, wrap_space, frame_3d, |_: &mpm_solver3d::SolverError| false);
