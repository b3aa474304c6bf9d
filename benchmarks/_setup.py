"""Set-up shared by the benchmark scripts.

They run as ``python benchmarks/<script>.py``, so this folder is on ``sys.path`` and
``from _setup import ...`` finds this module.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

#: The repository.
ROOT = Path(__file__).resolve().parents[1]
#: The Vicon reference data shared next to the repository (may be absent).
VICON = ROOT.parent / "shared" / "data" / "vicon"


def one_thread() -> None:
    """Pin the BLAS and OpenMP thread pools to one thread (unless set in the environment);
    call it before numpy is imported."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")


def best_of(call: Callable[[], object], repeats: int, *, warm_up: bool = True) -> float:
    """The shortest of ``repeats`` timed calls of ``call`` (s, wall clock), after one
    untimed call unless ``warm_up`` is False."""
    if warm_up:
        call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)
