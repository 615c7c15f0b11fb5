//! What a 3D run records beyond the shared series: the runout measures taken in the vertical
//! plane of the runout direction (`SpaceScene::runout_direction`: a particle at x counts at
//! station x·d and height y, so the front, tail, thickness over the whole width and travel angle
//! follow that direction; the centre of mass's travel is its 3D distance; the front and tail
//! are those of the main mass in plan), the hazard maps (`[output] hazard_maps`, `maps/`), the
//! comparison with an observed deposit in plan and the plots.

use std::path::Path;

use glam::DVec2;
use mpm_output::checkpoint::History;
use mpm_output::csv::{self, ProbeRow};
use mpm_output::{maps, report};
use mpm_scene::edges::{EdgeWatch, Grain};
use mpm_scene::envelope::{self, Envelope};
use mpm_scene::plan::PlanEnvelope;
use mpm_scene::summary::{self, OutflowReport, RunSummary, RunoutMetrics};
use mpm_scene::{SectionLine, SpaceGrid, SpaceScene, fnv1a};
use mpm_solver3d::{EnergyCheck, Vector};

use super::{Common, Stepper, View, Wing};
use crate::error::RunError;

/// The 3D wing of the driver: its scene, the particle spacing and the floor in the runout plane.
pub(crate) struct Space<'a> {
    scene: &'a SpaceScene,
    common: Common<'a>,
    /// the floor as a polyline in the runout plane (station along the runout direction, y).
    ground: Vec<DVec2>,
    /// the centre of mass at t = 0 (m).
    com0: Vector,
    /// the runout line's start: the point of station 0 of the envelopes, where the line through
    /// the flow's initial centre of mass along the runout direction enters the plan (y = 0).
    line_start: Vector,
    /// the runout line's length across the plan, to where it leaves it (m).
    line_length: f64,
}

