//! Hazard maps of a 3D run on a regular grid: at every plan cell (a column of the grid's
//! cells, x–z), the largest flow height, depth-averaged and particle speed, impact pressure and
//! momentum over a run, the first arrival time and the final deposit's depth — the rasters a
//! hazard map is drawn from (FLO-2D's maximum depth, velocity, impact pressure and arrival
//! time; RAMMS and r.avaflow the same kinds of map).
//!
//! The ground is the grid's: the floor y = y₀ of a regular grid, the DEM's surface g(x, z) of
//! a terrain grid. Per plan cell and observation, over the particles whose (x, z) fall in it:
//! - flow height `h = max_p (y_p − g(x_p, z_p)) cos θ(x_p, z_p) + s/2`, the highest particle
//!   top (centre plus half the particle spacing s) above the ground, measured normal to it
//!   (θ the ground's slope there; on a flat floor, plainly the height above it);
//! - depth-averaged speed `ū = |Σ m v| / Σ m`; particle speed `max |v|`;
//! - impact pressure `ρ̄ ū²` with the column's bulk density `ρ̄ = Σ m / Σ V`; momentum `h ū`
//!   (m²/s, the flux per unit width);
//! - arrival: the first observation time at which the cell holds a particle.
//!
//! Map frame of the rasters: map x = x (east), map y = −z (north): with y up, x east and z
//! south the axes are right-handed. Row r of a raster (from the north) is the plan row of
//! z ∈ [z₀ + r·w, z₀ + (r+1)·w).

use mpm_solver3d::Vector;
use serde::{Deserialize, Serialize};

use crate::observed::DepositComparison;

/// One plan cell's maxima over the observations so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanCell {
    /// largest flow height above the floor (m).
    pub max_height: f64,
    /// largest depth-averaged speed (m/s).
    pub max_mean_speed: f64,
    /// largest particle speed (m/s).
    pub max_speed: f64,
    /// largest impact pressure ρ̄ ū² (Pa).
    pub max_pressure: f64,
    /// largest momentum h ū (m²/s).
    pub max_momentum: f64,
    /// first time material was in the cell (s); `None`: never reached.
    pub arrival: Option<f64>,
}

/// The hazard maps of a run: `cols × rows` plan cells of side `cell` from (`x0`, `z0`), row by
/// row along z.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PlanEnvelope {
    /// x of the first column's west edge (m).
    pub x0: f64,
    /// z of the first row's edge (m).
    pub z0: f64,
    /// cell side (m).
    pub cell: f64,
    /// cells along x.
    pub cols: usize,
    /// cells along z.
    pub rows: usize,
    /// the cells, row by row (z), each row along x.
    pub cells: Vec<PlanCell>,
    /// one observation's sums per cell, kept between observations (not part of the state:
    /// every observation leaves it empty again).
    #[serde(skip)]
    scratch: Vec<Sums>,
    /// the cells the current observation touched.
    #[serde(skip)]
    touched: Vec<u32>,
}

/// What one observation sums per cell.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sums {
    top: f64,
    mass: f64,
    volume: f64,
    momentum: Vector,
    max_speed: f64,
    count: usize,
}

impl Default for Sums {
    fn default() -> Self {
        Self {
            top: f64::NEG_INFINITY,
            mass: 0.0,
            volume: 0.0,
            momentum: Vector::ZERO,
            max_speed: 0.0,
            count: 0,
        }
    }
}

impl PlanEnvelope {
    /// The plan cells from (`x0`, `z0`) with `cols × rows` cells of side `cell`.
    pub fn new([x0, z0]: [f64; 2], cell: f64, [cols, rows]: [usize; 2]) -> Self {
        Self {
            x0,
            z0,
            cell,
            cols,
            rows,
            cells: vec![PlanCell::default(); cols * rows],
            scratch: Vec::new(),
            touched: Vec::new(),
        }
    }

    /// the cell holding plan point (x, z).
    pub fn index(&self, x: f64, z: f64) -> Option<usize> {
        let i = ((x - self.x0) / self.cell).floor();
        let k = ((z - self.z0) / self.cell).floor();
        let inside = i >= 0.0 && k >= 0.0 && i < self.cols as f64 && k < self.rows as f64;
        inside.then(|| k as usize * self.cols + i as usize)
    }

