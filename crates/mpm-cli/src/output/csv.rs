//! CSV time series: the energy ledger, probe particles and runout metrics.
//!
//! Every file has a header line; times in s, lengths in m, energies in J per metre of thickness.

use std::fmt::Write;

use mpm_solver::EnergyLedger;
use serde::{Deserialize, Serialize};

use crate::summary::RunoutMetrics;

/// One row of `energy.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct EnergyRow {
    pub time: f64,
    pub step: u64,
    pub dt: f64,
    pub ledger: EnergyLedger,
}

/// One row of `probes.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct ProbeRow {
    pub time: f64,
    /// probe number (order in `output.probes`).
    pub probe: usize,
    /// particle index.
    pub particle: usize,
    pub position: [f64; 2],
    pub displacement: [f64; 2],
    pub velocity: [f64; 2],
    /// displacement along the reference direction (x without a reference).
    pub along: f64,
    /// the analytic displacement along the same direction, when the scene declares one.
    pub reference: Option<f64>,
}

pub(crate) fn energy(rows: &[EnergyRow]) -> String {
    let mut s = String::from(
        "time,step,dt,kinetic,strain,potential,plastic_dissipation,friction_work,\
         constraint_work,external_work,residual,stored,dissipated,total\n",
    );
    for r in rows {
        let e = &r.ledger;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.time,
            r.step,
            r.dt,
            e.kinetic,
            e.strain,
            e.potential,
            e.plastic_dissipation,
            e.friction_work,
            e.constraint_work,
            e.external_work,
            e.residual,
            e.stored(),
            e.dissipated(),
            e.total()
        );
    }
    s
}

pub(crate) fn probes(rows: &[ProbeRow]) -> String {
    let mut s =
        String::from("time,probe,particle,x,y,ux,uy,vx,vy,displacement_along,reference_along\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
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
            r.reference.map_or(String::new(), |v| v.to_string())
        );
    }
    s
}

pub(crate) fn runout(rows: &[RunoutMetrics]) -> String {
    let mut s = String::from(
        "time,front_x,tail_x,leading_x,front_travel,max_thickness,com_x,com_y,com_travel\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            r.time,
            r.front_x,
            r.tail_x,
            r.leading_x,
            r.front_travel,
            r.max_thickness,
            r.com_x,
            r.com_y,
            r.com_travel
        );
    }
    s
}
