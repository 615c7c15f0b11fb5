//! `walls.csv` and the summary's wall loads: per grid side and declared wall, the force it takes
//! over time, its peak and its impulse (what a check dam's or a barrier's designer needs).
//!
//! The solver keeps, per boundary, the impulse it gave the material since the start
//! (`Solver::boundary_loads`). Each row here is the mean force over the interval since the
//! previous row, (I(t_k) − I(t_{k−1})) / (t_k − t_{k−1}), turned round to be the load **on** the
//! boundary: the normal load ≥ 0 when the material presses on it, the shear load the size of the
//! friction the material drags along it, and the force vector on it. A mean over the series
//! interval, not one step's value: a single explicit step's contact force rings from node to node
//! as grains arrive, its mean over many steps does not. Forces are in N (per metre of thickness
//! in 2D: N/m); impulses in N·s (N·s/m).

use std::fmt::Write as _;

use mpm_scene::summary::WallLoad;
use serde::{Deserialize, Serialize};

/// What the solver reports for one boundary, dimension-free: the impulse vector (z = 0 in 2D), the
/// normal impulse and the tangential impulse vector, all since the start of the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LoadSample {
    /// Σ J (N·s): what the boundary gave the material.
    pub impulse: [f64; 3],
    /// Σ J·n (N·s).
    pub normal: f64,
    /// Σ (J − (J·n) n) (N·s).
    pub tangential: [f64; 3],
}

/// The wall-load series of a run, kept in its history (so that a resumed run continues it).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WallSeries {
    /// the boundaries recorded, in order: (name, index in the solver's loads).
    pub boundaries: Vec<(String, usize)>,
    /// 2 or 3: how many force components a row has per boundary.
    pub dim: usize,
    /// (time, per boundary [normal, shear, f_x, f_y(, f_z)]): the mean loads since the row before.
    pub rows: Vec<(f64, Vec<f64>)>,
    /// the time of the last row and what the solver reported then, per boundary.
    pub last: Option<(f64, Vec<LoadSample>)>,
}

impl WallSeries {
    /// a series over `boundaries` (name, index in the solver's loads) of a `dim`-dimensional run.
    pub fn new(boundaries: Vec<(String, usize)>, dim: usize) -> Self {
        Self { boundaries, dim, rows: Vec::new(), last: None }
    }

    /// why the series cannot be one a run wrote (a checkpoint's, decoded), if it cannot: a
    /// dimension of 2 or 3, and every row and the last sample one entry per boundary.
    pub fn malformed(&self) -> Option<String> {
        if !(self.dim == 2 || self.dim == 3) {
            return Some(format!("a wall-load series of dimension {}", self.dim));
        }
        let width = self.boundaries.len() * (2 + self.dim);
        let bad_row = self.rows.iter().any(|(_, v)| v.len() != width);
        let bad_last = self.last.as_ref().is_some_and(|(_, l)| l.len() != self.boundaries.len());
        (bad_row || bad_last).then(|| {
            format!(
                "wall-load rows that are not {width} values wide ({} boundaries)",
                self.boundaries.len()
            )
        })
    }

    /// the header line of `walls.csv`.
    pub fn header(&self) -> String {
        let mut s = String::from("time");
        let axes = &["x", "y", "z"][..self.dim];
        for (name, _) in &self.boundaries {
            let _ = write!(s, ",{name}_normal,{name}_shear");
            for a in axes {
                let _ = write!(s, ",{name}_f{a}");
            }
        }
        s.push('\n');
        s
    }

    /// appends a row at `time` from `loads`, every boundary's entry of the solver's loads. The
    /// first row has no interval: zero loads. A row at the time of the last is not added.
    pub fn push(&mut self, time: f64, loads: &[LoadSample]) {
        let now: Vec<LoadSample> = self
            .boundaries
            .iter()
            .map(|&(_, k)| loads.get(k).copied().unwrap_or_default())
            .collect();
        let mut values = Vec::with_capacity(self.boundaries.len() * (2 + self.dim));
        match &self.last {
            Some((t0, _)) if time <= *t0 => return,
            Some((t0, before)) => {
                let span = time - t0;
                for (a, b) in now.iter().zip(before) {
                    let d = |x: [f64; 3], y: [f64; 3]| {
                        [(x[0] - y[0]) / span, (x[1] - y[1]) / span, (x[2] - y[2]) / span]
                    };
                    let shear = d(a.tangential, b.tangential);
                    let force = d(a.impulse, b.impulse);
                    values.push((a.normal - b.normal) / span);
                    values.push(shear.iter().map(|c| c * c).sum::<f64>().sqrt());
                    values.extend(force[..self.dim].iter().map(|f| 0.0 - f)); // (never −0)
                }
            }
            None => values.resize(self.boundaries.len() * (2 + self.dim), 0.0),
        }
        self.rows.push((time, values));
        self.last = Some((time, now));
    }

