//! What a run reports, whatever front end ran it: [`RunSummary`] (the `mpm` command writes it as
//! `summary.json`) and the runout measures of a flow ([`runout`], [`surface`](crate::surface)), taken from the
//! particles' positions over the ground.
//!
//! Field names are stable: `cargo xtask` and scripts read them.

use mpm_solver::{EnergyLedger, Vector};
use serde::{Deserialize, Serialize};

use crate::ground::{ground_height, surface};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// the end time was reached.
    Completed,
    /// stopped by Ctrl-C or `RunOptions::stop_after`; a checkpoint was written.
    Interrupted,
    /// the solver stopped with an instability (see `error`).
    Failed,
    /// the energy residual exceeded `[solver] energy_alarm` of the run's energy scale (see
    /// `energy_check`): the run went on to its end time (or came to rest, with
    /// `stop_at_rest`), or stopped there with `energy_alarm_stop = true`. Its results are
    /// suspect.
    EnergyAlarm,
    /// the run reached `[solver] max_steps` before its end time.
    StepLimit,
    /// `[solver] stop_at_rest`: the kinetic energy stayed below its stated fraction of the
    /// peak for its stated time, and the run ended there, before its end time.
    AtRest,
}

impl RunStatus {
    /// the process exit code `mpm` ends with (README's table): 0 completed or at rest, 3 failed,
    /// 4 energy alarm, 5 step limit, 130 interrupted (143 when by SIGTERM, which the front end
    /// knows).
    pub fn exit_code(self) -> u8 {
        match self {
            RunStatus::Completed | RunStatus::AtRest => 0,
            RunStatus::Failed => 3,
            RunStatus::EnergyAlarm => 4,
            RunStatus::StepLimit => 5,
            RunStatus::Interrupted => 130,
        }
    }
}

/// The run's energy error against its scale (`mpm_solver::EnergyCheck`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyReport {
    /// residual / scale at the end (negative: energy lost without being booked).
    pub relative_residual: f64,
    /// the residual / scale of largest magnitude over the run (sampled at every series row).
    pub worst_relative_residual: f64,
    /// when it was reached (s).
    pub worst_time: f64,
    /// the alarm threshold (`[solver] energy_alarm`).
    pub alarm_threshold: f64,
    /// when |residual| / scale first exceeded the threshold (s); `None` if it never did.
    pub alarm_time: Option<f64>,
}

/// Statistics of the time steps taken (s).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DtStats {
    /// smallest Δt (the last, shortened step to land on the end time excluded when other steps
    /// exist, and with `[output] exact_times` the steps shortened to land on an output mark).
    pub min: f64,
    /// largest Δt.
    pub max: f64,
    /// mean Δt = simulated time / steps.
    pub mean: f64,
    /// Δt of the first step.
    pub first: f64,
}

/// Runout metrics of the material at one instant (m). Horizontal positions are x coordinates;
/// thickness is measured vertically above the ground.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunoutMetrics {
    /// simulated time (s).
    pub time: f64,
    /// front position of the main mass plus half a particle spacing (m). The main mass: the
    /// particles sorted by x are split wherever two neighbours are more than one cell width
    /// apart; the group with the most mass is the main mass (so a few particles thrown ahead do
    /// not count as the front).
    pub front_x: f64,
    /// tail position of the main mass minus half a particle spacing (m).
    pub tail_x: f64,
    /// largest x of any particle plus half a particle spacing (m), stray particles included.
    pub leading_x: f64,
    /// front travel since t = 0 (m).
    pub front_travel: f64,
    /// largest vertical thickness of the material above the ground over columns of one cell
    /// width: highest particle above the ground plus half a particle spacing (m).
    pub max_thickness: f64,
    /// centre of mass x (m).
    pub com_x: f64,
    /// centre of mass y (m).
    pub com_y: f64,
    /// distance travelled by the centre of mass since t = 0 (m).
    pub com_travel: f64,
    /// speed of the main mass's front: |Σ m v| / Σ m over the particles whose centres lie
    /// within one column width behind the frontmost centre of the main mass (m/s).
    #[serde(default)]
    pub front_speed: f64,
}

