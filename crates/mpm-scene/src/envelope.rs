//! Hazard envelopes along the path: at every ground station (a column of the grid), the largest
//! flow thickness, depth-averaged speed, particle speed and impact pressure over a run, the
//! first arrival time, and the final deposit's thickness — the quantities a hazard map is drawn
//! from (as depth-averaged runout tools such as RAMMS or DAN3D report them).
//!
//! A station is a column `[x0 + k·w, x0 + (k+1)·w)` of width `w` over the ground polyline; the
//! particles whose x falls in it are its flow. Per station and observation:
//! - thickness normal to the ground: `h = max_p (y_p + s/2 − g(x_p)) cos β`, the largest over
//!   the column's particles of their top (centre plus half the particle spacing s) above the
//!   ground under them, with `β` the ground's inclination in the column (the terrain grid's
//!   ground is straight within a column);
//! - depth-averaged speed `ū = |Σ m v| / Σ m` over the column's particles; particle speed
//!   `max |v|`;
//! - impact pressure `ρ̄ ū²` with the column's bulk density `ρ̄ = Σ m / Σ V` (the dynamic
//!   pressure on an obstacle normal to the flow, as hazard guidelines use it);
//! - arrival: the first observation time at which the column holds a particle (0 where the
//!   source lies).

use glam::DVec3;
use mpm_solver::Vector;
use serde::{Deserialize, Serialize};

use crate::ground::{ground_height, segment_at};

/// One station's maxima over the observations so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Station {
    /// the station's centre (m).
    pub x: f64,
    /// ground height at the centre (m).
    pub ground: f64,
    /// the ground's slope dy/dx in the column.
    pub slope: f64,
    /// largest flow thickness normal to the ground (m).
    pub max_thickness: f64,
    /// largest depth-averaged speed (m/s).
    pub max_mean_speed: f64,
    /// largest particle speed (m/s).
    pub max_speed: f64,
    /// largest impact pressure ρ̄ ū² (Pa).
    pub max_pressure: f64,
    /// first time material was in the column (s); `None`: never reached.
    pub arrival: Option<f64>,
}

/// The envelopes of a run: one [`Station`] per column over the ground.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Envelope {
    /// x of the first column's left edge (m).
    pub x0: f64,
    /// column width (m).
    pub column: f64,
    /// the stations, left to right.
    pub stations: Vec<Station>,
}

/// A particle's velocity as the envelopes sum it: in the plane, or in space (a 3D run's strip
/// along its runout line, whose lateral speed counts in the speeds and the momentum's size).
pub trait FlowVelocity: Copy {
    /// the velocity in space (z = 0 for the plane's: the same sums and lengths to the bit).
    fn in_space(self) -> DVec3;
}

impl FlowVelocity for Vector {
    fn in_space(self) -> DVec3 {
        DVec3::new(self.x, self.y, 0.0)
    }
}

impl FlowVelocity for DVec3 {
    fn in_space(self) -> DVec3 {
        self
    }
}

/// What one observation sums per column. The largest top is kept along the ground's vertical
/// and the largest speed squared: cos β > 0 and the square root are monotonic, and so is
/// rounding, so scaling and rooting the largest once per column gives the same bits as taking
/// the largest of every particle's scaled top and speed (a hypot and a root per particle fewer).
#[derive(Clone, Copy, Default)]
struct Column {
    vertical_top: f64,
    mass: f64,
    volume: f64,
    momentum: DVec3,
    max_speed_squared: f64,
    count: usize,
}

impl Envelope {
    /// Stations at the centres of the columns of width `column` over `ground` (x increasing).
    pub fn new(ground: &[Vector], column: f64) -> Self {
        let (Some(first), Some(last)) = (ground.first(), ground.last()) else {
            return Self::default();
        };
        let n = ((last.x - first.x) / column - 1e-9).ceil().max(0.0) as usize;
        let stations = (0..n)
            .map(|k| {
                let x = first.x + (k as f64 + 0.5) * column;
                let (a, b) = segment_at(ground, x);
                let slope = if b.x != a.x { (b.y - a.y) / (b.x - a.x) } else { 0.0 };
                Station { x, ground: ground_height(ground, x), slope, ..Default::default() }
            })
            .collect();
        Self { x0: first.x, column, stations }
    }