    /// the summary's entry per boundary: the peak normal and shear loads of the rows (with the
    /// time of the normal one), and the impulses over the whole run from `loads` (the solver's at
    /// the end).
    pub fn summary(&self, loads: &[LoadSample]) -> Vec<WallLoad> {
        let stride = 2 + self.dim;
        let unit = if self.dim == 2 { "N/m" } else { "N" };
        self.boundaries
            .iter()
            .enumerate()
            .map(|(b, (name, k))| {
                let end = loads.get(*k).copied().unwrap_or_default();
                let mut peak = (0.0, 0.0, 0.0);
                for (t, v) in &self.rows {
                    if v[b * stride] > peak.0 {
                        peak = (v[b * stride], *t, peak.2);
                    }
                    peak.2 = f64::max(peak.2, v[b * stride + 1]);
                }
                WallLoad {
                    name: name.clone(),
                    unit: unit.to_string(),
                    peak_normal_force: peak.0,
                    peak_normal_time: peak.1,
                    peak_shear_force: peak.2,
                    normal_impulse: end.normal,
                    impulse: end.impulse[..self.dim].iter().map(|j| 0.0 - j).collect(),
                }
            })
            .collect()
    }
}

/// appends the lines of `rows` (of a [`WallSeries`]) to `s`.
pub fn lines(s: &mut String, rows: &[(f64, Vec<f64>)]) {
    for (t, values) in rows {
        let _ = write!(s, "{t}");
        for v in values {
            let _ = write!(s, ",{v}");
        }
        s.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// a wall pushed at a load growing and easing over two intervals: the rows are the mean loads, the
    /// summary's peak the largest row and its impulse the last total.
    #[test]
    fn rows_are_mean_loads_and_the_summary_takes_their_peak() {
        let mut s = WallSeries::new(vec![("ground".into(), 0), ("wall_1".into(), 3)], 2);
        let at = |jx: f64, n: f64, ty: f64| LoadSample {
            impulse: [jx, ty, 0.0],
            normal: n,
            tangential: [0.0, ty, 0.0],
        };
        let quiet = LoadSample::default();
        s.push(0.0, &[quiet, quiet, quiet, at(0.0, 0.0, 0.0)]);
        s.push(0.5, &[quiet, quiet, quiet, at(15.0, 15.0, -2.0)]);
        s.push(0.5, &[quiet, quiet, quiet, at(99.0, 99.0, 0.0)]);
        s.push(1.0, &[quiet, quiet, quiet, at(20.0, 20.0, -3.0)]);
        assert_eq!(s.rows.len(), 3, "a row at the same time is not added");
        assert_eq!(s.rows[1].1, vec![0.0, 0.0, 0.0, 0.0, 30.0, 4.0, -30.0, 4.0]);
        assert_eq!(s.rows[2].1[4..], [10.0, 2.0, -10.0, 2.0]);
        let mut text = s.header();
        lines(&mut text, &s.rows);
        assert_eq!(
            text.lines().next(),
            Some(
                "time,ground_normal,ground_shear,ground_fx,ground_fy,wall_1_normal,\
                 wall_1_shear,wall_1_fx,wall_1_fy"
            )
        );
        assert_eq!(text.lines().nth(2), Some("0.5,0,0,0,0,30,4,-30,4"));
        let sum = s.summary(&[quiet, quiet, quiet, at(20.0, 20.0, -3.0)]);
        assert_eq!(sum[1].peak_normal_force, 30.0);
        assert_eq!(sum[1].peak_normal_time, 0.5);
        assert_eq!(sum[1].peak_shear_force, 4.0);
        assert_eq!(sum[1].normal_impulse, 20.0);
        assert_eq!(sum[1].impulse, vec![-20.0, 3.0]);
        assert_eq!(sum[0].peak_normal_force, 0.0);
    }
}