    /// Takes the particles' state at `time` into the maxima. `spacing` is the particle spacing
    /// (a particle's top is half of it above its centre); `ground(x, z)` the ground's height
    /// under a plan point and the cosine of its slope there. Costs the particles and the cells
    /// they are in, not the plan's area.
    pub fn observe(
        &mut self,
        time: f64,
        spacing: f64,
        [position, velocity]: [&[Vector]; 2],
        [mass, volume]: [&[f64]; 2],
        ground: impl Fn(f64, f64) -> (f64, f64),
    ) {
        if self.scratch.len() != self.cells.len() {
            self.scratch = vec![Sums::default(); self.cells.len()];
        }
        self.touched.clear();
        for q in 0..position.len() {
            let (x, v) = (position[q], velocity[q]);
            if !(x.is_finite() && v.is_finite()) {
                continue;
            }
            let Some(c) = self.index(x.x, x.z) else { continue };
            let s = &mut self.scratch[c];
            if s.count == 0 {
                self.touched.push(c as u32);
            }
            let (g, cos) = ground(x.x, x.z);
            s.top = s.top.max((x.y - g) * cos + 0.5 * spacing);
            s.mass += mass[q];
            s.volume += volume[q];
            s.momentum += mass[q] * v;
            s.max_speed = s.max_speed.max(v.length());
            s.count += 1;
        }
        for &c in &self.touched {
            let s = std::mem::take(&mut self.scratch[c as usize]);
            let cell = &mut self.cells[c as usize];
            cell.arrival.get_or_insert(time);
            let height = s.top.max(0.0);
            let mean = if s.mass > 0.0 { s.momentum.length() / s.mass } else { 0.0 };
            let density = if s.volume > 0.0 { s.mass / s.volume } else { 0.0 };
            cell.max_height = cell.max_height.max(height);
            cell.max_mean_speed = cell.max_mean_speed.max(mean);
            cell.max_speed = cell.max_speed.max(s.max_speed);
            cell.max_pressure = cell.max_pressure.max(density * mean * mean);
            cell.max_momentum = cell.max_momentum.max(height * mean);
        }
    }

    /// The deposit's depth per cell (the highest particle top above the ground, measured
    /// normal to it as the flow height; 0 where empty) from the particles' final positions, row
    /// by row as [`PlanEnvelope::cells`].
    pub fn deposit(
        &self,
        spacing: f64,
        positions: &[Vector],
        ground: impl Fn(f64, f64) -> (f64, f64),
    ) -> Vec<f64> {
        let mut depth = vec![0.0f64; self.cells.len()];
        for p in positions.iter().filter(|p| p.is_finite()) {
            if let Some(c) = self.index(p.x, p.z) {
                let (g, cos) = ground(p.x, p.z);
                depth[c] = depth[c].max((p.y - g) * cos + 0.5 * spacing);
            }
        }
        depth
    }

    /// The run's plan indicators from the maxima and the final `deposit` depths.
    ///
    /// `vertical` is the same deposit's depth measured vertically (a cosine of 1 in
    /// [`PlanEnvelope::deposit`]): the volume is Σ vertical depth × plan area, the others from
    /// `deposit`, measured normal to the ground.
    pub fn indicators(&self, deposit: &[f64], vertical: &[f64]) -> PlanIndicators {
        let area = self.cell * self.cell;
        let reached = self.cells.iter().filter(|c| c.arrival.is_some()).count();
        let covered = deposit.iter().filter(|d| **d > 0.0).count();
        PlanIndicators {
            affected_area: reached as f64 * area,
            deposit_area: covered as f64 * area,
            deposit_volume: vertical.iter().sum::<f64>() * area,
            max_deposit_depth: deposit.iter().copied().fold(0.0, f64::max),
            max_flow_height: self.cells.iter().map(|c| c.max_height).fold(0.0, f64::max),
            max_pressure: self.cells.iter().map(|c| c.max_pressure).fold(0.0, f64::max),
        }
    }
}

