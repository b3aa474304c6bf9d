"""Reading the annotation groups of a decoded C3D file: ``EVENT`` (the trial's events),
``PROCESSING`` (the subject's measurements) and ``ANALYSIS`` (Vicon Nexus' spatio-temporal
parameters), for :func:`fuzzygait.io.c3d.read_c3d`.

Each reader is lenient: what a group lacks or holds inconsistently is noted as a
:class:`~fuzzygait.core.findings.Finding` (a warning) and the consistent part is used.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.trial import AnalysisValue, Event
from fuzzygait.io.c3d_backends import RawC3D, suffixed
from fuzzygait.io.subject import PROCESSING_NAMES


def warning(message: str, kind: FindingKind = FindingKind.FILE_FORMAT) -> Finding:
    """A reader's finding: what it had to assume or repair (a warning)."""
    return Finding(kind, message, Severity.WARNING)


def read_events(path: Path, raw: RawC3D, notes: list[Finding]) -> list[Event]:
    """The ``EVENT`` group (``TIMES``, ``LABELS``, ... and their ``TIMES2``, ``LABELS2``, ...
    continuations) as events; without one, the C3D header's events (context unknown)."""
    used = raw.get("EVENT", "USED")
    n = int(np.ravel(used)[0]) if used is not None and np.size(used) else 0
    if n <= 0:
        stored = [v for part in suffixed(raw.get, "EVENT", "LABELS") if isinstance(part, list) for v in part]
        if any(stored):
            notes.append(warning(f"EVENT:USED is {n} but EVENT:LABELS lists {len(stored)} events; they are ignored",
                                 FindingKind.EVENTS))  # fmt: skip
        if raw.header_events:
            notes.append(warning("events taken from the C3D header (no EVENT group); context unknown",
                                 FindingKind.EVENTS))  # fmt: skip
        return [Event(label=lbl, context="General", time=t) for lbl, t in raw.header_events]
    parts = [_event_times(part) for part in suffixed(raw.get, "EVENT", "TIMES")]  # TIMES2...: events 256...
    times = np.concatenate([np.zeros((2, 0)), *parts], axis=1)
    if times.shape[-1] < n:
        notes.append(warning(f"EVENT:USED says {n} events but EVENT:TIMES holds {times.shape[-1]}; "
                             f"using {times.shape[-1]}", FindingKind.EVENTS))  # fmt: skip
        n = times.shape[-1]
    elif times.shape[-1] > n:
        notes.append(warning(
            f"EVENT:USED says {n} events but EVENT:TIMES holds {times.shape[-1]}; only the first {n} are read "
            "(set EVENT:USED in the file if the others are real events)",
            FindingKind.EVENTS,
        ))
    seconds = times[0, :n] * 60.0 + times[1, :n]

    def texts(name: str, default: str) -> list[str]:  # LABELS, LABELS2, ...: each as long as its TIMES part
        stored = [part if isinstance(part, list) else [] for part in suffixed(raw.get, "EVENT", name)]
        values: list[str] = []
        for i, part in enumerate(parts):
            got = stored[i] if i < len(stored) else []
            values += (got + [default] * part.shape[1])[: part.shape[1]]
        return values[:n]

    def numbers(name: str) -> list[int | None]:  # ICON_IDS, GENERIC_FLAGS: None where not stored
        values: list[int | None] = []
        found = suffixed(raw.get, "EVENT", name)
        for i, part in enumerate(parts):
            got = found[i] if i < len(found) and not isinstance(found[i], list) else []
            stored = [int(v) for v in np.ravel(np.asarray(got, dtype=float)) if np.isfinite(v)]
            values += (stored + [None] * part.shape[1])[: part.shape[1]]
        return values[:n]

    events = []
    for lbl, ctx, t, subj, desc, icon, flag in zip(texts("LABELS", "Event"), texts("CONTEXTS", "General"), seconds,
                                                   texts("SUBJECTS", ""), texts("DESCRIPTIONS", ""),
                                                   numbers("ICON_IDS"), numbers("GENERIC_FLAGS")):  # fmt: skip
        event = Event(label=lbl, context=ctx or "General", time=float(t), subject=subj, description=desc,
                      flag=flag or 0)  # fmt: skip
        events.append(event if icon is None or icon == event.icon_id() else replace(event, icon=icon))
    return events


