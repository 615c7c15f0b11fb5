//! The explicit alternative to the implicit solve: gravity ramped up over an explicit run, held,
//! then the velocities zeroed and the clock restarted.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;

use std::ops::ControlFlow;

use crate::error::SolverError;
use crate::math::{Real, Vector};
use crate::report::{RunEnd, StepReport};
use crate::solver::{Observer, Solver};

/// What the explicit gravity ramp of [`Solver::settle`] left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleReport {
    /// Explicit steps taken.
    pub steps: u64,
    /// Kinetic energy at its end, before the velocities were zeroed (J/m): what the ramp did
    /// not settle.
    pub kinetic_energy: Real,
    /// The fastest particle's speed at its end (m/s).
    pub max_speed: Real,
}

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// The explicit alternative to [`Solver::solve_geostatic`]: steps the scheme from rest with
    /// gravity ramped from zero over `ramp` seconds and held for `hold` more, then starts the run
    /// there: the particles get back the velocities they were given, and clock, step count,
    /// displacement reference and energy ledger restart from the settled state, whose stresses
    /// and positions are kept. The kinetic energy the ramp left is reported (and dropped).
    /// Call before the first step.
    pub fn settle(&mut self, ramp: Real, hold: Real) -> Result<SettleReport, SolverError> {
        if self.step != 0 {
            return Err(SolverError::InvalidSetting {
                name: "initial_state",
                value: self.step as f64,
                expected: "an initial state is settled before the first step",
            });
        }
        if !(ramp.is_finite() && ramp > 0.0 && hold.is_finite() && hold >= 0.0) {
            return Err(SolverError::InvalidSetting {
                name: "initial_state.ramp_time",
                value: ramp,
                expected: "a ramp time > 0 and a settle time ≥ 0 (s)",
            });
        }
        // The ramp settles the material from rest; the bodies' own velocities (a block thrown
        // at t = 0) are given back once it has.
        // (a failed ramp gives the particles back as they were)
        let given = self.particles.clone();
        let declared = std::mem::take(&mut self.particles.velocity);
        let declared_affine = std::mem::take(&mut self.particles.affine);
        self.particles.velocity = vec![Vector::ZERO; declared.len()];
        self.particles.affine = vec![crate::math::Matrix::ZERO; declared_affine.len()];
        self.next_signal = None;
        self.scratch.stencils_ahead = None;
        let own = self.config.gravity_ramp;
        self.config.gravity_ramp = ramp;
        // nothing leaves while the material settles (its arrays are given back whole below);
        // a particle beyond an outflow side leaves at the run's first step
        let outflow = std::mem::take(&mut self.config.outflow);
        let end = match self.interrupt.clone() {
            // stopped between steps by the flag (`Solver::set_interrupt`)
            Some(flag) => self.run_until(ramp + hold, &mut Interrupt(flag)).and_then(|e| match e {
                RunEnd::Stopped => {
                    Err(SolverError::InitialStateInterrupted { method: "gravity_ramp" })
                }
                end => Ok(end),
            }),
            None => self.run_until(ramp + hold, &mut ()),
        };
        self.config.gravity_ramp = own;
        self.config.outflow = outflow;
        if let Err(e) = end {
            *self.particles_mut() = given;
            self.restart_clock();
            return Err(e);
        }
        let kinetic = self.energy().kinetic;
        let p_speed = self.particles.velocity.iter().map(|v| v.length()).fold(0.0, Real::max);
        let report = SettleReport { steps: self.step, kinetic_energy: kinetic, max_speed: p_speed };
        let p = &mut self.particles;
        p.velocity = declared;
        p.affine = declared_affine;
        p.initial_position.clone_from(&p.position);
        // (the run measures its travel from the settled positions, wrapped into the strip)
        p.unwrap.iter_mut().for_each(|u| *u = 0.0);
        self.restart_clock();
        Ok(report)
    }

    /// time, step, last report and dissipation back to those of a run not yet started, and the
    /// ledger's reference to the current stored energy.
    fn restart_clock(&mut self) {
        self.time = 0.0;
        self.step = 0;
        self.last = crate::report::StepReport {
            step: 0,
            time: 0.0,
            dt: 0.0,
            courant: 0.0,
            active_nodes: 0,
            branches: crate::report::BranchCounts::none(M::BRANCHES),
        };
        self.grid_mass_kept = None;
        self.dissipation = crate::energy::Dissipation::default();
        self.loads.fill(crate::BoundaryLoad::default());
        self.next_signal = None;
        self.initial_stored = self.energy().stored();
    }
}

/// The ramp's observer: stops it once the interrupt flag is raised.
struct Interrupt(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Observer<M, S, N> for Interrupt {
    fn after_step(&mut self, _: &Solver<M, S, N>, _: &StepReport) -> ControlFlow<()> {
        if self.0.load(std::sync::atomic::Ordering::Relaxed) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}
