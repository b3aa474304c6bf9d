"""Outputs of the CLI before and after a refactoring: the same files with the same content.

Run:  .venv/bin/python benchmarks/compare_outputs.py [--base REV] [--new REV] [--commands a,b] [--keep DIR]
      (4-7 min on the project's 2-core machine)

A temporary ``git worktree`` of the base revision (default ``bea6ae1``, the last commit
before the issue-12 refactoring) is made under a temporary folder and removed afterwards.
A fixed set of cheap CLI commands on the bundled ``sample_data/`` is then run twice with
this interpreter as ``python -m fuzzygait ...``: once with ``PYTHONPATH=<worktree>/src``
("base") and once with this repository's working-tree ``src`` ("new"; or a second
worktree with ``--new REV``).  Each command runs in its own empty folder (with a
``sample_data`` link to one copy of the inputs), single-threaded BLAS, Agg backend, fixed
terminal width, and its own compiled-library cache per side (``FUZZYGAIT_CACHE_DIR``), so
a stale cached library cannot hide a change of the model code (``--shared-cache`` uses the
user's cache instead).

The two folders are compared file by file:

* same set of files (a ``*.zarr`` directory is one entry);
* CSV: pandas, exact and NaN-aware (else the largest absolute difference);
* C3D: ezc3d, header, parameters and data (points, residuals, analogs) exactly;
* netCDF / zarr: every group, every variable (values, dims, dtype, attributes) and the
  attributes of every group, exactly, except timing-like attributes (``seconds``,
  ``wall_time*``, ``time_*_s``, ``created``, ``date``, ``version``).  The marker-error
  dataset may change from one variable per angle component (``LKneeAngles_X``,
  ``LKneeAngles_X__deviation``) to ``hull`` / ``deviation`` with a ``component``
  dimension, and from one flat dataset with ``refined_*``/``allowable_*``/``source_*``
  variables (layout version 1) to the bands at the root and the groups ``allowable`` and
  ``sources`` (layout version 2, issue 38; mapped with
  :func:`fuzzygait.markererror.legacy.from_flat`), and the bands' and kinetics' error
  sources from the comma-joined attribute ``sources`` to the coordinate ``error_source``
  (issue 38 item 2; :func:`fuzzygait.markererror.legacy.upgrade_sources`): when the two
  files differ in just that way the old layout is mapped onto the new one and the values
  are compared (.nc);
* PNG: decoded pixels (matplotlib.image.imread), exactly;
* SVG, HTML, Markdown, text and the printed stdout: text after masking dates, times,
  timing numbers, versions, matplotlib's random SVG ids and absolute temporary paths;
* Rerun ``.rrd``: the rows of every entity (``rerun.chunk.RrdReader``), without row ids
  and the recording start time, as sets per entity (chunking is not compared);
* anything else: bytes.

One row per file (markdown table): ``same`` or ``differs (...)``.  Exit code 0 when
everything is the same, 1 when anything differs (or a command timed out), 2 when the
comparison itself could not run.

Determinism check (both sides from the same commit; 52 of 52 same at bea6ae1):
    .venv/bin/python benchmarks/compare_outputs.py --base bea6ae1 --new bea6ae1

A command that fails on both sides counts as a difference (it verifies nothing).  stderr
(progress bars, warnings) is kept in ``logs/`` but not compared.  ``--compare-only DIR``
compares the outputs of an earlier ``--keep DIR`` run again without running anything.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT_BASE = "bea6ae1"
DATA = "sample_data"  # the link to the inputs inside every command folder

# name -> steps, each the arguments of ``python -m fuzzygait`` (split like a shell), run in
# the command's folder; ``sample_data/`` there links to one copy of the inputs, ``{c3d}``
# stands for every sample C3D file (sorted).  Times on the project's 2-core machine, per
# side: demo 20 s, uncertainty 14 s, report 15 s, the simulator commands 4-12 s (including
# compiling the model once per side), the others 3-5 s.
MODEL = "--static sample_data/static.c3d --subject sample_data/subject.toml"
FRV = "frv-sim stance --disc 10 --alphas 0,0.5 --duration 0.05 --workers 1 --out frv.zarr"
COMMANDS: dict[str, list[str]] = {
    "demo": ["demo --out D"],
    "angles": [f"angles sample_data/walking.c3d {MODEL} --out angles.csv --cycles cycles.csv --c3d-out out.c3d"],
    "preprocess": ["preprocess sample_data/walking_noisy.c3d --out pre.c3d"],
    "info": ["info {c3d}"],
    "uncertainty": [
        f"uncertainty sample_data/walking.c3d {MODEL} --angles LKneeAngles --alphas 0,0.5 --out u.nc --rrd u.rrd"
    ],
    "report": [f"report sample_data/walking.c3d {MODEL} --angles LKneeAngles --alphas 0,0.5 --out R"],
    "simulate": ["simulate swing --duration 0.05 --set eta=1e5 --out s.nc --plot s.png --rrd s.rrd"],
    "simulate-stance": ["simulate stance --duration 0.05 --sensitivities --out st.zarr --plot st.svg"],
    "fuzzy-sim": [
        "fuzzy-sim swing --fuzzy E=10% --duration 0.05 --set eta=1e5 --out f.nc --plot f.png"
        " --parameter-plot fp.svg --rrd f.rrd"
    ],
    "frv-sim": [f"{FRV} --samples 50", f"{FRV} --samples 20"],  # a new study, then extended by 20 samples
    "sample-data": ["sample-data --out sd"],
}

THREAD_VARIABLES = (
    "OPENBLAS_NUM_THREADS",
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMBA_NUM_THREADS",
)

# ---------------------------------------------------------------------------------------
# masking of volatile content
# ---------------------------------------------------------------------------------------

TIMING_KEY = re.compile(
    r"(^|_)(seconds|wall|wall_time|elapsed|created|date|datetime|timestamp|version|runtime)(_|$)"
    r"|^time_\w+_s$|_time_s$|^start_time$",
    re.IGNORECASE,
)
MASKS: list[tuple[re.Pattern[str], str]] = [
    # ISO and report dates/times: 2026-12-01T22:21:37.363789, 2026-12-01 22:21 UTC
    (re.compile(r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(:\d{2}(\.\d+)?)?(\s?(UTC|Z|[+-]\d{2}:?\d{2}))?"), "<DATE>"),
    (re.compile(r"\b\d{4}-\d{2}-\d{2}\b"), "<DATE>"),
    # timing numbers after a timing word: "wall time 0.04 s", "'wall_time': 1.86", seconds=10.9
    (
        re.compile(
            r"(?i)(\b(?:wall[ _-]?time|elapsed|took|runtime|seconds|last_wall_time)\w*['\"]?\s*[:=]?\s*)"
            r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"
        ),
        r"\1<T>",
    ),
    # the notes' run times: "3 runs, 1.7 s", "22 refinement runs, 14.0 s"
    (re.compile(r"(\bruns, )\d+(?:\.\d+)? s\b"), r"\1<T> s"),
    # package and library versions
    (
        re.compile(r"(?i)\b(fuzzygait|matplotlib|rerun|xarray|numpy|ezc3d)(\s+v?|[ -]?)\d+\.\d+(\.\d+)?[\w.+-]*"),
        r"\1 <VERSION>",
    ),
    # temporary files anywhere
    (re.compile(r"(/private)?/(tmp|var/folders)/[^\s\"'<>)\]]*"), "<TMP>"),
]
# matplotlib's SVG ids are salted with a fresh uuid per figure unless svg.hashsalt is set
SVG_ID = re.compile(r"\b(?:[pmh]|(?:Im_)?image|C[0-9a-f]+_[0-9a-f]+_)[0-9a-f]{10}\b")


def mask_text(text: str, replacements: Sequence[tuple[str, str]] = ()) -> str:
    for old, new in replacements:
        text = text.replace(old, new)
    for pattern, repl in MASKS:
        text = pattern.sub(repl, text)
    ids: dict[str, str] = {}
    return SVG_ID.sub(lambda m: ids.setdefault(m.group(0), f"<id{len(ids)}>"), text)


def mask_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Attributes without the timing-like keys (recursively), string values masked."""
    out: dict[str, Any] = {}
    for key, value in attrs.items():
        if TIMING_KEY.search(str(key)):
            continue
        if isinstance(value, Mapping):
            value = mask_attrs(value)
        elif isinstance(value, str):
            value = mask_text(value)
        out[str(key)] = value
    return out