impl<'a> Space<'a> {
    /// the wing of a run of `scene` whose records so far are `h` (empty for a new run) and
    /// whose solver is `sv`.
    pub(crate) fn new<Sv: Stepper<Vector = Vector>>(
        scene: &'a SpaceScene,
        h: &History,
        sv: &Sv,
    ) -> Self {
        let g = &scene.grid;
        let o = &scene.output;
        let common = Common {
            origin: scene.origin(),
            text: scene.text(),
            files_dir: scene.files_dir(),
            inputs: scene.inputs(),
            hash: format!("{:016x}", fnv1a(scene.text().as_bytes())),
            end_time: scene.end_time,
            max_steps: scene.max_steps,
            alarm: scene.alarm,
            stop_at_rest: scene.stop_at_rest,
            series_interval: o.series_interval,
            interval: o.interval,
            checkpoint_interval: o.checkpoint_interval,
            exact_times: o.exact_times,
            vtk: o.vtk,
            vtk_format: o.vtk_format,
            fields: &o.fields,
            plots: o.plots,
            spacing: g.plan_cell() / scene.gimp_ppc as f64,
            probes: &o.probes,
            warnings: &scene.warnings,
            scheme: scene.config.scheme.name(),
            shape_function: scene.shape_function.name(),
        };
        // (from the generation positions: a resumed run's particles have moved; and kept by
        // the history, as particles may have left since)
        let p = sv.particles();
        let com0 = match h.initial_centre {
            Some(c) => Vector::from_array(c),
            None => {
                // (of the flowing materials: the runout measures', not an obstacle's)
                let flow = || flowing(scene, &p);
                let mass: f64 = flow().map(|q| p.mass[q]).sum();
                flow().map(|q| p.initial_position[q] * p.mass[q]).sum::<Vector>() / mass
            }
        };
        let d = scene.runout_direction;
        let ([x0, z0], [x1, z1]) = (g.plan_origin(), g.plan_end());
        let corners =
            [x0, x1].into_iter().flat_map(|x| [z0, z1].map(|z| Vector::new(x, 0.0, z).dot(d)));
        let (s0, s1) =
            corners.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| (a.min(s), b.max(s)));
        // the ground in the runout plane: under the line through the initial centre of mass
        // along the runout direction, at the plan cells' spacing (the floor of a regular grid)
        let ground = match g {
            SpaceGrid::Regular(r) => {
                let y0 = r.origin().y;
                vec![DVec2::new(s0, y0), DVec2::new(s1, y0)]
            }
            SpaceGrid::Terrain(_) => {
                let along = com0.dot(d);
                let n = ((s1 - s0) / g.plan_cell()).ceil().max(1.0) as usize;
                (0..=n)
                    .map(|k| {
                        let s = s0 + (s1 - s0) * k as f64 / n as f64;
                        let x = com0 + (s - along) * d;
                        DVec2::new(s, g.ground(x.x, x.z).0)
                    })
                    .collect()
            }
        };
        // the runout line's chord across the plan: com0 + t d for t in [t0, t1]
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for (c, lo, hi, da) in [(com0.x, x0, x1, d.x), (com0.z, z0, z1, d.z)] {
            if da != 0.0 {
                let (a, b) = ((lo - c) / da, (hi - c) / da);
                (t0, t1) = (t0.max(a.min(b)), t1.min(a.max(b)));
            }
        }
        let (t0, t1) =
            if t0 <= t1 && t0.is_finite() && t1.is_finite() { (t0, t1) } else { (0.0, 0.0) };
        let line_start = com0 + t0 * d;
        let line_start = Vector::new(line_start.x, 0.0, line_start.z);
        Self { scene, common, ground, com0, line_start, line_length: t1 - t0 }
    }

    /// the section the envelopes follow: the runout line on the map (x, −z).
    fn section(&self) -> SectionLine {
        let end = self.line_start + self.line_length * self.scene.runout_direction;
        SectionLine {
            dem: self.scene.dem().unwrap_or_default().to_string(),
            from: [self.line_start.x, -self.line_start.z],
            to: [end.x, -end.z],
        }
    }

    /// the ground along the runout line, at the plan cells' spacing: (station from the line's
    /// start, height).
    fn line_ground(&self) -> Vec<DVec2> {
        let (g, d) = (&self.scene.grid, self.scene.runout_direction);
        let n = (self.line_length / g.plan_cell()).ceil().max(1.0) as usize;
        (0..=n)
            .map(|k| {
                let s = self.line_length * k as f64 / n as f64;
                let x = self.line_start + s * d;
                let y = match g {
                    SpaceGrid::Regular(r) => r.origin().y,
                    SpaceGrid::Terrain(_) => g.ground(x.x, x.z).0,
                };
                DVec2::new(s, y)
            })
            .collect()
    }

    /// the flowing particles in the strip one plan cell wide about the runout line, in the
    /// line's vertical plane (station from the line's start, height), with their velocities in
    /// space (a lateral speed counts in the envelopes' speeds), masses and volumes.
    fn strip(
        &self,
        p: &View<'_, Vector>,
        at: &[Vector],
    ) -> (Vec<DVec2>, Vec<Vector>, Vec<f64>, Vec<f64>) {
        let d = self.scene.runout_direction;
        let n = Vector::new(-d.z, 0.0, d.x);
        let half = 0.5 * self.scene.grid.plan_cell();
        let (mut x, mut v, mut m, mut vol) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for q in flowing(self.scene, p) {
            let r = at[q] - self.line_start;
            // (half-open: a particle on the strip's edge counts on one side only)
            if !(-half..half).contains(&r.dot(n)) {
                continue;
            }
            x.push(DVec2::new(r.dot(d), at[q].y));
            v.push(p.velocity[q]);
            m.push(p.mass[q]);
            vol.push(p.volume[q]);
        }
        (x, v, m, vol)
    }

    /// the flowing particles' positions now.
    fn flow_positions(&self, p: &View<'_, Vector>) -> Vec<Vector> {
        flowing(self.scene, p).map(|q| p.position[q]).collect()
    }

    /// the deposit's depth per plan cell of `e`: normal to the ground, and vertical.
    fn deposits(&self, e: &PlanEnvelope, p: &View<'_, Vector>) -> (Vec<f64>, Vec<f64>) {
        let (g, spacing) = (&self.scene.grid, self.common.spacing);
        let flow = self.flow_positions(p);
        let normal = e.deposit(spacing, &flow, |x, z| g.ground(x, z));
        let vertical = e.deposit(spacing, &flow, |x, z| (g.ground(x, z).0, 1.0));
        (normal, vertical)
    }

    /// takes the strip's state now into the envelopes along the runout line.
    fn observe_envelope<Sv: Stepper<Vector = Vector>>(&self, e: &mut Envelope, sv: &Sv) {
        let p = sv.particles();
        let (x, v, m, vol) = self.strip(&p, p.position);
        e.observe(sv.time(), self.common.spacing, (&x, &v), [&m, &vol]);
    }

    /// takes the flowing particles' state now into the hazard maps `e`.
    fn observe_into<Sv: Stepper<Vector = Vector>>(&self, e: &mut PlanEnvelope, sv: &Sv) {
        let (scene, spacing) = (self.scene, self.common.spacing);
        let p = sv.particles();
        let ground = |x, z| scene.grid.ground(x, z);
        if scene.materials.flow_mask().is_none() {
            e.observe(sv.time(), spacing, [p.position, p.velocity], [p.mass, p.volume], ground);
            return;
        }
        let keep: Vec<usize> = flowing(self.scene, &p).collect();
        let pick = |v: &[Vector]| -> Vec<Vector> { keep.iter().map(|&q| v[q]).collect() };
        let pick_f = |v: &[f64]| -> Vec<f64> { keep.iter().map(|&q| v[q]).collect() };
        e.observe(
            sv.time(),
            spacing,
            [&pick(p.position), &pick(p.velocity)],
            [&pick_f(p.mass), &pick_f(p.volume)],
            ground,
        );
    }
}

