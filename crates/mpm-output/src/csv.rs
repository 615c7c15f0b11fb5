//! CSV time series: the energy ledger, probe particles and runout metrics.
//!
//! Every file has a header line; times in s, lengths in m, energies in J per metre of thickness.
//! The row functions append lines to a buffer, so that a run writes only its new rows.

use std::fmt::Write;
use std::path::Path;

use mpm_scene::RunoutMetrics;
use mpm_solver::EnergyLedger;
use serde::{Deserialize, Serialize};

use crate::OutputError;
use crate::atomic;

/// One row of `energy.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EnergyRow {
    /// simulated time (s).
    pub time: f64,
    /// step number.
    pub step: u64,
    /// the step's Δt (s).
    pub dt: f64,
    /// the energy ledger (J/m).
    pub ledger: EnergyLedger,
}

/// One row of `probes.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProbeRow {
    /// simulated time (s).
    pub time: f64,
    /// probe number (order in `output.probes`).
    pub probe: usize,
    /// particle index.
    pub particle: usize,
    /// position (m; z is 0 in a plane-strain run).
    pub position: [f64; 3],
    /// displacement from the initial position (m).
    pub displacement: [f64; 3],
    /// velocity (m/s).
    pub velocity: [f64; 3],
    /// displacement along the reference direction (x without a reference; in 3D along the
    /// scene's `runout_direction`).
    pub along: f64,
    /// the analytic displacement along the same direction, when the scene declares one.
    pub reference: Option<f64>,
}

/// brings the CSV file at `path` up to `rows`, of which `flushed` are on disk: the first flush
/// of a session writes the header and every row atomically (replacing whatever the file held);
/// later ones append only the new rows, with one write.
pub fn flush<R>(
    path: &Path,
    header: &str,
    rows: &[R],
    flushed: &mut usize,
    lines: fn(&mut String, &[R]),
) -> Result<(), OutputError> {
    if *flushed == 0 {
        let mut text = String::from(header);
        lines(&mut text, rows);
        atomic::write(path, text.as_bytes())?;
    } else if let Some(new) = rows.get(*flushed..).filter(|new| !new.is_empty()) {
        let mut text = String::new();
        lines(&mut text, new);
        atomic::append(path, text.as_bytes())?;
    }
    *flushed = rows.len();
    Ok(())
}

/// header line of `energy.csv`.
pub const ENERGY_HEADER: &str = "time,step,dt,kinetic,strain,potential,plastic_dissipation,\
     friction_work,constraint_work,transfer_dissipation,external_work,residual,stored,dissipated,\
     total,side_wall_friction,outflow\n";

/// header line of `probes.csv`.
pub const PROBES_HEADER: &str =
    "time,probe,particle,x,y,ux,uy,vx,vy,displacement_along,reference_along\n";

/// header line of a 3D run's `probes.csv` (no analytic reference in 3D).
pub const PROBES_HEADER_3D: &str =
    "time,probe,particle,x,y,z,ux,uy,uz,vx,vy,vz,displacement_along\n";

/// header line of `runout.csv`.
pub const RUNOUT_HEADER: &str =
    "time,front_x,tail_x,leading_x,front_travel,max_thickness,com_x,com_y,com_travel,front_speed\n";

/// appends the lines of `rows` to `s`.
pub fn energy(s: &mut String, rows: &[EnergyRow]) {
    for r in rows {
        let e = &r.ledger;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.time,
            r.step,
            r.dt,
            e.kinetic,
            e.strain,
            e.potential,
            e.plastic_dissipation,
            e.friction_work,
            e.constraint_work,
            e.transfer_dissipation,
            e.external_work,
            e.residual,
            e.stored(),
            e.dissipated(),
            e.total(),
            e.side_wall_friction,
            e.outflow
        );
    }
}

/// appends the lines of `rows` to `s`.
pub fn probes(s: &mut String, rows: &[ProbeRow]) {
    for r in rows {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},{},{},",
            r.time,
            r.probe,
            r.particle,
            r.position[0],
            r.position[1],
            r.displacement[0],
            r.displacement[1],
            r.velocity[0],
            r.velocity[1],
            r.along,
        );
        if let Some(v) = r.reference {
            let _ = write!(s, "{v}");
        }
        s.push('\n');
    }
}

/// appends the lines of a 3D run's `rows` to `s` ([`PROBES_HEADER_3D`]).
pub fn probes_3d(s: &mut String, rows: &[ProbeRow]) {
    for r in rows {
        let [x, y, z] = r.position;
        let [ux, uy, uz] = r.displacement;
        let [vx, vy, vz] = r.velocity;
        let _ = writeln!(
            s,
            "{},{},{},{x},{y},{z},{ux},{uy},{uz},{vx},{vy},{vz},{}",
            r.time, r.probe, r.particle, r.along
        );
    }
}