# ---------------------------------------------------------------------------------------
# generic equality
# ---------------------------------------------------------------------------------------


STRING_KINDS = "USO"


def arrays_equal(a: Any, b: Any) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return False
    if a.dtype.kind in STRING_KINDS and b.dtype.kind in STRING_KINDS:  # fixed or variable length text
        return bool(np.array_equal(a.astype(str), b.astype(str)))
    if a.dtype.kind != b.dtype.kind:
        return False
    if a.dtype.kind in "fc":
        return bool(np.array_equal(a, b, equal_nan=True))
    return bool(np.array_equal(a, b))


def max_abs_difference(a: Any, b: Any) -> str:
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return f"shape {a.shape} vs {b.shape}"
    if a.dtype.kind not in "fciub" or b.dtype.kind not in "fciub":
        return f"{int(np.sum(a != b))} of {a.size} values"
    a, b = a.astype(float), b.astype(float)
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    text = []
    if (nan_a != nan_b).any():
        text.append(f"NaN at {int((nan_a != nan_b).sum())} other places")
    both = ~(nan_a | nan_b)
    if both.any():
        diff = np.abs(a[both] - b[both])
        if np.isinf(diff).any() or (diff > 0).any():
            text.append(f"max abs diff {np.nanmax(diff):.3g} at {int((diff != 0).sum())} of {a.size}")
    if a.dtype != b.dtype:
        text.append(f"dtype {a.dtype} vs {b.dtype}")
    return ", ".join(text) or "equal values"