/// The load one boundary (a grid side or a declared wall) took over a run (`summary.json` `walls`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WallLoad {
    /// `ground`, `left_wall`, `right_wall` (`back_wall`, `front_wall` in 3D), or `wall_k` for the
    /// k-th `[[boundaries.walls]]` entry.
    pub name: String,
    /// the forces' unit: "N/m" (per metre of thickness, 2D) or "N" (3D); impulses are it times s.
    pub unit: String,
    /// the largest normal load (the material pressing on it), as a mean over a series interval.
    pub peak_normal_force: f64,
    /// when (s): the end of that interval.
    pub peak_normal_time: f64,
    /// the largest shear (friction) load, as a mean over a series interval.
    pub peak_shear_force: f64,
    /// ∫ normal load dt over the run.
    pub normal_impulse: f64,
    /// ∫ force on it dt over the run, as a vector.
    pub impulse: Vec<f64>,
}

/// Everything a run reports, written as `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// version of the `mpm` crate that ran it.
    pub code_version: String,
    /// where the scene came from.
    pub scene_origin: String,
    /// FNV-1a 64 hash of the scene text (hex).
    pub scene_hash: String,
    /// how the run ended.
    pub status: RunStatus,
    /// the solver's message when `status` is `failed`.
    pub error: Option<String>,
    /// number of particles.
    pub particles: usize,
    /// update scheme (USL, MUSL, USF, USAVG).
    pub scheme: String,
    /// shape functions.
    pub shape_function: String,
    /// steps taken (over all sessions of a resumed run).
    pub steps: u64,
    /// simulated time reached (s).
    pub simulated_time: f64,
    /// the scene's end time (s).
    pub end_time: f64,
    /// time-step statistics.
    pub dt: DtStats,
    /// wall-clock time of the stepping, over all sessions (s).
    pub wall_time_s: f64,
    /// particles × steps / wall time.
    pub particle_steps_per_s: f64,
    /// wall-clock time spent writing particle frames and time series, over all sessions (s);
    /// the frames and rows written during the steps are also part of `wall_time_s`.
    #[serde(default)]
    pub output_time_s: f64,
    /// rayon threads used.
    pub threads: usize,
    /// the energy ledger at the end (J per metre of thickness).
    pub energy: EnergyLedger,
    /// the energy residual against the run's energy scale, and the alarm.
    #[serde(default)]
    pub energy_check: EnergyReport,
    /// runout metrics at the end, and the run's runout indicators.
    pub runout: RunoutReport,
    /// the deposit against the observed one, when the scene gives one (`[output] observed`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed: Option<crate::observed::DepositComparison>,
    /// FNV-1a 64 hash (hex) of the final solver state's bytes (particles, clock, dissipation):
    /// equal hashes mean bit-identical runs.
    pub state_hash: String,
    /// how the initial stresses were found (a new run with an `[initial_state]`; absent after
    /// `mpm resume`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_state: Option<InitialStateSummary>,
    /// the scene's plausibility warnings (`mpm check` prints them; `silence` turns one off).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// 2 (plane strain: energies in J per metre of thickness) or 3 (energies in J).
    #[serde(default = "plane")]
    pub dimension: u8,
    /// a 3D run's plan indicators, when it draws hazard maps (`[output] hazard_maps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hazard_maps: Option<crate::plan::PlanIndicators>,
    /// the loads each grid side and declared wall took (`walls.csv` has them over time).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallLoad>,
    /// what left through the outflow faces, when the scene declares one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outflow: Option<OutflowReport>,
    /// the grid's side faces that the scene did not declare and that the material reached
    /// (each also a warning).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub edges: Vec<crate::edges::EdgeContact>,
}

/// What left the run through its outflow faces (`summary.json` `outflow`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutflowReport {
    /// the faces declared `"outflow"`.
    pub faces: Vec<String>,
    /// particles that left.
    pub particles: u64,
    /// their mass (kg; kg/m in plane strain).
    pub mass: f64,
    /// that mass as a fraction of the run's material at the start.
    pub mass_fraction: f64,
    /// their momentum as they left (N·s; per metre in plane strain).
    pub momentum: Vec<f64>,
    /// their kinetic, elastic and potential energy as they left (J; J/m in plane strain),
    /// `energy.csv`'s `outflow`.
    pub energy: f64,
    /// when the first particle left (s).
    pub first_time: Option<f64>,
}

