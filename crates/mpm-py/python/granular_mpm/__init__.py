"""granular_mpm: the Material Point Method for dry granular flows and landslide runout.

The solver of Abe, Johansson & Konagai (2005) and beyond (Drucker-Prager and mu(I) soils,
Coulomb boundaries on any plane, terrain-following grids over DEM sections), scripted from
Python. Scenes are the TOML files of ``docs/scene-format.md``; a scene is validated as the
``mpm`` command validates it, and a refused one raises :class:`SceneError` with the same
located message (file, line, field, value, admissible range, fix).

>>> import granular_mpm as gm
>>> scene = gm.Scene.embedded("sliding_inclined").set("solver.end_time", 0.5)
>>> result = gm.run(scene)
>>> result.summary["status"]
'completed'
>>> front = result.series("runout")["front_x"]   # NumPy arrays (result.runout: a DataFrame
...                                              # with pandas installed, else the same dict)
>>> round(float(front[-1] - front[0]), 2)        # how far the block's front slid (m)
0.26

Runs release the GIL while they step; Ctrl-C stops a run after its current step and raises
``KeyboardInterrupt`` (a run with an output folder leaves a checkpoint that :func:`resume`
continues).
"""

from __future__ import annotations

import json
import numbers
import os
import re
import struct
import sys
import tempfile
import warnings
import zlib
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import SceneError, SolverError

__all__ = [
    "Scene",
    "Simulation",
    "Result",
    "SceneError",
    "SolverError",
    "run",
    "resume",
    "scenes",
    "read_series",
    "read_frame",
    "read_raster",
    "sweep",
    "__version__",
]

__version__: str = _native.__version__

#: The series a run writes, by name (``<name>.csv`` in its folder), when the scene asks for them.
SERIES = ("energy", "runout", "probes", "envelope", "deposit", "walls")

PathLike = Union[str, "os.PathLike[str]"]
ProgressCallback = Callable[[float, float, int], Any]


def scenes() -> List[str]:
    """The embedded scenes' names; the first (the paper's dry-sand flume) is the default."""
    return list(_native.scenes())


def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for c in text:
        if c in ('"', "\\"):
            out.append("\\" + c)
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04X}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def _toml_key(key: Any) -> str:
    key = str(key)
    bare = key and all(c.isascii() and (c.isalnum() or c in "_-") for c in key)
    return key if bare else _toml_string(key)