def deep_diff(a: Any, b: Any, where: str = "", limit: int = 5) -> list[str]:
    """Where two nested dict/list/array structures differ (at most ``limit`` places)."""
    out: list[str] = []

    def walk(x: Any, y: Any, at: str) -> None:
        if len(out) >= limit:
            return
        if isinstance(x, Mapping) and isinstance(y, Mapping):
            kx, ky = set(map(str, x)), set(map(str, y))
            if kx != ky:
                out.append(f"{at or '/'}: keys only in base {sorted(kx - ky)[:5]}, only in new {sorted(ky - kx)[:5]}")
            for key in sorted(kx & ky):
                walk(x[key], y[key], f"{at}/{key}")
        elif isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if not arrays_equal(x, y):
                out.append(f"{at}: {max_abs_difference(x, y)}")
        elif isinstance(x, list | tuple) and isinstance(y, list | tuple):
            if len(x) != len(y):
                out.append(f"{at}: length {len(x)} vs {len(y)}")
            else:
                for i, (u, v) in enumerate(zip(x, y, strict=True)):
                    walk(u, v, f"{at}[{i}]")
        elif isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y):
            return
        elif type(x) is not type(y) or x != y:
            out.append(f"{at}: {str(x)[:60]!s} vs {str(y)[:60]!s}")

    walk(a, b, where)
    return out


# ---------------------------------------------------------------------------------------
# comparison per file type
# ---------------------------------------------------------------------------------------


@dataclass
class Outcome:
    same: bool
    detail: str = ""

    def __str__(self) -> str:
        word = "same" if self.same else "differs"
        return f"{word} ({self.detail})" if self.detail else word


def bytes_note(a: Path, b: Path) -> str:
    return "" if a.is_dir() or a.read_bytes() == b.read_bytes() else "bytes differ"


def compare_bytes(a: Path, b: Path) -> Outcome:
    return Outcome(a.read_bytes() == b.read_bytes(), "" if a.read_bytes() == b.read_bytes() else "bytes")


def first_text_difference(x: str, y: str) -> str:
    lx, ly = x.splitlines(), y.splitlines()
    for i, (u, v) in enumerate(zip(lx, ly, strict=False), start=1):
        if u != v:
            return f"line {i}: {u.strip()[:90]!r} vs {v.strip()[:90]!r}"
    extra = lx[len(ly)] if len(lx) > len(ly) else ly[len(lx)]
    return f"{len(lx)} vs {len(ly)} lines, first extra line {extra.strip()[:90]!r}"


def compare_text_content(x: str, y: str, replacements: Sequence[tuple[str, str]]) -> Outcome:
    mx, my = mask_text(x, replacements), mask_text(y, replacements)
    if mx == my:
        return Outcome(True, "" if x == y else "after masking")
    return Outcome(False, first_text_difference(mx, my))


def compare_csv(a: Path, b: Path) -> Outcome:
    import pandas as pd

    x, y = pd.read_csv(a), pd.read_csv(b)
    if list(x.columns) != list(y.columns):
        only_a, only_b = sorted(set(x.columns) - set(y.columns)), sorted(set(y.columns) - set(x.columns))
        return Outcome(False, f"columns: only in base {only_a[:5]}, only in new {only_b[:5]}, or order")
    if x.shape != y.shape:
        return Outcome(False, f"shape {x.shape} vs {y.shape}")
    if x.equals(y):
        return Outcome(True, bytes_note(a, b))
    worst = [f"{c}: {max_abs_difference(x[c].to_numpy(), y[c].to_numpy())}" for c in x.columns if not x[c].equals(y[c])]
    return Outcome(False, f"{len(worst)} columns, e.g. " + "; ".join(worst[:3]))


def compare_c3d(a: Path, b: Path) -> Outcome:
    import ezc3d

    def content(path: Path) -> dict[str, Any]:
        c = ezc3d.c3d(str(path))
        return {"header": c["header"], "parameters": c["parameters"], "data": c["data"]}

    problems = deep_diff(content(a), content(b))
    return Outcome(not problems, "; ".join(problems) if problems else bytes_note(a, b))


MARKER_ERROR_COMPONENT = re.compile(r"^[LR]\w+Angles_[XYZ]$")


def marker_error_layout(ds: Any) -> str | None:
    """'component' (hull/deviation with a component dim), 'per-variable' (old) or None."""
    if "component" in ds.dims and "hull" in ds.data_vars:
        return "component"
    if any(MARKER_ERROR_COMPONENT.match(str(v)) for v in ds.data_vars) and "ball_radius" in ds.data_vars:
        return "per-variable"
    return None


