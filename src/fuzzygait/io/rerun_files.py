"""Rerun recording files (``.rrd``): a recording stream whose only sink is a file,
written atomically.

What goes into a recording (entities, units, blueprints) is built by
:mod:`fuzzygait.viz` (``viz.rerun_log``, ``viz.mechanics``, ``viz.fuzzy_dynamics``),
which logs into the stream it is given and writes nothing itself.  Written against
rerun-sdk 0.41; the stream is a dedicated :class:`rerun.RecordingStream` (never the
global one): no viewer is spawned and no network is used.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.atomic import atomic_output

__all__ = ["import_rerun", "recording_file"]


def import_rerun() -> tuple[Any, Any]:
    """``(rerun, rerun.blueprint)``, or one :class:`FuzzyGaitError` saying how to
    install rerun-sdk."""
    try:
        import rerun as rr
        import rerun.blueprint as rrb
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise FuzzyGaitError(
            "writing Rerun recordings needs the rerun-sdk package; install it with "
            "`pip install rerun-sdk`"
        ) from exc
    return rr, rrb


@contextmanager
def recording_file(
    path: Path, recording_name: str, title: str, blueprint: Callable[[Any], Any] | None = None
) -> Iterator[tuple[Any, Any]]:
    """Open a Rerun recording stream saving to ``path`` atomically; yields ``(rec, rr)``.

    ``recording_name`` is the application id, ``title`` the recording's name and
    ``blueprint(rrb)`` builds the default blueprint.  The stream is flushed and closed
    when the block ends; the temporary file beside ``path`` is renamed onto it only
    then.  Raises one :class:`FuzzyGaitError` naming ``path`` when Rerun is disabled
    (``RERUN=off``), the file cannot be written or Rerun fails; nothing is left at
    ``path`` then.
    """
    rr, rrb = import_rerun()
    disabled = FuzzyGaitError(
        f"{path}: Rerun logging is disabled in this environment (RERUN=off?); unset RERUN to write recordings"
    )
    # checked before a stream exists: rerun warns at exit about every disabled stream made
    if os.environ.get("RERUN", "").strip().lower() in ("0", "no", "off", "false"):
        raise disabled
    rec = rr.RecordingStream(recording_name, recording_id=uuid.uuid4())
    if not rr.is_enabled(rec):
        raise disabled
    try:
        with atomic_output(path) as tmp:
            try:
                rec.save(tmp, default_blueprint=blueprint(rrb) if blueprint is not None else None)
                rec.send_recording_name(title)
                yield rec, rr
                rec.flush()
            finally:
                rec.disconnect()  # closes the file sink and writes the footer
            if tmp.stat().st_size == 0:
                raise FuzzyGaitError(f"{path}: Rerun wrote nothing; check the free disk space")
    except FuzzyGaitError:
        raise
    except OSError as exc:
        raise FuzzyGaitError(f"{path}: cannot write the Rerun recording ({exc.strerror or exc})") from exc
    except (RuntimeError, ValueError) as exc:
        raise FuzzyGaitError(f"{path}: Rerun could not write the recording ({exc})") from exc
