"""Tests of the Python package against independent references: free fall's momentum (m g t),
the run driver's own bits (a run and a stepped simulation of the same scene end with the same
state hash; a resumed run too), the located messages of the scene validation, and the worked
examples' answers."""

import _thread
import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import granular_mpm as gm

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "docs" / "examples"
G = 9.81


def short_fall(end_time=0.02):
    return gm.Scene.embedded("free_fall").set("solver.end_time", end_time)


def test_embedded_scenes_are_listed_with_the_flume_first():
    names = gm.scenes()
    assert names[0] == "flume"
    assert {"free_fall", "sliding_horizontal", "sliding_inclined"} <= set(names)


def test_free_fall_momentum_is_m_g_t_to_round_off():
    # Free fall is exact in MPM: every node gains g Δt a step, so the mass-weighted mean velocity
    # is -g t to round-off (the tolerance: 1e-12 relative, a few hundred steps of rounding).
    sim = gm.Simulation(short_fall(0.05))
    assert sim.advance_to(0.03) is None
    f = sim.fields()
    vy = np.sum(f["mass"] * f["velocity"][:, 1]) / np.sum(f["mass"])
    assert sim.time == pytest.approx(0.03, abs=1e-15)
    assert vy == pytest.approx(-G * 0.03, rel=1e-12)
    assert f["position"].shape == (sim.particle_count, 2)
    assert f["stress"].shape == (sim.particle_count, 4)
    # the ledger's kinetic energy is the particles' (1e-12: summation order)
    kinetic = 0.5 * np.sum(f["mass"] * np.sum(f["velocity"] ** 2, axis=1))
    assert sim.energy["kinetic"] == pytest.approx(kinetic, rel=1e-12)


def test_a_stepped_simulation_gives_the_runs_bits():
    scene = short_fall()
    ran = gm.run(scene)
    sim = gm.Simulation(scene)
    sim.step(5)
    assert sim.steps == 5
    sim.advance_to(scene.end_time)
    stepped = sim.summary()
    assert stepped["state_hash"] == ran.summary["state_hash"]
    assert stepped["steps"] == ran.summary["steps"]
    assert ran.status == "completed"


def test_series_are_arrays_of_the_runs_csv_files(tmp_path):
    r = gm.run(short_fall(), out=tmp_path / "fall")
    energy = r.series("energy")
    assert isinstance(energy["time"], np.ndarray)
    assert energy["time"][0] == 0.0 and energy["time"][-1] == pytest.approx(0.02)
    # the series' last row is the summary's ledger
    assert energy["kinetic"][-1] == pytest.approx(r.summary["energy"]["kinetic"], rel=1e-12)
    assert (tmp_path / "fall" / "summary.json").is_file()
    assert r.out == tmp_path / "fall"


def test_a_checkpoint_resumes_to_the_same_bits(tmp_path):
    # step() keeps the steps of a run in one go; advance_to() shortens its last step to land on
    # its time, so the reference is the simulation itself continued past the checkpoint
    scene = short_fall()
    whole = gm.run(scene).summary
    sim = gm.Simulation(scene)
    sim.step(20)
    sim.checkpoint(tmp_path / "steps")
    assert gm.resume(tmp_path / "steps").summary["state_hash"] == whole["state_hash"]
    sim.advance_to(0.015)  # (20 steps reached 0.0136 s: a time already passed is refused)
    sim.checkpoint(tmp_path / "landed")
    sim.advance_to(scene.end_time)
    resumed = gm.resume(tmp_path / "landed").summary
    assert resumed["state_hash"] == sim.summary()["state_hash"]
    assert resumed["status"] == "completed"


BLOCK_3D = """
silence = ["no_floor"]  # a free fall, meant
[grid]
dimension = 3
kind = "regular"
origin = [0.0, 0.0, 0.0]
cell = [0.1, 0.1, 0.1]
cells = [8, 6, 6]

[materials.block]
kind = "elastic"
young = 1.0e6
poisson = 0.3
density = 1000.0

[[bodies]]
material = "block"
shape = "box"
min = [0.2, 0.1, 0.2]
max = [0.6, 0.3, 0.4]

[solver]
gravity = [0.0, -9.81, 0.0]
end_time = 0.05

[output]
interval = 0.01
"""


