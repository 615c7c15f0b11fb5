//! Comparison of a run's deposit with an observed one (`[output] observed`): the numbers a
//! back-analysis is judged by.
//!
//! Both deposits are thicknesses measured vertically above the ground (as a post-event DEM minus
//! the pre-event one gives them) along x. The observed one is a polyline (x, h_obs), zero outside
//! its x range; the simulated one is sampled per ground station (a column of width w): the top
//! of its highest particle (centre plus half the particle spacing) above the ground under it.
//! Over the stations where either deposit is present:
//! - RMS thickness error `√(mean (h_sim − h_obs)²)`;
//! - overlap of the deposit areas in the section, intersection over union
//!   `IoU = Σ min(h_sim, h_obs) / Σ max(h_sim, h_obs)` (1: the same deposit, 0: disjoint);
//! - front and tail errors: the simulated main mass's front and tail
//!   ([`crate::summary::RunoutMetrics`]) minus the observed deposit's (the ends of the x range
//!   where h_obs > 0).

use mpm_solver::Vector;
use serde::{Deserialize, Serialize};

/// An observed deposit: thickness above the ground (m, vertical) at increasing x (m).
#[derive(Clone, Debug, PartialEq)]
pub struct ObservedDeposit {
    /// the file it was read from, as the scene names it.
    pub file: String,
    /// (x, vertical thickness ≥ 0), x strictly increasing, at least two points.
    pub points: Vec<[f64; 2]>,
}

impl ObservedDeposit {
    /// the thickness at x: linear between the points, zero outside them (and for fewer than two).
    pub fn thickness(&self, x: f64) -> f64 {
        let p = &self.points;
        if p.len() < 2 || x < p[0][0] || x > p[p.len() - 1][0] {
            return 0.0;
        }
        let k = p.partition_point(|q| q[0] <= x).clamp(1, p.len() - 1);
        let ([x0, h0], [x1, h1]) = (p[k - 1], p[k]);
        h0 + (h1 - h0) * (x - x0) / (x1 - x0)
    }

    /// the ends (tail, front) of the x range where the thickness is positive: from the last
    /// zero point before the first positive one to the first zero point after the last positive
    /// one (the ends of the polyline if it starts or ends positive); `None` if nowhere positive.
    pub fn extent(&self) -> Option<(f64, f64)> {
        let p = &self.points;
        let first = p.iter().position(|q| q[1] > 0.0)?;
        let last = p.iter().rposition(|q| q[1] > 0.0)?;
        Some((p[first.saturating_sub(1)][0], p[(last + 1).min(p.len() - 1)][0]))
    }
}

/// How a run's deposit compares with the observed one (module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DepositComparison {
    /// the observation's file.
    pub file: String,
    /// the observed deposit's tail x (m).
    pub observed_tail_x: f64,
    /// the observed deposit's front x (m).
    pub observed_front_x: f64,
    /// simulated minus observed front x (m): positive when the run goes too far.
    pub front_error: f64,
    /// simulated minus observed tail x (m).
    pub tail_error: f64,
    /// RMS of the thickness difference over the stations where either deposit lies (m).
    pub rms_thickness_error: f64,
    /// the largest observed thickness (m), the scale of the RMS error.
    pub max_observed_thickness: f64,
    /// intersection over union of the two deposits' areas in the section (0–1).
    pub iou: f64,
    /// stations compared (where either deposit lies; in 3D, plan cells).
    pub stations: usize,
    /// (3D) simulated minus observed lateral spread, the deposit's width across the runout
    /// direction (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lateral_error: Option<f64>,
    /// (3D) the deposits' plan areas' intersection over union (0–1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area_iou: Option<f64>,
}

/// The simulated deposit's vertical thickness at the envelopes' stations (columns of width
/// `column` from the ground's first x, [`crate::envelope::Envelope::new`]): (station centre x,
/// thickness), the free surface's height above the ground there
/// ([`crate::surface`]: the top of the column's highest particle, centre plus half
/// `spacing`, above the ground under that particle), zero for an empty column.
pub fn simulated(
    ground: &[Vector],
    column: f64,
    spacing: f64,
    positions: &[Vector],
) -> Vec<(f64, f64)> {
    // the envelopes' stations; the free surface's columns are those that hold particles
    let stations = crate::envelope::Envelope::new(ground, column);
    let mut thickness = vec![0.0f64; stations.stations.len()];
    for (x, top, g) in crate::ground::surface(positions, ground, spacing, column) {
        if let Some(k) = stations.index(x) {
            thickness[k] = top - g;
        }
    }
    stations.stations.iter().zip(thickness).map(|(s, h)| (s.x, h)).collect()
}

