//! What the 3D run's observer does: begins a run, records its series, frames, maps and
//! checkpoints after each step, and writes the final files and the summary.

use super::*;

impl<'a> SpaceDriver<'a> {
    pub(crate) fn begin<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        scene: &'a SpaceScene,
        dir: Option<&'a Path>,
        opts: &'a RunOptions,
        solver: &Solver<M, S, N>,
        history: Option<History>,
    ) -> Self {
        let g = &scene.grid;
        let d = scene.runout_direction;
        let ([x0, z0], [x1, z1]) = (g.plan_origin(), g.plan_end());
        let corners =
            [x0, x1].into_iter().flat_map(|x| [z0, z1].map(|z| Vector::new(x, 0.0, z).dot(d)));
        let (s0, s1) =
            corners.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| (a.min(s), b.max(s)));
        let p = solver.particles();
        let check = EnergyCheck::new(
            &solver.energy(),
            &p.position,
            &p.mass,
            scene.config.gravity.length(),
            |x| g.ground(x.x, x.z).0,
        );
        let mass: f64 = p.mass.iter().sum();
        // (from the generation positions: a resumed run's particles have moved; and kept by
        // the history, as particles may have left since)
        let com0 = match history.as_ref().and_then(|h| h.initial_centre) {
            Some(c) => Vector::from_array(c),
            None => {
                p.initial_position.iter().zip(&p.mass).map(|(x, m)| *x * *m).sum::<Vector>() / mass
            }
        };
        let crown = match history.as_ref().and_then(|h| h.crown) {
            Some(c) => Vector::from_array(c),
            None => p
                .initial_position
                .iter()
                .copied()
                .max_by(|a, b| a.y.total_cmp(&b.y))
                .unwrap_or(Vector::ZERO),
        };
        let spacing = g.plan_cell() / scene.gimp_ppc as f64;
        let plan = scene.output.hazard_maps.then(|| {
            let [nx, _, nz] = g.cells();
            let mut e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            observe(&mut e, scene, spacing, solver);
            e
        });
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
        let mut d = SpaceDriver {
            scene,
            plan,
            session: (Instant::now(), solver.step_count()),
            session_particle_steps: 0.0,
            earlier: (0.0, 0.0),
            checkpoint_slot: 0,
            dir,
            progress: opts.progress.clone(),
            interrupt: opts.interrupt.clone(),
            stop_after: opts.stop_after,
            io_error: None,
            stop: None,
            ground,
            spacing,
            com0,
            crown,
            energy: Vec::new(),
            runout: Vec::new(),
            probes: Vec::new(),
            frames: Vec::new(),
            flushed: [0; 4],
            walls: None,
            edges: edge_watch(scene),
            check,
            alarm_time: None,
            rest_peak: 0.0,
            rest_since: None,
            series_slot: 0,
            frame_slot: 0,
            dt: DtStats { min: f64::INFINITY, ..DtStats::default() },
            output_time: 0.0,
            wall_time: 0.0,
        };
        if let Some(h) = history {
            d.energy = h.energy;
            d.runout = h.runout;
            d.probes = h.probes;
            d.frames = h.frames;
            (d.frame_slot, d.series_slot, d.checkpoint_slot) =
                (h.frame_slot, h.series_slot, h.checkpoint_slot);
            d.dt = DtStats { min: h.dt_min, max: h.dt_max, first: h.dt_first, mean: 0.0 };
            d.output_time = h.output_time;
            d.earlier = (h.wall_time, h.particle_steps);
            if let Some(c) = h.energy_check {
                d.check = EnergyCheck {
                    initial_scale: c.initial_scale,
                    initial_potential: c.initial_potential,
                    released: c.released,
                    worst: c.worst,
                    worst_time: c.worst_time,
                };
            }
            d.alarm_time = h.alarm_time;
            d.walls = h.walls;
            d.edges = h.edges;
            if d.plan.is_some() {
                d.plan = h.plan;
            }
            // the rest watch as the rows left it
            let rows: Vec<(f64, f64)> =
                d.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
            for (t, kinetic) in rows {
                d.watch_rest(t, kinetic);
            }
        }
        d
    }

    /// the output history as a resumed run needs it, at this step.
    pub(crate) fn history(&self) -> History {
        let (start, _) = self.session;
        let c = &self.check;
        History {
            energy: self.energy.clone(),
            probes: self.probes.clone(),
            runout: self.runout.clone(),
            frames: self.frames.clone(),
            frame_slot: self.frame_slot,
            series_slot: self.series_slot,
            checkpoint_slot: self.checkpoint_slot,
            dt_min: self.dt.min,
            dt_max: self.dt.max,
            dt_first: self.dt.first,
            wall_time: self.earlier.0 + start.elapsed().as_secs_f64(),
            particle_steps: self.earlier.1 + self.session_particle_steps,
            output_time: self.output_time,
            initial: self.runout.first().copied(),
            energy_check: Some(mpm_solver::EnergyCheck {
                initial_scale: c.initial_scale,
                initial_potential: c.initial_potential,
                released: c.released,
                worst: c.worst,
                worst_time: c.worst_time,
            }),
            alarm_time: self.alarm_time,
            envelope: None,
            plan: self.plan.clone(),
            walls: self.walls.clone(),
            edges: self.edges.clone(),
            initial_centre: Some(self.com0.to_array()),
            crown: Some(self.crown.to_array()),
        }
    }

    /// the marks `[output] exact_times` lands on: series rows, frames, checkpoints.
    pub(super) fn marks(&self) -> [Option<f64>; 3] {
        let o = &self.scene.output;
        [Some(o.series_interval), Some(o.interval), o.checkpoint_interval]
    }

    /// writes `checkpoint.bin` (atomically): the solver state, the scene and the history.
    pub(super) fn write_checkpoint<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let file = CheckpointFile::new(
            self.scene.origin(),
            self.scene.text(),
            self.scene.files_dir(),
            self.scene.inputs(),
            M::wrap_space(solver.checkpoint()),
            self.history(),
        );
        Ok(checkpoint::write(&dir.join(checkpoint::FILE_NAME), &file)?)
    }

    /// rewrites the series and the frame collection from the history (a resumed run's).
    pub(super) fn rewrite_outputs(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        self.flushed = [0; 4];
        self.flush()?;
        if self.scene.output.vtk {
            atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.frames).as_bytes())?;
        }
        Ok(())
    }

    /// `stop_at_rest`: the kinetic energy `kinetic` at time `t` against the run's peak.
    pub(super) fn watch_rest(&mut self, t: f64, kinetic: f64) {
        if let Some(rest) = self.scene.stop_at_rest {
            self.rest_peak = self.rest_peak.max(kinetic);
            if self.rest_peak > 0.0 && kinetic <= rest.kinetic_fraction * self.rest_peak {
                let since = *self.rest_since.get_or_insert(t);
                if t - since >= rest.duration {
                    self.stop.get_or_insert(Stop::AtRest);
                }
            } else {
                self.rest_since = None;
            }
        }
    }

    /// the runout measures now, in the vertical plane of the runout direction.
    pub(super) fn metrics<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> RunoutMetrics {
        let p = solver.particles();
        let d = self.scene.runout_direction;
        let keep: Vec<usize> = flowing(self.scene, p).collect();
        // every flowing particle has left through outflow sides: the measures stay where they
        // were last taken
        if keep.is_empty()
            && let Some(last) = self.runout.last()
        {
            return RunoutMetrics { time: solver.time(), front_speed: 0.0, ..*last };
        }
        let plane = |v: &[mpm_solver3d::Vector]| -> Vec<DVec2> {
            keep.iter().map(|&q| DVec2::new(v[q].dot(d), v[q].y)).collect()
        };
        // (with periodic sides, the positions the particles have had they never wrapped: the
        // runout of an endless slope; R3-15)
        let unwrapped: Vec<mpm_solver3d::Vector>;
        let at: &[mpm_solver3d::Vector] = if p.unwrap.is_empty() {
            &p.position
        } else {
            unwrapped = (0..p.len()).map(|q| p.unwrapped_position(q)).collect();
            &unwrapped
        };
        let (position, velocity) = (plane(at), plane(&p.velocity));
        let mass: Vec<f64> = keep.iter().map(|&q| p.mass[q]).collect();
        let mut m = summary::runout(
            solver.time(),
            [&position, &velocity],
            &mass,
            &self.ground,
            self.spacing,
            self.scene.grid.plan_cell(),
            self.runout.first(),
        );
        let total: f64 = mass.iter().sum();
        let com = keep.iter().map(|&q| at[q] * p.mass[q]).sum::<mpm_solver3d::Vector>() / total;
        m.com_travel = (com - self.com0).length();
        // The main mass in plan: the section rule above splits the particles sorted along d at
        // gaps wider than a column, but in 3D the grains beside those thrown ahead close such
        // gaps (the flume extruded: 4.19 m against 3.42 m in 2D). Its front, tail and front
        // speed are taken from the heaviest set of plan cells joined by an edge or a corner.
        let column = self.scene.grid.plan_cell();
        let plan: Vec<mpm_solver3d::Vector> = keep.iter().map(|&q| at[q]).collect();
        let main = main_mass_in_plan(&plan, &mass, column);
        if !main.is_empty() {
            let half = 0.5 * self.spacing;
            let (lo, hi) = main.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| {
                (a.min(position[q].x), b.max(position[q].x))
            });
            m.front_x = hi + half;
            m.tail_x = lo - half;
            m.front_travel = m.front_x - self.runout.first().map_or(m.front_x, |i| i.front_x);
            let (mut ms, mut momentum) = (0.0, DVec2::ZERO);
            for &q in main.iter().filter(|&&q| position[q].x >= hi - column) {
                ms += mass[q];
                momentum += mass[q] * velocity[q];
            }
            m.front_speed = if ms > 0.0 { momentum.length() / ms } else { 0.0 };
        }
        m
    }

    pub(crate) fn record<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) {
        let t = solver.time();
        let l = solver.energy();
        let relative = self.check.observe(t, &l);
        let alarm = self.scene.alarm;
        if self.alarm_time.is_none() && relative.abs() > alarm.threshold {
            self.alarm_time = Some(t);
            self.progress.warn(&format!(
                "energy alarm at t = {t:.4} s: |energy residual| is {:.1} % of the energy scale \
                 (threshold {:.1} %)",
                100.0 * relative.abs(),
                100.0 * alarm.threshold
            ));
            if alarm.stop {
                self.stop = Some(Stop::EnergyAlarm);
            }
        }
        self.watch_rest(t, l.kinetic);
        self.energy.push(EnergyRow {
            time: t,
            step: solver.step_count(),
            dt: solver.last_report().dt,
            ledger: l,
        });
        let m = self.metrics(solver);
        self.runout.push(m);
        let p = solver.particles();
        for (k, &i) in self.scene.output.probes.iter().enumerate() {
            if i >= p.len() {
                continue;
            }
            // (unwrapped across a periodic pair: the probe follows its particle, not its image)
            let x = p.unwrapped_position(i);
            let u = x - p.initial_position[i];
            self.probes.push(ProbeRow {
                time: t,
                probe: k,
                particle: i,
                position: x.to_array(),
                displacement: u.to_array(),
                velocity: p.velocity[i].to_array(),
                along: u.dot(self.scene.runout_direction),
                reference: None,
            });
        }
        if let Some(w) = &mut self.edges {
            let (scene, p) = (self.scene, solver.particles());
            let grains: Vec<Grain> = flowing(scene, p)
                .map(|q| {
                    let x = p.position[q];
                    let ground = scene.grid.ground(x.x, x.z).0;
                    Grain { position: x.to_array(), ground, mass: p.mass[q] }
                })
                .collect();
            w.observe(t, &grains, 0.5 * self.spacing);
        }
        if self.walls.is_none() {
            let (b, walls) = (&self.scene.config.boundaries, self.scene.config.walls.len());
            let sides = [b.ground, b.left_wall, b.right_wall, b.back_wall, b.front_wall];
            let sides = sides.map(|s| s.is_some());
            let boundaries =
                crate::loads::boundaries(&mpm_solver3d::SIDE_NAMES, &sides, walls, false);
            if !boundaries.is_empty() {
                self.walls = Some(WallSeries::new(boundaries, 3));
            }
        }
        if let Some(w) = &mut self.walls {
            w.push(t, &load_samples(solver.boundary_loads()));
        }
    }

    pub(super) fn write_frame<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let o = &self.scene.output;
        let Some(dir) = self.dir.filter(|_| o.vtk) else { return Ok(()) };
        let clock = Instant::now();
        let name = format!("frames/particles_{:06}.vtp", self.frames.len());
        let path = dir.join(&name);
        if self.frames.is_empty() {
            std::fs::create_dir_all(dir.join("frames"))
                .map_err(|source| OutputError::Io { path: dir.join("frames"), source })?;
        }
        let frame = vtk::frame_3d(
            solver.particles(),
            solver.materials(),
            &o.fields,
            o.vtk_format,
            solver.time(),
        )
        .map_err(|source| RunError::from(OutputError::Io { path: path.clone(), source }))?;
        atomic::write_parts(&path, &frame.parts())?;
        self.frames.push((solver.time(), name));
        atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.frames).as_bytes())?;
        self.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    pub(super) fn flush(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let clock = Instant::now();
        let [e, r, w, p] = &mut self.flushed;
        csv::flush(&dir.join("energy.csv"), csv::ENERGY_HEADER, &self.energy, e, csv::energy)?;
        csv::flush(&dir.join("runout.csv"), csv::RUNOUT_HEADER, &self.runout, r, csv::runout)?;
        if !self.scene.output.probes.is_empty() {
            let header = csv::PROBES_HEADER_3D;
            csv::flush(&dir.join("probes.csv"), header, &self.probes, p, csv::probes_3d)?;
        }
        if let Some(s) = &self.walls {
            csv::flush(&dir.join("walls.csv"), &s.header(), &s.rows, w, loads::lines)?;
        }
        self.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    pub(super) fn alarm_message(&self) -> Option<String> {
        let t = self.alarm_time?;
        Some(format!(
            "energy alarm: at t = {t:.4} s the energy residual exceeded {:.1} % of the run's \
             energy scale (`[solver] energy_alarm`); the worst was {:+.1} % at t = {:.4} s",
            100.0 * self.scene.alarm.threshold,
            100.0 * self.check.worst,
            self.check.worst_time
        ))
    }

    pub(crate) fn finish<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> Result<RunSummary, RunError> {
        let t = solver.time();
        // the checkpoint of an interrupted run holds the history as an uninterrupted run has it
        // at this step (before the closing row and frame below)
        if status == RunStatus::Interrupted {
            self.write_checkpoint(solver)?;
        }
        if self.energy.last().is_none_or(|row| row.time < t) {
            self.record(solver);
        }
        if self.frames.last().is_none_or(|f| f.0 < t) {
            self.write_frame(solver)?;
        }
        let (status, error) = match status {
            RunStatus::Completed | RunStatus::AtRest if self.alarm_time.is_some() => {
                (RunStatus::EnergyAlarm, self.alarm_message())
            }
            _ => (status, error),
        };
        self.flush()?;
        let scene = self.scene;
        let steps = solver.step_count();
        let n = solver.particles().len();
        let p = solver.particles();
        let d = scene.runout_direction;
        let crown =
            DVec2::new(self.crown.dot(d), self.crown.y) + DVec2::new(0.0, 0.5 * self.spacing);
        let kinetic: Vec<(f64, f64)> =
            self.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
        let mut check = self.check;
        let wall = self.earlier.0 + self.wall_time;
        let particle_steps = self.earlier.1 + self.session_particle_steps;
        let gone = solver.outflowed();
        let edges = self.edges.as_ref().map_or_else(Vec::new, |w| {
            w.reached(flowing(scene, p).map(|q| p.mass[q]).sum::<f64>() + gone.mass)
        });
        let mut warnings: Vec<String> = scene.warnings.iter().map(ToString::to_string).collect();
        warnings.extend(edges.iter().map(EdgeContact::warning));
        let o = scene.config.outflow;
        let outflow = OutflowReport::new(
            &[
                ("left_wall", o.x_min),
                ("right_wall", o.x_max),
                ("back_wall", o.z_min),
                ("front_wall", o.z_max),
            ],
            (gone.particles, gone.mass, gone.momentum.to_array().to_vec(), gone.energy),
            gone.first_time,
            p.mass.iter().sum::<f64>(),
        );
        let mut summary = RunSummary {
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_origin: scene.origin().to_string(),
            scene_hash: format!("{:016x}", fnv1a(scene.text().as_bytes())),
            status,
            error,
            particles: n,
            scheme: scene.config.scheme.name().to_string(),
            shape_function: scene.shape_function.name().to_string(),
            steps,
            simulated_time: t,
            end_time: scene.end_time,
            dt: DtStats {
                min: if self.dt.min.is_finite() { self.dt.min } else { 0.0 },
                mean: if steps > 0 { t / steps as f64 } else { 0.0 },
                ..self.dt
            },
            wall_time_s: wall,
            particle_steps_per_s: if wall > 0.0 { particle_steps / wall } else { 0.0 },
            output_time_s: self.output_time,
            threads,
            energy: solver.energy(),
            energy_check: EnergyReport {
                relative_residual: check.observe(t, &solver.energy()),
                worst_relative_residual: check.worst,
                worst_time: check.worst_time,
                alarm_threshold: scene.alarm.threshold,
                alarm_time: self.alarm_time,
            },
            runout: RunoutReport {
                last: self.runout.last().copied().unwrap_or_default(),
                indicators: summary::indicators(&self.runout, &kinetic, crown, &self.ground),
            },
            observed: None,
            state_hash: state_hash(&solver.checkpoint()),
            initial_state: None,
            warnings,
            dimension: 3,
            hazard_maps: None,
            walls: self
                .walls
                .as_ref()
                .map(|w| w.summary(&load_samples(solver.boundary_loads())))
                .unwrap_or_default(),
            outflow,
            edges,
        };
        let deposit = self.plan.as_ref().map(|e| {
            let flow: Vec<mpm_solver3d::Vector> =
                flowing(scene, p).map(|q| p.position[q]).collect();
            let normal = e.deposit(self.spacing, &flow, |x, z| scene.grid.ground(x, z));
            let vertical = e.deposit(self.spacing, &flow, |x, z| (scene.grid.ground(x, z).0, 1.0));
            (normal, vertical)
        });
        if let (Some(e), Some((depth, vertical))) = (&self.plan, &deposit) {
            summary.hazard_maps = Some(e.indicators(depth, vertical));
        }
        if let Some((file, raster)) = &scene.output.observed {
            // the deposit's vertical depth per plan cell, as an observed DEM difference gives it
            let g = &scene.grid;
            let [nx, _, nz] = g.cells();
            let e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            let flow: Vec<Vector> = flowing(scene, p).map(|q| p.position[q]).collect();
            let depth = e.deposit(self.spacing, &flow, |x, z| (g.ground(x, z).0, 1.0));
            summary.observed = e.compare(file, raster, &depth, scene.runout_direction);
        }
        if let Some(dir) = self.dir {
            let json = serde_json::to_string_pretty(&summary)
                .map_err(|e| RunError::Setup(format!("cannot encode summary.json: {e}")))?;
            atomic::write(&dir.join("summary.json"), json.as_bytes())?;
            if let (Some(e), Some((depth, _))) = (&self.plan, &deposit) {
                maps::write(dir, e, depth, &scene.output.crs)?;
                let centre = |k: usize| e.cell * (k as f64 + 0.5);
                let ground: Vec<f64> = (0..e.rows * e.cols)
                    .map(|k| {
                        let (c, r) = (k % e.cols, k / e.cols);
                        scene.grid.ground(e.x0 + centre(c), e.z0 + centre(r)).0
                    })
                    .collect();
                let mut release = vec![false; e.rows * e.cols];
                for q in flowing(scene, p) {
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
                let edges: Vec<String> = summary.edges.iter().map(|c| c.face.clone()).collect();
                let context = maps::Context {
                    title: &title,
                    ground: &ground,
                    release: &release,
                    edges: &edges,
                };
                maps::figures(dir, e, depth, &context)?;
            }
            if scene.output.plots {
                // the flowing particles, north (−z) up as in maps/
                let plan = |v: &[mpm_solver3d::Vector]| {
                    flowing(scene, p).map(|q| (v[q].x, -v[q].z)).collect()
                };
                let deposit = report::PlanDeposit {
                    positions: plan(&p.position),
                    initial: plan(&p.initial_position),
                    time: t,
                };
                report::space_plots(&dir.join("plots"), &self.energy, &self.runout, &deposit)?;
            }
        }
        Ok(summary)
    }
}