def test_a_3d_scene_falls_freely_and_resumes_to_the_same_bits(tmp_path):
    scene = gm.Scene.from_str(BLOCK_3D, "block3d").set("output.checkpoint_interval", 0.03)
    assert scene.dimension == 3 and scene.particle_count == 4 * 2 * 2 * 8
    whole = gm.run(scene, tmp_path / "run").summary
    assert whole["dimension"] == 3 and whole["status"] == "completed"
    # nothing touches the block: the explicit update (v += g Δt, then x += v Δt) drops its
    # centre of mass between g t²/2 and g t (t + Δt)/2
    t, dt = 0.05, whole["dt"]["max"]
    travel = whole["runout"]["com_travel"]
    assert G * t * t / 2 - 1e-12 <= travel <= G * t * (t + dt) / 2 + 1e-12
    # the folder keeps the checkpoint of t = 0.03 s: resuming it runs the rest again, to the
    # same bits
    assert gm.resume(tmp_path / "run").summary["state_hash"] == whole["state_hash"]
    # stepped from Python, the same run to the bit, with 3-component vectors and 6-component
    # stresses; a free fall is exact: the mean vertical velocity is -g t (1e-12, round-off)
    sim = gm.Simulation(scene)
    assert sim.dimension == 3
    sim.step(3)
    sim.advance_to(scene.end_time)
    assert sim.summary()["state_hash"] == whole["state_hash"]
    f = sim.fields()
    n = sim.particle_count
    assert f["position"].shape == (n, 3) and f["stress"].shape == (n, 6)
    assert np.average(f["velocity"][:, 1], weights=f["mass"]) == pytest.approx(-G * t, rel=1e-12)
    with pytest.raises(ValueError, match="N × 3"):
        sim.set_velocities(np.zeros((n, 2)))
    sim.set_body_force([0.0, G, 0.0])  # gravity cancelled: the block keeps its velocity
    v = sim.velocities
    sim.step(4)
    assert sim.velocities == pytest.approx(v, rel=1e-12)


def test_set_changes_a_field_and_refuses_a_bad_value_with_the_clis_message():
    flume = gm.Scene.embedded("flume")
    flume.set("materials.sand.friction_angle_deg", 35.0)
    assert "friction_angle_deg = 35.0" in flume.text
    before = flume.text
    with pytest.raises(gm.SceneError) as caught:
        flume.set("materials.sand.friction_angle_deg", 95.0)
    e = caught.value
    assert e.path == "materials.sand.friction_angle_deg"
    assert e.line is not None and e.fix
    assert "materials.sand.friction_angle_deg" in str(e) and "fix:" in str(e)
    assert flume.text == before  # a refused change leaves the scene as it was
    with pytest.raises(gm.SceneError) as unknown:
        flume.set("solver.no_such_setting", 1)
    assert "no_such_setting" in str(unknown.value)
    # what `mpm` refuses to read (a scene above 4 MiB) is refused here too, set or given as text
    with pytest.raises(gm.SceneError) as long_value:
        flume.set("title", "x" * (5 << 20))
    assert "larger than" in str(long_value.value)
    with pytest.raises(gm.SceneError) as long_text:
        gm.Scene.from_str(before + "#" * (5 << 20))
    assert "larger than 4 MiB" in str(long_text.value)
    assert flume.text == before


def test_python_values_become_toml_values():
    v = gm._toml_value
    assert (v(np.bool_(True)), v(np.float64(35.0)), v(np.int64(3))) == ("true", "35.0", "3")
    assert v(np.array(2.5)) == "2.5"
    assert v([1, [2.5, 'a"b\\']]) == '[1, [2.5, "a\\"b\\\\"]]'
    assert v({"friction angle": 20.0, "kind": "x"}) == '{ "friction angle" = 20.0, kind = "x" }'
    # a string with quotes, a backslash, a control character and non-ASCII text goes through
    title = 'a "quoted" \\ title\x7f é 🙂'
    scene = gm.Scene.embedded("flume").set("title", title)
    tomllib = pytest.importorskip("tomllib")  # (Python ≥ 3.11)
    assert tomllib.loads(scene.text)["title"] == title
    with pytest.raises(TypeError):
        v(object())


def test_a_missing_file_and_a_bad_text_raise_located_errors(tmp_path):
    with pytest.raises(gm.SceneError):
        gm.Scene.from_file(tmp_path / "absent.toml")
    with pytest.raises(gm.SceneError) as caught:
        gm.Scene.from_str("[grid]\nkind = 3\n", name="inline")
    assert caught.value.origin == "inline" and caught.value.line == 2


