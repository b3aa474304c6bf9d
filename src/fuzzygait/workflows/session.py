"""Gait-lab sessions for the batch report: a folder per patient visit holding its static
trial, its walking trials and a subject file.

:func:`find_sessions` turns the report's inputs into :class:`Session` s.  A folder is a
session when it holds C3D files (a folder without any is searched for sub-folders that
do: a clinic folder of session folders); files given directly form one session of their
own with the ``--static`` / ``--subject`` given (no detection, as before sessions).

In a session folder a C3D file is a **static trial** by the first rule that fires
(:data:`STATIC_RULES`, the one that fired is reported):

1. ``markers``: it holds static-only calibration markers (knee alignment device
   ``L/RKAX``, ``L/RKD1``, ``L/RKD2`` or medial ``L/RKNM``, ``L/RMED``), has no gait events
   and its pelvis moves less than :data:`STATIC_MARKERS_TRAVEL` mm;
2. ``file name``: its name contains "static", "calib" or "standing" (any case);
3. ``motion``: no gait events and near-zero motion: the ASIS midpoint's range over the
   trial is below :data:`STATIC_TRAVEL` mm.

Every other C3D file is a walking trial.  Each walking trial gets the static trial of
the same subject (C3D ``SUBJECTS:NAMES``) whose name shares the longest start with its
own (a folder may hold several calibrations: ``PiGKad_Calibration`` for
``PiGKad_Motion``), then the most marker labels in common, and the subject file
(``.vsk``, ``.toml``, pyCGM2 ``.mp``, QTM ``session.xml``) named after its subject, else
the folder's only one.  A subject file or static trial of another subject than the
trial's is used but gives a warning (on the trial's page and in the index).
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.options import Option
from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d
from fuzzygait.io.qtm_session import is_qtm_session, qtm_subject_name
from fuzzygait.io.subject import is_subject_file
from fuzzygait.io.tomlfile import load_toml
from fuzzygait.mocap.sanity import MOTIONLESS_TRAVEL, STATIC_MAX_TRAVEL, pelvis_range

__all__ = ["STATIC_RULES", "Session", "SessionTrial", "StaticTrial", "find_sessions", "static_rule"]

#: The static-trial rules in the order they are tried.
STATIC_RULES = ("markers", "file name", "motion")
#: Markers only a static (calibration) trial carries.
STATIC_ONLY_MARKERS = ("LKAX", "RKAX", "LKD1", "RKD1", "LKD2", "RKD2", "LKNM", "RKNM", "LMED", "RMED")
#: Largest pelvis range (mm) of a static trial recognised by its markers (the content
#: checks' bound for a standing trial: the two cannot drift apart).
STATIC_MARKERS_TRAVEL = STATIC_MAX_TRAVEL
#: Largest pelvis range (mm) of a static trial recognised by its motion alone (the
#: content checks' "motionless" bound).
STATIC_TRAVEL = MOTIONLESS_TRAVEL
_STATIC_NAME = re.compile(r"static|calib|standing", re.IGNORECASE)


@dataclass(frozen=True)
class StaticTrial:
    """A static trial found in a session folder and the rule that found it."""

    path: Path
    rule: str  # one of STATIC_RULES
    detail: str  # what the rule saw, e.g. "LKAX, LMED; no gait events"
    subject: str = ""
    labels: frozenset[str] = frozenset()  # its marker labels


@dataclass(frozen=True)
class SessionTrial:
    """A walking trial with the static trial and subject file it is processed with."""

    path: Path
    static: Path | None
    subject_file: Path | None
    subject: str = ""
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class Session:
    """One session of the batch.

    Attributes:
        name: the session's name (its folder's name; "trials" for files given directly).
        folder: the session folder (None: files given directly).
        output: the sub-folder of the report holding its pages ("" for files given
            directly: the report folder itself).
        trials: the walking trials.
        statics: every static trial found (with its rule).
        subject_files: every subject file found.
        notes: what the discovery could not decide (:attr:`~fuzzygait.core.findings.FindingKind.SESSION`
            findings, one line each).
    """

    name: str
    folder: Path | None
    output: str
    trials: tuple[SessionTrial, ...]
    statics: tuple[StaticTrial, ...] = ()
    subject_files: tuple[Path, ...] = ()
    notes: tuple[Finding, ...] = ()

    @property
    def warnings(self) -> list[str]:
        """Every trial's warnings, each prefixed by the trial's file name."""
        return [f"{t.path.name}: {w}" for t in self.trials for w in t.warnings]


def _read(path: Path) -> Trial | None:
    """The trial, or None when it cannot be read (it is then reported as a failed trial)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return read_c3d(path)
    except FuzzyGaitError:
        return None


def _has_gait_events(trial: Trial) -> bool:
    return any(e.label.lower() in ("foot strike", "foot off") for e in trial.events)