/// appends the lines of `rows` to `s`.
pub fn runout(s: &mut String, rows: &[RunoutMetrics]) {
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{}",
            r.time,
            r.front_x,
            r.tail_x,
            r.leading_x,
            r.front_travel,
            r.max_thickness,
            r.com_x,
            r.com_y,
            r.com_travel,
            r.front_speed
        );
    }
}

/// header line of a DEM section (`mpm section`); a scene reads `station` and `z` back as a
/// polyline.
pub const SECTION_HEADER: &str = "station,x,y,z\n";

/// appends the stations of a DEM section to `s`.
pub fn section(s: &mut String, stations: &[mpm_dem::Station]) {
    for p in stations {
        let _ = writeln!(s, "{},{},{},{}", p.station, p.x, p.y, p.z);
    }
}

/// header line of `envelope.csv`: per ground station (column centre x), the maxima over the
/// run and the first arrival (empty: never reached); over a DEM section, [`MAP_COLUMNS`]
/// follow.
pub const ENVELOPE_HEADER: &str =
    "x,ground,max_thickness,max_mean_speed,max_speed,max_pressure,arrival_time\n";

/// The columns `envelope.csv` and `deposit.csv` end with when the ground is a DEM section: the
/// station's map x and y.
pub const MAP_COLUMNS: &str = ",map_x,map_y";

/// `header` (one of the headers above) with [`MAP_COLUMNS`] when there is a `section`.
pub fn header(header: &str, section: Option<&mpm_scene::SectionLine>) -> String {
    match section {
        Some(_) => format!("{}{MAP_COLUMNS}\n", header.trim_end()),
        None => header.to_string(),
    }
}

/// appends the stations of `e` to `s`, placed on the map along `section` when there is one.
pub fn envelope(
    s: &mut String,
    e: &mpm_scene::envelope::Envelope,
    section: Option<&mpm_scene::SectionLine>,
) {
    for p in &e.stations {
        let _ = write!(
            s,
            "{},{},{},{},{},{},",
            p.x, p.ground, p.max_thickness, p.max_mean_speed, p.max_speed, p.max_pressure
        );
        if let Some(t) = p.arrival {
            let _ = write!(s, "{t}");
        }
        end_row(s, p.x, section);
    }
}

/// header line of `deposit.csv`: the final deposit's thickness normal to the ground per
/// station; over a DEM section, [`MAP_COLUMNS`] follow.
pub const DEPOSIT_HEADER: &str = "x,ground,thickness\n";

/// appends the deposit's (x, ground, thickness) rows to `s`, placed on the map along
/// `section` when there is one.
pub fn deposit(s: &mut String, rows: &[(f64, f64, f64)], section: Option<&mpm_scene::SectionLine>) {
    for (x, g, h) in rows {
        let _ = write!(s, "{x},{g},{h}");
        end_row(s, *x, section);
    }
}

/// ends a row: `,map_x,map_y` of station `x` when there is a section.
fn end_row(s: &mut String, x: f64, section: Option<&mpm_scene::SectionLine>) {
    if let Some(line) = section {
        let [mx, my] = line.map(x);
        let _ = write!(s, ",{mx},{my}");
    }
    s.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(time: f64) -> RunoutMetrics {
        RunoutMetrics { time, front_x: 2.0 * time, ..RunoutMetrics::default() }
    }

    #[test]
    fn flushes_create_the_file_once_then_append_only_new_rows() {
        let dir = std::env::temp_dir().join(format!("mpm-csv-flush-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runout.csv");
        std::fs::write(&path, "stale,rows\n1,2\n").unwrap();
        let mut rows = vec![metrics(0.0), metrics(0.5)];
        let mut flushed = 0;
        flush(&path, RUNOUT_HEADER, &rows, &mut flushed, runout).unwrap();
        assert_eq!(flushed, 2);
        let first = std::fs::read_to_string(&path).unwrap();
        assert!(first.starts_with(RUNOUT_HEADER) && !first.contains("stale"));
        assert_eq!(first.lines().count(), 3);
        // a mark in the written part survives later flushes: they only append
        let marked = first.replacen("time,", "TIME,", 1);
        std::fs::write(&path, &marked).unwrap();
        flush(&path, RUNOUT_HEADER, &rows, &mut flushed, runout).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), marked);
        rows.push(metrics(1.0));
        flush(&path, RUNOUT_HEADER, &rows, &mut flushed, runout).unwrap();
        let mut all = String::from(RUNOUT_HEADER);
        runout(&mut all, &rows);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), all.replacen("time,", "TIME,", 1));
        assert_eq!(flushed, 3);
        // a new session (nothing flushed) rewrites the file whole
        let mut fresh = 0;
        flush(&path, RUNOUT_HEADER, &rows[..2], &mut fresh, runout).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), first);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