/// the indices of the particles of flowing materials (not obstacles; as the runout measures).
fn flowing<'p>(scene: &SpaceScene, p: &'p View<'_, Vector>) -> impl Iterator<Item = usize> + 'p {
    let mask = scene.materials.flow_mask();
    let material = p.material;
    (0..p.len()).filter(move |&q| {
        mask.as_ref().is_none_or(|m| m.get(usize::from(material[q])).copied().unwrap_or(true))
    })
}

/// The main mass of a 3D run in plan: the particles (indices into `positions`) of the heaviest
/// set of plan cells of side `column` (in x and z) joined by an edge or a corner; the first such
/// set in cell order on a tie. Empty without a finite position.
fn main_mass_in_plan(positions: &[Vector], mass: &[f64], column: f64) -> Vec<usize> {
    use std::collections::{HashMap, HashSet};
    let key = |p: &Vector| ((p.x / column).floor() as i64, (p.z / column).floor() as i64);
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (q, p) in positions.iter().enumerate().filter(|(_, p)| p.is_finite()) {
        cells.entry(key(p)).or_default().push(q);
    }
    let mut order: Vec<(i64, i64)> = cells.keys().copied().collect();
    order.sort_unstable();
    let mut seen = HashSet::new();
    let mut best: (f64, Vec<usize>) = (f64::NEG_INFINITY, Vec::new());
    for start in order {
        if !seen.insert(start) {
            continue;
        }
        let (mut stack, mut members, mut total) = (vec![start], Vec::new(), 0.0);
        while let Some((i, k)) = stack.pop() {
            for &q in &cells[&(i, k)] {
                members.push(q);
                total += mass[q];
            }
            for di in -1..=1 {
                for dk in -1..=1 {
                    let next = (i + di, k + dk);
                    if cells.contains_key(&next) && seen.insert(next) {
                        stack.push(next);
                    }
                }
            }
        }
        if total > best.0 {
            best = (total, members);
        }
    }
    best.1.sort_unstable();
    best.1
}

