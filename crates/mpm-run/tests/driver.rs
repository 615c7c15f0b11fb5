//! The run driver's own guarantees, through its public API: a checkpoint that cannot belong to
//! its scene is refused, and a run advanced from outside (`Simulation`) is the run itself.

use mpm_output::OutputError;
use mpm_output::checkpoint::{self, CheckpointFile};
use mpm_run::{Limit, RunError, RunOptions, Simulation, load_scene_str, resume, run_scene};
use mpm_scene::SavedState;

/// A checkpoint whose checksum holds but whose content cannot belong to its scene (a time of
/// −1.9e305 s made `resume` run forever; another particle count) is refused before the solver
/// takes it.
#[test]
fn a_checksummed_checkpoint_that_does_not_fit_its_scene_is_refused() {
    let text =
        mpm_run::embedded_scene("free_fall").unwrap().replace("end_time = 1.0", "end_time = 0.02");
    let scene = load_scene_str(&text, "free_fall").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-fits-{}", std::process::id()));
    let opts =
        RunOptions { out_dir: Some(dir.clone()), stop_after: Some(0.01), ..Default::default() };
    run_scene(&scene, &opts).unwrap();
    let path = dir.join(checkpoint::FILE_NAME);
    let good = checkpoint::read(&path).unwrap();
    type Edit = fn(&mut CheckpointFile);
    let edits: [(&str, Edit); 3] = [
        ("time -1.9e305", |c| {
            if let SavedState::Elastic(s) = &mut c.state {
                s.time = -1.9e305;
            }
        }),
        ("particles, but its scene generates", |c| {
            if let SavedState::Elastic(s) = &mut c.state {
                s.particles.position.pop();
            }
        }),
        ("energy rows after", |c| {
            let row = c.history.energy[0];
            c.history.energy.extend(std::iter::repeat_n(row, 10_000));
        }),
    ];
    for (expect, edit) in edits {
        let mut bad = good.clone();
        edit(&mut bad);
        checkpoint::write(&path, &bad).unwrap();
        let e =
            resume(&dir, &RunOptions { threads: opts.threads, ..Default::default() }).unwrap_err();
        assert!(matches!(e, RunError::Output(OutputError::Checkpoint { .. })), "{expect}: {e}");
        assert!(e.to_string().contains(expect), "{expect}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run advanced from outside in pieces (steps, then to its end time) ends with the bits of the same
/// run in one go: the same state hash, step count and energy ledger; its checkpoint resumes to
/// them too.
#[test]
fn a_simulation_advanced_in_pieces_is_the_run_itself() {
    let text = mpm_run::embedded_scene("sliding_inclined")
        .unwrap()
        .replace("end_time = 2.0", "end_time = 0.05");
    let scene = load_scene_str(&text, "sliding_inclined").unwrap();
    assert_eq!(scene.end_time(), 0.05, "the scene's end time was shortened");
    let whole = run_scene(&scene, &RunOptions::default()).unwrap();

    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    let a = sim.advance(Limit::Steps(7), &mut || false).unwrap();
    assert_eq!((a.steps, a.stopped), (7, None));
    // (an advance to a time shortens its last step to land on it: steps keep the run's steps)
    sim.advance(Limit::Steps(30), &mut || false).unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-simulation-{}", std::process::id()));
    sim.checkpoint(&dir).unwrap();
    let a = sim.advance(Limit::Time(0.05), &mut || false).unwrap();
    assert_eq!(a.time, 0.05);
    let stepped = sim.summary().unwrap();
    assert_eq!(stepped.state_hash, whole.state_hash);
    assert_eq!(stepped.steps, whole.steps);
    assert_eq!(stepped.energy, whole.energy);
    let f = sim.fields().unwrap();
    assert_eq!(f.position.len(), scene.particle_count());

    let resumed = resume(&dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, whole.state_hash);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[output] exact_times`: every series row and frame falls on its k·interval mark (to the
/// slack the output's slots allow, 1e-9 of an interval: round-off of summed steps), in 2D and
/// 3D; the run takes at most one extra step per mark; the shortened steps do not count as the
/// smallest Δt (that stays the stability limit's, which a landing does not change: within 1 %);
/// and a run stopped and resumed writes the bytes of one in one go.
#[test]
fn exact_times_put_every_record_on_its_mark_and_resume_to_the_same_bytes() {
    let rows = |d: &std::path::Path, file: &str| -> Vec<f64> {
        let text = std::fs::read_to_string(d.join(file)).unwrap();
        text.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect()
    };
    let on_marks = |times: &[f64], interval: f64, what: &str| {
        for (k, &t) in times.iter().enumerate() {
            let mark = k as f64 * interval;
            assert!((t - mark).abs() <= 1e-9 * interval, "{what}: row {k} at {t} s, not {mark} s");
        }
    };
    let base = std::env::temp_dir().join(format!("mpm-exact-{}", std::process::id()));
    // 2D: the flume's first 0.06 s, rows every 0.004 s, frames every 0.015 s
    let text = mpm_run::embedded_scene("flume").unwrap();
    let plain = load_scene_str(text, "flume")
        .unwrap()
        .modified(|f| {
            f.solver.end_time = 0.06;
            f.output.interval = Some(0.015);
            f.output.series_interval = Some(0.004);
            f.output.checkpoint_interval = None;
        })
        .unwrap();
    let exact = plain.modified(|f| f.output.exact_times = Some(true)).unwrap();
    let at = |name: &str| RunOptions { out_dir: Some(base.join(name)), ..Default::default() };
    let loose = run_scene(&plain, &at("plain")).unwrap();
    let whole = run_scene(&exact, &at("whole")).unwrap();
    let times = rows(&base.join("whole"), "energy.csv");
    assert_eq!(times.len(), 16, "rows at 0, 0.004, ..., 0.06 s");
    on_marks(&times, 0.004, "2D energy.csv");
    on_marks(&rows(&base.join("whole"), "runout.csv"), 0.004, "2D runout.csv");
    assert_ne!(rows(&base.join("plain"), "energy.csv"), times, "without it rows fall on steps");
    // (15 series marks and 4 frame marks, of which 3 coincide with series marks)
    assert!(whole.steps > loose.steps && whole.steps <= loose.steps + 16, "{whole:?}");
    assert!((whole.dt.min / loose.dt.min - 1.0).abs() < 0.01, "{:?} {:?}", whole.dt, loose.dt);
    // stepped from outside by steps, the run lands on the same marks: the same bits
    let mut sim = Simulation::new(&exact, None, &mut || false).unwrap();
    sim.advance(Limit::Steps(whole.steps - 10), &mut || false).unwrap();
    sim.advance(Limit::Time(0.06), &mut || false).unwrap();
    assert_eq!(sim.summary().unwrap().state_hash, whole.state_hash, "stepped by steps");
    let stopped = run_scene(&exact, &RunOptions { stop_after: Some(0.025), ..at("part") }).unwrap();
    assert_eq!(stopped.status, mpm_run::RunStatus::Interrupted);
    let resumed = resume(&base.join("part"), &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, whole.state_hash);
    for file in ["energy.csv", "runout.csv"] {
        let read = |d: &str| std::fs::read(base.join(d).join(file)).unwrap();
        assert!(read("part") == read("whole"), "{file} after the resume differs");
    }
    // 3D: the sliding block, rows every 0.01 s, frames every 0.03 s
    let text = BLOCK_3D.replace(
        "interval = 0.03\n",
        "interval = 0.03\nseries_interval = 0.01\nexact_times = true\n",
    );
    let scene = mpm_scene::load_space_str(&text, "block3d").unwrap();
    assert!(scene.output.exact_times);
    let s = mpm_run::run_space_scene(&scene, &at("space")).unwrap();
    assert_eq!(s.status, mpm_scene::RunStatus::Completed);
    let times = rows(&base.join("space"), "energy.csv");
    assert_eq!(times.len(), 13, "rows at 0, 0.01, ..., 0.12 s");
    on_marks(&times, 0.01, "3D energy.csv");
    std::fs::remove_dir_all(&base).unwrap();
}

/// A run steered between steps (a coupled code's, a script's): the free-falling elastic block
/// (no stress, no boundary reached: every node's velocity changes by (g + b)Δt, so momentum is
/// exact to round-off, 1e-12) thrown sideways at 1 m/s keeps that velocity and falls from rest
/// again, the kinetic energy set booked as external work (the residual moves by less than 1e-9
/// of the kinetic energy); a body force of 2 m/s² along x adds 2 m/s per second (its work's
/// booking is the solver's test); a material's stiffness changed
/// goes into the checkpoint's scene, from which `resume` continues to the bits of the steered
/// run; a change of model, of density or of a field that is not a material's is refused, and so
/// is a value the scene refuses, naming it.
#[test]
fn a_simulation_takes_velocities_body_forces_and_material_changes_between_steps() {
    let text =
        mpm_run::embedded_scene("free_fall").unwrap().replace("end_time = 1.0", "end_time = 0.2");
    let scene = load_scene_str(&text, "free_fall").unwrap();
    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    let mean = |sim: &mut Simulation| {
        let f = sim.fields().unwrap();
        let m: f64 = f.mass.iter().sum();
        let vx = f.velocity.iter().zip(&f.mass).map(|(v, m)| v[0] * m).sum::<f64>() / m;
        let vy = f.velocity.iter().zip(&f.mass).map(|(v, m)| v[1] * m).sum::<f64>() / m;
        (vx, vy)
    };
    sim.advance(Limit::Time(0.05), &mut || false).unwrap();
    let n = sim.particle_count();
    let e0 = sim.energy().unwrap();
    sim.set_velocities([1.0, 0.0].repeat(n)).unwrap();
    let e1 = sim.energy().unwrap();
    assert!((e1.residual - e0.residual).abs() < 1e-9 * e0.kinetic, "{e0:?} {e1:?}");
    sim.advance(Limit::Time(0.1), &mut || false).unwrap();
    let (vx, vy) = mean(&mut sim);
    assert!((vx - 1.0).abs() < 1e-12, "vx {vx}");
    assert!((vy + 9.81 * 0.05).abs() < 1e-12, "vy {vy}");
    sim.set_body_force(Some([2.0, 0.0].repeat(n))).unwrap();
    sim.advance(Limit::Time(0.15), &mut || false).unwrap();
    let (vx, _) = mean(&mut sim);
    assert!((vx - 1.1).abs() < 1e-12, "vx {vx} after 0.05 s at 2 m/s²");
    let refused = sim.set_body_force(Some([2.0, 0.0].repeat(n - 1))).unwrap_err();
    assert!(refused.to_string().contains("body_force"), "{refused}");
    sim.set_body_force(None).unwrap();
    for (path, value, names) in [
        ("materials.block.kind", "\"drucker_prager\"", "kind"),
        ("materials.block.density", "2000.0", "density"),
        ("solver.courant", "0.2", "materials.<name>.<field>"),
    ] {
        let e = sim.set_material(path, value).unwrap_err();
        assert!(matches!(e, RunError::Arguments(_)) && e.to_string().contains(names), "{e}");
    }
    let e = sim.set_material("materials.block.young", "-1.0").unwrap_err();
    assert!(matches!(&e, RunError::Scene(s) if s.path == "materials.block.young"), "{e}");
    sim.set_material("materials.block.young", "2.0e6").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-steered-{}", std::process::id()));
    sim.checkpoint(&dir).unwrap();
    let saved = std::fs::read_to_string(dir.join("scene.toml")).unwrap();
    assert!(saved.contains("young = 2.0e6"), "{saved}");
    sim.advance(Limit::Time(0.2), &mut || false).unwrap();
    let steered = sim.summary().unwrap();
    let resumed = resume(&dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, steered.state_hash);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A poll that asks to stop ends an advance after its current step, as Ctrl-C ends a run.
#[test]
fn a_poll_that_asks_to_stop_interrupts_after_a_step() {
    let scene = load_scene_str(mpm_run::embedded_scene("flume").unwrap(), "flume").unwrap();
    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    let a = sim.advance(Limit::Time(scene.end_time()), &mut || true).unwrap();
    assert_eq!(a.stopped, Some(mpm_run::RunStatus::Interrupted));
    assert!(a.steps >= 1 && a.time < scene.end_time(), "{a:?}");
    // and it goes on from there
    let b = sim.advance(Limit::Steps(3), &mut || false).unwrap();
    assert_eq!(b.steps, a.steps + 3);
}

/// A small 3D scene: a sand block sliding and spreading on a 30° floor (a gravity tilted in the
/// x–y plane), B-spline APIC, with checkpoints.
const BLOCK_3D: &str = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [16, 6, 6]

[materials.sand]
kind = "drucker_prager"
young = 2.0e6
poisson = 0.3
density = 1600.0
cohesion = 0.0
friction_angle_deg = 33.0

[[bodies]]
material = "sand"
shape = "box"
min = [0.3, 0.0, 0.2]
max = [0.7, 0.3, 0.4]

[boundaries]
ground = { friction_angle_deg = 20.0 }
back_wall = "frictionless"
front_wall = "frictionless"

[solver]
scheme = "musl"
transfer = "apic"
shape_function = "bspline"
gravity = [4.905, -8.496, 0.0]
end_time = 0.12

[output]
interval = 0.03
checkpoint_interval = 0.05
hazard_maps = true
envelope = true
probes = [{ nearest = [0.5, 0.1, 0.3] }, 7]
"#;

/// A 3D run stopped part-way writes a checkpoint, and `resume` continues it to the bits of the
/// same run in one go: state hash, steps, energy ledger, every row of energy.csv, runout.csv and
/// probes.csv, the hazard maps and the envelopes along the runout line.
#[test]
fn a_3d_run_resumed_from_its_checkpoint_is_the_run_itself() {
    let scene = mpm_scene::load_space_str(BLOCK_3D, "block3d").unwrap();
    let base = std::env::temp_dir().join(format!("mpm-resume3d-{}", std::process::id()));
    let (whole_dir, part_dir) = (base.join("whole"), base.join("part"));
    let whole = mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(whole_dir.clone()), ..Default::default() },
    )
    .unwrap();
    assert_eq!(whole.status, mpm_scene::RunStatus::Completed);
    let stopped = mpm_run::run_space_scene(
        &scene,
        &RunOptions {
            out_dir: Some(part_dir.clone()),
            stop_after: Some(0.07),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(stopped.status, mpm_scene::RunStatus::Interrupted);
    let c = checkpoint::read(&part_dir.join(checkpoint::FILE_NAME)).unwrap();
    assert_eq!(c.state.dimension(), 3);
    assert!(c.state.clock().0 >= 0.07, "the checkpoint is the stopping step's");
    let resumed = resume(&part_dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.status, mpm_scene::RunStatus::Completed);
    assert_eq!(resumed.dimension, 3);
    assert_eq!(resumed.state_hash, whole.state_hash);
    assert_eq!(resumed.steps, whole.steps);
    assert_eq!(resumed.energy, whole.energy);
    let energy = |d: &std::path::Path| std::fs::read_to_string(d.join("energy.csv")).unwrap();
    assert_eq!(energy(&part_dir), energy(&whole_dir), "energy.csv as in one go");
    let runout = |d: &std::path::Path| std::fs::read_to_string(d.join("runout.csv")).unwrap();
    assert_eq!(runout(&part_dir), runout(&whole_dir), "runout.csv as in one go");
    let probes = |d: &std::path::Path| std::fs::read_to_string(d.join("probes.csv")).unwrap();
    assert_eq!(probes(&part_dir), probes(&whole_dir), "probes.csv as in one go");
    let series_rows = energy(&whole_dir).lines().count() - 1;
    assert_eq!(probes(&whole_dir).lines().count(), 1 + 2 * series_rows, "2 probes a series row");
    assert_eq!(resumed.hazard_maps, whole.hazard_maps);
    for map in ["max_height", "max_pressure", "arrival_time", "deposit_depth"] {
        let read = |d: &std::path::Path| std::fs::read(d.join(format!("maps/{map}.tif"))).unwrap();
        assert_eq!(read(&part_dir), read(&whole_dir), "maps/{map}.tif as in one go");
    }
    for file in ["envelope.csv", "deposit.csv", "section.geojson"] {
        let read = |d: &std::path::Path| std::fs::read_to_string(d.join(file)).unwrap();
        assert_eq!(read(&part_dir), read(&whole_dir), "{file} as in one go");
        assert!(read(&whole_dir).lines().count() > 2, "{file} has rows");
    }
    std::fs::remove_dir_all(&base).unwrap();
}

/// A 3D run advanced from outside in pieces is the run itself (the state hash, steps and energy
/// ledger of `run_space_scene` in one go), with 3-component fields and 6-component stresses; it
/// takes velocities between steps (booked: the residual moves by less than 1e-9 of the kinetic
/// energy set) and a material's change, and its checkpoint resumes to the bits of the steered
/// run; a wrong count of components is refused.
#[test]
fn a_3d_simulation_is_the_run_itself_and_is_steered_between_steps() {
    let scene = mpm_scene::load_space_str(BLOCK_3D, "block3d").unwrap();
    let whole = mpm_run::run_space_scene(&scene, &RunOptions::default()).unwrap();
    let mut sim = Simulation::new_space(&scene, None, &mut || false).unwrap();
    assert_eq!(sim.dimension(), 3);
    sim.advance(Limit::Steps(7), &mut || false).unwrap();
    sim.advance(Limit::Steps(30), &mut || false).unwrap();
    sim.advance(Limit::Time(scene.end_time), &mut || false).unwrap();
    let stepped = sim.summary().unwrap();
    assert_eq!(stepped.state_hash, whole.state_hash);
    assert_eq!(stepped.steps, whole.steps);
    assert_eq!(stepped.energy, whole.energy);
    let f = sim.space_fields().unwrap();
    assert_eq!((f.position.len(), f.stress.len()), (sim.particle_count(), sim.particle_count()));
    assert!(f.stress.iter().all(|s| s[1] <= 0.0), "the block presses on its floor");
    assert!(sim.fields().is_err(), "a 3D run's fields are space_fields");

    let mut sim = Simulation::new_space(&scene, None, &mut || false).unwrap();
    sim.advance(Limit::Time(0.03), &mut || false).unwrap();
    let n = sim.particle_count();
    assert!(sim.set_velocities([0.0, 0.0, 1.0].repeat(n - 1)).is_err(), "one short");
    let e0 = sim.energy().unwrap();
    sim.set_velocities([0.0, 0.0, 0.5].repeat(n)).unwrap();
    let e1 = sim.energy().unwrap();
    assert!((e1.residual - e0.residual).abs() < 1e-9 * e1.kinetic, "{e0:?} {e1:?}");
    sim.advance(Limit::Steps(5), &mut || false).unwrap();
    sim.set_material("materials.sand.friction_angle_deg", "25.0").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-steered3d-{}", std::process::id()));
    sim.checkpoint(&dir).unwrap();
    sim.advance(Limit::Time(scene.end_time), &mut || false).unwrap();
    let steered = sim.summary().unwrap();
    assert_ne!(steered.state_hash, whole.state_hash);
    let resumed = resume(&dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, steered.state_hash);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A block 0.4 × 0.2 × 0.4 m sliding rigidly at 2 m/s along +x for 0.5 s (no gravity, a
/// frictionless floor), with `output` added to its `[output]` table (no frames, no plots).
fn sliding_block(output: &str) -> String {
    let scene = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [20, 4, 10]
[materials.block]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "block"
shape = "box"
min = [0.2, 0.0, 0.3]
max = [0.6, 0.2, 0.7]
velocity = [2.0, 0.0, 0.0]
[boundaries]
ground = "frictionless"
[solver]
gravity = [0.0, 0.0, 0.0]
end_time = 0.5
[output]
vtk = false
plots = false
"#;
    format!("{scene}{output}\n")
}

/// Hazard maps of a 0.4 × 0.2 × 0.4 m elastic block sliding without gravity at 2 m/s along x
/// over a frictionless floor (a rigid translation): every plan cell it passes sees the height
/// 0.2 m (its top particles' centres plus half a spacing), speeds of 2 m/s, ρ u² = 6 400 Pa
/// and h u = 0.4 m²/s; it arrives at the first step after its front particle's centre reaches
/// the cell; the final deposit covers 0.4 × 0.4 m² at 0.2 m (0.032 m³) and the swept area is
/// 1.4 × 0.4 m². Tolerance 1e-9: the velocity field stays uniform to round-off.
#[test]
fn a_rigidly_sliding_block_draws_exact_hazard_maps() {
    let scene = mpm_scene::load_space_str(&sliding_block("hazard_maps = true"), "slide").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-hazard3d-{}", std::process::id()));
    let s = mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(dir.clone()), force: true, ..Default::default() },
    )
    .unwrap();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let h = s.hazard_maps.unwrap();
    assert!(near(h.affected_area, 0.56) && near(h.deposit_area, 0.16), "{h:?}");
    assert!(near(h.deposit_volume, 0.032) && near(h.max_deposit_depth, 0.2), "{h:?}");
    assert!(near(h.max_flow_height, 0.2) && near(h.max_pressure, 6400.0), "{h:?}");
    let map = |name: &str| mpm_dem::Raster::read(&dir.join(format!("maps/{name}.asc"))).unwrap();
    let (height, speed, momentum, arrival) =
        (map("max_height"), map("max_mean_speed"), map("max_momentum"), map("arrival_time"));
    for row in 0..10 {
        for col in 0..20 {
            let k = row * 20 + col;
            let z = (row as f64 + 0.5) * 0.1;
            let x = col as f64 * 0.1;
            if !(0.3..0.7).contains(&z) || !(0.2..1.6).contains(&(x + 0.05)) {
                assert_eq!(height.heights()[k], 0.0, "({col}, {row}) untouched");
                assert_eq!(arrival.heights()[k], mpm_output::maps::NODATA);
                continue;
            }
            assert!(near(height.heights()[k], 0.2), "({col}, {row}): {}", height.heights()[k]);
            assert!(near(speed.heights()[k], 2.0) && near(momentum.heights()[k], 0.4));
            // the front particle's centre, 0.575 m at t = 0, reaches x at (x − 0.575) / 2
            let reach = ((x - 0.575) / 2.0).max(0.0);
            let t = arrival.heights()[k];
            assert!(t >= reach - 1e-9 && t < reach + s.dt.max + 1e-9, "({col}, {row}): {t}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The 3D envelopes along the runout line: a block 0.4 m long, 0.2 m high and 0.4 m wide
/// slides rigidly at 2 m/s along +x for 0.5 s (no gravity, a frictionless floor), so the strip
/// one plan cell wide about the line through its centre of mass (z = 0.5 m) sees, at every
/// station of 0.1 m the block passes over (x from 0.2 to 1.6 m), a flow 0.2 m thick moving at
/// 2 m/s, with the impact pressure ρ̄ū² = 1600 · 4 (its particles fill their volumes exactly);
/// the deposit is 0.2 m thick over x ∈ [1.2, 1.6] m and nothing beside; the stations lie on
/// the map at (x, −0.5), the line running from x = 0 to the grid's end at 2 m. These are the
/// 2D envelopes' columns, whose numbers are tested in 2D; tolerance 1e-9 as the hazard maps'
/// (a uniform velocity field stays uniform to round-off).
#[test]
fn a_rigidly_sliding_block_draws_exact_envelopes_along_its_runout_line() {
    let scene = mpm_scene::load_space_str(&sliding_block("envelope = true"), "slide").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-envelope3d-{}", std::process::id()));
    mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(dir.clone()), force: true, ..Default::default() },
    )
    .unwrap();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let rows = |name: &str| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        assert!(header.ends_with(",map_x,map_y"), "{name}: {header}");
        lines.map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect()
    };
    // x, ground, max_thickness, max_mean_speed, max_speed, max_pressure, arrival, map_x, map_y
    let envelope = rows("envelope.csv");
    assert_eq!(envelope.len(), 20, "a station per plan cell along the 2 m line");
    for (k, r) in envelope.iter().enumerate() {
        let x = (k as f64 + 0.5) * 0.1;
        assert!(near(r[0], x) && near(r[1], 0.0) && near(r[7], x) && near(r[8], -0.5), "{r:?}");
        if (0.2..1.6).contains(&x) {
            assert!(near(r[2], 0.2) && near(r[3], 2.0) && near(r[4], 2.0), "station {x}: {r:?}");
            assert!(near(r[5], 6400.0), "station {x}: {r:?}");
        } else {
            assert!(r[2] == 0.0 && r[6].is_nan(), "station {x} untouched: {r:?}");
        }
    }
    // x, ground, thickness, map_x, map_y
    for r in rows("deposit.csv") {
        let expected = if (1.2..1.6).contains(&r[0]) { 0.2 } else { 0.0 };
        assert!(near(r[2], expected), "deposit at {}: {r:?}", r[0]);
    }
    let line = std::fs::read_to_string(dir.join("section.geojson")).unwrap();
    let line: serde_json::Value = serde_json::from_str(&line).unwrap();
    let ends = &line["features"][0]["geometry"]["coordinates"];
    let at = |k: usize, c: usize| ends[k][c].as_f64().unwrap();
    let ends = [at(0, 0), at(0, 1), at(1, 0), at(1, 1)];
    assert!(near(ends[0], 0.0) && near(ends[1], -0.5) && near(ends[2], 2.0), "{ends:?}");
    assert!(near(ends[3], -0.5), "{ends:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An oblique runout line: a block slides at 2 m/s along (1, 0, 1)/√2 (no gravity), its centre
/// of mass at (0.4, 0.6) in plan off the plan's diagonal, so the line enters the 2 × 2 m plan at
/// (0, 0.2) and leaves it at (1.8, 2.0): `section.geojson` holds that chord on the map (x, −z),
/// the stations start at its entry, and the strip about it sees the block 0.2 m thick at 2 m/s
/// (a particle's speed is its 3D speed). Tolerance 1e-9: a rigid slide, round-off only.
#[test]
fn an_oblique_runout_line_runs_across_the_plan_from_edge_to_edge() {
    let text = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [20, 4, 20]
[materials.block]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "block"
shape = "box"
min = [0.2, 0.0, 0.4]
max = [0.6, 0.2, 0.8]
velocity = [1.4142135623730951, 0.0, 1.4142135623730951]
[boundaries]
ground = "frictionless"
[solver]
gravity = [0.0, 0.0, 0.0]
end_time = 0.3
[output]
vtk = false
plots = false
envelope = true
runout_direction = [1.0, 0.0, 1.0]
"#;
    let scene = mpm_scene::load_space_str(text, "oblique").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-oblique3d-{}", std::process::id()));
    mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(dir.clone()), force: true, ..Default::default() },
    )
    .unwrap();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let line = std::fs::read_to_string(dir.join("section.geojson")).unwrap();
    let line: serde_json::Value = serde_json::from_str(&line).unwrap();
    let ends = &line["features"][0]["geometry"]["coordinates"];
    let at = |k: usize, c: usize| ends[k][c].as_f64().unwrap();
    let ends = [at(0, 0), at(0, 1), at(1, 0), at(1, 1)];
    assert!(near(ends[0], 0.0) && near(ends[1], -0.2), "enters at (0, 0.2): {ends:?}");
    assert!(near(ends[2], 1.8) && near(ends[3], -2.0), "leaves at (1.8, 2.0): {ends:?}");
    let text = std::fs::read_to_string(dir.join("envelope.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect())
        .collect();
    // x, ground, max_thickness, max_mean_speed, max_speed, max_pressure, arrival, map_x, map_y
    let h = 0.1 / 2f64.sqrt();
    assert!(near(rows[0][7], 0.5 * h) && near(rows[0][8], -(0.2 + 0.5 * h)), "{:?}", rows[0]);
    let length = 1.8 * 2f64.sqrt();
    assert_eq!(rows.len(), (length / 0.1).ceil() as usize, "a station per plan cell along it");
    // (the strip meets the block's back corner at 0.28 m along the line)
    let touched: Vec<&Vec<f64>> = rows.iter().filter(|r| r[2] > 0.0).collect();
    assert!(!touched.is_empty());
    for r in &touched {
        assert!(near(r[2], 0.2) && near(r[4], 2.0), "station {}: {r:?}", r[0]);
    }
    assert!(rows.iter().filter(|r| r[0] < 0.2).all(|r| r[2] == 0.0), "nothing behind the source");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A 2D section of a DEM puts its stations on the map: `envelope.csv` and `deposit.csv` carry
/// each station's map x and y, which lie on the section line at their station's distance from
/// its start (the section runs obliquely, 100 m from (5, 5) to (65, 85), over a plane tilted
/// along map x), and `section.geojson` holds that line. Tolerance: a point computed as
/// from + s·(to − from)/|to − from|, so round-off of a few ulps of 100 m.
#[test]
fn a_dem_section_writes_its_stations_map_coordinates() {
    let dir = std::env::temp_dir().join(format!("mpm-section-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 80 × 100 cells of 1 m, z = 100 − 0.5 x
    let mut asc = String::from("ncols 80\nnrows 100\nxllcorner 0\nyllcorner 0\ncellsize 1\n");
    for _ in 0..100 {
        let row: Vec<String> =
            (0..80).map(|c| format!("{}", 100.0 - 0.5 * (c as f64 + 0.5))).collect();
        asc.push_str(&row.join(" "));
        asc.push('\n');
    }
    std::fs::write(dir.join("plane.asc"), asc).unwrap();
    // along the section z = 97.5 − 0.3 s; a 10 m release 2 m deep between s = 20 and 30
    let scene = r#"
[grid]
kind = "terrain"
cell_width = 1.0
row_height = 1.0
rows = 8
profile = { dem = "plane.asc", from = [5.0, 5.0], to = [65.0, 85.0] }
rupture_surface = [[20.0, 91.5], [25.0, 88.0], [30.0, 88.5]]
[materials.sand]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "sand"
shape = "between_profiles"
top = { dem = "plane.asc", from = [5.0, 5.0], to = [65.0, 85.0] }
bottom = [[20.0, 91.5], [25.0, 88.0], [30.0, 88.5]]
[boundaries]
ground = "rough"
[solver]
end_time = 0.02
[output]
vtk = false
plots = false
envelope = true
"#;
    let scene = mpm_scene::load_scene_str_in(scene, "section.toml", &dir).unwrap();
    let out = dir.join("out");
    let opts = RunOptions { out_dir: Some(out.clone()), force: true, ..Default::default() };
    run_scene(&scene, &opts).unwrap();
    let on_line = |x: f64, mx: f64, my: f64| {
        let expect = [5.0 + 0.6 * x, 5.0 + 0.8 * x];
        assert!((mx - expect[0]).abs() < 1e-12 && (my - expect[1]).abs() < 1e-12, "{x}: {mx} {my}");
    };
    for (file, width) in [("envelope.csv", 9), ("deposit.csv", 5)] {
        let text = std::fs::read_to_string(out.join(file)).unwrap();
        let mut lines = text.lines();
        assert!(lines.next().unwrap().ends_with(",map_x,map_y"), "{file}");
        let mut rows = 0;
        for line in lines {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), width, "{file}: {line}");
            let num = |k: usize| f[k].parse::<f64>().unwrap();
            on_line(num(0), num(width - 2), num(width - 1));
            rows += 1;
        }
        assert!(rows >= 50, "{file}: {rows} stations over the 100 m section");
    }
    let geo: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("section.geojson")).unwrap())
            .unwrap();
    let coords = &geo["features"][0]["geometry"]["coordinates"];
    assert_eq!(coords, &serde_json::json!([[5.0, 5.0], [65.0, 85.0]]));
    assert_eq!(geo["features"][0]["properties"]["length_m"], 100.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Sand released on a 3D terrain grid over a DEM file (a plane falling 0.5 m per metre towards
/// map east, tilted 0.2 m per metre towards map north): the run completes with every particle
/// above the terrain, writes its hazard maps on the DEM's map frame, and a run stopped part-way
/// resumes (the DEM read again, relative to the scene file) to the same bits.
#[test]
fn sand_released_over_a_dem_stays_above_it_and_resumes_to_the_same_bits() {
    let base = std::env::temp_dir().join(format!("mpm-terrain-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let ground = |x: f64, y: f64| 20.0 - 0.5 * (x - 500.0) + 0.2 * (y - 800.0);
    let mut dem = String::from("ncols 24\nnrows 12\nxllcorner 500\nyllcorner 800\ncellsize 0.25\n");
    for r in 0..12 {
        let y = 800.0 + (12 - r) as f64 * 0.25 - 0.125;
        let row: Vec<String> =
            (0..24).map(|c| format!("{}", ground(500.125 + c as f64 * 0.25, y))).collect();
        dem += &(row.join(" ") + "\n");
    }
    std::fs::write(base.join("plane.asc"), dem).unwrap();
    let scene_text = r#"
[grid]
dimension = 3
kind = "terrain"
dem = "plane.asc"
from = [500.125, 800.125]
to = [505.875, 802.875]
plan_cell = 0.25
layer_height = 0.25
layers = 6
[materials.sand]
kind = "drucker_prager"
young = 2.0e6
poisson = 0.3
density = 1600.0
cohesion = 0.0
friction_angle_deg = 33.0
cone_match = "outer"
[[bodies]]
material = "sand"
shape = "box"
min = [500.6, 18.0, -802.2]
max = [501.4, 20.5, -800.8]
[boundaries]
ground = { friction_angle_deg = 25.0 }
left_wall = "frictionless"
right_wall = "frictionless"
back_wall = "frictionless"
front_wall = "frictionless"
[solver]
scheme = "musl"
courant = 0.3
end_time = 0.6
[output]
vtk = false
plots = false
checkpoint_interval = 0.2
hazard_maps = true
observed = { deposit = "plane.asc" }
"#;
    let path = base.join("scene.toml");
    std::fs::write(&path, scene_text).unwrap();
    let mpm_scene::AnyScene::Space(scene) = mpm_scene::load_any_scene_file(&path).unwrap() else {
        panic!("a 3D scene")
    };
    let (whole_dir, part_dir) = (base.join("whole"), base.join("part"));
    let whole = mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(whole_dir.clone()), ..Default::default() },
    )
    .unwrap();
    assert_eq!(whole.status, mpm_scene::RunStatus::Completed);
    let c = checkpoint::read(&whole_dir.join(checkpoint::FILE_NAME)).unwrap();
    // (cohesionless sand without hardening runs as the perfectly plastic model)
    let SavedState::SpacePerfectlyPlastic(state) = &c.state else { panic!("{:?}", c.state) };
    let mpm_scene::SpaceGrid::Terrain(t) = &scene.grid else { panic!("a terrain grid") };
    let positions = &state.particles.position;
    for x in positions {
        assert!(x.y > t.ground_height(x.x, x.z), "a particle at {x} below the terrain");
    }
    let moved = positions.iter().map(|x| x.x).fold(f64::NEG_INFINITY, f64::max);
    assert!(moved > 501.6, "the sand did not flow down the slope: front at {moved}");
    // (the DEM itself as an "observed depth": positive on every one of the 23 × 11 plan cells,
    // so every cell is compared and the area overlap is the run's share of the plan)
    let o = whole.observed.as_ref().unwrap();
    assert_eq!(o.stations, 23 * 11, "{o:?}");
    let covered = whole.hazard_maps.unwrap().deposit_area / (0.25 * 0.25);
    assert!((o.area_iou.unwrap() - covered / 253.0).abs() < 1e-12, "{o:?} {covered}");
    let maps = std::fs::read_to_string(whole_dir.join("maps/max_height.asc")).unwrap();
    assert!(maps.contains("xllcorner 500.125") && maps.contains("yllcorner 800.125"), "{maps}");
    // the deposit outline covers the summary's deposit area; the figure is drawn
    let outlines = std::fs::read_to_string(whole_dir.join("maps/outlines.geojson")).unwrap();
    let tag = "\"name\":\"deposit\",\"area_m2\":";
    let at = outlines.find(tag).expect("a deposit feature") + tag.len();
    let area: f64 = outlines[at..].split(['}', ',']).next().unwrap().parse().unwrap();
    assert_eq!(area, whole.hazard_maps.unwrap().deposit_area);
    assert!(whole_dir.join("maps/hazard_map.png").is_file());
    // the ground's load: pressed (3D: in N)
    let ground = &whole.walls[0];
    assert_eq!((ground.name.as_str(), ground.unit.as_str()), ("ground", "N"));
    assert!(ground.normal_impulse > 0.0 && ground.impulse.len() == 3, "{ground:?}");
    let stopped = mpm_run::run_space_scene(
        &scene,
        &RunOptions {
            out_dir: Some(part_dir.clone()),
            stop_after: Some(0.3),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(stopped.status, mpm_scene::RunStatus::Interrupted);
    let resumed = resume(&part_dir, &RunOptions::default()).unwrap();
    assert_eq!(resumed.state_hash, whole.state_hash);
    assert_eq!(resumed.hazard_maps, whole.hazard_maps);
    std::fs::remove_dir_all(&base).unwrap();
}

/// `walls.csv` against the rigid block of eq 21: a 1 m² block of 1000 kg/m³ sliding at 10 m/s on
/// a floor of μ = 0.3 presses on it with its weight, m g = 9 810 N/m, and drags it forward with
/// μ m g. Every floor node slides, so each row's shear is μ times its normal load to rounding. The
/// elastic block starts unstressed and rings vertically for the whole run (the rows swing ±30 %
/// about the weight: a real dynamic load, not noise), so the weight is checked on the mean of the
/// rows from 0.5 s to 2 s (within 2 %) and on the normal impulse, m g T less the block's vertical
/// momentum at the end (within 1 %; measured 0.02 % over 4 s).
#[test]
fn a_sliding_block_loads_the_floor_with_its_weight_and_its_friction() {
    let text = mpm_run::embedded_scene("sliding_horizontal")
        .unwrap()
        .replace("end_time = 4.0", "end_time = 2.0");
    let scene = load_scene_str(&text, "sliding_horizontal").unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-walls-{}", std::process::id()));
    let opts = RunOptions { out_dir: Some(dir.clone()), force: true, ..Default::default() };
    let summary = run_scene(&scene, &opts).unwrap();
    let csv = std::fs::read_to_string(dir.join("walls.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("time,ground_normal,ground_shear,ground_fx,ground_fy"));
    let weight = 1000.0 * 9.81;
    let (mut rows, mut sum) = (0, 0.0);
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let (t, normal, shear, fx, fy) = (v[0], v[1], v[2], v[3], v[4]);
        assert!((shear - 0.3 * normal).abs() <= 1e-9 * weight, "t = {t}: {shear} vs {normal}");
        assert!((fx - shear).abs() <= 1e-9 * weight, "t = {t}: drags the floor along +x: {fx}");
        assert!((fy + normal).abs() <= 1e-9 * weight, "t = {t}: pressed down: {fy}");
        if t >= 0.5 {
            rows += 1;
            sum += normal;
        }
    }
    assert!(rows >= 15, "{rows} rows");
    let mean = sum / f64::from(rows);
    assert!((mean / weight - 1.0).abs() < 0.02, "mean normal load {mean} over {rows} rows");
    let ground = &summary.walls[0];
    assert_eq!((ground.name.as_str(), ground.unit.as_str()), ("ground", "N/m"));
    assert!((ground.normal_impulse / (2.0 * weight) - 1.0).abs() < 0.01, "{ground:?}");
    assert!((ground.peak_shear_force / ground.peak_normal_force - 0.3).abs() < 0.01, "{ground:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// R3-04: a terrain run resumed from its checkpoint reads its DEM again, and refuses one that is
/// not the file it started on (naming it), instead of running the rest on another terrain; the
/// checkpoint records the scene's folder as an absolute path, so that a resume from another
/// working directory finds the DEM (the scene is loaded here by a path relative to the working
/// directory, as a user types it).
#[test]
fn a_resumed_terrain_run_refuses_a_changed_dem_and_finds_it_from_anywhere() {
    let base = std::env::temp_dir().join(format!("mpm-resume-dem-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let dem = |drop: f64| {
        let mut t = String::from("ncols 12\nnrows 8\nxllcorner 0\nyllcorner 0\ncellsize 0.25\n");
        for _ in 0..8 {
            let row: Vec<String> =
                (0..12).map(|c| format!("{}", 3.0 - 0.4 * (c as f64 * 0.25) - drop)).collect();
            t += &(row.join(" ") + "\n");
        }
        t
    };
    std::fs::write(base.join("plane.asc"), dem(0.0)).unwrap();
    let text = r#"
[grid]
dimension = 3
kind = "terrain"
dem = "plane.asc"
from = [0.125, 0.125]
to = [2.875, 1.875]
plan_cell = 0.25
layer_height = 0.25
layers = 6
[materials.sand]
kind = "drucker_prager"
young = 2.0e6
poisson = 0.3
density = 1600.0
cohesion = 0.0
friction_angle_deg = 33.0
cone_match = "outer"
[[bodies]]
material = "sand"
shape = "box"
min = [0.5, 1.0, -1.5]
max = [1.0, 3.5, -0.5]
[boundaries]
ground = { friction_angle_deg = 25.0 }
left_wall = "frictionless"
right_wall = "frictionless"
back_wall = "frictionless"
front_wall = "frictionless"
[solver]
end_time = 0.3
[output]
vtk = false
plots = false
"#;
    // the scene's folder as a path relative to the working directory
    let cwd = std::env::current_dir().unwrap();
    let up = cwd.components().count() - 1;
    let relative = std::path::PathBuf::from("../".repeat(up)).join(base.strip_prefix("/").unwrap());
    let scene = mpm_scene::load_space_str_in(text, "scene.toml", &relative).unwrap();
    let part = base.join("part");
    let opts =
        RunOptions { out_dir: Some(part.clone()), stop_after: Some(0.1), ..Default::default() };
    let s = mpm_run::run_space_scene(&scene, &opts).unwrap();
    assert_eq!(s.status, mpm_scene::RunStatus::Interrupted);
    let c = checkpoint::read(&part.join(checkpoint::FILE_NAME)).unwrap();
    let recorded = c.scene_dir.clone().unwrap();
    assert!(std::path::Path::new(&recorded).is_absolute(), "{recorded}");
    assert_eq!(std::fs::canonicalize(&recorded).unwrap(), std::fs::canonicalize(&base).unwrap());
    assert_eq!(c.inputs.len(), 1, "{:?}", c.inputs);
    // the DEM lowered by 0.1 m: refused, naming it, and nothing is run
    std::fs::write(base.join("plane.asc"), dem(0.1)).unwrap();
    match resume(&part, &RunOptions::default()) {
        Err(RunError::Output(OutputError::Checkpoint { reason, .. })) => {
            assert!(reason.contains("`plane.asc`"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // the DEM restored: the run goes on to its end
    std::fs::write(base.join("plane.asc"), dem(0.0)).unwrap();
    let r = resume(&part, &RunOptions::default()).unwrap();
    assert_eq!(r.status, mpm_scene::RunStatus::Completed);
    std::fs::remove_dir_all(&base).unwrap();
}

/// Bad arguments are refused before any work, naming the argument: a thread count outside
/// 1..=MAX_THREADS (0 was taken silently as one), and a time the simulation has already passed
/// (it returned at once, as if the time had been reached).
#[test]
fn a_thread_count_of_zero_and_a_time_already_passed_are_refused() {
    assert_eq!(mpm_run::available_threads(Some(3)).unwrap(), 3);
    for bad in [0, mpm_run::MAX_THREADS + 1] {
        let e = mpm_run::available_threads(Some(bad)).unwrap_err().to_string();
        assert!(e.contains(&format!("threads = {bad}")), "{e}");
    }
    let scene = load_scene_str(mpm_run::embedded_scene("free_fall").unwrap(), "free_fall").unwrap();
    // refused before the output folder is touched: with force, an earlier run's files stay
    let dir = std::env::temp_dir().join(format!("mpm-threads0-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("energy.csv"), "earlier run").unwrap();
    let zero = RunOptions {
        threads: Some(0),
        out_dir: Some(dir.clone()),
        force: true,
        ..Default::default()
    };
    assert!(matches!(run_scene(&scene, &zero), Err(RunError::Arguments(_))));
    assert_eq!(std::fs::read_to_string(dir.join("energy.csv")).unwrap(), "earlier run");
    assert!(matches!(resume(&dir, &zero), Err(RunError::Arguments(_))));
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(Simulation::new(&scene, Some(0), &mut || false).is_err());
    let mut sim = Simulation::new(&scene, None, &mut || false).unwrap();
    sim.advance(Limit::Steps(3), &mut || false).unwrap();
    let now = sim.time();
    let e = sim.advance(Limit::Time(now - 1e-3), &mut || false).unwrap_err().to_string();
    assert!(e.contains("already at"), "{e}");
    assert_eq!(sim.time(), now);
    // the time it is at is admissible: nothing to do
    sim.advance(Limit::Time(now), &mut || false).unwrap();
    assert_eq!(sim.steps(), 3);
}

/// A 3D probe follows its particle: a box thrown at (1, 0, 0.5) m/s in free flight moves as one
/// body, so the particle nearest the probe's point (found here from the scene's seeds) has at
/// every series row the velocity (1, −g t, 0.5) and the horizontal displacement (t, 0.5 t) of
/// the closed form, to the rounding of the steps' sums (1e-9); its fall is the explicit
/// update's, Σ v_k Δt_k with v_k = −g t_k at the end of step k, which lies between −½ g t² and
/// −½ g t² − ½ g t Δt_max (a right Riemann sum of ∫ g t dt). A 3D probe point of two
/// coordinates is refused naming the field.
#[test]
fn a_3d_probe_follows_its_particle_in_free_flight() {
    let text = r#"
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [12, 20, 8]
[materials.block]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1600.0
[[bodies]]
material = "block"
shape = "box"
min = [0.2, 1.5, 0.2]
max = [0.4, 1.7, 0.4]
velocity = [1.0, 0.0, 0.5]
[solver]
end_time = 0.3
[output]
interval = 0.3
series_interval = 0.05
vtk = false
plots = false
probes = [{ nearest = [0.33, 1.62, 0.27] }]
"#;
    let scene = mpm_scene::load_space_str(text, "thrown3d").unwrap();
    let target = mpm_solver3d::Vector::new(0.33, 1.62, 0.27);
    let nearest = (0..scene.seeds.len())
        .min_by(|&a, &b| {
            let d = |i: usize| scene.seeds[i].position.distance_squared(target);
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    let dir = std::env::temp_dir().join(format!("mpm-probe3d-{}", std::process::id()));
    let s = mpm_run::run_space_scene(
        &scene,
        &RunOptions { out_dir: Some(dir.clone()), ..Default::default() },
    )
    .unwrap();
    assert_eq!(s.status, mpm_scene::RunStatus::Completed);
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), mpm_output::csv::PROBES_HEADER_3D.trim_end());
    let g = 9.81;
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let t = v[0];
        assert_eq!(v[2] as usize, nearest, "the particle nearest the point");
        let expected = [t, 0.5 * t, 1.0, -g * t, 0.5];
        for (got, want) in [v[6], v[8], v[9], v[10], v[11]].into_iter().zip(expected) {
            assert!((got - want).abs() < 1e-9, "t = {t}: {got} against {want} in {line}");
        }
        // (1e-12 m: the rounding of the sums, as above but on a fall of at most 0.45 m)
        let (fall, closed) = (-v[7], 0.5 * g * t * t);
        assert!(
            fall >= closed - 1e-12 && fall <= closed + 0.5 * g * t * s.dt.max + 1e-12,
            "{line}"
        );
        rows += 1;
    }
    assert_eq!(rows, 7, "t = 0, 0.05, …, 0.3");
    std::fs::remove_dir_all(&dir).unwrap();

    let flat = text.replace("nearest = [0.33, 1.62, 0.27]", "nearest = [0.33, 1.62]");
    let e = mpm_scene::load_space_str(&flat, "flat").unwrap_err();
    assert_eq!(e.path, "output.probes[0].nearest", "{e}");
    assert!(e.problem.contains("2 coordinates in a 3D scene"), "{e}");
    let beyond = text.replace("{ nearest = [0.33, 1.62, 0.27] }", "64");
    let e = mpm_scene::load_space_str(&beyond, "beyond").unwrap_err();
    assert_eq!((e.path.as_str(), e.value.as_deref()), ("output.probes[0]", Some("64")), "{e}");
    assert!(e.admissible.contains("0 ≤ index < 64"), "2 cells a side at 2 per cell: 4³: {e}");
    let leaving = text.replace("[solver]", "[boundaries]\nright_wall = \"outflow\"\n[solver]");
    let e = mpm_scene::load_space_str(&leaving, "leaving").unwrap_err();
    assert_eq!(e.path, "output.probes", "{e}");
    assert!(e.problem.contains("outflow"), "{e}");
    let flume = mpm_run::embedded_scene("flume").unwrap();
    let deep = flume.replace("nearest = [0.745, 1.42]", "nearest = [0.745, 1.42, 0.0]");
    assert_ne!(deep, flume);
    let e = load_scene_str(&deep, "flume").unwrap_err();
    assert_eq!(e.path, "output.probes[0].nearest", "{e}");
    assert!(e.problem.contains("3 coordinates in a 2D scene"), "{e}");
}