impl PlanEnvelope {
    /// the centre (x, z) of plan cell `c` (m).
    pub fn centre(&self, c: usize) -> (f64, f64) {
        let (col, row) = (c % self.cols, c / self.cols);
        (self.x0 + (col as f64 + 0.5) * self.cell, self.z0 + (row as f64 + 0.5) * self.cell)
    }

    /// Compares the simulated deposit `simulated` (a depth per plan cell, vertical, as
    /// [`PlanEnvelope::deposit`] gives it with a cosine of 1) with the `observed` one (a
    /// raster of vertical depths in map coordinates, map y = −z, sampled bilinearly at each
    /// cell's centre; 0 off the raster or on a hole), along the unit plan `direction` of the
    /// runout: over the cells where either deposit lies, the RMS depth error, the overlap
    /// Σ min / Σ max (as in 2D), the plan areas' intersection over union, and the errors of
    /// the front and tail (the farthest and nearest deposit cells' centres along `direction`)
    /// and of the lateral spread (the deposit's width across it). `None` when the
    /// observation holds no deposit on the plan.
    pub fn compare(
        &self,
        file: &str,
        observed: &mpm_dem::Raster,
        simulated: &[f64],
        direction: Vector,
    ) -> Option<DepositComparison> {
        let across = Vector::new(-direction.z, 0.0, direction.x);
        let obs: Vec<f64> = (0..self.cells.len())
            .map(|c| {
                let (x, z) = self.centre(c);
                observed.height(x, -z).map_or(0.0, |h| if h.is_finite() { h.max(0.0) } else { 0.0 })
            })
            .collect();
        // (tail, front, lateral min, lateral max) over the cells with a positive depth.
        let extent = |depth: &[f64]| -> Option<[f64; 4]> {
            let mut e = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
            let mut any = false;
            for (c, _) in depth.iter().enumerate().filter(|(_, h)| **h > 0.0) {
                let (x, z) = self.centre(c);
                let p = Vector::new(x, 0.0, z);
                let (s, t) = (p.dot(direction), p.dot(across));
                e = [e[0].min(s), e[1].max(s), e[2].min(t), e[3].max(t)];
                any = true;
            }
            any.then_some(e)
        };
        let o = extent(&obs)?;
        let m = extent(simulated).unwrap_or([o[0], o[0], o[2], o[2]]);
        let (mut sq, mut inter, mut union, mut n) = (0.0, 0.0, 0.0, 0usize);
        let (mut both, mut either) = (0usize, 0usize);
        for (&h_sim, &h_obs) in simulated.iter().zip(&obs) {
            if h_sim > 0.0 || h_obs > 0.0 {
                sq += (h_sim - h_obs).powi(2);
                inter += h_sim.min(h_obs);
                union += h_sim.max(h_obs);
                n += 1;
                either += 1;
                both += usize::from(h_sim > 0.0 && h_obs > 0.0);
            }
        }
        Some(DepositComparison {
            file: file.to_string(),
            observed_tail_x: o[0],
            observed_front_x: o[1],
            front_error: m[1] - o[1],
            tail_error: m[0] - o[0],
            rms_thickness_error: if n > 0 { (sq / n as f64).sqrt() } else { 0.0 },
            max_observed_thickness: obs.iter().copied().fold(0.0, f64::max),
            iou: if union > 0.0 { inter / union } else { 0.0 },
            stations: n,
            lateral_error: Some((m[3] - m[2]) - (o[3] - o[2])),
            area_iou: Some(if either > 0 { both as f64 / either as f64 } else { 0.0 }),
        })
    }
}