    /// Takes the particles' state at `time` into the maxima. `spacing` is the particle spacing
    /// (a particle's top is half of it above its centre).
    pub fn observe<V: FlowVelocity>(
        &mut self,
        time: f64,
        spacing: f64,
        (position, velocity): (&[Vector], &[V]),
        [mass, volume]: [&[f64]; 2],
    ) {
        let mut cols = vec![
            Column { vertical_top: f64::NEG_INFINITY, ..Default::default() };
            self.stations.len()
        ];
        for i in 0..position.len() {
            let (x, v) = (position[i], velocity[i].in_space());
            let Some(k) = self.index(x.x) else { continue };
            if !(x.is_finite() && v.is_finite()) {
                continue;
            }
            let (s, c) = (&self.stations[k], &mut cols[k]);
            // the particle's top above the ground under it, along the vertical
            c.vertical_top =
                c.vertical_top.max(x.y + 0.5 * spacing - s.ground - s.slope * (x.x - s.x));
            c.mass += mass[i];
            c.volume += volume[i];
            c.momentum += mass[i] * v;
            c.max_speed_squared = c.max_speed_squared.max(v.length_squared());
            c.count += 1;
        }
        for (s, c) in self.stations.iter_mut().zip(&cols) {
            if c.count == 0 {
                continue;
            }
            s.arrival.get_or_insert(time);
            // normal to the ground
            let thickness = (c.vertical_top * cos(s)).max(0.0);
            let mean = if c.mass > 0.0 { c.momentum.length() / c.mass } else { 0.0 };
            let density = if c.volume > 0.0 { c.mass / c.volume } else { 0.0 };
            s.max_thickness = s.max_thickness.max(thickness);
            s.max_mean_speed = s.max_mean_speed.max(mean);
            s.max_speed = s.max_speed.max(c.max_speed_squared.sqrt());
            s.max_pressure = s.max_pressure.max(density * mean * mean);
        }
    }

    /// the station whose column holds x.
    pub(crate) fn index(&self, x: f64) -> Option<usize> {
        let k = ((x - self.x0) / self.column).floor();
        (k >= 0.0 && k < self.stations.len() as f64).then_some(k as usize)
    }
}

/// cos β of a station's ground.
fn cos(s: &Station) -> f64 {
    1.0 / s.slope.hypot(1.0)
}