def to_component_layout(ds: Any, like: Any) -> Any:
    """The old per-variable marker-error dataset in the new layout of ``like``."""
    import xarray as xr

    components = [str(c) for c in like["component"].values]
    old = [str(v) for v in ds.data_vars if MARKER_ERROR_COMPONENT.match(str(v))]
    if sorted(old) != sorted(components):
        raise ValueError(f"components: base {sorted(old)} vs new {sorted(components)}")
    coord = xr.DataArray(components, dims="component", name="component")
    data = {"hull": xr.concat([ds[c] for c in components], dim=coord, coords="minimal", compat="override")}
    if all(f"{c}__deviation" in ds for c in components):
        deviations = [ds[f"{c}__deviation"] for c in components]
        data["deviation"] = xr.concat(deviations, dim=coord, coords="minimal", compat="override")
    rest = [v for v in ds.data_vars if v not in old and not str(v).endswith("__deviation")]
    out = xr.Dataset({**data, **{v: ds[v] for v in rest}}, attrs=ds.attrs)
    # the new layout may label the components by angle and axis ("LKneeAngles", "X")
    derived = {"angle": [c.rsplit("_", 1)[0] for c in components], "axis": [c.rsplit("_", 1)[1] for c in components]}
    for name, values in derived.items():
        if name in like.coords and like[name].dims == ("component",):
            out = out.assign_coords({name: ("component", values)})
    for name in ("hull", "deviation"):
        if name in out and name in like:
            out[name] = out[name].transpose(*like[name].dims)
            out[name].attrs = ds[components[0] if name == "hull" else f"{components[0]}__deviation"].attrs
    return out


#: Variables of a version-1 (flat) marker-error dataset that version 2 keeps in groups.
FLAT_MARKER_ERROR = ("refined_alpha", "allowable_status", "source_hull")


def netcdf_groups(path: Path) -> dict[str, Any]:
    """Every group of a netCDF file, loaded: ``{"/": root, "/name": group, ...}``."""
    import xarray as xr

    groups = xr.open_groups(path)
    try:
        return {name: ds.load() for name, ds in groups.items()}
    finally:
        for ds in groups.values():
            ds.close()


def to_marker_error_groups(ds: Any) -> dict[str, Any]:
    """A version-1 (flat) marker-error dataset as the groups version 2 writes."""
    from fuzzygait.markererror.legacy import from_flat

    return from_flat(ds).groups()


def map_error_sources(x_groups: dict[str, Any], y_groups: dict[str, Any]) -> bool:
    """Where a group of one file names the error sources in the old comma-joined attribute
    and the same group of the other has the coordinate, give the old one the coordinate
    (in place); True when any was mapped."""
    from fuzzygait.markererror.legacy import SOURCES_ATTR, upgrade_sources
    from fuzzygait.markererror.result import SOURCES_COORD

    mapped = False
    for groups, other in ((x_groups, y_groups), (y_groups, x_groups)):
        for name in set(groups) & set(other):
            ds = groups[name]
            if SOURCES_ATTR in ds.attrs and SOURCES_COORD not in ds.coords and SOURCES_COORD in other[name].coords:
                groups[name] = upgrade_sources(ds)
                mapped = True
    return mapped


def compare_variables(x: Any, y: Any, where: str, allow_transpose: bool = False) -> list[str]:
    """Differences of two xarray Datasets (all variables, attributes)."""
    problems = []
    vx, vy = set(map(str, x.variables)), set(map(str, y.variables))
    if vx != vy:
        problems.append(f"{where}variables only in base {sorted(vx - vy)[:6]}, only in new {sorted(vy - vx)[:6]}")
    for name in sorted(vx & vy):
        a, b = x.variables[name], y.variables[name]
        if a.dims != b.dims:
            if allow_transpose and set(a.dims) == set(b.dims):
                b = b.transpose(*a.dims)
            else:
                problems.append(f"{where}{name}: dims {a.dims} vs {b.dims}")
                continue
        if not arrays_equal(a.values, b.values):
            problems.append(f"{where}{name}: {max_abs_difference(a.values, b.values)}")
        if a.dtype != b.dtype and not (a.dtype.kind in STRING_KINDS and b.dtype.kind in STRING_KINDS):
            problems.append(f"{where}{name}: dtype {a.dtype} vs {b.dtype}")
        attr_problems = deep_diff(mask_attrs(a.attrs), mask_attrs(b.attrs), f"{where}{name}.attrs", limit=2)
        problems.extend(attr_problems)
    problems.extend(deep_diff(mask_attrs(x.attrs), mask_attrs(y.attrs), f"{where}attrs", limit=3))
    return problems