/// compares the `simulated` deposit (per station, see [`simulated`]) and its main mass's
/// `front` and `tail` x with the `observed` one; `None` when the observation holds no deposit.
pub fn compare(
    observed: &ObservedDeposit,
    simulated: &[(f64, f64)],
    front: f64,
    tail: f64,
) -> Option<DepositComparison> {
    let (observed_tail_x, observed_front_x) = observed.extent()?;
    let (mut sq, mut inter, mut union, mut n) = (0.0, 0.0, 0.0, 0usize);
    for &(x, h_sim) in simulated {
        let h_obs = observed.thickness(x);
        if h_sim > 0.0 || h_obs > 0.0 {
            sq += (h_sim - h_obs).powi(2);
            inter += h_sim.min(h_obs);
            union += h_sim.max(h_obs);
            n += 1;
        }
    }
    Some(DepositComparison {
        file: observed.file.clone(),
        observed_tail_x,
        observed_front_x,
        front_error: front - observed_front_x,
        tail_error: tail - observed_tail_x,
        rms_thickness_error: if n > 0 { (sq / n as f64).sqrt() } else { 0.0 },
        max_observed_thickness: observed.points.iter().map(|p| p[1]).fold(0.0, f64::max),
        iou: if union > 0.0 { inter / union } else { 0.0 },
        stations: n,
        lateral_error: None,
        area_iou: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(points: &[[f64; 2]]) -> ObservedDeposit {
        ObservedDeposit { file: "o.csv".into(), points: points.to_vec() }
    }

    #[test]
    fn thickness_is_linear_between_points_and_zero_outside() {
        let o = obs(&[[1.0, 0.0], [2.0, 1.0], [4.0, 0.0]]);
        assert_eq!(o.thickness(0.5), 0.0);
        assert_eq!(o.thickness(1.5), 0.5);
        assert_eq!(o.thickness(2.0), 1.0);
        assert_eq!(o.thickness(3.0), 0.5);
        assert_eq!(o.thickness(4.5), 0.0);
        assert_eq!(o.extent(), Some((1.0, 4.0)));
        // positive at the ends: the ends of the polyline
        assert_eq!(obs(&[[1.0, 0.2], [2.0, 0.0], [3.0, 0.0]]).extent(), Some((1.0, 2.0)));
        assert_eq!(obs(&[[1.0, 0.0], [2.0, 0.0]]).extent(), None);
    }

    /// A rectangular deposit 0.5 m thick over x ∈ [2, 6] against an observed one 0.5 m thick over
    /// [4, 8], on 1 m stations: they share 2 of 6 stations (IoU 1/3), differ by 0.5 m on the 4
    /// others (RMS 0.5 √(4/6)), and the run falls 2 m short at both ends.
    #[test]
    fn a_shifted_rectangle_gives_its_exact_overlap_and_errors() {
        let ground = [Vector::new(0.0, 0.0), Vector::new(10.0, 0.0)];
        // particles at 0.25 m spacing filling [2, 6] × [0, 0.5]
        let positions: Vec<Vector> = (0..16)
            .flat_map(|i| {
                (0..2).map(move |j| Vector::new(2.125 + 0.25 * i as f64, 0.125 + 0.25 * j as f64))
            })
            .collect();
        let sim = simulated(&ground, 1.0, 0.25, &positions);
        assert_eq!(sim.len(), 10);
        assert_eq!(sim.iter().filter(|s| s.1 > 0.0).count(), 4);
        assert!(sim.iter().all(|s| s.1 == 0.0 || (s.1 - 0.5).abs() < 1e-15));
        let o = obs(&[[3.9999, 0.0], [4.0, 0.5], [8.0, 0.5], [8.0001, 0.0]]);
        let c = compare(&o, &sim, 6.0, 2.0).unwrap();
        assert_eq!(c.stations, 6);
        assert!((c.iou - 1.0 / 3.0).abs() < 1e-12, "{c:?}");
        assert!((c.rms_thickness_error - 0.5 * (4.0f64 / 6.0).sqrt()).abs() < 1e-12, "{c:?}");
        assert!((c.front_error + 2.0001).abs() < 1e-12 && (c.tail_error + 1.9999).abs() < 1e-12);
        // the same deposit observed: IoU 1, no error
        let same: Vec<[f64; 2]> = sim.iter().map(|&(x, h)| [x, h]).collect();
        let c = compare(&obs(&same), &sim, 6.0, 2.0).unwrap();
        assert_eq!((c.iou, c.rms_thickness_error), (1.0, 0.0));
    }

    /// On a slope the thickness is vertical: a particle's top above the ground under it.
    #[test]
    fn simulated_thickness_is_vertical_above_a_sloping_ground() {
        let ground = [Vector::new(0.0, 2.0), Vector::new(4.0, 0.0)];
        // a particle at x = 1.25 (ground 1.375), centre 0.1 above it, spacing 0.2
        let sim = simulated(&ground, 1.0, 0.2, &[Vector::new(1.25, 1.475)]);
        assert!((sim[1].1 - 0.2).abs() < 1e-12, "{sim:?}");
    }
}
