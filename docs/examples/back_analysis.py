"""Back-analysis: recover the basal friction angle of the valley landslide from its deposit.

The "observed" deposit is made by a run of `valley_landslide.toml` at a known basal friction
angle (25°); the script then forgets it and searches the angle whose deposit fits best, by
scipy's bounded scalar search (Brent's method on [18°, 32°]). It is what a back-analysis of a
real slide does with a surveyed deposit, on a case whose answer is known.

The deposit error is the distance the deposited mass would have to move to match the observed
deposit: the earth mover's (1-Wasserstein) distance between the two thickness distributions along
the path, in metres. A granular flow is chaotic in its detail (a tenth of a degree moves single
grains by metres), so a station-by-station RMS difference is a rough landscape with many local
minima; the mass's placement varies smoothly with the friction angle, and so does this error.

    pip install ./crates/mpm-py scipy
    python docs/examples/back_analysis.py            # the example's resolution
    python docs/examples/back_analysis.py --quick    # a coarser grid, a shorter run (the tests)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

import granular_mpm as gm

HERE = Path(__file__).resolve().parent
#: The angle the "observed" deposit is made with (the scene's own basal friction angle).
TRUE_ANGLE = 25.0
#: The search interval (degrees): the plausible basal friction of a dry debris.
BOUNDS = (18.0, 32.0)


def valley(quick: bool) -> gm.Scene:
    """The valley example, writing only what the fit reads (no frames or plots)."""
    scene = gm.Scene.from_file(HERE / "valley_landslide.toml")
    if quick:
        # twice the cell size, and stopped once the main mass has come to rest
        scene.set("grid.cell_width", 5.0).set("grid.row_height", 2.5).set("grid.rows", 16)
        scene.set("solver.end_time", 45.0)
    return scene.set("output.interval", scene.end_time).set("output.plots", False)


def deposit(scene: gm.Scene, angle: float) -> tuple:
    """The stations (m along the path) and the deposit thickness there (m) of a run at basal
    friction `angle` (degrees)."""
    s = scene.copy().set("boundaries.ground", {"friction_angle_deg": float(angle)})
    d = gm.run(s).series("deposit")
    return np.asarray(d["x"]), np.asarray(d["thickness"])


def deposit_error(x: np.ndarray, h: np.ndarray, observed: np.ndarray) -> float:
    """The earth mover's distance (m) between the thickness distributions `h` and `observed` on
    the stations `x`: the integral of the difference of their cumulative shares."""
    share = np.cumsum(h) / h.sum()
    share_observed = np.cumsum(observed) / observed.sum()
    return float(np.sum(np.abs(share - share_observed)[:-1] * np.diff(x)))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a coarser grid, a shorter run")
    args = parser.parse_args()
    scene = valley(args.quick)
    start = time.perf_counter()
    x, observed = deposit(scene, TRUE_ANGLE)
    print(f"observed deposit: {scene.particle_count} particles, "
          f"largest thickness {observed.max():.2f} m (made at {TRUE_ANGLE}°)")

    runs = []

    def misfit(angle: float) -> float:
        stations, h = deposit(scene, angle)
        assert np.array_equal(stations, x), "the same grid gives the same stations"
        error = deposit_error(x, h, observed)
        runs.append((angle, error))
        print(f"  basal friction {angle:7.3f}°: deposit error {error:7.3f} m")
        return error

    fit = minimize_scalar(misfit, bounds=BOUNDS, method="bounded", options={"xatol": 0.05})
    error = fit.x - TRUE_ANGLE
    print(f"recovered basal friction angle: {fit.x:.3f}° (true {TRUE_ANGLE}°, error {error:+.3f}°) "
          f"after {len(runs)} runs, {time.perf_counter() - start:.0f} s")
    if abs(error) > 0.5:
        print("the fit missed the known angle by more than 0.5°", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