def compare_netcdf(a: Path, b: Path) -> Outcome:
    x_groups, y_groups = netcdf_groups(a), netcdf_groups(b)
    x, y = x_groups["/"], y_groups["/"]
    notes = []
    allow_transpose = False
    la, lb = marker_error_layout(x), marker_error_layout(y)
    if la == "per-variable" and lb == "component":
        try:
            x = to_component_layout(x, y)
        except ValueError as error:
            return Outcome(False, f"marker-error layout changed and cannot be mapped: {error}")
        notes.append("marker-error layout mapped: base per-component variables -> new hull/deviation[component]")
        allow_transpose = True
    elif la != lb and None not in (la, lb):
        notes.append(f"marker-error layout base {la} vs new {lb}")
    x_groups["/"] = x
    flat = any(v in x.data_vars for v in FLAT_MARKER_ERROR) and len(x_groups) == 1
    if flat and lb == "component" and not any(v in y.data_vars for v in FLAT_MARKER_ERROR):
        try:
            x_groups = to_marker_error_groups(x)
        except Exception as error:  # noqa: BLE001 - any failure: the layouts cannot be mapped
            return Outcome(False, f"marker-error groups cannot be mapped: {error}")
        notes.append("marker-error layout mapped: base flat refined_/allowable_/source_ variables -> new groups")
    try:
        if map_error_sources(x_groups, y_groups):
            notes.append("marker-error sources mapped: attribute 'sources' -> coordinate 'error_source'")
    except Exception as error:  # noqa: BLE001 - any failure: the sources cannot be mapped
        return Outcome(False, f"marker-error sources cannot be mapped: {error}")
    problems = []
    if set(x_groups) != set(y_groups):
        problems.append(f"groups: base {sorted(x_groups)} vs new {sorted(y_groups)}")
    for name in sorted(set(x_groups) & set(y_groups)):
        where = "" if name == "/" else f"{name}: "
        problems += compare_variables(x_groups[name], y_groups[name], where, allow_transpose)
    if problems:
        return Outcome(
            False, "; ".join(notes + problems[:8]) + (f"; ... {len(problems) - 8} more" if len(problems) > 8 else "")
        )
    return Outcome(True, "; ".join(notes) or bytes_note(a, b))


def compare_zarr(a: Path, b: Path) -> Outcome:
    """Every group and array of two zarr stores: values, dtype, shape, attributes."""
    import zarr

    x, y = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    problems: list[str] = []

    def walk(g: Any, h: Any, at: str) -> None:
        fx, fy = g.metadata.zarr_format, h.metadata.zarr_format
        if fx != fy:
            problems.append(f"{at}: zarr format {fx} vs {fy}")
        problems.extend(deep_diff(mask_attrs(dict(g.attrs)), mask_attrs(dict(h.attrs)), f"{at}.attrs", limit=3))
        ax, ay = dict(g.arrays()), dict(h.arrays())
        if set(ax) != set(ay):
            problems.append(
                f"{at}: arrays only in base {sorted(set(ax) - set(ay))}, only in new {sorted(set(ay) - set(ax))}"
            )
        for name in sorted(set(ax) & set(ay)):
            u, v = ax[name], ay[name]
            if u.dtype != v.dtype:
                problems.append(f"{at}/{name}: dtype {u.dtype} vs {v.dtype}")
            if u.shape != v.shape:
                problems.append(f"{at}/{name}: shape {u.shape} vs {v.shape}")
            elif not arrays_equal(u[...], v[...]):
                problems.append(f"{at}/{name}: {max_abs_difference(u[...], v[...])}")
            problems.extend(deep_diff(mask_attrs(dict(u.attrs)), mask_attrs(dict(v.attrs)), f"{at}/{name}.attrs", 2))
        gx, gy = dict(g.groups()), dict(h.groups())
        if set(gx) != set(gy):
            problems.append(
                f"{at}: groups only in base {sorted(set(gx) - set(gy))}, only in new {sorted(set(gy) - set(gx))}"
            )
        for name in sorted(set(gx) & set(gy)):
            walk(gx[name], gy[name], f"{at}/{name}")

    walk(x, y, "")
    if problems:
        return Outcome(
            False, "; ".join(problems[:8]) + (f"; ... {len(problems) - 8} more" if len(problems) > 8 else "")
        )
    return Outcome(True)


def compare_png(a: Path, b: Path) -> Outcome:
    import matplotlib.image as mpimg

    x, y = mpimg.imread(a), mpimg.imread(b)
    if x.shape != y.shape:
        return Outcome(False, f"image size {x.shape} vs {y.shape}")
    if np.array_equal(x, y):
        return Outcome(True, bytes_note(a, b))
    diff = np.abs(x.astype(float) - y.astype(float))
    pixels = int((diff.reshape(diff.shape[0], diff.shape[1], -1) > 0).any(axis=2).sum())
    return Outcome(False, f"{pixels} of {x.shape[0] * x.shape[1]} pixels, max abs diff {diff.max():.3g}")


RRD_DROP = {"rerun.controls.RowId", "log_time", "log_tick", "RecordingInfo:start_time"}