impl OutflowReport {
    /// the report of a run whose sides named in `faces` (name, `Some` when it is an outflow
    /// side) let material leave: `particles` of `mass` with `momentum` and `energy` left, from
    /// `first_time`, and `left` is the mass still in the run; `None` without an outflow side.
    pub fn new(
        faces: &[(&str, Option<f64>)],
        (particles, mass, momentum, energy): (u64, f64, Vec<f64>, f64),
        first_time: Option<f64>,
        left: f64,
    ) -> Option<Self> {
        let faces: Vec<String> =
            faces.iter().filter(|(_, c)| c.is_some()).map(|(n, _)| n.to_string()).collect();
        let total = left + mass;
        (!faces.is_empty()).then(|| Self {
            faces,
            particles,
            mass,
            mass_fraction: if total > 0.0 { mass / total } else { 0.0 },
            momentum,
            energy,
            first_time,
        })
    }

    /// the run's last line about it.
    pub fn line(&self) -> String {
        match self.first_time {
            None => format!("nothing left through the outflow faces ({})", self.faces.join(", ")),
            Some(t) => format!(
                "{} particles ({:.4e} kg, {:.2} % of the mass) left through the outflow faces \
                 ({}) from t = {t:.3} s, carrying {:.4e} J of energy",
                self.particles,
                self.mass,
                100.0 * self.mass_fraction,
                self.faces.join(", "),
                self.energy
            ),
        }
    }
}

/// the dimension of a summary written before 3D scenes existed.
fn plane() -> u8 {
    2
}

/// What the initial-state stage of a run did (`[initial_state]`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InitialStateSummary {
    /// `"implicit"` or `"gravity_ramp"`.
    pub method: String,
    /// its wall time (s).
    pub wall_time_s: f64,
    /// implicit: load steps that converged.
    pub load_steps: Option<u32>,
    /// implicit: Newton iterations (linear solves).
    pub iterations: Option<u32>,
    /// implicit: final ‖R‖ / ‖f_gravity‖.
    pub residual: Option<f64>,
    /// implicit: the residual after every Newton iteration, in order.
    pub residual_history: Vec<f64>,
    /// implicit: particles left on a plastic branch.
    pub plastic_particles: Option<usize>,
    /// implicit: poorly supported surface nodes tied to their neighbours.
    pub tied_nodes: Option<usize>,
    /// implicit: boundary planes let go because they would have pulled their node.
    pub released_planes: Option<usize>,
    /// implicit: largest nodal displacement of the solve (m).
    pub max_displacement: Option<f64>,
    /// implicit: Σ tangential / Σ μ·normal reactions on the friction planes (≤ 1).
    pub base_friction_ratio: Option<f64>,
    /// gravity_ramp: explicit steps taken.
    pub steps: Option<u64>,
    /// gravity_ramp: kinetic energy the ramp left at its end, dropped (J/m).
    pub kinetic_energy: Option<f64>,
}

