//! Stage 7, the domain's edges at the end of a step: particles wrapped across periodic sides,
//! taken out through outflow faces (their mass, momentum and energy booked), and the guard that
//! no particle ends a step outside the grid or non-finite.

use mpm_constitutive::ConstitutiveModel;
use mpm_grid::ShapeFunctions;

use crate::error::SolverError;
use crate::math::Real;
use crate::scratch::Ahead;
use crate::solver::Solver;

impl<M: ConstitutiveModel, S: ShapeFunctions<N>, const N: usize> Solver<M, S, N> {
    /// Periodic sides ([`crate::Periodic`]): a particle that has left through one side enters
    /// through the other, `length` further, once its step's grid passes are done (the remap
    /// still needs the unwrapped position). Its potential energy −m g·x jumps by −m g·Δx, which
    /// the ledger books as external work: the endless strip supplies it. Nothing without
    /// periodic sides.
    ///
    /// The gravity of the jump is the mid-step one: during a gravity ramp the ramp's work is
    /// taken at the wrapped end positions, and the two together then book the potential change
    /// the wrap causes at the end of the step.
    pub(crate) fn wrap_periodic(&mut self, dt: Real) {
        let Some(periodic) = self.config.periodic else { return };
        let g = self.config.gravity_at(self.time + 0.5 * dt);
        let p = &mut self.particles;
        if p.unwrap.len() != p.position.len() {
            p.unwrap.resize(p.position.len(), 0.0);
        }
        let mut supplied = 0.0;
        for (i, (x, m)) in p.position.iter_mut().zip(&p.mass).enumerate() {
            let shift = -((x.x - periodic.x_min) / periodic.length).floor() * periodic.length;
            if shift != 0.0 && shift.is_finite() {
                x.x += shift;
                p.unwrap[i] -= shift;
                supplied += -m * g.x * shift;
                // the body force's work counts the unwrapped displacement (advance() sums the
                // wrapped end positions)
                if let Some(b) = self.body_force.get(i) {
                    supplied -= m * b.x * shift;
                }
            }
        }
        self.dissipation.external += supplied;
    }

    /// Outflow faces ([`crate::Outflow`]): at the end of a step, the particles beyond one leave
    /// the run. What they carry out (their mass, momentum, and their kinetic, elastic and
    /// potential energy as [`Solver::energy`] counts them at this time) is booked, so that the
    /// ledger's residual is the same before and after they go (to round-off). The remaining
    /// particles keep their order; the stencils computed for the next step are dropped, and the
    /// guard that follows locates the particles again. Nothing without outflow faces, and one
    /// comparison per particle with them.
    pub(crate) fn leave_through_outflow(&mut self) {
        let outflow = self.config.outflow;
        if !outflow.any() {
            return;
        }
        let p = &self.particles;
        if !p.position.iter().any(|&x| outflow.has_left(x)) {
            return;
        }
        let leaving: Vec<bool> = p.position.iter().map(|&x| outflow.has_left(x)).collect();
        let g = self.config.gravity_at(self.time);
        let mut gone = self.dissipation.outflow;
        for i in (0..p.len()).filter(|&i| leaving[i]) {
            gone.particles += 1;
            gone.mass += p.mass[i];
            gone.momentum += p.mass[i] * p.velocity[i];
            gone.energy += self.kinetic_of(i) + self.strain_of(i) + self.potential_of(i, g);
        }
        gone.first_time.get_or_insert(self.time);
        self.dissipation.outflow = gone;
        let keep: Vec<bool> = leaving.iter().map(|l| !l).collect();
        self.particles.retain(&keep, &mut self.body_force);
        self.scratch.stencils_ahead = None;
        self.scratch.located = false;
        self.next_signal = None;
    }

    /// the end-of-step guard: every particle is still inside the grid (G2P already checked that
    /// positions and velocities are finite). The stress update that ends USL, MUSL and USAVG
    /// found each particle's next stencil, so this costs nothing there; otherwise (USF, or a
    /// particle that left the grid) the next step's `locate` runs now, and the next step then
    /// reuses it. So no step, the last one included, can end with material outside the grid,
    /// and the error names the step that carried it out.
    pub(crate) fn check_inside(&mut self) -> Result<(), SolverError> {
        if self.scratch.stencils_ahead.is_some() {
            return Ok(());
        }
        let step = self.step;
        self.grid_mass_kept = Some(self.scratch.mass.iter().sum());
        self.locate().map_err(|e| match e {
            SolverError::OutsideGrid { particle, position, cause, .. } => {
                SolverError::OutsideGrid { step, particle, position, cause }
            }
            other => other,
        })?;
        // Everything `locate` builds now describes the current positions.
        self.scratch.stencils_ahead = Some(Ahead { changed: false, numbered: true });
        Ok(())
    }
}
