//! The run's two ends, in either dimension: its driver begun (a new or resumed run, its first
//! records written) and finished (how it ended, the final files and the summary).

use super::*;

impl<'a, W: Wing> Driver<'a, W> {
    /// the driver of a run writing into `dir`, continuing `history` (empty for a new run; a new
    /// run's `stop_at_rest` watch starts empty, a resumed one's from its rows).
    pub(crate) fn begin(
        wing: W,
        dir: Option<&'a Path>,
        history: History,
        opts: &crate::options::RunOptions,
    ) -> Self {
        let rest = match wing.common().stop_at_rest {
            Some(rest) => RestWatch::over(&history.energy, rest.kinetic_fraction),
            None => RestWatch::default(),
        };
        Driver {
            wing,
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
            session: None,
        }
    }

    /// a new run's first records: the dimension's (the initial runout measures, the energy
    /// check's scale, envelopes or maps), then the first series row and frame.
    pub(crate) fn record_start<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
    ) -> Result<(), RunError> {
        self.wing.start(&mut self.history, sv);
        self.record_series(sv);
        self.write_frame(sv)?;
        self.flush_series()
    }

    /// how the run ended, and its message: from the solver's result and why the driver stopped
    /// it (an error's message through `describe`).
    pub(crate) fn status<Sv: Stepper<Vector = W::Vector>>(
        &self,
        result: &Result<RunEnd, Sv::Error>,
        sv: &Sv,
        describe: &dyn Fn(&Sv::Error) -> String,
    ) -> (RunStatus, Option<String>) {
        let c = self.wing.common();
        match (result, self.stop) {
            // (no checkpoint: the run has not started, see `finish`)
            (Err(e), _) if Sv::interrupted_initial_state(e) => {
                (RunStatus::Interrupted, Some(describe(e)))
            }
            (Err(e), _) => (RunStatus::Failed, Some(describe(e))),
            (Ok(RunEnd::Stopped), Some(Stop::StepLimit)) => (
                RunStatus::StepLimit,
                Some(format!(
                    "step limit: {} steps reached at t = {:.6e} s before end_time = {} s (Δt \
                     {:.3e} s); no checkpoint is written: if the run is sound, run the scene \
                     again with a higher `[solver] max_steps`",
                    sv.step_count(),
                    sv.time(),
                    c.end_time,
                    sv.last_dt()
                )),
            ),
            (Ok(RunEnd::Stopped), Some(Stop::AtRest)) => (RunStatus::AtRest, None),
            (Ok(RunEnd::Stopped), Some(Stop::EnergyAlarm)) => {
                (RunStatus::EnergyAlarm, alarm_message(&self.history, c.alarm.threshold))
            }
            (Ok(RunEnd::Stopped), None) => (RunStatus::Interrupted, None),
            // (judged in `finish`, once the final row is in)
            (Ok(RunEnd::EndTime), _) => (RunStatus::Completed, None),
        }
    }

    /// ends the run's files: the checkpoint of an interrupted run, the final series row and
    /// frame, the energy alarm judged on the last state too, the dimension's files (envelopes
    /// or maps, plots) and `summary.json`; returns the summary.
    pub(crate) fn finish<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> Result<RunSummary, RunError> {
        // The checkpoint holds the history as an uninterrupted run has it at this step (the
        // extra row and frame of the stop below are not part of it).
        // (an interrupted initial state has none: a resume would start the run without it)
        if status == RunStatus::Interrupted && error.is_none() {
            self.write_checkpoint(sv)?;
        }
        // the final state: a last series row and frame unless this very step was recorded.
        let (status, error) = self.closing_row(sv, status, error);
        if self.history.frames.last().is_none_or(|f| f.0 < sv.time()) {
            self.write_frame(sv)?;
        }
        self.flush_series()?;
        let summary = self.summary(sv, status, error, threads);
        if let Some(dir) = self.dir {
            // (the summary first: a failure to draw a map or a plot leaves it readable)
            let json = serde_json::to_string_pretty(&summary)
                .map_err(|e| RunError::Setup(format!("cannot encode summary.json: {e}")))?;
            atomic::write(&dir.join("summary.json"), json.as_bytes())?;
            self.wing.files(&self.history, sv, dir, &summary)?;
        }
        Ok(summary)
    }

    /// the summary of the run as it would end now, without ending it: the closing row `finish`
    /// adds (unless this step was recorded) and the energy alarm judged on it, taken on a copy
    /// of the history (a caller stepping the run on finds its records as they were).
    pub(crate) fn summary_now<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> RunSummary {
        let kept = self.history.clone();
        let (status, error) = self.closing_row(sv, status, error);
        let summary = self.summary(sv, status, error, threads);
        self.history = kept;
        summary
    }

    /// a series row of the state now unless this very step was recorded, and how the run ends
    /// judged on it: a completed run or one at rest whose energy alarm tripped (on this row
    /// too) ends with the alarm.
    fn closing_row<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
        status: RunStatus,
        error: Option<String>,
    ) -> (RunStatus, Option<String>) {
        if self.history.energy.last().is_none_or(|row| row.time < sv.time()) {
            self.record_series(sv);
        }
        let threshold = self.wing.common().alarm.threshold;
        match status {
            RunStatus::Completed | RunStatus::AtRest if self.history.alarm_time.is_some() => {
                (RunStatus::EnergyAlarm, alarm_message(&self.history, threshold))
            }
            _ => (status, error),
        }
    }

    /// steps `sv` to `end` with this driver observing, the session's wall time and
    /// particle-steps added to the history.
    pub(crate) fn run<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &mut Sv,
        end: f64,
    ) -> Result<RunEnd, Sv::Error> {
        self.session = Some(Instant::now());
        let result = sv.run_to(end, self);
        self.close_session();
        result
    }

    /// steps `sv` by `steps` steps (fewer when the driver stops it), landing on the output
    /// marks as [`Self::run`] does.
    pub(crate) fn run_steps<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &mut Sv,
        steps: u64,
    ) -> Result<RunEnd, Sv::Error> {
        let steps0 = sv.step_count();
        self.session = Some(Instant::now());
        let result = loop {
            // (once every particle has left through outflow sides there is nothing to step)
            if sv.step_count() - steps0 >= steps || sv.particles().len() == 0 {
                break Ok(RunEnd::EndTime);
            }
            let t = sv.time();
            let landing = self.next_landing(t);
            let cap = if landing > t { landing - t } else { f64::INFINITY };
            match sv.step_within(cap) {
                Err(e) => break Err(e),
                Ok(report) => {
                    if self.stepped(sv, &report).is_break() {
                        break Ok(RunEnd::Stopped);
                    }
                }
            }
        };
        self.close_session();
        result
    }

    /// adds the stepping session's wall time and particle-steps to the history.
    fn close_session(&mut self) {
        if let Some(start) = self.session.take() {
            self.history.wall_time += start.elapsed().as_secs_f64();
        }
        self.history.particle_steps += std::mem::take(&mut self.session_particle_steps);
    }

    /// runs a built solver to the scene's end time and ends the run: a new run's first records
    /// (or a resumed run's files rewritten from its history), the steps, the final files and the
    /// summary. `early` is an error before the first step (a failed initial state); `describe`
    /// words a solver error. A solver error returns [`RunError::Solver`] after the files.
    pub(crate) fn drive<Sv: Stepper<Vector = W::Vector>>(
        mut self,
        sv: &mut Sv,
        fresh: bool,
        early: Option<Sv::Error>,
        describe: &dyn Fn(&Sv::Error) -> String,
        threads: usize,
    ) -> Result<RunSummary, RunError> {
        let end = self.wing.common().end_time;
        self.progress.start(end, sv.time(), sv.step_count());
        if fresh {
            self.record_start(sv)?;
        } else {
            // the rows and frames a stopped session wrote past its checkpoint give way to the
            // checkpoint's
            self.rewrite_outputs()?;
        }
        let result = match early {
            Some(e) => Err(e),
            None => self.run(sv, end),
        };
        self.progress.finish();
        if let Some(e) = self.io_error.take() {
            return Err(e);
        }
        let (status, error) = self.status(&result, sv, describe);
        let summary = self.finish(sv, status, error, threads)?;
        match result {
            Err(e) => Err(RunError::Solver { message: describe(&e), summary: Box::new(summary) }),
            Ok(_) => Ok(summary),
        }
    }
}