/// Runout metrics of `positions` (masses `mass`) over `ground`, with particle spacing `spacing`
/// and column width `column`, relative to the state `initial` (pass `None` at t = 0).
pub fn runout(
    time: f64,
    [positions, velocities]: [&[Vector]; 2],
    mass: &[f64],
    ground: &[Vector],
    spacing: f64,
    column: f64,
    initial: Option<&RunoutMetrics>,
) -> RunoutMetrics {
    let half = 0.5 * spacing;
    let (tail, front, leading) = main_mass_extent(positions, mass, column);
    let (mut m_sum, mut mx, mut my) = (0.0, 0.0, 0.0);
    for (p, &m) in positions.iter().zip(mass) {
        if p.is_finite() {
            m_sum += m;
            mx += m * p.x;
            my += m * p.y;
        }
    }
    let max_thickness = surface(positions, ground, spacing, column)
        .iter()
        .map(|&(_, top, g)| top - g)
        .fold(0.0, f64::max);
    let (com_x, com_y) = if m_sum > 0.0 { (mx / m_sum, my / m_sum) } else { (0.0, 0.0) };
    let front_x = front + half;
    let (front0, cx0, cy0) =
        initial.map_or((front_x, com_x, com_y), |i| (i.front_x, i.com_x, i.com_y));
    RunoutMetrics {
        time,
        leading_x: leading + half,
        front_x,
        tail_x: tail - half,
        front_travel: front_x - front0,
        max_thickness,
        com_x,
        com_y,
        com_travel: (com_x - cx0).hypot(com_y - cy0),
        front_speed: {
            let (mut m, mut p) = (0.0, Vector::ZERO);
            for ((x, v), &mi) in positions.iter().zip(velocities).zip(mass) {
                if x.is_finite() && v.is_finite() && x.x <= front && x.x >= front - column {
                    m += mi;
                    p += mi * *v;
                }
            }
            if m > 0.0 { p.length() / m } else { 0.0 }
        },
    }
}

/// (tail, front, leading) x of the main mass and of all particles, see
/// [`RunoutMetrics::front_x`].
fn main_mass_extent(positions: &[Vector], mass: &[f64], gap: f64) -> (f64, f64, f64) {
    let mut xs: Vec<(f64, f64)> =
        positions.iter().zip(mass).filter(|(p, _)| p.is_finite()).map(|(p, &m)| (p.x, m)).collect();
    if xs.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    xs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let leading = xs[xs.len() - 1].0;
    let (mut best, mut best_mass) = ((xs[0].0, xs[0].0), f64::NEG_INFINITY);
    let (mut start, mut group_mass) = (0usize, 0.0);
    for k in 0..xs.len() {
        group_mass += xs[k].1;
        let last = k + 1 == xs.len() || xs[k + 1].0 - xs[k].0 > gap;
        if last {
            if group_mass > best_mass {
                best_mass = group_mass;
                best = (xs[start].0, xs[k].0);
            }
            start = k + 1;
            group_mass = 0.0;
        }
    }
    (best.0, best.1, leading)
}

/// What `summary.json` reports under `runout`: the measures at the end ([`RunoutMetrics`], its
/// keys at the same level) and the indicators of the whole run ([`RunoutIndicators`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunoutReport {
    /// the runout measures at the end.
    #[serde(flatten)]
    pub last: RunoutMetrics,
    /// the indicators of the whole run.
    #[serde(flatten)]
    pub indicators: RunoutIndicators,
}

/// The fraction of its peak below which the kinetic energy counts as stopped.
pub const STOP_FRACTION: f64 = 0.01;

/// Runout indicators of a whole run, as landslide runout analyses state them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunoutIndicators {
    /// travel angle (Fahrböschung): atan(H/L) from the top of the source (its highest
    /// particle's top) to the distal end of the deposit's main mass on the ground (degrees);
    /// `None` when the mass did not move away from below its top.
    pub travel_angle_deg: Option<f64>,
    /// centre-of-mass travel angle: atan(Δy/Δx) of the centre of mass's drop over its horizontal
    /// travel (degrees); `None` without horizontal travel.
    pub com_travel_angle_deg: Option<f64>,
    /// largest speed of the main mass's front over the series rows
    /// ([`RunoutMetrics::front_speed`], m/s).
    pub max_front_speed: f64,
    /// when (s).
    pub max_front_speed_time: f64,
    /// when the kinetic energy fell below [`STOP_FRACTION`] of its peak for good (the start of
    /// the last stretch below it, which lasts to the end of the run, s); `None`: still moving
    /// at the end.
    pub stop_time: Option<f64>,
    /// the fraction used for `stop_time`.
    pub stop_fraction: f64,
}

