//! The run's observer, one for both dimensions: after each step it records the time series,
//! frames and checkpoints a scene asks for, watches for rest, alarms, limits and interrupts, and
//! at the end writes the final files and the summary.
//!
//! [`Driver`] is generic over a [`Wing`], what one dimension adds: the plane's envelopes along
//! the ground and its analytic probe curves ([`plane::Plane`]), space's hazard maps and runout
//! measured in the vertical plane of the runout direction ([`space::Space`]). It reads the
//! solver through [`Stepper`], which both builds implement; the pair is chosen once, when the
//! scene is dispatched (as CB-Geo registers `MPMExplicit<2>` and `<3>`). Everything a resumed
//! run needs is in its [`History`], so a checkpoint continues to the same bits.

use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_output::csv::{self, EnergyRow, ProbeRow};
use mpm_output::loads::{self, WallSeries};
use mpm_output::{OutputError, atomic, report, vtk};
use mpm_scene::edges::{EdgeContact, Grain};
use mpm_scene::envelope::Envelope;
use mpm_scene::file::{VtkField, VtkFormat};
use mpm_scene::inputs::InputFile;
use mpm_scene::summary::{
    DtStats, EnergyReport, RunStatus, RunSummary, RunoutMetrics, RunoutReport,
};
use mpm_scene::{EnergyAlarm, SectionLine, StopAtRest, Warning};
use mpm_solver::{RunEnd, StepReport};

use crate::error::RunError;
use crate::progress::ProgressSink;

mod ends;
pub(crate) mod plane;
pub(crate) mod space;
mod stepper;

pub(crate) use stepper::{Point, Stepper, View, describe};

/// What the driver reads of a scene of either dimension.
pub(crate) struct Common<'a> {
    pub(crate) origin: &'a str,
    pub(crate) text: &'a str,
    pub(crate) files_dir: Option<&'a str>,
    pub(crate) inputs: &'a [InputFile],
    /// `summary.json` `scene_hash`.
    pub(crate) hash: String,
    pub(crate) end_time: f64,
    pub(crate) max_steps: u64,
    pub(crate) alarm: EnergyAlarm,
    pub(crate) stop_at_rest: Option<StopAtRest>,
    pub(crate) series_interval: f64,
    pub(crate) interval: f64,
    pub(crate) checkpoint_interval: Option<f64>,
    pub(crate) exact_times: bool,
    pub(crate) vtk: bool,
    pub(crate) vtk_format: VtkFormat,
    pub(crate) fields: &'a [VtkField],
    pub(crate) plots: bool,
    /// the particle spacing (m).
    pub(crate) spacing: f64,
    pub(crate) probes: &'a [usize],
    pub(crate) warnings: &'a [Warning],
    pub(crate) scheme: &'static str,
    pub(crate) shape_function: &'static str,
}