impl Wing for Space<'_> {
    type Vector = Vector;
    const DIMENSION: usize = 3;
    const PROBES: (&'static str, fn(&mut String, &[ProbeRow])) =
        (csv::PROBES_HEADER_3D, csv::probes_3d);

    fn common(&self) -> &Common<'_> {
        &self.common
    }

    fn start<Sv: Stepper<Vector = Vector>>(&self, h: &mut History, sv: &Sv) {
        let (scene, g) = (self.scene, &self.scene.grid);
        let p = sv.particles();
        h.energy_check = Some(EnergyCheck::new(
            &sv.energy(),
            p.position,
            p.mass,
            scene.config.gravity.length(),
            |x: Vector| x.y - g.ground(x.x, x.z).0,
        ));
        h.initial_centre = Some(self.com0.to_array());
        let crown =
            flowing(scene, &p).map(|q| p.initial_position[q]).max_by(|a, b| a.y.total_cmp(&b.y));
        h.crown = Some(crown.unwrap_or(Vector::ZERO).to_array());
        if scene.output.hazard_maps {
            let [nx, _, nz] = g.cells();
            let mut e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            self.observe_into(&mut e, sv);
            h.plan = Some(e);
        }
        if scene.output.envelope {
            let mut e = Envelope::new(&self.line_ground(), g.plan_cell());
            self.observe_envelope(&mut e, sv);
            h.envelope = Some(e);
        }
        h.edges = edge_watch(scene);
        h.initial = Some(self.metrics(h, sv));
    }

    fn observe<Sv: Stepper<Vector = Vector>>(&self, h: &mut History, sv: &Sv) {
        if let Some(e) = &mut h.plan {
            self.observe_into(e, sv);
        }
        if let Some(e) = &mut h.envelope {
            self.observe_envelope(e, sv);
        }
    }

    fn metrics<Sv: Stepper<Vector = Vector>>(&self, h: &History, sv: &Sv) -> RunoutMetrics {
        let p = sv.particles();
        let d = self.scene.runout_direction;
        let keep: Vec<usize> = flowing(self.scene, &p).collect();
        // every flowing particle has left through outflow sides: the measures stay where they
        // were last taken
        if keep.is_empty()
            && let Some(last) = h.runout.last()
        {
            return RunoutMetrics { time: sv.time(), front_speed: 0.0, ..*last };
        }
        let plane = |v: &[Vector]| -> Vec<DVec2> {
            keep.iter().map(|&q| DVec2::new(v[q].dot(d), v[q].y)).collect()
        };
        // (with periodic sides, the positions the particles have had they never wrapped: the
        // runout of an endless slope; R3-15)
        let at = p.unwrapped();
        let (position, velocity) = (plane(&at), plane(p.velocity));
        let mass: Vec<f64> = keep.iter().map(|&q| p.mass[q]).collect();
        let column = self.scene.grid.plan_cell();
        let spacing = self.common.spacing;
        let mut m = summary::runout(
            sv.time(),
            [&position, &velocity],
            &mass,
            &self.ground,
            spacing,
            column,
            h.initial.as_ref(),
        );
        let total: f64 = mass.iter().sum();
        let com = keep.iter().map(|&q| at[q] * p.mass[q]).sum::<Vector>() / total;
        m.com_travel = (com - self.com0).length();
        // The main mass in plan: the section rule above splits the particles sorted along d at
        // gaps wider than a column, but in 3D the grains beside those thrown ahead close such
        // gaps (the flume extruded: 4.19 m against 3.42 m in 2D). Its front, tail and front
        // speed are taken from the heaviest set of plan cells joined by an edge or a corner.
        let plan: Vec<Vector> = keep.iter().map(|&q| at[q]).collect();
        let main = main_mass_in_plan(&plan, &mass, column);
        if !main.is_empty() {
            let half = 0.5 * spacing;
            let (lo, hi) = main.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| {
                (a.min(position[q].x), b.max(position[q].x))
            });
            m.front_x = hi + half;
            m.tail_x = lo - half;
            m.front_travel = m.front_x - h.initial.map_or(m.front_x, |i| i.front_x);
            let (mut ms, mut momentum) = (0.0, DVec2::ZERO);
            for &q in main.iter().filter(|&&q| position[q].x >= hi - column) {
                ms += mass[q];
                momentum += mass[q] * velocity[q];
            }
            m.front_speed = if ms > 0.0 { momentum.length() / ms } else { 0.0 };
        }
        m
    }

    fn grains<Sv: Stepper<Vector = Vector>>(&self, sv: &Sv) -> Vec<Grain> {
        let p = sv.particles();
        let g = &self.scene.grid;
        flowing(self.scene, &p)
            .map(|q| {
                let x = p.position[q];
                Grain { position: x.to_array(), ground: g.ground(x.x, x.z).0, mass: p.mass[q] }
            })
            .collect()
    }

    fn flow_mass<Sv: Stepper<Vector = Vector>>(&self, sv: &Sv) -> f64 {
        let p = sv.particles();
        flowing(self.scene, &p).map(|q| p.mass[q]).sum()
    }

    fn probe_direction(&self) -> Vector {
        self.scene.runout_direction
    }

    fn reference(&self, _t: f64) -> Option<f64> {
        None
    }

    fn boundaries(&self) -> Vec<(String, usize)> {
        let c = &self.scene.config;
        let b = &c.boundaries;
        let sides = [b.ground, b.left_wall, b.right_wall, b.back_wall, b.front_wall];
        let sides = sides.map(|s| s.is_some());
        crate::loads::boundaries(&mpm_solver3d::SIDE_NAMES, &sides, c.walls.len(), false)
    }

    fn complete<Sv: Stepper<Vector = Vector>>(&self, h: &History, sv: &Sv, s: &mut RunSummary) {
        let scene = self.scene;
        let p = sv.particles();
        let d = scene.runout_direction;
        let crown = h.crown.map_or(Vector::ZERO, Vector::from_array);
        let crown = DVec2::new(crown.dot(d), crown.y) + DVec2::new(0.0, 0.5 * self.common.spacing);
        let kinetic: Vec<(f64, f64)> =
            h.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
        s.runout.indicators = summary::indicators(&h.runout, &kinetic, crown, &self.ground);
        let o = scene.config.outflow;
        let (particles, mass, momentum, energy, first) = sv.outflowed();
        s.outflow = OutflowReport::new(
            &[
                ("left_wall", o.x_min),
                ("right_wall", o.x_max),
                ("back_wall", o.z_min),
                ("front_wall", o.z_max),
            ],
            (particles, mass, momentum, energy),
            first,
            p.mass.iter().sum::<f64>(),
        );
        if let Some(e) = &h.plan {
            let (depth, vertical) = self.deposits(e, &p);
            s.hazard_maps = Some(e.indicators(&depth, &vertical));
        }
        if let Some((file, raster)) = &scene.output.observed {
            // the deposit's vertical depth per plan cell, as an observed DEM difference gives it
            let g = &scene.grid;
            let [nx, _, nz] = g.cells();
            let e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            let flow = self.flow_positions(&p);
            let depth = e.deposit(self.common.spacing, &flow, |x, z| (g.ground(x, z).0, 1.0));
            s.observed = e.compare(file, raster, &depth, d);
        }
    }

    fn files<Sv: Stepper<Vector = Vector>>(
        &self,
        h: &History,
        sv: &Sv,
        dir: &Path,
        s: &RunSummary,
    ) -> Result<(), RunError> {
        let scene = self.scene;
        let p = sv.particles();
        let t = sv.time();
        if let Some(e) = &h.plan {
            let (depth, _) = self.deposits(e, &p);
            maps::write(dir, e, &depth, &scene.output.crs)?;
            let centre = |k: usize| e.cell * (k as f64 + 0.5);
            let ground: Vec<f64> = (0..e.rows * e.cols)
                .map(|k| {
                    let (c, r) = (k % e.cols, k / e.cols);
                    scene.grid.ground(e.x0 + centre(c), e.z0 + centre(r)).0
                })
                .collect();
            let mut release = vec![false; e.rows * e.cols];
            for q in flowing(self.scene, &p) {
                let x = p.initial_position[q];
                let (c, r) = ((x.x - e.x0) / e.cell, (x.z - e.z0) / e.cell);
                if c >= 0.0 && r >= 0.0 && (c as usize) < e.cols && (r as usize) < e.rows {
                    release[r as usize * e.cols + c as usize] = true;
                }
            }
            let title = format!(
                "{}: largest flow height, t = {t:.1} s",
                scene.title().unwrap_or("hazard map")
            );
            let edges: Vec<String> = s.edges.iter().map(|c| c.face.clone()).collect();
            let context =
                maps::Context { title: &title, ground: &ground, release: &release, edges: &edges };
            maps::figures(dir, e, &depth, &context)?;
        }
        if let Some(e) = &h.envelope {
            let (at, ..) = self.strip(&p, p.position);
            let deposit = envelope::deposit(e, self.common.spacing, &at);
            let plots = self.common.plots;
            super::envelope_files(dir, e, &deposit, Some(&self.section()), plots, &[])?;
        }
        if self.common.plots {
            // the flowing particles, north (−z) up as in maps/
            let plan = |v: &[Vector]| flowing(self.scene, &p).map(|q| (v[q].x, -v[q].z)).collect();
            let deposit = report::PlanDeposit {
                positions: plan(p.position),
                initial: plan(p.initial_position),
                time: t,
            };
            report::space_plots(&dir.join("plots"), &h.energy, &h.runout, &deposit)?;
        }
        Ok(())
    }
}

