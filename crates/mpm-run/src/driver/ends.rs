//! The 2D run's two ends: its driver begun (a new or resumed run, its output files opened, its
//! first records written) and finished (how it ended, the final files and the summary).

use super::*;

impl<'a> Driver<'a> {
    /// the driver of a run of `scene` writing into `dir`, continuing `history` (empty for a new
    /// run; a new run's `stop_at_rest` watch starts empty, a resumed one's from its rows).
    pub(crate) fn begin(
        scene: &'a Scene,
        dir: Option<&'a Path>,
        history: History,
        initial: Option<InitialStateSummary>,
        opts: &RunOptions,
    ) -> Self {
        let rest = match scene.resolved().stop_at_rest {
            Some(rest) => RestWatch::over(&history.energy, rest.kinetic_fraction),
            None => RestWatch::default(),
        };
        Driver {
            initial,
            scene,
            dir,
            history,
            flushed: Flushed::default(),
            progress: opts.progress.clone(),
            interrupt: opts.interrupt.clone(),
            stop_after: opts.stop_after,
            io_error: None,
            stop: None,
            rest,
            session_particle_steps: 0.0,
        }
    }

    /// a new run's first records: the envelopes, the initial runout measures, the energy check's
    /// scale, the first series row and frame.
    pub(crate) fn record_start<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let r = self.scene.resolved();
        if r.output.envelope {
            let column = r.grid.column_width();
            let mut e = Envelope::new(&r.ground, column);
            observe(&mut e, r, solver);
            self.history.envelope = Some(e);
        }
        let m0 = self.metrics(solver);
        self.history.initial = Some(m0);
        self.history.edges = edge_watch(r);
        let f = Flow::of(r, solver.particles());
        let top = f.initial_position.iter().copied().max_by(|a, b| a.y.total_cmp(&b.y));
        self.history.crown = top.map(|c| [c.x, c.y, 0.0]);
        let p = solver.particles();
        self.history.energy_check = Some(EnergyCheck::new(
            &solver.energy(),
            &p.position,
            &p.mass,
            r.config.gravity.length(),
            |x| ground_height(&r.ground, x.x),
        ));
        self.record_series(solver);
        self.write_frame(solver)?;
        self.flush_series()
    }

    /// how the run ended, and its message: from the solver's result and why the driver stopped
    /// it (an error's message through `describe`).
    pub(crate) fn status<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        result: &Result<RunEnd, SolverError>,
        solver: &Solver<M, S, N>,
        describe: &dyn Fn(&SolverError) -> String,
    ) -> (RunStatus, Option<String>) {
        let r = self.scene.resolved();
        match (result, self.stop) {
            // (no checkpoint: the run has not started, see `finish`)
            (Err(e @ SolverError::InitialStateInterrupted { .. }), _) => {
                (RunStatus::Interrupted, Some(describe(e)))
            }
            (Err(e), _) => (RunStatus::Failed, Some(describe(e))),
            (Ok(RunEnd::Stopped), Some(Stop::StepLimit)) => (
                RunStatus::StepLimit,
                Some(format!(
                    "step limit: {} steps reached at t = {:.6e} s before end_time = {} s (Δt \
                     {:.3e} s); no checkpoint is written: if the run is sound, run the scene \
                     again with a higher `[solver] max_steps`",
                    solver.step_count(),
                    solver.time(),
                    r.end_time,
                    solver.last_report().dt
                )),
            ),
            (Ok(RunEnd::Stopped), Some(Stop::AtRest)) => (RunStatus::AtRest, None),
            (Ok(RunEnd::Stopped), Some(Stop::EnergyAlarm)) => {
                (RunStatus::EnergyAlarm, alarm_message(&self.history, r.alarm.threshold))
            }
            (Ok(RunEnd::Stopped), None) => (RunStatus::Interrupted, None),
            // (judged in `finish`, once the final row is in)
            (Ok(RunEnd::EndTime), _) => (RunStatus::Completed, None),
        }
    }

    /// ends the run's files: the checkpoint of an interrupted run, the final series row and
    /// frame, the energy alarm judged on the last state too, the envelopes, plots and
    /// `summary.json`; returns the summary.
    pub(crate) fn finish<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> Result<RunSummary, RunError> {
        let r = self.scene.resolved();
        // The checkpoint holds the history as an uninterrupted run has it at this step (the
        // extra row and frame of the stop below are not part of it).
        // (an interrupted initial state has none: a resume would start the run without it)
        if status == RunStatus::Interrupted && error.is_none() {
            self.write_checkpoint(solver)?;
        }
        // the final state: a last series row and frame unless this very step was recorded.
        let t = solver.time();
        if self.history.energy.last().is_none_or(|row| row.time < t) {
            self.record_series(solver);
        }
        if self.history.frames.last().is_none_or(|f| f.0 < t) {
            self.write_frame(solver)?;
        }
        // The final row may trip the alarm: a run is judged on its last state too.
        let (status, error) = match status {
            RunStatus::Completed | RunStatus::AtRest if self.history.alarm_time.is_some() => {
                (RunStatus::EnergyAlarm, alarm_message(&self.history, r.alarm.threshold))
            }
            _ => (status, error),
        };
        self.flush_series()?;
        let summary = self.summary(solver, status, error, threads);
        if let Some(dir) = self.dir {
            self.envelope_files(solver)?;
            self.plots(solver)?;
            let json = serde_json::to_string_pretty(&summary)
                .map_err(|e| RunError::Setup(format!("cannot encode summary.json: {e}")))?;
            atomic::write(&dir.join("summary.json"), json.as_bytes())?;
        }
        Ok(summary)
    }
}