def _toml_value(value: Any) -> str:
    """A Python value as a TOML value: numbers, booleans, strings, and lists and dicts of them
    (NumPy scalars and arrays too)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if v != v:
            return "nan"  # TOML's spelling; validation refuses it where a number is due
        if v in (float("inf"), float("-inf")):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + items + " }"
    raise TypeError(f"cannot write {type(value).__name__} as a TOML value: {value!r}")


class Scene:
    """A validated scene.

    Build one with :meth:`from_file`, :meth:`from_str` or :meth:`embedded`; change a field with
    :meth:`set` (validated again as a whole, so a bad value raises :class:`SceneError` as the
    file would).
    """

    def __init__(self, native: "_native.Scene") -> None:
        self._native = native

    @classmethod
    def from_file(cls, path: PathLike) -> "Scene":
        """Loads a scene file; the files it names (DEM, polylines) are relative to it."""
        return cls(_native.Scene.from_file(os.fspath(path)))

    @classmethod
    def from_str(cls, text: str, name: str = "<string>") -> "Scene":
        """A scene given as TOML text; ``name`` is how error messages call it."""
        return cls(_native.Scene.from_str(text, name))

    @classmethod
    def embedded(cls, name: str = "flume") -> "Scene":
        """An embedded scene (:func:`scenes` lists them)."""
        return cls(_native.Scene.embedded(name))

    def set(self, path: str, value: Any) -> "Scene":
        """Sets the field at ``path`` (``"materials.sand.friction_angle_deg"``,
        ``"bodies[0].min"``) to ``value`` and validates the scene again; returns the scene, so
        calls chain. On a refusal the scene is left as it was."""
        self._native = self._native.with_value(path, _toml_value(value))
        return self

    def get(self, path: str) -> Any:
        """The value the scene gives at ``path`` (a number, string, bool, list or dict), or
        ``None`` when it gives none and the format's default applies."""
        text = self._native.value_json(path)
        return None if text is None else json.loads(text)

    def unset(self, path: str) -> "Scene":
        """Removes the field at ``path`` so that its default applies (e.g. ``solver.courant``
        before ``solver.dt`` is set: the two are exclusive), and validates the scene again;
        returns the scene. On a refusal the scene is left as it was."""
        self._native = self._native.without_value(path)
        return self

    def __reduce__(self) -> Any:
        # pickled as its text, origin and files folder: a scene travels to worker processes
        return (_scene_from_parts, (self.text, self.origin, self._native.files_dir))

    def copy(self) -> "Scene":
        """An independent copy (to vary one scene in a loop)."""
        return Scene(self._native)

    @property
    def text(self) -> str:
        """The scene's TOML text, as it would run."""
        return self._native.text

    @property
    def origin(self) -> str:
        """Where the scene came from (a path, ``embedded:NAME`` or the name given)."""
        return self._native.origin

    @property
    def dimension(self) -> int:
        """2 for a plane-strain scene, 3 for a 3D one (``[grid] dimension = 3``)."""
        return self._native.dimension

    @property
    def particle_count(self) -> int:
        """Particles the scene generates."""
        return self._native.particle_count

    @property
    def end_time(self) -> float:
        """The simulated time the run ends at (s)."""
        return self._native.end_time

    @property
    def initial_dt(self) -> float:
        """The first step's time increment (s)."""
        return self._native.initial_dt

    @property
    def materials(self) -> List[str]:
        """The materials' names, in the order the particles' ``material`` numbers them."""
        return list(self._native.materials)

    def check(self) -> Dict[str, Any]:
        """``mpm check``: validates fully without stepping and estimates particles, steps,
        memory and disk."""
        return json.loads(self._native.check_json())

    def write(self, path: PathLike) -> None:
        """Writes the scene's TOML text to ``path``."""
        Path(path).write_text(self.text)

    def __repr__(self) -> str:
        return repr(self._native)


def _scene_from_parts(text: str, origin: str, files_dir: Optional[str]) -> Scene:
    if files_dir is None:
        return Scene(_native.Scene.from_str(text, origin))
    return Scene(_native.Scene.from_str_in(text, origin, files_dir))


def read_series(path: PathLike) -> Dict[str, np.ndarray]:
    """One of a run's CSV series as a dict of column name to NumPy array (empty cells are NaN)."""
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
    columns: Dict[str, np.ndarray] = {}
    for i, name in enumerate(header):
        columns[name] = np.array([float(r[i]) if i < len(r) and r[i] else np.nan for r in rows])
    return columns


_VTK_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int32": "<i4", "Int64": "<i8", "UInt8": "u1"}


def _appended_bytes(data: bytes, at: int, compressed: bool) -> bytes:
    """One appended array's bytes at ``at``: a UInt64 byte count then the values, or (zlib) the
    header ``[blocks, block size, last partial size, compressed sizes...]`` then the blocks."""
    if not compressed:
        (n,) = struct.unpack_from("<Q", data, at)
        return data[at + 8 : at + 8 + n]
    blocks, _, _ = struct.unpack_from("<3Q", data, at)
    sizes = struct.unpack_from(f"<{blocks}Q", data, at + 24)
    p = at + 24 + 8 * blocks
    out = []
    for size in sizes:
        out.append(zlib.decompress(data[p : p + size]))
        p += size
    return b"".join(out)