/// What one dimension adds to the run's records; its state lives in the [`History`] (the
/// plane's envelopes, space's hazard maps), so that a checkpoint holds it.
pub(crate) trait Wing {
    /// the dimension's vector.
    type Vector: Point;
    /// 2 or 3 (`summary.json` `dimension`, the columns of `walls.csv`).
    const DIMENSION: usize;
    /// the header and the rows of `probes.csv`.
    const PROBES: (&'static str, fn(&mut String, &[ProbeRow]));

    fn common(&self) -> &Common<'_>;
    /// a new run's first records before its first row: the initial runout measures, the
    /// energy check's scale, the source's crown and centre, the envelopes or maps, the watch
    /// over the open sides.
    fn start<Sv: Stepper<Vector = Self::Vector>>(&self, h: &mut History, sv: &Sv);
    /// takes the state after a step into the envelopes or maps (every step).
    fn observe<Sv: Stepper<Vector = Self::Vector>>(&self, h: &mut History, sv: &Sv);
    /// the runout measures now.
    fn metrics<Sv: Stepper<Vector = Self::Vector>>(&self, h: &History, sv: &Sv) -> RunoutMetrics;
    /// the flowing particles as the watch over the open sides sees them.
    fn grains<Sv: Stepper<Vector = Self::Vector>>(&self, sv: &Sv) -> Vec<Grain>;
    /// the flowing particles' mass.
    fn flow_mass<Sv: Stepper<Vector = Self::Vector>>(&self, sv: &Sv) -> f64;
    /// the direction a probe's displacement is measured along.
    fn probe_direction(&self) -> Self::Vector;
    /// the analytic displacement a probe is compared with at time `t` (2D reference curves).
    fn reference(&self, t: f64) -> Option<f64>;
    /// the boundaries `walls.csv` lists: (name, index in the solver's loads).
    fn boundaries(&self) -> Vec<(String, usize)>;
    /// what the dimension adds to the summary: the runout indicators, the comparison with an
    /// observed deposit, the outflow, the initial state, the hazard maps' figures.
    fn complete<Sv: Stepper<Vector = Self::Vector>>(
        &self,
        h: &History,
        sv: &Sv,
        s: &mut RunSummary,
    );
    /// the dimension's final files in `dir` (envelopes or maps, plots).
    fn files<Sv: Stepper<Vector = Self::Vector>>(
        &self,
        h: &History,
        sv: &Sv,
        dir: &Path,
        s: &RunSummary,
    ) -> Result<(), RunError>;
}

/// the summary's message for a tripped energy alarm (`None` if it did not trip).
fn alarm_message(h: &History, threshold: f64) -> Option<String> {
    let t = h.alarm_time?;
    let worst = h.energy_check.unwrap_or_default();
    Some(format!(
        "energy alarm: at t = {t:.4} s the energy residual exceeded {:.1} % of the run's energy \
         scale (`[solver] energy_alarm`); the worst was {:+.1} % at t = {:.4} s. The results are \
         suspect: check the time step, the material's stiffness and the contact settings",
        100.0 * threshold,
        100.0 * worst.worst,
        worst.worst_time
    ))
}

/// The run's observer (see the module's docs).
pub(crate) struct Driver<'a, W> {
    pub(crate) wing: W,
    pub(crate) dir: Option<&'a Path>,
    pub(crate) history: History,
    flushed: Flushed,
    pub(crate) progress: ProgressSink,
    pub(crate) interrupt: Option<Arc<AtomicBool>>,
    pub(crate) stop_after: Option<f64>,
    pub(crate) io_error: Option<RunError>,
    /// why the driver stopped the run, when not on request.
    pub(crate) stop: Option<Stop>,
    /// the kinetic energy's course for `stop_at_rest`, kept as the rows come.
    rest: RestWatch,
    /// particle-steps of this session not yet in the history: the particles of each step
    /// (fewer once some left through outflow sides).
    pub(crate) session_particle_steps: f64,
    /// when the stepping session under way started (its wall time is not yet in the history).
    session: Option<Instant>,
}

/// The peak of the kinetic energy over the series rows so far, and the time of the first row of
/// the trailing run of rows at or below `fraction` of it (`None` when the last row is above).
/// Updated row by row; rebuilt from the rows on resume, so a resumed run decides as the
/// uninterrupted one does.
#[derive(Clone, Copy, Debug, Default)]
struct RestWatch {
    peak: f64,
    since: Option<f64>,
}

impl RestWatch {
    /// the watch after the rows of a history.
    fn over(rows: &[EnergyRow], fraction: f64) -> Self {
        let mut w = Self::default();
        for r in rows {
            w.push(r.time, r.ledger.kinetic, fraction);
        }
        w
    }

    /// takes one row. A rise to a new peak ends any rest; a run that has not moved (zero
    /// peak) is not at rest: it has not started.
    fn push(&mut self, time: f64, kinetic: f64, fraction: f64) {
        self.peak = self.peak.max(kinetic);
        if self.peak > 0.0 && kinetic <= fraction * self.peak {
            self.since.get_or_insert(time);
        } else {
            self.since = None;
        }
    }

    /// whether the kinetic energy has stayed at or below the fraction for `duration` up to `now`.
    fn at_rest(&self, now: f64, duration: f64) -> bool {
        self.since.is_some_and(|t| now - t >= duration)
    }
}

/// Why the driver stopped a run before its end time (other than an interrupt).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stop {
    /// the energy alarm tripped with `energy_alarm_stop = true`.
    EnergyAlarm,
    /// `max_steps` was reached.
    StepLimit,
    /// `stop_at_rest`: the material has come to rest.
    AtRest,
}

/// Rows of each series this session has on disk.
#[derive(Clone, Copy, Debug, Default)]
struct Flushed {
    energy: usize,
    walls: usize,
    probes: usize,
    runout: usize,
}

/// A slot time counts as reached when the clock is within this fraction of the interval of it
/// (round-off of summed steps, never a physical time difference).
pub(crate) const SLOT_SLACK: f64 = 1e-9;

/// index of the last slot k·interval reached at time t.
pub(crate) fn slot(t: f64, interval: f64) -> u64 {
    (t / interval + SLOT_SLACK).floor().max(0.0) as u64
}