def test_ctrl_c_stops_a_run_after_a_step_and_leaves_a_checkpoint(tmp_path):
    # the flume to 30 s runs for many seconds: the signal at 0.3 s finds it stepping
    out = tmp_path / "interrupted"
    scene = gm.Scene.embedded("flume").set("solver.end_time", 30.0)
    # Python raises KeyboardInterrupt for SIGINT only with its default handler, which it does
    # not install when started with SIGINT ignored (a background job of a script, as in CI)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            gm.run(scene, out=out)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    # what `mpm` leaves on Ctrl-C: the summary of an interrupted run and its checkpoint
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert 0.0 < summary["simulated_time"] < 30.0
    assert (out / "checkpoint.bin").is_file()


def run_example(name, *args):
    return subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        capture_output=True,
        text=True,
        cwd=os.fspath(ROOT),
        check=False,
    )


def test_back_analysis_recovers_the_basal_friction_angle():
    pytest.importorskip("scipy")
    p = run_example("back_analysis.py", "--quick")
    assert p.returncode == 0, p.stdout + p.stderr
    line = [l for l in p.stdout.splitlines() if l.startswith("recovered")][0]
    recovered = float(line.split(":")[1].split("°")[0])
    assert abs(recovered - 25.0) <= 0.5, line