def static_rule(path: Path, trial: Trial | None) -> tuple[str, str] | None:
    """``(rule, detail)`` of the first static-trial rule that fires for ``path`` (see the
    module docstring), or None: a walking trial."""
    travel = None if trial is None else pelvis_range(trial)
    events = trial is not None and _has_gait_events(trial)
    if trial is not None and not events:
        markers = [m for m in STATIC_ONLY_MARKERS if m in trial.marker_labels]
        if markers and travel is not None and travel < STATIC_MARKERS_TRAVEL:
            return "markers", f"static-only markers {', '.join(markers)}, no gait events, pelvis range {travel:.0f} mm"
    named = _STATIC_NAME.search(path.stem)
    if named:
        return "file name", f"its name contains {named[0]!r}"
    if not events and travel is not None and travel < STATIC_TRAVEL:
        return "motion", f"near-zero motion: pelvis range {travel:.0f} mm, no gait events"
    return None


def subject_file_name(path: Path) -> str | None:
    """The subject a subject file belongs to: a ``.vsk`` / ``.mp`` file's stem (Nexus and
    pyCGM2 name them after the subject), a TOML file's ``Name`` / ``SubjectName`` text,
    a QTM ``session.xml``'s patient ("First Last"); None when unknown."""
    if is_qtm_session(path):
        return qtm_subject_name(path)
    if path.suffix.lower() != ".toml":
        return path.stem
    try:
        data = load_toml(path, "subject file")
    except FuzzyGaitError:
        return None
    for key in ("Name", "name", "SubjectName", "subject_name"):
        if isinstance(data.get(key), str):
            return str(data[key])
    return None


def _labels(trial: Trial | None) -> frozenset[str]:
    return frozenset(trial.marker_labels) if trial is not None else frozenset()


def _same(a: str, b: str) -> bool:
    return a.strip().lower() == b.strip().lower()


def _common_start(a: str, b: str) -> int:
    n = 0
    for x, y in zip(a.lower(), b.lower(), strict=False):
        if x != y:
            break
        n += 1
    return n


def _shared_labels(a: frozenset[str], b: frozenset[str]) -> float:
    """The share of the marker labels of either that both have (Jaccard): 1 for the same set."""
    return len(a & b) / len(a | b) if a or b else 0.0


def _pick_static(trial: Path, subject: str, labels: frozenset[str],
                 statics: Sequence[StaticTrial]) -> StaticTrial | None:  # fmt: skip
    """The static trial of ``trial`` (marker ``labels``): same subject first, then the
    longest common start of the file names, then the most marker labels in common (e.g.
    a Plug-in Gait walking trial beside a Plug-in Gait and a CGM 2.4 static), then the
    first by name."""
    if not statics:
        return None
    return max(statics, key=lambda s: (bool(subject) and _same(s.subject, subject),
                                       _common_start(s.path.stem, trial.stem), _shared_labels(s.labels, labels),
                                       -statics.index(s)))  # fmt: skip


def _pick_subject_file(subject: str, files: Sequence[Path]) -> Path | None:
    named = [f for f in files if subject and _same(subject_file_name(f) or "", subject)]
    if named:
        return named[0]
    return files[0] if len(files) == 1 else None


def subject_mismatch(trial: str, subject: str, what: str, path: Path, other: str | None) -> str | None:
    """The warning when the ``what`` at ``path`` belongs to ``other`` and the trial to
    ``subject`` (None when either is unknown or they are the same, any case)."""
    if not subject or not other or _same(subject, other):
        return None
    return (f"subject mismatch: the trial is of subject {subject!r} but the {what} {path.name} is of {other!r}; "
            f"check that the right {what} is in the session folder")  # fmt: skip


def unmatched_subject_files(subject: str, files: Sequence[Path]) -> str:
    """The warning when a session folder holds several subject files and none names the
    trial's subject: which files were seen, whose each is, and what is used instead."""
    seen = ", ".join(f"{f.name} (of {name!r})" if (name := subject_file_name(f)) else f"{f.name} (names no subject)"
                     for f in files)  # fmt: skip
    who = f"its subject {subject!r}" if subject else "its subject (the C3D names none)"
    return (f"none of the subject files {seen} is named after {who}: none is used, the trial's PROCESSING group "
            "gives the subject; keep one subject file per session folder, name it after the subject, or give "
            f"{Option.SUBJECT}")