def _event_times(found: Any) -> np.ndarray:
    """``EVENT:TIMES`` (or ``TIMES2``, ...) as ``(2, events)``: minutes, seconds."""
    times = np.zeros((2, 0)) if isinstance(found, list) else np.asarray(found, dtype=float)
    if times.ndim != 2 or times.shape[0] != 2:  # stored flat: (minutes, seconds) pairs one after the other
        times = times.ravel()[: times.size // 2 * 2].reshape(2, -1, order="F")
    return times


def read_processing_parameters(raw: RawC3D, notes: list[Finding]) -> dict[str, float]:
    """The single-number parameters of the ``PROCESSING`` group (Vicon's subject
    measurements, mm / kg / rad as stored); a subject measurement found in another group
    is noted and not used when the file has a ``PROCESSING`` group (a damaged group number
    moves a parameter silently otherwise; files of other software keep e.g. ``SUBJECT:HEIGHT``)."""
    known = {name.upper() for name in PROCESSING_NAMES}
    for group, names in raw.parameter_names.items():
        if group == "PROCESSING" or "PROCESSING" not in raw.parameter_names:
            continue
        for name in names:
            if name.upper() in known:
                notes.append(warning(
                    f"parameter {group}:{name} is a subject measurement outside the PROCESSING group; "
                    "it is not used (give it in a subject file if it is needed)"
                ))
    # C3D parameter names are case-insensitive (the c3d package reads them in capitals):
    # Vicon's spelling of the names this package knows
    spelling = {name.upper(): name for name in PROCESSING_NAMES}
    result: dict[str, float] = {}
    for name in raw.parameter_names.get("PROCESSING", []):
        value = raw.get("PROCESSING", name)
        if value is None or isinstance(value, list) or np.size(value) != 1:
            continue
        result[spelling.get(name.upper(), name)] = float(np.ravel(value)[0])
    return result


def read_analysis_values(raw: RawC3D, notes: list[Finding]) -> list[AnalysisValue]:
    """The ``ANALYSIS`` group: ``USED`` values with ``NAMES``, ``CONTEXTS``, ``UNITS``,
    ``VALUES`` (and ``SUBJECTS``, ``DESCRIPTIONS`` when present).

    A group that is absent or declares no values gives ``[]``; one whose lists are
    shorter than ``USED`` or not of the expected types gives what it holds consistently
    (or nothing) and a note -- never an error, since the group is informative only.
    """
    if "ANALYSIS" not in raw.parameter_names:
        return []
    try:
        used = raw.get("ANALYSIS", "USED")
        n = int(np.ravel(used)[0]) if used is not None and np.size(used) else 0
        if n <= 0:
            return []
        names = raw.get("ANALYSIS", "NAMES")
        values = raw.get("ANALYSIS", "VALUES")
        if not isinstance(names, list) or values is None or isinstance(values, list):
            notes.append(warning("ANALYSIS group without NAMES/VALUES lists; its values are ignored"))
            return []
        numbers = np.ravel(np.asarray(values, dtype=float))

        def texts(name: str) -> list[str]:
            found = raw.get("ANALYSIS", name)
            found = found if isinstance(found, list) else []
            return (found + [""] * n)[:n]

        count = min(n, len(names), numbers.size)
        if count < n:
            notes.append(warning(f"ANALYSIS:USED says {n} values but the group holds {count}; using {count}"))
        return [
            AnalysisValue(name=name, context=ctx or "General", unit=unit, value=float(value),
                          subject=subj, description=desc)  # fmt: skip
            for name, ctx, unit, value, subj, desc in zip(
                names[:count], texts("CONTEXTS"), texts("UNITS"), numbers[:count],
                texts("SUBJECTS"), texts("DESCRIPTIONS"), strict=False,
            )
        ]
    except (TypeError, ValueError, IndexError) as exc:
        notes.append(warning(f"ANALYSIS group unreadable ({exc}); its values are ignored"))
        return []