def test_parametric_sweep_plots_the_travel_angle(tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "parametric.png"
    p = run_example("parametric.py", "--quick", "--out", str(png))
    assert p.returncode == 0, p.stdout + p.stderr
    assert png.stat().st_size > 10_000
    table = gm.read_series(png.with_suffix(".csv"))
    assert list(table["basal_friction_deg"]) == [20.0, 25.0, 30.0]
    # a rougher base stops the slide sooner: the travel angle grows with the friction angle
    assert np.all(np.diff(table["travel_angle_deg"]) > 0), table


def test_bad_arguments_are_value_errors_naming_the_argument():
    # threads=-1 was an OverflowError, threads=0 was taken as one thread, advance_to a past
    # time returned at once, and a mistyped embedded name was a plain ValueError
    for bad in (-1, 0, True, 2.0, 10**6):
        with pytest.raises(ValueError, match="threads"):
            gm.run(short_fall(), threads=bad)
    sim = gm.Simulation(short_fall())
    with pytest.raises(ValueError, match="step"):
        sim.step(-1)
    sim.step(2)
    with pytest.raises(ValueError, match="already at"):
        sim.advance_to(-1.0)
    assert sim.steps == 2
    with pytest.raises(gm.SceneError, match="did you mean `flume`") as caught:
        gm.Scene.embedded("flum")
    assert caught.value.fix == "`flume`" and caught.value.path == "name"


def test_get_reads_a_field_and_unset_lets_its_default_apply():
    flume = gm.Scene.embedded("flume")
    assert flume.get("solver.courant") == 0.1
    assert flume.get("output.probes")[1]["nearest"] == [1.07, 0.86]
    assert flume.get("solver.dt") is None
    # courant and dt are exclusive: switching needs courant removed first
    with pytest.raises(gm.SceneError):
        flume.copy().set("solver.dt", 1e-4)
    fixed = flume.copy().unset("solver.courant").set("solver.dt", 1e-4)
    assert fixed.get("solver.courant") is None and fixed.get("solver.dt") == 1e-4
    with pytest.raises(gm.SceneError, match="does not give it"):
        flume.copy().unset("solver.dt")
    # a mistyped table is refused with the nearest name (it created a material without a kind)
    with pytest.raises(gm.SceneError, match="did you mean `sand`"):
        flume.copy().set("materials.snd.friction_angle_deg", 30.0)


@pytest.mark.parametrize("vtk_format", ["binary", "compressed", "ascii"])
def test_a_frame_reads_back_the_particles_of_the_run(tmp_path, vtk_format):
    # the run's last frame holds, to the bit, the state a stepped simulation ends with (every
    # format keeps full f64 precision), and the series the run wrote are in the result
    scene = short_fall().set("output.vtk", True).set("output.vtk_format", vtk_format)
    ran = gm.run(scene, out=tmp_path / vtk_format)
    times = [t for t, _ in ran.frames]
    assert times[0] == 0.0 and times[-1] == pytest.approx(scene.end_time, abs=1e-12)
    last = ran.frame()
    sim = gm.Simulation(scene)
    sim.advance_to(scene.end_time)
    f = sim.fields()
    assert last["time"] == times[-1]
    np.testing.assert_array_equal(last["position"][:, :2], f["position"])
    np.testing.assert_array_equal(last["velocity"][:, :2], f["velocity"])
    assert last["stress"].shape == (sim.particle_count, 3, 3)
    np.testing.assert_array_equal(last["material"], f["material"])
    first = ran.frame(0)
    np.testing.assert_array_equal(first["position"][:, :2], f["initial_position"])
    assert ran.series("walls") is not None
    with pytest.raises(ValueError, match="frames"):
        ran.frame(len(times))
    with pytest.raises(ValueError, match="out="):
        _ = gm.run(scene).frames


def test_a_3d_runs_hazard_maps_are_arrays_that_add_up_to_its_summary(tmp_path):
    # the maps are read from the run's rasters: their sums must be the summary's own figures
    # (1e-12: summation order), and cells the block never covered have no arrival (NaN)
    scene = (
        gm.Scene.from_str(BLOCK_3D, "block3d")
        .set("output.hazard_maps", True)
        .set("boundaries.ground", "rough")
    )
    ran = gm.run(scene, out=tmp_path / "maps")
    maps, h = ran.maps, ran.summary["hazard_maps"]
    depth, geo = maps["deposit_depth"]
    cell = geo["cellsize"]
    assert cell == pytest.approx(0.1) and geo["xllcorner"] == 0.0
    assert np.nansum(depth) * cell**2 == pytest.approx(h["deposit_volume"], rel=1e-12)
    assert np.nanmax(maps["max_height"][0]) == pytest.approx(h["max_flow_height"], rel=1e-12)
    arrival = maps["arrival_time"][0]
    assert np.count_nonzero(~np.isnan(arrival)) * cell**2 == pytest.approx(h["affected_area"])
    assert np.isnan(arrival).any()
    assert gm.run(short_fall(), out=tmp_path / "plane").maps == {}


def test_a_sweep_gives_each_runs_own_results_in_order(tmp_path, monkeypatch):
    # each row is what the same run gives alone, to the bit, in the order of the values; a
    # refused value is refused before anything runs
    path, values = "boundaries.ground.friction", [0.4, 0.2]
    table = gm.sweep("sliding_inclined", path, values, processes=2)
    rows = table.to_dict("list") if hasattr(table, "to_dict") else table
    assert list(rows["value"]) == values
    for value, front in zip(values, rows["front_x"]):
        alone = gm.run(gm.Scene.embedded("sliding_inclined").set(path, value)).summary
        assert front == alone["runout"]["front_x"]
    with pytest.raises(gm.SceneError):
        gm.sweep("sliding_inclined", path, [0.3, -1.0])
    # a scene travels to a worker process with its files' folder: the valley's DEM is found
    # from another working directory
    import pickle

    valley = gm.Scene.from_file(EXAMPLES / "valley_landslide.toml")
    monkeypatch.chdir(tmp_path)
    again = pickle.loads(pickle.dumps(valley))
    assert again.text == valley.text and again.particle_count == valley.particle_count


def test_series_at_common_times_interpolate_between_the_rows_around_them():
    # on a row's own time the row itself; halfway between two rows their mean (linear
    # interpolation, 1e-12: rounding); beyond the series' span refused
    r = gm.run(short_fall())
    s = r.series("runout")
    t = s["time"]
    mid = 0.5 * (t[3] + t[4])
    at = r.series_at("runout", [t[2], mid])
    assert at["com_y"][0] == s["com_y"][2]
    assert at["com_y"][1] == pytest.approx(0.5 * (s["com_y"][3] + s["com_y"][4]), rel=1e-12)
    with pytest.raises(ValueError, match="beyond"):
        r.series_at("runout", [t[-1] + 1.0])
    with pytest.raises(ValueError, match="no 'walls2'"):
        r.series_at("walls2", [0.0])


def test_a_sweep_takes_an_array_and_checks_its_arguments_first():
    with pytest.raises(ValueError, match="threads"):
        gm.sweep("free_fall", "solver.end_time", [0.01], threads=0)
    table = gm.sweep("free_fall", "solver.end_time", np.array([0.01, 0.02]), processes=1)
    rows = table.to_dict("list") if hasattr(table, "to_dict") else table
    assert list(rows["value"]) == [0.01, 0.02] and list(rows["status"]) == ["completed"] * 2
    with pytest.raises(gm.SceneError, match="did you mean `flume`"):
        gm.run("flum")


@pytest.mark.parametrize("pandas", [False, True])
def test_the_docstring_examples_run_as_doctests_with_and_without_pandas(pandas, monkeypatch):
    # The examples a reader copies must give what they show, whether pandas is installed or not
    # (with pandas the series are DataFrames). CI installs pandas and sets MPM_REQUIRE_PANDAS,
    # so that the pandas half runs there rather than being skipped.
    import doctest

    if pandas:
        if os.environ.get("MPM_REQUIRE_PANDAS"):
            import pandas  # noqa: F401  (an ImportError fails the test)
        else:
            pytest.importorskip("pandas")
    else:
        monkeypatch.setitem(sys.modules, "pandas", None)  # `import pandas` raises ImportError
    result = doctest.testmod(gm, optionflags=doctest.ELLIPSIS, report=False)
    assert result.attempted >= 10
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed"


def test_a_simulation_is_steered_between_steps(tmp_path):
    # The free-falling block (no stress, no boundary reached: momentum exact to round-off,
    # 1e-12) thrown sideways at 1 m/s keeps that velocity, then gains 2 m/s per second under a
    # body force of 2 m/s²; the kinetic energy set is booked as external work (the residual
    # moves by less than 1e-9 of it); bad arrays and fields are refused naming the argument.
    sim = gm.Simulation(short_fall(0.2))
    sim.advance_to(0.05)
    n = sim.particle_count
    f = sim.fields()
    # density = mass / volume, 1000 kg/m³ as the scene gives it (the block is unstrained)
    assert f["density"] == pytest.approx(np.full(n, 1000.0), rel=1e-12)
    assert f["pressure"].shape == (n,) and np.all(f["plastic_strain"] == 0.0)
    before = sim.energy
    sim.set_velocities(np.tile([1.0, 0.0], (n, 1)))
    after = sim.energy
    assert after["kinetic"] == pytest.approx(0.5 * np.sum(f["mass"]), rel=1e-12)
    assert abs(after["residual"] - before["residual"]) < 1e-9 * after["kinetic"]
    mean = lambda: np.average(sim.velocities, axis=0, weights=sim.fields()["mass"])
    sim.advance_to(0.1)
    assert mean() == pytest.approx([1.0, -G * 0.05], rel=1e-12)
    sim.set_body_force([2.0, 0.0])
    sim.advance_to(0.15)
    assert mean()[0] == pytest.approx(1.1, rel=1e-12)
    sim.set_body_force(None)
    for bad, name in [
        (np.zeros((n - 1, 2)), "velocities"),
        ([[np.nan, 0.0]] * n, "not finite"),
        ("fast", "velocities"),
    ]:
        with pytest.raises(ValueError, match=name):
            sim.set_velocities(bad)
    with pytest.raises(ValueError, match="force"):
        sim.set_body_force(np.zeros((n, 3)))
    with pytest.raises(ValueError, match="kind"):
        sim.set("materials.block.kind", "drucker_prager")
    with pytest.raises(ValueError, match="materials.<name>.<field>"):
        sim.set("solver.courant", 0.2)
    with pytest.raises(gm.SceneError) as e:
        sim.set("materials.block.young", -1.0)
    assert e.value.path == "materials.block.young"
    sim.set("materials.block.young", 2.0e6)
    sim.checkpoint(tmp_path / "steered")
    assert "young = 2000000.0" in (tmp_path / "steered" / "scene.toml").read_text()
    sim.advance_to(0.2)
    assert gm.resume(tmp_path / "steered").summary["state_hash"] == sim.summary()["state_hash"]


def test_a_sweep_stacks_a_series_on_common_times():
    # with series=, each run lands its rows on the k·series_interval marks (exact_times), so
    # the runs share their times exactly (to the slack of the output's slots, 1e-9 of an
    # interval) and stack without interpolation; the friction changes the slide
    table = gm.sweep(
        "sliding_inclined", "boundaries.ground.friction", [0.2, 0.4], processes=1, series="runout"
    )
    rows = table.to_dict("list") if hasattr(table, "to_dict") else table
    value, time = np.asarray(rows["value"]), np.asarray(rows["time"])
    a, b = time[value == 0.2], time[value == 0.4]
    assert len(a) == len(b) > 10 and np.array_equal(a, b)
    interval = a[1] - a[0]
    assert np.allclose(a / interval, np.round(a / interval), rtol=0, atol=1e-9)
    front = np.asarray(rows["front_x"])
    assert front[value == 0.2][-1] > front[value == 0.4][-1]
    with pytest.raises(ValueError, match="series"):
        gm.sweep("sliding_inclined", "boundaries.ground.friction", [0.2], series="walls2")