/// the next output time after `t` with `[output] exact_times` (the earliest of the next series
/// row, frame and checkpoint marks; infinity without it): where a step must end so that each
/// record falls on its mark.
pub(crate) fn next_mark(t: f64, exact: bool, intervals: &[Option<f64>]) -> f64 {
    if !exact {
        return f64::INFINITY;
    }
    intervals.iter().flatten().map(|&i| (slot(t, i) + 1) as f64 * i).fold(f64::INFINITY, f64::min)
}

/// whether a step ending at `t` was shortened to land on a mark of `intervals` (with
/// `exact_times`): such a step does not count as the run's smallest Δt.
pub(crate) fn on_mark(t: f64, exact: bool, intervals: &[Option<f64>]) -> bool {
    exact
        && intervals.iter().flatten().any(|&i| {
            let k = t / i;
            (k - k.round()).abs() <= SLOT_SLACK
        })
}

impl<W: Wing> Driver<'_, W> {
    /// the marks `[output] exact_times` lands on: series rows, frames, checkpoints.
    fn marks(&self) -> [Option<f64>; 3] {
        let c = self.wing.common();
        [Some(c.series_interval), Some(c.interval), c.checkpoint_interval]
    }

    /// the time the step after `time` must end on (`Observer::landing`).
    pub(crate) fn next_landing(&self, time: f64) -> f64 {
        next_mark(time, self.wing.common().exact_times, &self.marks())
    }

    /// what the driver does after each step (`Observer::after_step`).
    pub(crate) fn stepped<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
        report: &StepReport,
    ) -> ControlFlow<()> {
        let marks = self.marks();
        let c = self.wing.common();
        let (end_time, max_steps) = (c.end_time, c.max_steps);
        let (series_interval, interval) = (c.series_interval, c.interval);
        let checkpoint_interval = c.checkpoint_interval;
        let landed = on_mark(report.time, c.exact_times, &marks);
        let h = &mut self.history;
        // The step that lands on the end time (or on an output mark) is shortened; it does not
        // count as the smallest.
        if (!landed && !mpm_solver::reached(report.time, end_time)) || h.dt_max == 0.0 {
            h.dt_min = h.dt_min.min(report.dt);
        }
        h.dt_max = h.dt_max.max(report.dt);
        if h.dt_first == 0.0 {
            h.dt_first = report.dt;
        }
        self.session_particle_steps += sv.particles().len() as f64;
        self.wing.observe(&mut self.history, sv);
        let t = report.time;
        let series = slot(t, series_interval);
        let frame = slot(t, interval);
        if series > self.history.series_slot {
            self.history.series_slot = series;
            self.record_series(sv);
        }
        if frame > self.history.frame_slot {
            self.history.frame_slot = frame;
            if let Err(e) = self.write_frame(sv).and_then(|()| self.flush_series()) {
                self.io_error = Some(e);
                return ControlFlow::Break(());
            }
        }
        if let Some(every) = checkpoint_interval {
            let c = slot(t, every);
            if c > self.history.checkpoint_slot {
                self.history.checkpoint_slot = c;
                if let Err(e) = self.write_checkpoint(sv) {
                    self.io_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
        }
        self.progress.update(t, report.step);
        if report.step >= max_steps && !mpm_solver::reached(t, end_time) {
            self.stop.get_or_insert(Stop::StepLimit);
        }
        let interrupted = self.interrupt.as_ref().is_some_and(|f| f.load(Ordering::Relaxed));
        if interrupted {
            self.progress
                .warn("interrupted: writing a checkpoint after this step (a second Ctrl-C aborts)");
        }
        if self.stop.is_some() || interrupted || self.stop_after.is_some_and(|s| t >= s) {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    /// a series row: the energy ledger (and its check against the alarm), the rest watch, the
    /// probes, the runout measures, the open sides' watch and the boundaries' loads.
    pub(crate) fn record_series<Sv: Stepper<Vector = W::Vector>>(&mut self, sv: &Sv) {
        let c = self.wing.common();
        let t = sv.time();
        let ledger = sv.energy();
        let h = &mut self.history;
        if let Some(check) = &mut h.energy_check {
            let relative = check.observe(t, &ledger);
            if h.alarm_time.is_none() && relative.abs() > c.alarm.threshold {
                h.alarm_time = Some(t);
                self.progress.warn(&format!(
                    "energy alarm at t = {t:.4} s: |energy residual| is {:.1} % of the energy \
                     scale (threshold {:.1} %)",
                    100.0 * relative.abs(),
                    100.0 * c.alarm.threshold
                ));
                if c.alarm.stop {
                    self.stop = Some(Stop::EnergyAlarm);
                }
            }
        }
        h.energy.push(EnergyRow { time: t, step: sv.step_count(), dt: sv.last_dt(), ledger });
        if let Some(rest) = c.stop_at_rest {
            self.rest.push(t, ledger.kinetic, rest.kinetic_fraction);
            if self.rest.at_rest(t, rest.duration) {
                self.stop.get_or_insert(Stop::AtRest);
            }
        }
        let p = sv.particles();
        let direction = self.wing.probe_direction();
        for (k, &i) in c.probes.iter().enumerate() {
            if i >= p.len() {
                continue;
            }
            // (unwrapped across a periodic pair: the probe follows its particle, not its image)
            let x = p.unwrapped_position(i);
            let u = x - p.initial_position[i];
            h.probes.push(ProbeRow {
                time: t,
                probe: k,
                particle: i,
                position: x.xyz(),
                displacement: u.xyz(),
                velocity: p.velocity[i].xyz(),
                along: u.dot_with(direction),
                reference: self.wing.reference(t),
            });
        }
        let m = self.wing.metrics(h, sv);
        h.runout.push(m);
        if let Some(w) = &mut h.edges {
            w.observe(t, &self.wing.grains(sv), 0.5 * c.spacing);
        }
        if h.walls.is_none() {
            let boundaries = self.wing.boundaries();
            if !boundaries.is_empty() {
                h.walls = Some(WallSeries::new(boundaries, W::DIMENSION));
            }
        }
        if let Some(w) = &mut h.walls {
            w.push(t, &sv.loads());
        }
    }

    pub(crate) fn write_frame<Sv: Stepper<Vector = W::Vector>>(
        &mut self,
        sv: &Sv,
    ) -> Result<(), RunError> {
        let c = self.wing.common();
        let Some(dir) = self.dir.filter(|_| c.vtk) else { return Ok(()) };
        let clock = Instant::now();
        let name = format!("frames/particles_{:06}.vtp", self.history.frames.len());
        let path = dir.join(&name);
        if self.history.frames.is_empty() {
            std::fs::create_dir_all(dir.join("frames"))
                .map_err(|source| OutputError::Io { path: dir.join("frames"), source })?;
        }
        let frame = sv
            .frame(c.fields, c.vtk_format)
            .map_err(|source| RunError::from(OutputError::Io { path: path.clone(), source }))?;
        atomic::write_parts(&path, &frame.parts())?;
        self.history.frames.push((sv.time(), name));
        // The collection is small (a line per frame): rewritten whole, atomically.
        atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.history.frames).as_bytes())?;
        self.history.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// rewrites the files a killed or stopped session may have written past its checkpoint
    /// (rows, a torn last line, frames in the collection) from the history, before a resumed
    /// run continues them.
    pub(crate) fn rewrite_outputs(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        self.flushed = Flushed::default();
        self.flush_series()?;
        if self.wing.common().vtk {
            atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.history.frames).as_bytes())?;
        }
        Ok(())
    }

    /// appends the series rows not yet on disk.
    pub(crate) fn flush_series(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let clock = Instant::now();
        let (h, f) = (&self.history, &mut self.flushed);
        csv::flush(
            &dir.join("energy.csv"),
            csv::ENERGY_HEADER,
            &h.energy,
            &mut f.energy,
            csv::energy,
        )?;
        csv::flush(
            &dir.join("runout.csv"),
            csv::RUNOUT_HEADER,
            &h.runout,
            &mut f.runout,
            csv::runout,
        )?;
        if let Some(w) = &h.walls {
            csv::flush(&dir.join("walls.csv"), &w.header(), &w.rows, &mut f.walls, loads::lines)?;
        }
        if !self.wing.common().probes.is_empty() {
            let (header, lines) = W::PROBES;
            csv::flush(&dir.join("probes.csv"), header, &h.probes, &mut f.probes, lines)?;
        }
        self.history.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// writes `checkpoint.bin` (atomically): the solver state, the scene and the history.
    pub(crate) fn write_checkpoint<Sv: Stepper<Vector = W::Vector>>(
        &self,
        sv: &Sv,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        Ok(checkpoint::write(&dir.join(checkpoint::FILE_NAME), &self.checkpoint(sv))?)
    }

    /// the run now as a checkpoint: the solver state, the scene and the history (with the
    /// wall time and particle-steps of the session under way, so that a resumed run's figures
    /// count it).
    pub(crate) fn checkpoint<Sv: Stepper<Vector = W::Vector>>(&self, sv: &Sv) -> CheckpointFile {
        let c = self.wing.common();
        let mut history = self.history.clone();
        if let Some(start) = self.session {
            history.wall_time += start.elapsed().as_secs_f64();
            history.particle_steps += self.session_particle_steps;
        }
        CheckpointFile::new(c.origin, c.text, c.files_dir, c.inputs, sv.saved(), history)
    }

    /// the run's summary now (`summary.json`), from its history and the solver's state.
    pub(crate) fn summary<Sv: Stepper<Vector = W::Vector>>(
        &self,
        sv: &Sv,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> RunSummary {
        let c = self.wing.common();
        let h = &self.history;
        let (steps, t) = (sv.step_count(), sv.time());
        let gone = sv.outflowed().1;
        let edges =
            h.edges.as_ref().map_or_else(Vec::new, |w| w.reached(self.wing.flow_mass(sv) + gone));
        let mut warnings: Vec<String> = c.warnings.iter().map(ToString::to_string).collect();
        warnings.extend(edges.iter().map(EdgeContact::warning));
        let mut s = RunSummary {
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_origin: c.origin.to_string(),
            scene_hash: c.hash.clone(),
            status,
            error,
            particles: sv.particles().len(),
            scheme: c.scheme.to_string(),
            shape_function: c.shape_function.to_string(),
            steps,
            simulated_time: t,
            end_time: c.end_time,
            dt: DtStats {
                min: if h.dt_min.is_finite() { h.dt_min } else { 0.0 },
                max: h.dt_max,
                mean: if steps > 0 { t / steps as f64 } else { 0.0 },
                first: h.dt_first,
            },
            wall_time_s: h.wall_time,
            particle_steps_per_s: if h.wall_time > 0.0 {
                h.particle_steps / h.wall_time
            } else {
                0.0
            },
            output_time_s: h.output_time,
            threads,
            energy: sv.energy(),
            energy_check: {
                let mut check = h.energy_check.unwrap_or_default();
                EnergyReport {
                    relative_residual: check.observe(t, &sv.energy()),
                    worst_relative_residual: check.worst,
                    worst_time: check.worst_time,
                    alarm_threshold: c.alarm.threshold,
                    alarm_time: h.alarm_time,
                }
            },
            runout: RunoutReport {
                last: h.runout.last().copied().unwrap_or_default(),
                indicators: Default::default(),
            },
            observed: None,
            state_hash: sv.state_hash(),
            initial_state: None,
            warnings,
            dimension: W::DIMENSION as u8,
            hazard_maps: None,
            walls: h.walls.as_ref().map(|w| w.summary(&sv.loads())).unwrap_or_default(),
            outflow: None,
            edges,
        };
        self.wing.complete(h, sv, &mut s);
        s
    }
}

/// `envelope.csv` and `deposit.csv` (with the stations' map coordinates along `section`), the
/// section as `section.geojson`, and with `plots` `plots/envelope.png` (marking `edges`, the
/// stations of the grid's open ends the flow reached).
pub(crate) fn envelope_files(
    dir: &Path,
    e: &Envelope,
    deposit: &[(f64, f64, f64)],
    section: Option<&SectionLine>,
    plots: bool,
    edges: &[f64],
) -> Result<(), RunError> {
    let mut s = csv::header(csv::ENVELOPE_HEADER, section);
    csv::envelope(&mut s, e, section);
    atomic::write(&dir.join("envelope.csv"), s.as_bytes())?;
    let mut s = csv::header(csv::DEPOSIT_HEADER, section);
    csv::deposit(&mut s, deposit, section);
    atomic::write(&dir.join("deposit.csv"), s.as_bytes())?;
    if let Some(line) = section {
        atomic::write(&dir.join("section.geojson"), section_geojson(line).as_bytes())?;
    }
    if plots {
        report::envelope(&dir.join("plots"), e, deposit, edges)?;
    }
    Ok(())
}

/// The section a DEM scene runs along as a GeoJSON feature collection: the line from `from` to
/// `to` in the DEM's map coordinates (no CRS member: a GIS must be given the DEM's), with the
/// DEM's name and the line's length.
pub(crate) fn section_geojson(line: &SectionLine) -> String {
    let length = (line.to[0] - line.from[0]).hypot(line.to[1] - line.from[1]);
    let doc = serde_json::json!({
        "type": "FeatureCollection",
        "features": [{
            "type": "Feature",
            "properties": { "name": "section", "dem": line.dem, "length_m": length },
            "geometry": { "type": "LineString", "coordinates": [line.from, line.to] },
        }],
    });
    format!("{doc:#}\n")
}
