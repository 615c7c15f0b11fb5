#!/usr/bin/env python3
"""Draws a 3D run's particle frame as a PNG, without ParaView: the particles seen from above
(coloured by their height) and a vertical section through the middle (coloured by speed).

    python3 docs/examples/render3d.py out/column3d [--frame N] [--out column3d.png]

Reads `particles.pvd` and the frame's `.vtp` in any of the formats `mpm` writes (binary, the
default; ascii; zlib-compressed), with NumPy and matplotlib only. ParaView opens the same files
(`particles.pvd`) for anything more.
"""
import argparse
import os
import re
import struct
import sys
import zlib

import numpy as np


def frames(run):
    """(time, path) of every frame in the run's collection."""
    text = open(os.path.join(run, "particles.pvd")).read()
    out = []
    for m in re.finditer(r'timestep="([^"]+)"[^>]*file="([^"]+)"', text):
        out.append((float(m.group(1)), os.path.join(run, m.group(2))))
    return out


def read_vtp(path):
    """{array name: (values, components)} of one frame."""
    data = open(path, "rb").read()
    head_end = data.find(b"<AppendedData")
    head = data[: head_end if head_end >= 0 else len(data)].decode()
    appended = b""
    if head_end >= 0:
        start = data.index(b"_", head_end) + 1
        appended = data[start:]
    compressed = "vtkZLibDataCompressor" in head
    arrays = {}
    for m in re.finditer(r"<DataArray ([^>]*?)(/?)>", head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        name, kind = attrs.get("Name"), attrs.get("type")
        if name is None or name == "TimeValue":
            continue
        ncomp = int(attrs.get("NumberOfComponents", "1"))
        dtype = {"Float64": "<f8", "Int32": "<i4", "Int64": "<i8"}[kind]
        if attrs.get("format") == "ascii":
            body = head[m.end(): head.index("</DataArray>", m.end())]
            values = np.array(body.split(), dtype=dtype)
        else:
            off = int(attrs["offset"])
            if compressed:
                blocks, _, _ = struct.unpack_from("<QQQ", appended, off)
                sizes = struct.unpack_from("<%dQ" % blocks, appended, off + 24)
                at = off + 24 + 8 * blocks
                raw = b""
                for s in sizes:
                    raw += zlib.decompress(appended[at: at + s])
                    at += s
            else:
                (n,) = struct.unpack_from("<Q", appended, off)
                raw = appended[off + 8: off + 8 + n]
            values = np.frombuffer(raw, dtype=dtype)
        arrays[name] = values.reshape(-1, ncomp) if ncomp > 1 else values
    return arrays


def main():
    p = argparse.ArgumentParser()
    p.add_argument("run")
    p.add_argument("--frame", type=int, default=-1, help="frame index (default: the last)")
    p.add_argument("--out", default="")
    a = p.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, path = frames(a.run)[a.frame]
    f = read_vtp(path)
    x = f["position"]
    first = read_vtp(frames(a.run)[0][1])["position"]
    speed = np.linalg.norm(f["velocity"], axis=1) if "velocity" in f else np.zeros(len(x))
    fig, (top, side) = plt.subplots(1, 2, figsize=(11, 4.6), gridspec_kw={"width_ratios": [1, 1.4]})
    order = np.argsort(x[:, 1])
    sc = top.scatter(x[order, 0], x[order, 2], c=x[order, 1], s=2, cmap="viridis")
    top.set_aspect("equal")
    top.set_xlabel("x (m)")
    top.set_ylabel("z (m)")
    top.set_title(f"from above at t = {t:.2f} s (colour: height)")
    fig.colorbar(sc, ax=top, label="y (m)", shrink=0.8)
    zc = np.median(first[:, 2])
    h = np.min(np.diff(np.unique(np.round(first[:, 2], 9)))) if len(first) > 1 else 0.01
    band = np.abs(x[:, 2] - zc) < h
    band0 = np.abs(first[:, 2] - zc) < h
    side.scatter(first[band0, 0], first[band0, 1], s=3, c="0.8", label="t = 0")
    sc2 = side.scatter(x[band, 0], x[band, 1], c=speed[band], s=3, cmap="plasma", label=f"t = {t:.2f} s")
    side.set_aspect("equal")
    side.set_xlabel("x (m)")
    side.set_ylabel("y (m)")
    side.set_title(f"section z = {zc:.3f} m (colour: speed)")
    side.legend(loc="upper right", markerscale=4)
    fig.colorbar(sc2, ax=side, label="speed (m/s)", shrink=0.8)
    fig.tight_layout()
    out = a.out or os.path.join(a.run, "render3d.png")
    fig.savefig(out, dpi=110)
    print(f"wrote {out}: frame at t = {t} s, {len(x)} particles", file=sys.stderr)


if __name__ == "__main__":
    main()
