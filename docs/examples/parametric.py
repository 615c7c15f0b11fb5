"""A parametric study: the valley landslide's travel angle against its basal friction angle.

Each angle is one run in its own process (`granular_mpm.sweep`: a process pool over the cores,
one solver thread each); the summaries give the travel angle (the source's top to the deposit's farthest point),
the runout and the stop time, and the script plots the travel angle against the friction angle
with the 1:1 line a frictional block would follow (the numbers beside it, as CSV).

    pip install ./crates/mpm-py matplotlib
    python docs/examples/parametric.py --out parametric.png
    python docs/examples/parametric.py --quick        # three angles on a coarser grid (the tests)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import granular_mpm as gm

HERE = Path(__file__).resolve().parent


def valley(quick: bool) -> gm.Scene:
    """The valley example, writing only what the sweep reads (no frames or plots)."""
    scene = gm.Scene.from_file(HERE / "valley_landslide.toml")
    if quick:
        scene.set("grid.cell_width", 5.0).set("grid.row_height", 2.5).set("grid.rows", 16)
        scene.set("solver.end_time", 45.0)
    return scene.set("output.interval", scene.end_time).set("output.plots", False)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="three angles on a coarser grid")
    parser.add_argument("--out", default="parametric.png", help="the plot (PNG)")
    args = parser.parse_args()
    angles = [20.0, 25.0, 30.0] if args.quick else [18.0, 20.0, 22.0, 24.0, 26.0, 28.0, 30.0]
    table = gm.sweep(valley(args.quick), "boundaries.ground.friction_angle_deg", angles)
    columns = table.to_dict("list") if hasattr(table, "to_dict") else table
    rows = [
        {
            "angle": columns["value"][i],
            "travel_angle": columns["travel_angle_deg"][i],
            "com_travel_angle": columns["com_travel_angle_deg"][i],
            "front_x": columns["front_x"][i],
            "stop_time": columns["stop_time"][i],
        }
        for i in range(len(angles))
    ]
    print(" basal φ   travel angle   centre of mass   front (m)   stops (s)")
    for r in rows:
        stop = "-" if r["stop_time"] is None else f"{r['stop_time']:.1f}"
        print(f"{r['angle']:7.1f}°  {r['travel_angle']:12.2f}°  {r['com_travel_angle']:14.2f}°"
              f"  {r['front_x']:10.1f}  {stop:>9}")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5), dpi=120)
    x = [r["angle"] for r in rows]
    ax.plot(x, [r["travel_angle"] for r in rows], "o-", label="travel angle (top to front)")
    ax.plot(x, [r["com_travel_angle"] for r in rows], "s--", label="centre-of-mass travel angle")
    ax.plot(x, x, ":", color="grey", label="1:1 (a sliding block)")
    ax.set_xlabel("basal friction angle (°)")
    ax.set_ylabel("travel angle (°)")
    ax.set_title("Valley landslide: travel angle against basal friction")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", framealpha=0.9)
    fig.tight_layout()
    fig.savefig(args.out)
    table = Path(args.out).with_suffix(".csv")
    with open(table, "w", encoding="utf-8") as f:
        f.write("basal_friction_deg,travel_angle_deg,com_travel_angle_deg,front_x,stop_time\n")
        for r in rows:
            stop = "" if r["stop_time"] is None else r["stop_time"]
            f.write(f"{r['angle']},{r['travel_angle']},{r['com_travel_angle']},{r['front_x']},{stop}\n")
    print(f"wrote {args.out} and {table}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