/// The indicators from the runout series `rows` (x increasing downslope or not), the kinetic
/// energy series `kinetic` (time, J/m), the source's top `crown` (the highest initial particle
/// top) and the ground.
pub fn indicators(
    rows: &[RunoutMetrics],
    kinetic: &[(f64, f64)],
    crown: Vector,
    ground: &[Vector],
) -> RunoutIndicators {
    let mut out = RunoutIndicators { stop_fraction: STOP_FRACTION, ..Default::default() };
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else { return out };
    let dx_com = last.com_x - first.com_x;
    // the distal end lies the way the centre of mass went
    let distal = if dx_com >= 0.0 { last.front_x } else { last.tail_x };
    let (h, l) = (crown.y - ground_height(ground, distal), (distal - crown.x).abs());
    if l > 0.0 && h > 0.0 {
        out.travel_angle_deg = Some(h.atan2(l).to_degrees());
    }
    if dx_com != 0.0 {
        out.com_travel_angle_deg =
            Some((first.com_y - last.com_y).atan2(dx_com.abs()).to_degrees());
    }
    for r in rows {
        if r.front_speed > out.max_front_speed {
            out.max_front_speed = r.front_speed;
            out.max_front_speed_time = r.time;
        }
    }
    let peak =
        kinetic.iter().enumerate().fold((0, 0.0), |b, (k, r)| if r.1 > b.1 { (k, r.1) } else { b });
    if peak.1 > 0.0 {
        // the start of the last stretch below the threshold, reaching the end of the run: a
        // mass that dipped below it and sped up again had not stopped
        let below = |r: &(f64, f64)| r.1 < STOP_FRACTION * peak.1;
        let tail = &kinetic[peak.0..];
        let still = tail.iter().rev().take_while(|r| below(r)).count();
        out.stop_time = (still > 0).then(|| tail[tail.len() - still].0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time: f64, front_x: f64, com: [f64; 2], front_speed: f64) -> RunoutMetrics {
        RunoutMetrics {
            time,
            front_x,
            com_x: com[0],
            com_y: com[1],
            front_speed,
            ..Default::default()
        }
    }

    /// A source whose top is at (2, 10) above a 30 m flat runout, a deposit whose front stops at
    /// x = 22: H/L = 10/20, the travel angle atan(0.5) = 26.565°; the centre of mass drops 6 m
    /// over 12 m: atan(0.5) too. The front is fastest (8 m/s) at 1 s. The kinetic energy peaks
    /// at 1 s and stays below 1 % of the peak from 3 s on.
    #[test]
    fn the_indicators_of_a_known_deposit() {
        let ground = [Vector::new(0.0, 0.0), Vector::new(30.0, 0.0)];
        let rows = [
            row(0.0, 5.0, [2.0, 7.0], 0.0),
            row(0.5, 6.0, [3.0, 6.0], 3.0),
            row(1.0, 10.0, [8.0, 3.0], 8.0),
            row(1.1, 9.0, [8.5, 2.8], 7.0),
            row(3.0, 22.0, [14.0, 1.0], 0.1),
        ];
        let kinetic = [(0.0, 0.0), (1.0, 100.0), (2.0, 5.0), (3.0, 0.5), (4.0, 0.2)];
        let i = indicators(&rows, &kinetic, Vector::new(2.0, 10.0), &ground);
        let angle = 0.5f64.atan().to_degrees();
        // atan2 of exact small numbers: a few ulps
        assert!((i.travel_angle_deg.unwrap() - angle).abs() < 1e-12, "{i:?}");
        assert!((i.com_travel_angle_deg.unwrap() - angle).abs() < 1e-12, "{i:?}");
        assert_eq!((i.max_front_speed, i.max_front_speed_time), (8.0, 1.0));
        assert_eq!(i.stop_time, Some(3.0));
        // still moving at the end: no stop time
        let i = indicators(&rows, &kinetic[..3], Vector::new(2.0, 10.0), &ground);
        assert_eq!(i.stop_time, None);
        // below 1 % at 3 s but moving again at 4 s: not stopped
        let again = [(0.0, 0.0), (1.0, 100.0), (3.0, 0.5), (4.0, 2.0)];
        let i = indicators(&rows, &again, Vector::new(2.0, 10.0), &ground);
        assert_eq!(i.stop_time, None);
    }
}