def rrd_rows(path: Path) -> tuple[dict[tuple[str, bool], list[str]], str]:
    """Rows of every (entity, static) of a recording, canonical and sorted; and a summary."""
    import pyarrow as pa  # type: ignore[import-untyped]
    import rerun as rr

    reader = rr.chunk.RrdReader(path)
    rows: dict[tuple[str, bool], list[str]] = {}
    for chunk in reader.stream().to_chunks():
        table = pa.Table.from_batches([chunk.to_record_batch()])
        keep = [n for n in table.column_names if n not in RRD_DROP]
        for row in table.select(keep).to_pylist():
            rows.setdefault((str(chunk.entity_path), bool(chunk.is_static)), []).append(repr(sorted(row.items())))
    for value in rows.values():
        value.sort()
    apps = sorted(str(r.application_id) for r in reader.recordings())
    return rows, f"applications {apps}, {len(reader.blueprints())} blueprints"


def compare_rrd(a: Path, b: Path) -> Outcome:
    try:
        (x, sx), (y, sy) = rrd_rows(a), rrd_rows(b)
    except (ImportError, AttributeError) as error:  # no rerun, or another reader API
        return Outcome(
            True, f"not compared ({type(error).__name__}: {error}); sizes {a.stat().st_size} vs {b.stat().st_size}"
        )
    problems = []
    if sx != sy:
        problems.append(f"{sx} vs {sy}")
    if set(x) != set(y):
        problems.append(
            f"entities only in base {sorted(set(x) - set(y))[:4]}, only in new {sorted(set(y) - set(x))[:4]}"
        )
    differing = sorted(e for e in set(x) & set(y) if x[e] != y[e])
    if differing:
        problems.append(f"{len(differing)} entities differ, e.g. " + ", ".join(e for e, _ in differing[:4]))
    if problems:
        return Outcome(False, "; ".join(problems))
    return Outcome(True, f"{sum(map(len, x.values()))} rows in {len(x)} entities")


TEXT_SUFFIXES = {".svg", ".html", ".htm", ".md", ".txt", ".toml", ".json", ".xml", ".css", ".js", ".log"}


def compare_file(a: Path, b: Path, replacements: Sequence[tuple[str, str]]) -> Outcome:
    suffix = a.suffix.lower()
    comparers: dict[str, Callable[[Path, Path], Outcome]] = {
        ".csv": compare_csv,
        ".c3d": compare_c3d,
        ".nc": compare_netcdf,
        ".zarr": compare_zarr,
        ".png": compare_png,
        ".rrd": compare_rrd,
    }
    try:
        if suffix in comparers:
            return comparers[suffix](a, b)
        if suffix in TEXT_SUFFIXES:
            return compare_text_content(a.read_text(errors="replace"), b.read_text(errors="replace"), replacements)
        if a.is_dir():
            return Outcome(False, "directory of unknown type")
        return compare_bytes(a, b)
    except Exception as error:  # a file one side cannot read is a difference, not a crash
        return Outcome(False, f"cannot compare: {type(error).__name__}: {str(error)[:120]}")


def output_files(folder: Path) -> dict[str, Path]:
    """Files under ``folder`` by relative path; a ``*.zarr`` directory is one entry."""
    found: dict[str, Path] = {}

    def walk(d: Path) -> None:
        for p in sorted(d.iterdir()):
            if p.parent == folder and p.name == DATA:
                continue
            if p.is_dir() and p.suffix == ".zarr":
                found[p.relative_to(folder).as_posix()] = p
            elif p.is_dir():
                walk(p)
            else:
                found[p.relative_to(folder).as_posix()] = p

    walk(folder)
    return found


# ---------------------------------------------------------------------------------------
# running
# ---------------------------------------------------------------------------------------


class HarnessError(Exception):
    """The comparison itself cannot run (exit code 2)."""


@dataclass
class Run:
    code: int | None  # None: timed out
    stdout: str
    error: str  # last line of stderr when the step failed
    seconds: float
    cpu_seconds: float = float("nan")  # user + system time of the command's processes


@dataclass
class Side:
    name: str  # "base" or "new"
    label: str  # revision or "working tree"
    src: Path
    cache: Path | None
    runs: dict[str, list[Run]] = field(default_factory=dict)


def git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(REPO), *args], check=True, capture_output=True, text=True).stdout.strip()


@contextmanager
def worktree(revision: str, root: Path, name: str) -> Iterator[Path]:
    sha = git("rev-parse", "--verify", f"{revision}^{{commit}}")
    path = root / f"worktree-{name}"
    git("worktree", "add", "--detach", str(path), sha)
    try:
        yield path
    finally:
        subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(path)], capture_output=True)
        subprocess.run(["git", "-C", str(REPO), "worktree", "prune"], capture_output=True)


def environment(side: Side) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "FUZZYGAIT_"))}
    env.update({k: "1" for k in THREAD_VARIABLES})
    env.update(
        PYTHONPATH=str(side.src),
        PYTHONHASHSEED="0",
        PYTHONDONTWRITEBYTECODE="1",
        MPLBACKEND="Agg",
        COLUMNS="120",
        LINES="50",
        NO_COLOR="1",
        TERM="dumb",
        LC_ALL="C.UTF-8",
        PYTHONIOENCODING="utf-8",
    )
    if side.cache is not None:
        env["FUZZYGAIT_CACHE_DIR"] = str(side.cache)
    return env