/// the watch over the grid's side faces that the scene left undeclared (no wall law, not
/// outflow, not periodic); `None` when every side is declared.
fn edge_watch(scene: &SpaceScene) -> Option<EdgeWatch> {
    let (c, g) = (&scene.config, &scene.grid);
    let ([x0, z0], [x1, z1]) = (g.plan_origin(), g.plan_end());
    let (b, o) = (&c.boundaries, &c.outflow);
    let x_open = c.periodic.is_none();
    let faces = [
        ("left_wall", x_open && b.left_wall.is_none() && o.x_min.is_none(), 0, x0, -1.0),
        ("right_wall", x_open && b.right_wall.is_none() && o.x_max.is_none(), 0, x1, 1.0),
        ("back_wall", b.back_wall.is_none() && o.z_min.is_none(), 2, z0, -1.0),
        ("front_wall", b.front_wall.is_none() && o.z_max.is_none(), 2, z1, 1.0),
    ];
    let open = faces.into_iter().filter(|f| f.1).map(|(n, _, axis, at, out)| (n, axis, at, out));
    EdgeWatch::new(open.collect(), g.plan_cell())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// a block of 9 cells, a grain in the cell touching its corner (joined), a grain one empty
    /// cell ahead (not joined), and a lighter block elsewhere: the main mass is the block and
    /// the corner grain.
    #[test]
    fn the_main_mass_in_plan_joins_cells_by_edges_and_corners_only() {
        let at = |x: f64, z: f64| Vector::new(x, 0.0, z);
        let mut positions = Vec::new();
        for i in 0..3 {
            for k in 0..3 {
                positions.push(at(0.5 + f64::from(i), 0.5 + f64::from(k)));
            }
        }
        positions.push(at(3.5, 3.5)); // 9: the corner of cell (2, 2)
        positions.push(at(4.5, 1.5)); // 10: cell (4, 1), one empty column ahead of (2, 1)
        positions.push(at(10.5, 10.5)); // 11, 12: a lighter pair
        positions.push(at(10.5, 11.5));
        let mass = vec![1.0; positions.len()];
        let main = main_mass_in_plan(&positions, &mass, 1.0);
        assert_eq!(main, (0..10).collect::<Vec<_>>());
        assert!(main_mass_in_plan(&[at(f64::NAN, 0.0)], &[1.0], 1.0).is_empty());
    }
}
