"""The gait sessions the marker-error benchmarks run on, and how they are loaded.

* synthetic CGM 2.4: ``sample_data/cgm24_walking.c3d`` calibrated on ``cgm24_static.c3d``
  with ``cgm24_subject.toml``;
* real CGM 2.4: ``../shared/data/cgm2/qualisys-cgm24-input`` (``Gait - CGM2 1.c3d``, static
  ``Static - CGM2 1.c3d``, subject from its QTM session.xml: LL 1000 mm, KW 95, AW 65, 14 mm
  markers, 70 kg, 1800 mm; foot flat on as session.xml);
* Movement_trial: ``../shared/data/vicon/Movement_trial.c3d`` with ``Static_trial.c3d``,
  its subject from the trial's PROCESSING group (a Plug-in Gait session).

The shared sessions are skipped (with a line saying so) when the data is absent.  The
model of one angle component the analysis optimises, for the Monte Carlo checks, is
:meth:`fuzzygait.markererror.analysis.ComponentTask.angle_model`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from _setup import ROOT, VICON

from fuzzygait.workflows.angles import AnglesRun, run_angles

SAMPLE = ROOT / "sample_data"
SESSION = ROOT.parent / "shared" / "data" / "cgm2" / "qualisys-cgm24-input"


@dataclass
class Case:
    """One session: the dynamic and static trial, the subject file (None: the dynamic
    trial's PROCESSING group), the frame step a benchmark thins it to, flat foot."""

    name: str
    dynamic: Path
    static: Path
    subject: Path | None
    step: int = 1
    flat_foot: bool = False


def cases() -> list[Case]:
    """The synthetic and (when present) the real CGM 2.4 session (its subject file: its
    QTM session.xml)."""
    out = [Case("synthetic CGM 2.4", SAMPLE / "cgm24_walking.c3d", SAMPLE / "cgm24_static.c3d",
                SAMPLE / "cgm24_subject.toml", 4)]  # fmt: skip
    if SESSION.is_dir():
        out.append(Case("real CGM 2.4 session", SESSION / "Gait - CGM2 1.c3d", SESSION / "Static - CGM2 1.c3d",
                        SESSION / "session.xml", 2, flat_foot=True))  # fmt: skip
    else:
        print(f"(skipped the real session: {SESSION} is absent)")
    return out


def movement_case() -> Case | None:
    """Movement_trial with Static_trial (PROCESSING subject), or None when absent."""
    dynamic = VICON / "Movement_trial.c3d"
    if not dynamic.is_file():
        print(f"(skipped Movement_trial: {dynamic} is absent)")
        return None
    return Case("Movement_trial", dynamic, VICON / "Static_trial.c3d", None)


def load(case: Case, model: str) -> AnglesRun:
    """The angles pipeline on ``case`` with model version ``model``."""
    return run_angles(case.dynamic, static=case.static, subject_file=case.subject, model=model,
                      flat_foot=case.flat_foot)  # fmt: skip


def sparse_run(run: AnglesRun, frames: np.ndarray) -> AnglesRun:
    """The run with every marker NaN outside ``frames`` (0-based samples): the marker-error
    analysis then works on those frames only."""
    markers = np.full_like(run.trial.markers, np.nan)
    markers[frames] = run.trial.markers[frames]
    return replace(run, trial=run.trial.with_markers(markers))


def subset(run: AnglesRun, step: int) -> tuple[AnglesRun, np.ndarray]:
    """:func:`sparse_run` on every ``step``-th frame, and those frames."""
    keep = np.arange(0, run.trial.n_frames, step)
    return sparse_run(run, keep), keep