def find_session(folder: Path, output: str) -> Session:
    """The session in ``folder`` (see the module docstring); ``output`` is its report
    sub-folder."""
    c3d = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() == ".c3d")
    subject_files = sorted(p for p in folder.iterdir() if p.is_file() and is_subject_file(p))
    read = {p: _read(p) for p in c3d}
    statics, walking = [], []
    for path in c3d:
        found = static_rule(path, read[path])
        trial = read[path]
        if found is None:
            walking.append(path)
        else:
            statics.append(StaticTrial(path, found[0], found[1], trial.subject if trial is not None else "",
                                       _labels(trial)))  # fmt: skip
    notes: list[Finding] = []
    if not walking:
        raise FuzzyGaitError(f"{folder}: no walking trials in this session folder (every C3D file looks like a "
                             "static trial); give the walking trials as files")  # fmt: skip
    if not statics:
        notes.append(Finding(FindingKind.SESSION, "no static trial found: the trials use their own PROCESSING offsets"))
    if not subject_files:
        notes.append(Finding(FindingKind.SESSION, "no subject file (.vsk, .toml, .mp, session.xml): the trials' "
                             "PROCESSING groups give the subject"))  # fmt: skip
    trials = []
    for path in walking:
        trial = read[path]
        subject = trial.subject if trial is not None else ""
        static = _pick_static(path, subject, _labels(trial), statics)
        subject_file = _pick_subject_file(subject, subject_files)
        warned: list[str | None] = []
        if subject_file is None and len(subject_files) > 1:
            warned.append(unmatched_subject_files(subject, subject_files))
        if subject_file is not None:
            warned.append(subject_mismatch(path.name, subject, "subject file", subject_file,
                                          subject_file_name(subject_file)))  # fmt: skip
        if static is not None:
            warned.append(subject_mismatch(path.name, subject, "static trial", static.path, static.subject))
        trials.append(SessionTrial(path, static.path if static else None, subject_file, subject,
                                   tuple(w for w in warned if w)))  # fmt: skip
    return Session(folder.name, folder, output, tuple(trials), tuple(statics), tuple(subject_files), tuple(notes))


def _session_folders(folder: Path) -> list[Path]:
    """``folder`` when it holds C3D files, else its sub-folders that do (recursively)."""
    if any(p.is_file() and p.suffix.lower() == ".c3d" for p in folder.iterdir()):
        return [folder]
    found = []
    for child in sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")):
        found += _session_folders(child)
    return found


def _slug(text: str) -> str:
    slug = re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("._-")
    return slug or "session"


def find_sessions(inputs: Sequence[Path], static: Path | None = None,
                  subject_file: Path | None = None) -> list[Session]:  # fmt: skip
    """The sessions of the report's ``inputs`` (folders and C3D files, see the module
    docstring).  ``static`` / ``subject_file`` (``--static`` / ``--subject``) apply to
    the files given directly and override the detection in session folders."""
    sessions: list[Session] = []
    files: list[Path] = []
    used: set[str] = {""}
    for path in inputs:
        if not path.exists():
            raise FuzzyGaitError(f"{path}: no such file or folder; check the path")
        if not path.is_dir():
            files.append(path)
            continue
        folders = _session_folders(path)
        if not folders:
            raise FuzzyGaitError(f"{path}: no C3D files in this folder or its sub-folders")
        for folder in folders:
            name = _slug(folder.name)
            output, k = name, 2
            while output.lower() in used:
                output, k = f"{name}-{k}", k + 1
            used.add(output.lower())
            session = find_session(folder, output)
            if static is not None or subject_file is not None:
                session = _override(session, static, subject_file)
            sessions.append(session)
    if files:
        skip = {static.resolve()} if static is not None else set()
        unique = list({p.resolve(): p for p in files if p.resolve() not in skip}.values())
        if not unique:
            raise FuzzyGaitError(f"no trials to report (the only input is the {Option.STATIC} trial)")
        sessions.insert(0, _override(Session("trials", None, "", tuple(SessionTrial(p, None, None) for p in unique)),
                                     static, subject_file, check=subject_file is not None))  # fmt: skip
    return sessions


def _override(session: Session, static: Path | None, subject_file: Path | None, check: bool = True) -> Session:
    """``session`` with ``--static`` / ``--subject`` for every trial (subject names
    checked when ``check``)."""
    trials = []
    for t in session.trials:
        subject = t.subject
        if not subject and check and subject_file is not None:
            trial = _read(t.path)
            subject = trial.subject if trial is not None else ""
        new_subject = subject_file if subject_file is not None else t.subject_file
        found = [w for w in t.warnings if subject_file is None or "subject file" not in w]
        if subject_file is not None and check:
            warning = subject_mismatch(t.path.name, subject, "subject file", subject_file,
                                       subject_file_name(subject_file))  # fmt: skip
            found += [warning] if warning else []
        trials.append(SessionTrial(t.path, static if static is not None else t.static, new_subject, subject,
                                   tuple(found)))  # fmt: skip
    given = f"{Option.STATIC} {static} / {Option.SUBJECT} {subject_file} given: used for every trial"
    note = [Finding(FindingKind.SESSION, given)] if session.folder else []
    return Session(session.name, session.folder, session.output, tuple(trials), session.statics,
                   session.subject_files, session.notes + tuple(note))  # fmt: skip

