"""Tearing down a local Dask cluster: its workers stopped at once, killed if they do not
stop, and the cluster taken off distributed's list of clusters to close at exit.

Used by :mod:`fuzzygait.uncertainty.execution.evaluator` when an evaluator closes, is
interrupted or fails to start its cluster.
"""

from __future__ import annotations

import os
import signal
from typing import Any

#: Seconds the close of a cluster may take before its workers are killed.
CLOSE_TIMEOUT = 10.0
#: Seconds a worker is given to stop by itself when its evaluator stops quickly.
QUICK_STOP_SECONDS = 0.5


async def close_nannies(nannies: list[Any], timeout: float) -> None:
    import asyncio

    await asyncio.gather(*(nanny.close(timeout=timeout) for nanny in nannies), return_exceptions=True)


def stop_workers_now(cluster: Any) -> None:
    """Close a local cluster's nannies with a short timeout: a worker busy with a task is
    killed after :data:`QUICK_STOP_SECONDS` instead of the close's usual 4 s."""
    nannies = list(getattr(cluster, "workers", {}).values())
    try:
        cluster.sync(close_nannies, nannies, QUICK_STOP_SECONDS)
    except Exception:  # noqa: BLE001 - best effort: the close and the kill below follow
        pass


def kill_workers(cluster: Any) -> None:
    """SIGKILL what is left of a closed local cluster's worker processes (a close that
    timed out, or one interrupted)."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        process = getattr(getattr(nanny, "process", None), "process", None)
        pid = getattr(process, "pid", None)
        if pid:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass


def forget_cluster(cluster: Any) -> None:
    """Take a closed (or killed) local cluster off distributed's list to close at exit,
    whose second close prints a traceback for a worker interrupted while starting."""
    try:
        from distributed.deploy.spec import SpecCluster

        SpecCluster._instances.discard(cluster)
    except Exception:  # noqa: BLE001 - best effort: an older or newer distributed
        pass


def started_clusters(before: set[int]) -> list[Any]:
    """Local clusters created in this process since ``before`` (ids of the clusters then)."""
    from distributed.deploy.spec import SpecCluster

    return [cluster for cluster in list(SpecCluster._instances) if id(cluster) not in before]


def discard_cluster(cluster: Any) -> None:
    """Close, kill and forget a cluster that failed to start (None: nothing to do); an
    interrupt during the close still kills its workers."""
    if cluster is None:
        return
    try:
        cluster.close(timeout=CLOSE_TIMEOUT)
    except Exception:  # noqa: BLE001 - best effort: the kill follows
        pass
    finally:
        kill_workers(cluster)
        forget_cluster(cluster)