/// The plan indicators of a 3D run with hazard maps (`summary.json` `hazard_maps`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanIndicators {
    /// plan area ever reached by material (m²).
    pub affected_area: f64,
    /// plan area the final deposit covers (m²).
    pub deposit_area: f64,
    /// Σ depth × cell area over the final deposit (m³; the bulk volume up to the particles'
    /// tops, voids between them included).
    pub deposit_volume: f64,
    /// largest final deposit depth (m).
    pub max_deposit_depth: f64,
    /// largest flow height over the run (m).
    pub max_flow_height: f64,
    /// largest impact pressure over the run (Pa).
    pub max_pressure: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block 1 m × 0.3 m × 0.5 m (particles at 0.05 m spacing, ρ = 1500 kg/m³) sliding rigidly
    /// at 2 m/s along x over the floor: every cell it passes sees the height 0.3 m, speeds of
    /// 2 m/s, ρ u² = 6 kPa, momentum 0.6 m²/s, and its front reaches the column [x, x + w) at
    /// t = (x − 1) / 2 m/s; the cells beside its path see nothing (as the 2D envelope's test).
    #[test]
    fn a_rigidly_sliding_block_gives_the_exact_maxima() {
        let (w, s, v) = (0.1, 0.05, Vector::new(2.0, 0.0, 0.0));
        let mut e = PlanEnvelope::new([0.0, 0.0], w, [60, 20]);
        let mut start = Vec::new();
        for i in 0..20 {
            for j in 0..6 {
                for k in 0..10 {
                    let c = |n: usize| (n as f64 + 0.5) * s;
                    start.push(Vector::new(c(i), c(j), 0.5 + c(k)));
                }
            }
        }
        let mass = vec![1500.0 * s * s * s; start.len()];
        let volume = vec![s * s * s; start.len()];
        let vel = vec![v; start.len()];
        let dt = 1e-3;
        for step in 0..=2000 {
            let t = step as f64 * dt;
            let pos: Vec<Vector> = start.iter().map(|p| *p + t * v).collect();
            e.observe(t, s, [&pos, &vel], [&mass, &volume], |_, _| (0.0, 1.0));
        }
        for row in 0..20 {
            for col in 0..50 {
                let c = e.cells[row * 60 + col];
                let z = (row as f64 + 0.5) * w;
                if !(0.5..1.0).contains(&z) {
                    assert_eq!(c, PlanCell::default(), "row {row} col {col}");
                    continue;
                }
                let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
                assert!(near(c.max_height, 0.3), "{c:?}");
                assert!(near(c.max_mean_speed, 2.0) && near(c.max_speed, 2.0), "{c:?}");
                assert!(near(c.max_pressure, 6000.0), "{c:?}");
                assert!(near(c.max_momentum, 0.6), "{c:?}");
                // the front particle's centre (0.975 m + 2t) enters the column
                // [col w, (col + 1) w) at the first observation with 0.975 + 2t ≥ col w (at
                // t = 0 where the block lies; never on an observation's boundary: half-steps)
                let x = col as f64 * w;
                let expect = ((x - 0.975) / (2.0 * dt)).ceil().max(0.0) * dt;
                let arrival = c.arrival.unwrap();
                assert!((arrival - expect).abs() < 1e-9, "col {col}: {arrival} vs {expect}");
            }
        }
        let end: Vec<Vector> = start.iter().map(|p| *p + 2.0 * v).collect();
        let depth = e.deposit(s, &end, |_, _| (0.0, 1.0));
        let ind = e.indicators(&depth, &depth);
        // the block's footprint 1 m × 0.5 m, 0.3 m deep
        assert!((ind.deposit_area - 0.5).abs() < 1e-9 && (ind.deposit_volume - 0.15).abs() < 1e-9);
        assert!((ind.max_deposit_depth - 0.3).abs() < 1e-12);
        // swept: x from 0 to 5 m (the block's back end reaches 4 m) over 0.5 m
        assert!((ind.affected_area - 2.5).abs() < 1e-9, "{ind:?}");
    }

    /// The same block sliding rigidly down a 30° plane (its base on the plane): the flow
    /// height, measured normal to the ground, is the block's 0.3 m in every cell it passes
    /// (the vertical height above the ground would be 0.3 / cos 30° = 0.346 m).
    #[test]
    fn the_flow_height_over_a_slope_is_measured_normal_to_it() {
        let (w, s) = (0.1, 0.05);
        let theta = 30f64.to_radians();
        let down = Vector::new(theta.cos(), -theta.sin(), 0.0);
        let normal = Vector::new(theta.sin(), theta.cos(), 0.0);
        let ground = |x: f64, _z: f64| (-theta.tan() * x, theta.cos());
        let mut e = PlanEnvelope::new([0.0, 0.0], w, [60, 20]);
        let mut start = Vec::new();
        for i in 0..20 {
            for j in 0..6 {
                for k in 0..10 {
                    let c = |n: usize| (n as f64 + 0.5) * s;
                    start.push(c(i) * down + c(j) * normal + Vector::new(0.0, 0.0, 0.5 + c(k)));
                }
            }
        }
        let mass = vec![1500.0 * s * s * s; start.len()];
        let volume = vec![s * s * s; start.len()];
        let vel = vec![2.0 * down; start.len()];
        for step in 0..=200 {
            let t = step as f64 * 1e-2;
            let pos: Vec<Vector> = start.iter().map(|p| *p + t * 2.0 * down).collect();
            e.observe(t, s, [&pos, &vel], [&mass, &volume], ground);
        }
        // (the columns the whole block's section crossed: x from 1.2 m, past its start, to
        // 3.4 m, before its back end stops at 4 cos 30° = 3.46 m)
        let mut seen = 0;
        for (k, c) in e.cells.iter().enumerate().filter(|(_, c)| c.arrival.is_some()) {
            if (12..34).contains(&(k % 60)) {
                assert!((c.max_height - 0.3).abs() < 1e-9, "cell {k}: {c:?}");
                assert!((c.max_mean_speed - 2.0).abs() < 1e-9, "{c:?}");
                seen += 1;
            }
        }
        assert_eq!(seen, 22 * 5);
    }

    /// A simulated deposit 0.5 m deep over plan cells x ∈ [2, 6), z ∈ [1, 3) against an
    /// observed one 0.5 m deep over x ∈ [4, 8), z ∈ [1, 4) (a raster of 1 m cells on the same
    /// lattice, map y = −z): they share 2 × 2 of 4 × 2 + 4 × 3 − 4 = 16 cells (area IoU 1/4,
    /// Σ min / Σ max the same), differ by 0.5 m on the 12 others (RMS 0.5 √(12/16)); along +x
    /// the run stops 2 m short at both ends, and it is 1 m narrower.
    #[test]
    fn a_shifted_deposit_in_plan_gives_its_exact_overlap_and_errors() {
        let e = PlanEnvelope::new([0.0, 0.0], 1.0, [10, 5]);
        let mut sim = vec![0.0; 50];
        for row in 1..3 {
            for col in 2..6 {
                sim[row * 10 + col] = 0.5;
            }
        }
        // the raster: 10 × 5 cells of 1 m, north-west corner at map (0, 0) (z = 0)
        let mut z = vec![0.0; 50];
        for row in 1..4 {
            for col in 4..8 {
                z[row * 10 + col] = 0.5;
            }
        }
        let raster = mpm_dem::Raster::new("o.asc", [10, 5], 1.0, [0.0, 0.0], z, None).unwrap();
        let c = e.compare("o.asc", &raster, &sim, Vector::X).unwrap();
        assert_eq!(c.stations, 16);
        assert!((c.area_iou.unwrap() - 0.25).abs() < 1e-12, "{c:?}");
        assert!((c.iou - 0.25).abs() < 1e-12, "{c:?}");
        assert!((c.rms_thickness_error - 0.5 * (12.0f64 / 16.0).sqrt()).abs() < 1e-12, "{c:?}");
        assert!((c.front_error + 2.0).abs() < 1e-12 && (c.tail_error + 2.0).abs() < 1e-12);
        assert!((c.lateral_error.unwrap() + 1.0).abs() < 1e-12, "{c:?}");
        // the observation itself: all agree
        let same: Vec<f64> = (0..50).map(|k| raster.heights()[k]).collect();
        let c = e.compare("o.asc", &raster, &same, Vector::X).unwrap();
        assert_eq!((c.area_iou, c.iou, c.rms_thickness_error), (Some(1.0), 1.0, 0.0));
    }
}