/// The deposit's thickness normal to the ground at each station's centre: (x, ground height,
/// thickness), from the particles' final positions (zero where the column is empty).
pub fn deposit(envelope: &Envelope, spacing: f64, positions: &[Vector]) -> Vec<(f64, f64, f64)> {
    let mut top = vec![0.0f64; envelope.stations.len()];
    for p in positions.iter().filter(|p| p.is_finite()) {
        if let Some(k) = envelope.index(p.x) {
            let s = &envelope.stations[k];
            let h = (p.y + 0.5 * spacing - s.ground - s.slope * (p.x - s.x)) * cos(s);
            top[k] = top[k].max(h);
        }
    }
    envelope.stations.iter().zip(top).map(|(s, h)| (s.x, s.ground, h)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block 1 m long and 0.3 m thick (particles at 0.05 m spacing, ρ = 1500 kg/m³) sliding
    /// rigidly at 2 m/s along flat ground from x ∈ [0, 1]: every station it passes sees the
    /// thickness 0.3 m, speeds of 2 m/s, ρ u² = 6 kPa, and its front reaches the column
    /// [x, x + w) at t = x − 1 over 2 m/s.
    #[test]
    fn a_uniform_block_sliding_at_known_speed_gives_the_exact_maxima() {
        let ground = [Vector::new(0.0, 0.0), Vector::new(6.0, 0.0)];
        let (w, h, v) = (0.1, 0.05, Vector::new(2.0, 0.0));
        let mut e = Envelope::new(&ground, w);
        assert_eq!(e.stations.len(), 60);
        let start: Vec<Vector> = (0..20 * 6)
            .map(|k| Vector::new(((k % 20) as f64 + 0.5) * h, ((k / 20) as f64 + 0.5) * h))
            .collect();
        let mass = vec![1500.0 * h * h; start.len()];
        let volume = vec![h * h; start.len()];
        let vel = vec![v; start.len()];
        let dt = 1e-3;
        for step in 0..=2000 {
            let t = step as f64 * dt;
            let pos: Vec<Vector> = start.iter().map(|p| *p + t * v).collect();
            e.observe(t, h, (&pos, &vel), [&mass, &volume]);
        }
        // after 2 s the block covers [4, 5]: stations up to x = 5 have seen it
        for s in &e.stations[..50] {
            // sums of 120 equal terms and a product: rounding only
            assert!((s.max_thickness - 0.3).abs() < 1e-12, "{s:?}");
            assert!((s.max_mean_speed - 2.0).abs() < 1e-12 && (s.max_speed - 2.0).abs() < 1e-12);
            assert!((s.max_pressure - 1500.0 * 4.0).abs() < 1e-8, "{s:?}");
            // the front (last particle centre at 0.975 m) enters [x − w/2, …) at
            // t = (x − w/2 − 0.975)/2, observed at the next step of 1 ms
            let left = s.x - 0.5 * w;
            let expect = ((left - 0.975) / 2.0).max(0.0);
            let got = s.arrival.unwrap();
            assert!(got >= expect - 1e-12 && got < expect + dt + 1e-12, "{s:?} vs {expect}");
        }
        assert!(e.stations[55].arrival.is_none());
        let d = deposit(&e, h, &start.iter().map(|p| *p + 2.0 * v).collect::<Vec<_>>());
        assert!((d[45].2 - 0.3).abs() < 1e-12 && d[30].2 == 0.0, "{:?}", &d[28..47]);
    }

    #[test]
    fn thickness_is_measured_normal_to_an_inclined_ground() {
        // ground at 30°: a particle column of vertical height 1 m is cos 30° thick
        let ground = [Vector::new(0.0, 2.0), Vector::new(2.0 * 3f64.sqrt(), 0.0)];
        let mut e = Envelope::new(&ground, 0.1);
        let k = 10;
        let x = e.stations[k].x;
        let g = e.stations[k].ground;
        // a uniform layer 1 m high (vertically): particles at the column's uphill and downhill
        // edges, their tops 1 m above the ground under each
        let slope = -30f64.to_radians().tan();
        let at = |dx: f64| Vector::new(x + dx, g + slope * dx + 0.95);
        let pos = [at(-0.049), at(0.0), at(0.049)];
        let zero = [Vector::ZERO; 3];
        e.observe(0.0, 0.1, (&pos, &zero), [&[1.0; 3], &[1.0; 3]]);
        let expect = 1.0 * 30f64.to_radians().cos();
        assert!((e.stations[k].max_thickness - expect).abs() < 1e-12, "{:?}", e.stations[k]);
    }

    /// A column's largest top is taken along the vertical and scaled to the ground normal once,
    /// its largest speed squared and rooted once (`Column`): the same bits as scaling every
    /// particle's top and taking every particle's speed, on a slope and on the flat, with tops
    /// below the ground among them (a pseudo-random cloud of 2 000 particles).
    #[test]
    fn a_column_scaled_once_gives_the_bits_of_every_particle_scaled() {
        let ground = [Vector::new(0.0, 1.3), Vector::new(1.0, 0.4), Vector::new(2.0, 0.4)];
        let (w, h, n) = (0.1, 0.02, 2000);
        let mut e = Envelope::new(&ground, w);
        let mut seed = 12345u64;
        let mut rnd = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pos = Vec::new();
        let mut vel = Vec::new();
        for _ in 0..n {
            let x = 2.0 * rnd();
            pos.push(Vector::new(x, ground_height(&ground, x) + 0.5 * rnd() - 0.05));
            vel.push(Vector::new(4.0 * rnd() - 2.0, 4.0 * rnd() - 2.0));
        }
        e.observe(0.0, h, (&pos, &vel), [&vec![1.0; n], &vec![1e-3; n]]);
        let mut below = 0;
        for (k, s) in e.stations.iter().enumerate() {
            let members: Vec<usize> = (0..n).filter(|&i| e.index(pos[i].x) == Some(k)).collect();
            assert!(!members.is_empty(), "every column holds particles");
            let tops: Vec<f64> = members
                .iter()
                .map(|&i| (pos[i].y + 0.5 * h - s.ground - s.slope * (pos[i].x - s.x)) * cos(s))
                .collect();
            below += tops.iter().filter(|&&t| t < 0.0).count();
            let top = tops.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let speed = members.iter().map(|&i| vel[i].length()).fold(0.0, f64::max);
            assert_eq!(s.max_thickness.to_bits(), top.max(0.0).to_bits(), "station {k}");
            assert_eq!(s.max_speed.to_bits(), speed.to_bits(), "station {k}");
        }
        assert!(below > 0, "some tops lie below the ground");
    }
}
