"""ezc3d in a child process with a time limit, for files the sanity pass doubts.

ezc3d is C++: on some corrupt files it dies with a segmentation fault or loops for
minutes, and neither can be caught in the reading process. :func:`decode_isolated` runs
it in a fresh ``python -m fuzzygait.io.c3d_child`` process (about 0.1 s to start) that
sends back every parameter and the point data as a pickle; a crash or a run over the
time limit becomes a :class:`~fuzzygait.io.c3d_backends.BackendError` with one line. It
is only used for files that :mod:`fuzzygait.io.c3d_guard` doubts and the ``c3d`` package
refuses, so the normal path costs nothing.
"""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

#: Seconds ezc3d may take in the child: a base plus a per-megabyte allowance (ezc3d
#: reads about 20 ms per MB on one core; this leaves a factor of ~50 for a loaded machine).
BASE_LIMIT_S = 3.0
LIMIT_S_PER_MB = 1.0


def time_limit(size_bytes: int) -> float:
    """The child's time limit for a file of ``size_bytes``, seconds."""
    return BASE_LIMIT_S + LIMIT_S_PER_MB * size_bytes / 1e6


def decode_isolated(path: Path) -> Any:
    """:func:`~fuzzygait.io.c3d_backends._decode_ezc3d` of ``path`` in a child process.

    Returns:
        The :class:`~fuzzygait.io.c3d_backends.RawC3D` the child read.

    Raises:
        BackendError: ezc3d refused the file, crashed, or ran over :func:`time_limit`.
    """
    from fuzzygait.io.c3d_backends import BackendError, RawC3D

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
        kind, payload = pickle.loads(done.stdout)
    except Exception:
        raise BackendError(f"ezc3d's child process failed (exit {done.returncode})") from None
    if kind == "error":
        raise BackendError(str(payload))
    cache = payload.pop("cache")
    return RawC3D(get=lambda g, p: cache.get((g, p)), **payload)


def _main(argv: list[str]) -> int:
    """Child side: decode ``argv[0]`` with ezc3d and pickle the result to stdout."""
    from fuzzygait.io.c3d_backends import BackendError, _decode_ezc3d

    try:
        raw = _decode_ezc3d(Path(argv[0]))
    except BackendError as exc:
        result: tuple[str, Any] = ("error", str(exc))
    else:
        fields = {name: getattr(raw, name) for name in raw.__dataclass_fields__ if name != "get"}
        fields["cache"] = {(g, p): raw.get(g, p) for g, params in raw.parameter_names.items() for p in params}
        result = ("ok", fields)
    sys.stdout.buffer.write(pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
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