def read_frame(path: PathLike) -> Dict[str, Any]:
    """One particle frame (``frames/particles_NNNNNN.vtp``, any ``vtk_format``) as NumPy arrays:
    ``position``, ``velocity`` and ``displacement`` (N × 3, z = 0 in 2D), ``stress`` (N × 3 × 3,
    Pa, tension positive, plane strain's σ_zz included), ``pressure``, ``plastic_strain``,
    ``density`` (N), ``body`` and ``material`` (N, integers), as far as ``output.fields`` wrote
    them, and ``time`` (s)."""
    data = Path(path).read_bytes()
    marker = b'<AppendedData encoding="raw">'
    cut = data.find(marker)
    head = (data if cut < 0 else data[:cut]).decode("utf-8")
    if "<VTKFile" not in head or "PolyData" not in head:
        raise ValueError(f"{path}: not a VTK PolyData particle frame")
    compressed = 'compressor="vtkZLibDataCompressor"' in head
    start = None if cut < 0 else data.index(b"_", cut + len(marker)) + 1
    out: Dict[str, Any] = {}
    for m in re.finditer(r"<DataArray\s([^>]*?)(/?)>", head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        name = attrs.get("Name", "")
        if name in ("connectivity", "offsets"):
            continue
        dtype = np.dtype(_VTK_TYPES[attrs["type"]])
        if attrs.get("format") == "appended":
            if start is None:
                raise ValueError(f"{path}: an appended array without the appended data")
            raw = _appended_bytes(data, start + int(attrs["offset"]), compressed)
            values = np.frombuffer(raw, dtype=dtype).copy()
        else:
            text = head[m.end() : head.index("</DataArray>", m.end())]
            values = np.array(text.split(), dtype=dtype)
        if name == "TimeValue":
            out["time"] = float(values[0])
            continue
        components = int(attrs.get("NumberOfComponents", "1"))
        if components == 9:
            values = values.reshape(-1, 3, 3)
        elif components > 1:
            values = values.reshape(-1, components)
        out[name] = values
    return out


def read_raster(path: PathLike) -> Tuple[np.ndarray, Dict[str, float]]:
    """An ESRI ASCII grid (a 3D run's ``maps/*.asc``) as (values, georeference): values is
    nrows × ncols with row 0 the northernmost, cells of ``NODATA_value`` as NaN; the
    georeference has ``xllcorner``, ``yllcorner`` (the lower-left corner, map units) and
    ``cellsize``. Cell (r, c) is centred at x = xllcorner + (c + ½)·cellsize,
    y = yllcorner + (nrows − r − ½)·cellsize."""
    keys = ("ncols", "nrows", "xllcorner", "yllcorner", "cellsize", "nodata_value")
    header: Dict[str, float] = {}
    with open(path, encoding="utf-8") as f:
        tokens = f.read().split()
    at = 0
    # the header's known keys, then every value whatever the lines (NaN and inf read as such)
    while at + 1 < len(tokens) and tokens[at].lower() in keys:
        header[tokens[at].lower()] = float(tokens[at + 1])
        at += 2
    for key in keys[:5]:
        if key not in header:
            raise ValueError(f"{path}: not an ESRI ASCII grid (no {key})")
    shape = (int(header["nrows"]), int(header["ncols"]))
    values = np.array([float(v) for v in tokens[at:]], dtype=float)
    if values.size != shape[0] * shape[1]:
        raise ValueError(f"{path}: {values.size} values against the header's nrows × ncols")
    values = values.reshape(shape)
    if "nodata_value" in header:
        values[values == header["nodata_value"]] = np.nan
    geo = {k: header[k] for k in ("xllcorner", "yllcorner", "cellsize")}
    return values, geo


def _frame(columns: Dict[str, np.ndarray]) -> Any:
    try:
        import pandas as pd
    except ImportError:
        return columns
    return pd.DataFrame(columns)


class Result:
    """What a run returns: its summary and its series.

    ``summary`` is ``summary.json`` as a dict. Each series (``energy``, ``runout``, ``probes``,
    ``envelope``, ``deposit``, ``walls``) is a pandas DataFrame when pandas is installed, else a
    dict of NumPy arrays, or ``None`` when the scene did not ask for it. ``out`` is the run's
    folder (``None`` when the run wrote into a temporary folder, since removed); ``frames`` and
    ``frame(i)`` read its particle frames.
    """

    def __init__(
        self,
        summary: Dict[str, Any],
        series: Dict[str, Optional[Dict[str, np.ndarray]]],
        out: Optional[Path],
        messages: Sequence[str] = (),
    ) -> None:
        self.summary = summary
        self.out = out
        self.messages = list(messages)
        self._series = series

    def series(self, name: str) -> Optional[Dict[str, np.ndarray]]:
        """A series as a dict of NumPy arrays (whether or not pandas is installed)."""
        return self._series.get(name)

    def series_at(self, name: str, times: Sequence[float]) -> Dict[str, np.ndarray]:
        """Series ``name`` on the given ``times`` (s), each column interpolated linearly between
        the two rows around each time: by default the rows fall on step times (within a step of
        the ``series_interval`` marks), so runs of a sweep line up on common times this way.
        (A scene with ``output.exact_times = true`` puts every row on its mark: its runs stack
        row by row as they are.) A time outside the series' span is refused."""
        s = self._series.get(name)
        if s is None:
            raise ValueError(f"the run has no {name!r} series (`{name}.csv`)")
        t = np.asarray(times, dtype=float)
        if t.ndim != 1 or not np.all(np.isfinite(t)):
            raise ValueError("times: give a list of finite times (s)")
        span = s["time"]
        if t.size and (t.min() < span[0] or t.max() > span[-1]):
            raise ValueError(
                f"times: {t.min()}–{t.max()} s reaches beyond the series' {span[0]}–{span[-1]} s"
            )
        return {k: (t if k == "time" else np.interp(t, span, v)) for k, v in s.items()}

    def _get(self, name: str) -> Any:
        s = self._series.get(name)
        return None if s is None else _frame(s)

    @property
    def energy(self) -> Any:
        """The energy ledger over time (``energy.csv``)."""
        return self._get("energy")

    @property
    def runout(self) -> Any:
        """Front, tail, thickness and centre-of-mass travel over time (``runout.csv``)."""
        return self._get("runout")

    @property
    def probes(self) -> Any:
        """The probe particles over time (``probes.csv``)."""
        return self._get("probes")

    @property
    def envelope(self) -> Any:
        """Per ground station: largest thickness, speeds, pressure, first arrival."""
        return self._get("envelope")

    @property
    def deposit(self) -> Any:
        """Per ground station: the final deposit's thickness."""
        return self._get("deposit")

    @property
    def walls(self) -> Any:
        """Normal and shear load on each boundary over time (``walls.csv``)."""
        return self._get("walls")

    def _kept(self, what: str) -> Path:
        """The run's folder, which holds its ``what``; refused for a temporary one."""
        if self.out is None:
            raise ValueError(
                f"the run wrote into a temporary folder, removed with its {what}: run it with "
                "out=FOLDER to keep them"
            )
        return self.out

    @property
    def frames(self) -> List[Tuple[float, Path]]:
        """The particle frames as (time, path), from ``particles.pvd`` (empty when the scene
        wrote none). Needs a run with ``out``: a temporary folder is gone with its frames."""
        pvd = self._kept("frames") / "particles.pvd"
        if not pvd.is_file():
            return []
        text = pvd.read_text(encoding="utf-8")
        found = re.findall(r'<DataSet timestep="([^"]+)"[^>]*file="([^"]+)"', text)
        return [(float(t), self.out / f) for t, f in found]

    @property
    def maps(self) -> Dict[str, Tuple[np.ndarray, Dict[str, float]]]:
        """A 3D run's hazard maps (``maps/*.asc``: ``max_height``, ``max_speed``,
        ``arrival_time``, ``deposit_depth``, ...) by name, each as (values, georeference)
        (:func:`read_raster`); empty for a 2D run. Needs a run with ``out``."""
        folder = self._kept("maps") / "maps"
        if not folder.is_dir():
            return {}
        return {p.stem: read_raster(p) for p in sorted(folder.glob("*.asc"))}

    def frame(self, index: int = -1) -> Dict[str, Any]:
        """The particle fields of frame ``index`` (the last by default) as NumPy arrays
        (:func:`read_frame`)."""
        frames = self.frames
        if not frames:
            raise ValueError("the run wrote no particle frames (`[output] vtk = false`?)")
        if isinstance(index, bool) or not isinstance(index, numbers.Integral):
            raise ValueError(f"frame(index): index = {index!r}: give a whole number")
        if not -len(frames) <= index < len(frames):
            raise ValueError(f"frame(index): index = {index}: the run wrote {len(frames)} frames")
        return read_frame(frames[index][1])

    @property
    def status(self) -> str:
        """``"completed"``, ``"at_rest"``, ``"energy_alarm"``, ``"step_limit"``, ..."""
        return self.summary["status"]

    def __repr__(self) -> str:
        s = self.summary
        return (
            f"Result(status={s['status']!r}, t={s['simulated_time']:.4g} s, "
            f"steps={s['steps']}, front={s['runout']['front_x']:.4g} m)"
        )


def _progress_bar(time: float, end_time: float, steps: int) -> None:
    share = 0.0 if end_time <= 0 else min(1.0, time / end_time)
    bar = "#" * int(30 * share)
    sys.stderr.write(f"\r[{bar:<30}] t = {time:.4g} / {end_time:.4g} s, {steps} steps")
    sys.stderr.flush()


def _collect(raw: Any, out: Path, keep: bool, progress: Any) -> Result:
    summary_json, messages = raw
    if progress is True:
        sys.stderr.write("\n")
    for is_warning, text in messages:
        if is_warning:
            warnings.warn(text, RuntimeWarning, stacklevel=3)
    series = {}
    for name in SERIES:
        path = out / f"{name}.csv"
        series[name] = read_series(path) if path.is_file() else None
    return Result(json.loads(summary_json), series, out if keep else None, [t for _, t in messages])


def _callback(progress: Union[bool, ProgressCallback, None]) -> Optional[ProgressCallback]:
    if progress is True:
        return _progress_bar
    if progress is False or progress is None:
        return None
    if not callable(progress):
        raise TypeError("progress is True, False or a callable(time, end_time, steps)")
    return progress


def run(
    scene: Union[Scene, str, PathLike],
    out: Optional[PathLike] = None,
    threads: Optional[int] = None,
    progress: Union[bool, ProgressCallback, None] = False,
    force: bool = False,
) -> Result:
    """Runs a scene (a :class:`Scene`, a scene file's path or an embedded scene's name).

    ``out`` is the output folder (frames, series, plots, ``summary.json``, checkpoints); by
    default the run writes into a temporary folder that is removed once its series are read.
    ``threads`` caps the worker threads (default one per core; the results are the same bits for
    any count). ``progress`` is ``True`` for a bar on stderr, or a callable
    ``f(time, end_time, steps)`` called a few times a second. ``force`` overwrites a folder that
    holds another run.

    Raises :class:`SceneError` for a refused scene, :class:`SolverError` when the solver stops
    with an instability, ``KeyboardInterrupt`` on Ctrl-C (after the current step).
    """
    native = _as_scene(scene)._native
    callback = _callback(progress)
    if out is None:
        with tempfile.TemporaryDirectory(prefix="granular_mpm-") as tmp:
            raw = _native.run(native, tmp, _threads(threads), True, callback)
            return _collect(raw, Path(tmp), False, progress)
    raw = _native.run(native, os.fspath(out), _threads(threads), force, callback)
    return _collect(raw, Path(out), True, progress)


def resume(
    out: PathLike,
    threads: Optional[int] = None,
    progress: Union[bool, ProgressCallback, None] = False,
) -> Result:
    """Continues the run in folder ``out`` from its checkpoint, bit-identically to a run that
    was never interrupted."""
    raw = _native.resume(os.fspath(out), _threads(threads), _callback(progress))
    return _collect(raw, Path(out), True, progress)


# The most worker threads a run takes (mpm-run's MAX_THREADS).
_MAX_THREADS = 4096


def _threads(threads: Optional[int]) -> Optional[int]:
    """``threads`` checked: ``None`` (one per core) or a whole number 1..4096."""
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, numbers.Integral):
        raise ValueError(
            f"threads = {threads!r}: give a whole number of worker threads (1 to "
            f"{_MAX_THREADS}), or None for one per core"
        )
    if not 1 <= threads <= _MAX_THREADS:
        raise ValueError(
            f"threads = {threads}: give 1 to {_MAX_THREADS} worker threads, or None for one "
            "per core"
        )
    return int(threads)


