"""ezc3d in a child process with a time limit, for files the sanity pass doubts.

ezc3d is C++: on some corrupt files it dies with a segmentation fault or loops for
minutes, and neither can be caught in the reading process. :func:`decode_isolated` runs
it in a fresh ``python -m fuzzygait.io.c3d_child`` process (about 0.1 s to start) that
sends back every parameter and the point data (:func:`encode_raw`: an ``.npz`` archive of
the arrays and a JSON document of the rest, read without pickle); a crash or a run over the
time limit becomes a :class:`~fuzzygait.io.c3d_backends.BackendError` with one line. It
is only used for files that :mod:`fuzzygait.io.c3d_guard` doubts and the ``c3d`` package
refuses, so the normal path costs nothing.
"""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from fuzzygait.io.c3d_backends import RawC3D

#: Seconds ezc3d may take in the child: a base plus a per-megabyte allowance (ezc3d
#: reads about 20 ms per MB on one core; this leaves a factor of ~50 for a loaded machine).
BASE_LIMIT_S = 3.0
LIMIT_S_PER_MB = 1.0


def time_limit(size_bytes: int) -> float:
    """The child's time limit for a file of ``size_bytes``, seconds."""
    return BASE_LIMIT_S + LIMIT_S_PER_MB * size_bytes / 1e6


def decode_isolated(path: Path) -> RawC3D:
    """:func:`~fuzzygait.io.c3d_backends._decode_ezc3d` of ``path`` in a child process.

    Returns:
        The :class:`~fuzzygait.io.c3d_backends.RawC3D` the child read.

    Raises:
        BackendError: ezc3d refused the file, crashed, or ran over :func:`time_limit`.
    """
    from fuzzygait.io.c3d_backends import BackendError

    limit = time_limit(path.stat().st_size)
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    try:
        done = subprocess.run(
            [sys.executable, "-m", "fuzzygait.io.c3d_child", str(path)],
            capture_output=True,
            timeout=limit,
            env=env,
            check=False,
        )
    except subprocess.TimeoutExpired:  # subprocess.run has killed the child
        raise BackendError(f"ezc3d did not finish within {limit:.0f} s (a corrupt parameter makes it loop)") from None
    except OSError as exc:
        raise BackendError(f"ezc3d could not be started in a child process ({exc})") from None
    if done.returncode < 0:
        try:
            name = signal.Signals(-done.returncode).name
        except ValueError:
            name = f"signal {-done.returncode}"
        raise BackendError(f"ezc3d crashed on it ({name})")
    try:
        return decode_raw(done.stdout)
    except ChildError as exc:
        raise BackendError(str(exc)) from None
    except Exception:
        raise BackendError(f"ezc3d's child process failed (exit {done.returncode})") from None


class ChildError(Exception):
    """The child reported ezc3d's refusal of the file (its one-line reason)."""


def _plain(value: Any) -> Any:
    """``json.dumps``' fallback: numpy scalars as Python numbers, nothing else."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} cannot be sent back")


def _encode_value(value: Any, arrays: dict[str, np.ndarray]) -> list[Any]:
    """A parameter's value as ``[kind, data]``: ``["none"]``, ``["array", key]`` (a
    numeric or string array stored in ``arrays``), ``["objects", list]`` (an object
    array) or ``["json", value]`` (lists of strings or numbers as ezc3d gives them)."""
    if value is None:
        return ["none"]
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            return ["objects", value.tolist()]
        key = f"parameter/{len(arrays)}"
        arrays[key] = value
        return ["array", key]
    return ["json", value]


def encode_raw(raw: RawC3D) -> bytes:
    """What the child sends back: an ``.npz`` archive (no pickled object in it) holding
    the points, every numeric parameter and ``meta``, the UTF-8 JSON of the other fields
    and the parameters' values (:func:`decode_raw` reverses it)."""
    arrays: dict[str, np.ndarray] = {"points": np.asarray(raw.points, dtype=float)}
    parameters = [[g, p, _encode_value(raw.get(g, p), arrays)] for g, names in raw.parameter_names.items()
                  for p in names]  # fmt: skip
    meta = {"kind": "ok", "labels": raw.labels, "header_rate": raw.header_rate, "first_frame": raw.first_frame,
            "header_events": raw.header_events, "parameter_names": raw.parameter_names, "backend": raw.backend,
            "warnings": raw.warnings, "analog_per_frame": raw.analog_per_frame, "parameters": parameters}  # fmt: skip
    return _archive(meta, arrays)


def _archive(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> bytes:
    text = json.dumps(meta, default=_plain, ensure_ascii=False).encode("utf-8")
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.frombuffer(text, dtype=np.uint8), **arrays)  # type: ignore[arg-type]
    return buffer.getvalue()


def _decode_value(kind: list[Any], data: Any) -> Any:
    if kind[0] == "none":
        return None
    if kind[0] == "array":
        return np.asarray(data[kind[1]])
    if kind[0] == "objects":
        return np.array(kind[1], dtype=object)
    if kind[0] == "json":
        return kind[1]
    raise ValueError(f"unknown parameter kind {kind[0]!r}")


def decode_raw(payload: bytes) -> RawC3D:
    """The :class:`~fuzzygait.io.c3d_backends.RawC3D` of :func:`encode_raw`'s bytes
    (read with ``allow_pickle=False``).

    Raises:
        ChildError: the child reported ezc3d's refusal of the file.
        ValueError, KeyError, OSError: the bytes are not such an archive.
    """
    from fuzzygait.io.c3d_backends import RawC3D

    with np.load(io.BytesIO(payload), allow_pickle=False) as data:
        meta = json.loads(bytes(np.asarray(data["meta"], dtype=np.uint8)).decode("utf-8"))
        if meta["kind"] == "error":
            raise ChildError(str(meta["message"]))
        cache = {(str(g), str(p)): _decode_value(kind, data) for g, p, kind in meta["parameters"]}
        points = np.asarray(data["points"], dtype=float)
    per_frame = meta["analog_per_frame"]
    return RawC3D(points=points, labels=[str(x) for x in meta["labels"]], header_rate=float(meta["header_rate"]),
                  first_frame=int(meta["first_frame"]),
                  header_events=[(str(label), float(t)) for label, t in meta["header_events"]],
                  get=lambda g, p: cache.get((g, p)),
                  parameter_names={str(g): [str(p) for p in names] for g, names in meta["parameter_names"].items()},
                  backend=str(meta["backend"]), warnings=[str(w) for w in meta["warnings"]],
                  analog_per_frame=None if per_frame is None else int(per_frame))  # fmt: skip


def _main(argv: list[str]) -> int:
    """Child side: decode ``argv[0]`` with ezc3d and write :func:`encode_raw` of the
    result (or of ezc3d's refusal) to stdout."""
    from fuzzygait.io.c3d_backends import BackendError, _decode_ezc3d

    try:
        raw = _decode_ezc3d(Path(argv[0]))
    except BackendError as exc:
        sys.stdout.buffer.write(_archive({"kind": "error", "message": str(exc)}, {}))
        return 0
    sys.stdout.buffer.write(encode_raw(raw))
    return 0


def _die_with_parent() -> None:
    """Linux: have the kernel kill this child when its parent dies (a hanging ezc3d
    must not outlive a killed command)."""
    try:
        import ctypes

        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the parent's timeout still applies
        pass


if __name__ == "__main__":  # pragma: no cover - runs in the child
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and kills us
    _die_with_parent()
    raise SystemExit(_main(sys.argv[1:]))