def check_import(side: Side, cwd: Path) -> None:
    """The side's interpreter imports fuzzygait from the side's src (not the editable install)."""
    out = subprocess.run(
        [sys.executable, "-c", "import fuzzygait; print(fuzzygait.__file__)"],
        cwd=cwd,
        env=environment(side),
        capture_output=True,
        text=True,
    )
    where = Path(out.stdout.strip() or "?").resolve()
    if out.returncode != 0 or side.src.resolve() not in where.parents:
        raise HarnessError(f"{side.name}: fuzzygait imports from {where} instead of {side.src}\n{out.stderr[-2000:]}")


def expand(step: str, inputs: Path) -> list[str]:
    c3d = " ".join(shlex.quote(f"{DATA}/{p.name}") for p in sorted(inputs.glob("*.c3d")))
    return shlex.split(step.replace("{c3d}", c3d))


def run_command(side: Side, name: str, root: Path, inputs: Path, timeout: float) -> None:
    folder = root / side.name / name
    folder.mkdir(parents=True)
    (folder / DATA).symlink_to(inputs, target_is_directory=True)
    logs = root / "logs"
    logs.mkdir(exist_ok=True)
    results: list[Run] = []
    for k, step in enumerate(COMMANDS[name]):
        args = [sys.executable, "-m", "fuzzygait", *expand(step, inputs)]
        start, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            done = subprocess.run(
                args, cwd=folder, env=environment(side), capture_output=True, text=True, timeout=timeout
            )
            code, stdout, stderr = done.returncode, done.stdout, done.stderr
        except subprocess.TimeoutExpired as timed_out:
            partial = timed_out.stdout or ""
            code, stdout = None, partial.decode(errors="replace") if isinstance(partial, bytes) else partial
            stderr = f"timed out after {timeout:.0f} s"
        seconds = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu_seconds = (after.ru_utime - cpu.ru_utime) + (after.ru_stime - cpu.ru_stime)
        (logs / f"{side.name}-{name}-{k}.stderr").write_text(stderr if isinstance(stderr, str) else "")
        failure = "" if code == 0 else ((stderr or "").strip().splitlines()[-1:] or [""])[0][:200]
        results.append(Run(code, stdout, failure, seconds, cpu_seconds))
        (logs / f"{side.name}-{name}-{k}.json").write_text(json.dumps(asdict(results[-1]), indent=1))
        state = "timeout" if code is None else f"exit {code}"
        where = f"[{side.name}] {name} step {k + 1}/{len(COMMANDS[name])}"
        print(f"  {where}: {state}, {seconds:.1f} s ({cpu_seconds:.1f} s CPU)", file=sys.stderr)
        if failure:
            print(f"      {failure}", file=sys.stderr)
    side.runs[name] = results


def compare_command(name: str, root: Path, base: Side, new: Side) -> list[tuple[str, str, Outcome]]:
    rows: list[tuple[str, str, Outcome]] = []
    fa, fb = root / base.name / name, root / new.name / name
    replacements = [
        (str(fa), "<OUT>"),
        (str(fb), "<OUT>"),
        (str(base.src), "<SRC>"),
        (str(new.src), "<SRC>"),
        (str(root), "<ROOT>"),
    ]
    for k, (ra, rb) in enumerate(zip(base.runs[name], new.runs[name], strict=True)):
        step = f"step {k + 1}: " if len(COMMANDS[name]) > 1 else ""
        if None in (ra.code, rb.code):
            rows.append(
                (name, f"{step}(run)", Outcome(False, f"timed out: base {ra.code is None}, new {rb.code is None}"))
            )
        elif ra.code != rb.code:
            detail = f"exit {ra.code} vs {rb.code}: {ra.error or rb.error}"
            rows.append((name, f"{step}(exit code)", Outcome(False, detail)))
        elif ra.code != 0:  # failing the same way on both sides verifies nothing
            rows.append((name, f"{step}(exit code)", Outcome(False, f"exit {ra.code} on both sides: {rb.error}")))
        rows.append((name, f"{step}(stdout)", compare_text_content(ra.stdout, rb.stdout, replacements)))
    xa, xb = output_files(fa), output_files(fb)
    for rel in sorted(set(xa) | set(xb)):
        if rel not in xb:
            rows.append((name, rel, Outcome(False, "only in base")))
        elif rel not in xa:
            rows.append((name, rel, Outcome(False, "only in new")))
        else:
            rows.append((name, rel, compare_file(xa[rel], xb[rel], replacements)))
    return rows