def _sweep_one(
    scene: Scene, path: str, value: Any, threads: int, series: Optional[str] = None
) -> Dict[str, Any]:
    """One run of a sweep (in a worker process): the value and the summary's scalars (and the
    series named, under ``"_series"``)."""
    scene = scene.copy().set(path, value)
    rows = None
    try:
        r = run(scene, threads=threads)
        s = r.summary
        rows = r.series(series) if series else None
    except SolverError as e:
        # one run's instability is that row's result: the others are kept
        s = json.loads(getattr(e, "summary_json", "") or "{}")
        s.setdefault("steps", None)
        s.setdefault("simulated_time", None)
        s["status"] = "failed"
        s["error"] = str(e)
    row: Dict[str, Any] = {"value": value, "status": s["status"], "steps": s["steps"]}
    if "error" in s:
        row["error"] = s["error"]
    row["simulated_time"] = s["simulated_time"]
    for key, v in (s.get("runout") or {}).items():
        if isinstance(v, (int, float)) or v is None:
            row[key] = v
    if series:
        row["_series"] = rows
    return row


def sweep(
    scene: Union[Scene, str, PathLike],
    path: str,
    values: Sequence[Any],
    processes: Optional[int] = None,
    threads: int = 1,
    series: Optional[str] = None,
) -> Any:
    """Runs ``scene`` once per value of the field ``path`` and returns one table: a row per
    value, in their order, with ``value``, ``status``, ``steps``, ``simulated_time`` and the
    summary's runout indicators (``travel_angle_deg``, ``com_travel_angle_deg``, ``front_x``,
    ``com_travel``, ``stop_time``, ...; ``None`` where a run has none) — a pandas DataFrame
    when pandas is installed, else a dict of lists.

    Each run is a process of its own, ``processes`` at a time (default: the cores over
    ``threads``), each with ``threads`` solver threads; every value is checked before any runs
    (a refused one raises :class:`SceneError` naming it). A run's results are the bits the same
    run gives alone; a run the solver stops has status ``"failed"`` and its ``error``, and the
    other rows stand. ``values`` is a list or a NumPy array. The workers are processes: where
    Python starts them afresh (macOS, Windows), call ``sweep`` under
    ``if __name__ == "__main__":``.

    With ``series`` (``"energy"``, ``"runout"``, ...), the table is that series of every run
    stacked instead: a ``value`` column, then the series' columns, a run's rows after the
    previous run's. Each run then has ``output.exact_times = true``, so every row falls on a
    ``k · series_interval`` mark and the runs share their times (a run the solver stopped
    contributes no rows).

    >>> table = sweep("sliding_inclined", "boundaries.ground.friction", [0.3, 0.4],
    ...               processes=1)
    >>> [round(v, 2) for v in table["value"]]
    [0.3, 0.4]
    >>> list(table["status"])
    ['completed', 'completed']
    """
    threads = _threads(threads) or 1
    base = _as_scene(scene)
    if isinstance(values, (str, bytes, dict)):
        raise ValueError("values: give a list of the field's values, e.g. [20.0, 25.0, 30.0]")
    try:
        values = [v.item() if isinstance(v, np.generic) else v for v in values]
    except TypeError:
        raise ValueError("values: give a list of the field's values, e.g. [20.0, 25.0, 30.0]")
    if series is not None:
        if series not in SERIES:
            raise ValueError(f"series = {series!r}: give one of {', '.join(SERIES)}")
        base = base.copy().set("output.exact_times", True)
    for v in values:
        base.copy().set(path, v)  # refused here, before any run
    workers = processes if processes is not None else max(1, (os.cpu_count() or 1) // threads)
    if isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 1:
        raise ValueError(f"processes = {processes!r}: give a whole number of processes, 1 or more")
    from concurrent.futures import ProcessPoolExecutor

    n = len(values)
    with ProcessPoolExecutor(max_workers=min(int(workers), max(n, 1))) as pool:
        rows = list(
            pool.map(_sweep_one, [base] * n, [path] * n, list(values), [threads] * n, [series] * n)
        )
    if series is not None:
        stacked: Dict[str, List[Any]] = {"value": []}
        for r in rows:
            data = r.get("_series")
            if not data:
                continue
            count = len(next(iter(data.values())))
            stacked["value"] += [r["value"]] * count
            for k, col in data.items():
                stacked.setdefault(k, []).extend(col.tolist())
        try:
            import pandas as pd  # type: ignore
        except ImportError:
            return {k: np.asarray(v) for k, v in stacked.items()}
        return pd.DataFrame(stacked)
    keys: List[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    columns = {k: [r.get(k) for r in rows] for k in keys}
    try:
        import pandas as pd  # type: ignore
    except ImportError:
        return columns
    return pd.DataFrame(columns)


def _as_scene(scene: Union[Scene, str, PathLike]) -> Scene:
    if isinstance(scene, Scene):
        return scene
    name = os.fspath(scene)
    if not os.path.exists(name):
        if name in scenes():
            return Scene.embedded(name)
        try:
            Scene.embedded(name)
        except SceneError as e:
            # a mistyped embedded name, not a missing file: say which scene was meant
            if getattr(e, "fix", "").startswith("`"):
                raise
    return Scene.from_file(name)


class Simulation:
    """A run advanced by the caller: for coupling and custom analysis.

    >>> sim = Simulation(Scene.embedded("free_fall"))
    >>> sim.step(10)             # ten steps; None, or why the run stopped early
    >>> sim.advance_to(0.05)     # to t = 0.05 s
    >>> sim.time
    0.05
    >>> sim.positions.shape == (sim.particle_count, 2)
    True

    The fields are copies, taken when read. Advanced by :meth:`step`, the run takes the steps of
    :func:`run`, to the same bits. Between steps a caller may set the velocities, a body force
    and a material's parameters (:meth:`set_velocities`, :meth:`set_body_force`, :meth:`set`),
    each booked in the energy ledger. One call at a time: a call from another thread while one
    runs raises ``RuntimeError``. A 3D scene's ``Simulation`` is the same, with three
    components a vector and six a stress.
    """

    def __init__(self, scene: Union[Scene, str, PathLike], threads: Optional[int] = None):
        self._native = _native.Simulation(_as_scene(scene)._native, _threads(threads))

    def step(self, n: int = 1) -> Optional[str]:
        """``n`` more steps. Returns ``None``, or why the run stopped before (``"at_rest"``,
        ``"energy_alarm"``, ``"step_limit"``)."""
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 0:
            raise ValueError(f"step(n): n = {n!r}: give a whole number of steps, 0 or more")
        return self._native.step(int(n))

    def advance_to(self, t: float) -> Optional[str]:
        """Steps until simulated time ``t`` (s), the last step shortened to land on it (so the
        steps after it differ from those of a run in one go; :meth:`step` keeps them)."""
        return self._native.advance_to(t)

    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return self._native.time

    @property
    def steps(self) -> int:
        """Steps taken."""
        return self._native.steps

    @property
    def particle_count(self) -> int:
        """Number of particles."""
        return self._native.particle_count

    @property
    def dimension(self) -> int:
        """2 (plane strain) or 3."""
        return self._native.dimension

    def fields(self) -> Dict[str, np.ndarray]:
        """All particle fields at once: ``position``, ``velocity``, ``initial_position`` (N × 2,
        or N × 3 in 3D; m and m/s), ``stress`` (N × 4: xx, yy, zz, xy; in 3D N × 6: xx, yy,
        zz, xy, yz, zx; Pa, tension positive), ``pressure``
        (−tr σ / 3, Pa, compression positive), ``plastic_strain`` (the model's equivalent plastic
        strain; 0 for an elastic material), ``mass``, ``volume`` (per m of thickness in 2D),
        ``density`` (mass / volume, kg/m³), ``body`` and ``material`` (indices)."""
        f = dict(self._native.fields())
        f["pressure"] = -f["stress"][:, :3].sum(axis=1) / 3.0
        f["density"] = f["mass"] / f["volume"]
        return f

    def _pairs(self, values: Any, name: str, one_for_all: bool) -> np.ndarray:
        """``values`` as N × d finite floats in a row (d the dimension; one vector for every
        particle when ``one_for_all``), or a ``ValueError`` naming ``name``."""
        n, d = self.particle_count, self.dimension
        try:
            a = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{name}: give an N × {d} array of numbers (N = {n} particles)")
        if one_for_all and a.shape == (d,):
            a = np.tile(a, (n, 1))
        if a.shape != (n, d):
            what = f"an N × {d} array" + (" or one vector for all" if one_for_all else "")
            raise ValueError(f"{name}: give {what} (N = {n} particles); got shape {a.shape}")
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if bad.size:
            raise ValueError(f"{name}: particle {bad[0]}'s value {a[bad[0]].tolist()} is not finite")
        return np.ascontiguousarray(a).reshape(-1)

    def set_velocities(self, velocities: Any) -> None:
        """Sets every particle's velocity before the next step: an N × 2 (3D: N × 3) array
        (m/s) in the order of :meth:`fields`. The kinetic energy it changes is booked as external work in the
        ledger (its residual does not move); the next Δt follows the new velocities."""
        self._native.set_velocities(self._pairs(velocities, "velocities", False))

    def set_body_force(self, force: Any) -> None:
        """Adds a body force per unit mass (m/s²) to gravity on every particle from the next
        step until set again: an N × 2 (3D: N × 3) array, or one vector for all; ``None`` removes
        it. Its work is booked as external work. It is not part of a :meth:`checkpoint` (a
        resumed run has gravity alone)."""
        if force is None:
            self._native.set_body_force(None)
        else:
            self._native.set_body_force(self._pairs(force, "force", True))

    def set(self, path: str, value: Any) -> "Simulation":
        """Changes a material's parameter between steps, ``path`` as
        ``"materials.<name>.<field>"`` (e.g. a strength reduction:
        ``sim.set("materials.sand.friction_angle_deg", 25.0)``), the scene with it checked as
        :meth:`Scene.set` checks it (a refused value raises :class:`SceneError`). The model
        (``kind``), the ``density`` and every other field stay as the run started (a
        ``ValueError``). The particles keep their stresses (a stress outside a new yield
        surface returns to it in the next step); the elastic energy a new stiffness gives them
        is booked as external work. A :meth:`checkpoint` after it holds the changed scene.
        Returns the simulation."""
        if not isinstance(path, str):
            raise ValueError(f"path = {path!r}: give the field as text, e.g. 'materials.sand.young'")
        self._native.set_material(path, _toml_value(value))
        return self

    @property
    def positions(self) -> np.ndarray:
        """Particle positions, N × 2 (3D: N × 3) (m)."""
        return self._native.fields()["position"]

    @property
    def velocities(self) -> np.ndarray:
        """Particle velocities, N × 2 (3D: N × 3) (m/s)."""
        return self._native.fields()["velocity"]

    @property
    def stresses(self) -> np.ndarray:
        """Cauchy stresses, N × 4: xx, yy, zz (out of plane), xy; in 3D N × 6: xx, yy, zz, xy,
        yz, zx (Pa, tension positive)."""
        return self._native.fields()["stress"]

    @property
    def energy(self) -> Dict[str, float]:
        """The energy ledger now (J per m of thickness): kinetic, strain, potential, the
        dissipations, external work and the residual."""
        return json.loads(self._native.energy_json())

    def summary(self) -> Dict[str, Any]:
        """The run so far, as :func:`run` reports it: steps, time, energy ledger and state hash
        now; the runout measures of the last recorded series row; status ``"completed"`` once the
        scene's end time is reached, ``"interrupted"`` before."""
        return json.loads(self._native.summary_json())

    def checkpoint(self, out: PathLike) -> None:
        """Writes ``out/checkpoint.bin`` and ``out/scene.toml``: :func:`resume` (or
        ``mpm resume``) continues the run from here into that folder."""
        self._native.checkpoint(os.fspath(out))

    def __repr__(self) -> str:
        return f"Simulation(t={self.time:.6g} s, steps={self.steps}, particles={self.particle_count})"