def load_sides(root: Path, names: Sequence[str]) -> tuple[Side, Side]:
    """The two sides of an earlier run kept in ``root`` (for ``--compare-only``)."""
    sides = json.loads((root / "sides.json").read_text())
    out = []
    for name in ("base", "new"):
        side = Side(name, sides[name]["label"], Path(sides[name]["src"]), None)
        for command in names:
            logs = [root / "logs" / f"{name}-{command}-{k}.json" for k in range(len(COMMANDS[command]))]
            if not all(log.exists() for log in logs):
                raise HarnessError(f"{root} has no {name} run of {command}")
            side.runs[command] = [Run(**json.loads(log.read_text())) for log in logs]
        out.append(side)
    return out[0], out[1]


def run_sides(args: argparse.Namespace, names: Sequence[str]) -> tuple[Side, Side, list[tuple[str, str, Outcome]]]:
    with tempfile.TemporaryDirectory(prefix="fuzzygait-compare-") as tmp_name:
        tmp = Path(tmp_name)
        root = args.keep.resolve() if args.keep is not None else tmp / "out"
        root.mkdir(parents=True, exist_ok=True)
        inputs = root / "inputs" / DATA
        shutil.copytree(REPO / DATA, inputs)
        with (
            worktree(args.base, tmp, "base") as base_tree,
            worktree(args.new, tmp, "new") if args.new else _nothing(REPO) as new_tree,
        ):
            base = Side(
                "base",
                f"{args.base} ({git('rev-parse', '--short', args.base)})",
                base_tree / "src",
                None if args.shared_cache else tmp / "cache-base",
            )
            new_label = f"{args.new} ({git('rev-parse', '--short', args.new)})" if args.new else "working tree"
            new = Side("new", new_label, new_tree / "src", None if args.shared_cache else tmp / "cache-new")
            for side in (base, new):
                check_import(side, root)
            sides = {side.name: {"label": side.label, "src": str(side.src)} for side in (base, new)}
            (root / "sides.json").write_text(json.dumps(sides, indent=1))
            print(f"base: {base.label}, new: {new.label}; outputs in {root}", file=sys.stderr)
            for name in names:
                for side in (base, new):
                    run_command(side, name, root, inputs, args.timeout)
            rows = [row for name in names for row in compare_command(name, root, base, new)]
    return base, new, rows


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default=DEFAULT_BASE, help=f"base git revision (default {DEFAULT_BASE})")
    parser.add_argument("--new", default=None, help="revision for the new side (default: the working tree)")
    parser.add_argument("--commands", default=None, help=f"comma-separated subset of {','.join(COMMANDS)}")
    parser.add_argument("--keep", type=Path, default=None, help="keep the outputs in this (new or empty) folder")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per command step (default 300)")
    parser.add_argument(
        "--shared-cache",
        action="store_true",
        help="use the user's compiled-model cache instead of a fresh one per side",
    )
    parser.add_argument(
        "--compare-only",
        type=Path,
        default=None,
        metavar="DIR",
        help="run nothing; compare the outputs an earlier run kept with --keep DIR again",
    )
    args = parser.parse_args(argv)

    names = list(COMMANDS) if args.commands is None else [n.strip() for n in args.commands.split(",") if n.strip()]
    unknown = [n for n in names if n not in COMMANDS]
    if unknown:
        parser.error(f"unknown commands {unknown}; choose from {', '.join(COMMANDS)}")
    if args.compare_only is None and args.keep is not None and args.keep.exists() and any(args.keep.iterdir()):
        parser.error(f"--keep folder {args.keep} is not empty")
    started = time.perf_counter()
    try:
        if args.compare_only is not None:
            root = args.compare_only.resolve()
            base, new = load_sides(root, names)
            rows = [row for name in names for row in compare_command(name, root, base, new)]
        else:
            base, new, rows = run_sides(args, names)
    except subprocess.CalledProcessError as error:
        print(f"error: {' '.join(map(str, error.cmd))}: {(error.stderr or '').strip()}", file=sys.stderr)
        return 2
    except (HarnessError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2

    print(f"\nbase {base.label} vs new {new.label}; {len(names)} commands, {time.perf_counter() - started:.0f} s\n")
    print("| command | file | result |\n|---|---|---|")
    for name, rel, outcome in rows:
        print(f"| {name} | {rel} | {outcome} |")
    for name in names:
        (tb, cb), (tn, cn) = (
            (sum(r.seconds for r in s.runs[name]), sum(r.cpu_seconds for r in s.runs[name])) for s in (base, new)
        )
        if max(tb, tn) > 60:
            print(
                f"note: {name} took {tb:.0f} s wall / {cb:.0f} s CPU (base), {tn:.0f} s / {cn:.0f} s (new), "
                "more than the 60 s aimed at (machine load, or a slower command)"
            )
    differing = [r for r in rows if not r[2].same]
    print(f"\n{len(rows) - len(differing)} same, {len(differing)} differ")
    return 1 if differing else 0


@contextmanager
def _nothing(path: Path) -> Iterator[Path]:
    yield path


if __name__ == "__main__":
    sys.exit(main())
