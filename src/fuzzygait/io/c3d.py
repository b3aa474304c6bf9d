"""Read and write C3D trials.

:func:`read_c3d` gives a :class:`~fuzzygait.core.trial.Trial` with markers in mm (NaN for
missing samples), subject prefixes removed from the labels, model outputs (Plug-in Gait
angles, forces, moments, powers, modelled and segment-frame virtual markers) kept apart
from the markers, the ``EVENT`` group as :class:`~fuzzygait.core.trial.Event` objects, the ``PROCESSING`` group
as subject parameters and the ``ANALYSIS`` group (Vicon Nexus' spatio-temporal parameters)
as :class:`~fuzzygait.core.trial.AnalysisValue` objects (these three groups:
:mod:`fuzzygait.io.c3d_groups`).

:func:`write_c3d` writes a trial back as a float C3D that Vicon Nexus, Mokka and ezc3d
open: markers, model outputs (with Vicon's ``POINT:ANGLES`` etc. type lists), events,
subject parameters and the subject prefix; given the file the trial was read from, also
everything of that file it does not change (analog channels, force platforms, every other
parameter group, :mod:`fuzzygait.io.c3d_writeback`).

Every problem with a file raises one :class:`~fuzzygait.core.errors.C3DError` whose message
names the file and the cause.
"""

from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from fuzzygait.core.errors import C3DError, FuzzyGaitError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.paths import check_c3d_input, check_c3d_path, check_not_input
from fuzzygait.core.trial import OUTPUT_UNITS, Trial
from fuzzygait.io.atomic import atomic_output
from fuzzygait.io.c3d_backends import BackendError, RawC3D, decode
from fuzzygait.io.c3d_groups import read_analysis_values, read_events, read_processing_parameters, warning
from fuzzygait.io.c3d_params import check_blocks, event_parameters, integer_event_records, read_section

if TYPE_CHECKING:
    from fuzzygait.io.c3d_points import InputPoints
    from fuzzygait.io.c3d_writeback import Analogs


class _EzC3D(Protocol):
    """The part of ``ezc3d.c3d`` (untyped) that the writer uses."""

    def __getitem__(self, key: str) -> Any: ...

    def add_parameter(self, group: str, name: str, value: object) -> None: ...

    def write(self, path: str) -> None: ...


#: Length units the reader understands, as factors to millimetres.
LENGTH_UNITS_TO_MM = {"mm": 1.0, "millimeter": 1.0, "millimetre": 1.0, "cm": 10.0, "m": 1000.0}

#: ``POINT`` parameters listing model outputs, with the output kind each list means.
_TYPE_LISTS = {
    "ANGLES": "angle",
    "FORCES": "force",
    "MOMENTS": "moment",
    "POWERS": "power",
    "SCALARS": "scalar",
    "MODELED_MARKERS": "modeled_marker",
}
_KIND_TO_LIST = {kind: name for name, kind in _TYPE_LISTS.items()}
#: Output kinds that are positions (written in the file's length unit, as the markers).
LENGTH_KINDS = ("modeled_marker", "segment_frame")
_KIND_UNIT_PARAM = {
    "angle": "ANGLE_UNITS",
    "force": "FORCE_UNITS",
    "moment": "MOMENT_UNITS",
    "power": "POWER_UNITS",
    "scalar": "SCALAR_UNITS",
    "modeled_marker": "MODELED_MARKER_UNITS",
}

#: Plug-in Gait segment-frame virtual markers (origin, anterior, lateral, proximal).
_SEGMENT_FRAME = re.compile(r"^(PEL|HED|TRX|[LR](FE|TI|FO|TO|CL|HU|RA|HN))[OALP]$")
#: Output names by suffix, for files that carry no type lists.
_OUTPUT_SUFFIX = [
    (re.compile(r"Angles?$"), "angle"),
    (re.compile(r"Force$"), "force"),
    (re.compile(r"Moment$"), "moment"),
    (re.compile(r"Power$"), "power"),
]

_MAX_LABEL = 32  # characters per label as Vicon writes them


def _fail(path: Path, problem: str) -> C3DError:
    return C3DError(f"{path}: {problem}")


# =========================================================================== reading
def read_c3d(path: str | os.PathLike[str]) -> Trial:
    """Read a C3D file into a :class:`Trial` (markers in mm, NaN where missing).

    Args:
        path: the ``.c3d`` file.

    Returns:
        The trial; ``trial.notes`` lists anything the reader had to assume or repair
        (missing rate parameter, renamed duplicate labels, unit conversion, fallback
        reader, truncated data block).

    Raises:
        C3DError: the file is missing, unreadable, corrupt or inconsistent; the message
            names the file and the problem.
    """
    path = check_c3d_input(path)
    try:
        raw = decode(path)
    except BackendError as exc:
        raise _fail(path, f"cannot be read as C3D: {exc}; the file is corrupt or not C3D") from exc
    except OSError as exc:
        raise _fail(path, f"cannot be opened ({exc.strerror or exc})") from exc
    try:
        return _interpret(path, raw)
    except C3DError:
        raise
    except FuzzyGaitError as exc:  # e.g. Trial's own checks: name the file
        raise _fail(path, str(exc)) from exc
    except (ValueError, TypeError, IndexError, KeyError, OverflowError) as exc:
        # a last resort: parameters of unexpected types or shapes in a damaged file
        raise _fail(path, f"has inconsistent parameters ({type(exc).__name__}: {exc}); the file is corrupt") from exc


def _interpret(path: Path, raw: RawC3D) -> Trial:
    notes = [warning(w) for w in raw.warnings]
    n_frames, n_points = raw.points.shape[:2]
    if n_frames == 0:
        raise _fail(path, "holds no frames of point data")
    rate = _point_rate(path, raw, notes)
    labels = _point_labels(path, raw, n_points, notes)

    prefix = _label_prefix(raw, labels)
    if prefix:
        labels = [lbl[len(prefix) :] if lbl.startswith(prefix) else lbl for lbl in labels]
    labels = _deduplicate(labels, notes)

    points = raw.points.copy()
    points[np.all(points == 0.0, axis=2)] = np.nan  # C3D writers that mark gaps by zeros
    points[~np.all(np.isfinite(points), axis=2)] = np.nan
    to_mm = _length_factor(path, raw, notes)

    kinds = _output_kinds(raw, labels, prefix)
    marker_cols = [i for i, lbl in enumerate(labels) if lbl not in kinds]
    outputs: dict[str, np.ndarray] = {}
    for i, lbl in enumerate(labels):
        if lbl in kinds:
            scale = to_mm if kinds[lbl] in LENGTH_KINDS else 1.0
            outputs[lbl] = points[:, i, :] * scale

    return Trial(
        markers=points[:, marker_cols, :] * to_mm,
        marker_labels=[labels[i] for i in marker_cols],
        rate=rate,
        first_frame=raw.first_frame,
        outputs=outputs,
        output_kinds=kinds,
        events=read_events(path, raw, notes),
        parameters=read_processing_parameters(raw, notes),
        analysis=read_analysis_values(raw, notes),
        subject=_subject_name(raw),
        label_prefix=prefix,
        source=path,
        notes=notes,
    )


def _point_rate(path: Path, raw: RawC3D, notes: list[Finding]) -> float:
    value = raw.get("POINT", "RATE")
    rate = float(np.ravel(value)[0]) if value is not None and np.size(value) else float("nan")
    if not np.isfinite(rate) or rate <= 0:
        if raw.header_rate > 0:
            notes.append(warning(f"POINT:RATE missing or invalid; using the header rate {raw.header_rate:g} Hz"))
            rate = raw.header_rate
        else:
            raise _fail(path, "has no valid point rate (POINT:RATE and header); cannot time the data")
    return rate


def _point_labels(path: Path, raw: RawC3D, n_points: int, notes: list[Finding]) -> list[str]:
    labels = [_printable(str(lbl)) for lbl in raw.labels[:n_points]]
    cleaned = [new for new, old in zip(labels, raw.labels[:n_points]) if new != str(old).replace("\x00", " ").strip()]
    if cleaned:
        shown = ", ".join(cleaned[:5]) + (", ..." if len(cleaned) > 5 else "")
        notes.append(warning(f"{len(cleaned)} labels held control characters, replaced by '?': {shown}"))
    if len(labels) < n_points:
        notes.append(warning(f"{n_points - len(labels)} points have no label; named POINTnn"))
        labels += [""] * (n_points - len(labels))
    elif labels and not all(labels):
        notes.append(warning(f"{labels.count('')} points have an empty label; named POINTnn"))
    return [lbl if lbl else f"POINT{i + 1}" for i, lbl in enumerate(labels)]


def _printable(text: str) -> str:
    """``text`` with every control or format character (terminal escape codes, NUL,
    bidi marks, ...) replaced by ``?``, stripped: labels are printed to terminals and
    written into CSV headers."""
    text = text.replace("\x00", " ")  # NUL padding, as some writers pad labels
    return "".join("?" if unicodedata.category(ch)[0] == "C" else ch for ch in text).strip()


def _label_prefix(raw: RawC3D, labels: list[str]) -> str:
    """The subject prefix (``"A22:"``): from ``SUBJECTS:LABEL_PREFIXES`` or, failing
    that, a ``name:`` prefix shared by every label."""
    declared = raw.get("SUBJECTS", "LABEL_PREFIXES")
    for prefix in declared or []:
        if prefix and sum(lbl.startswith(prefix) for lbl in labels) >= len(labels) / 2:
            return prefix
    heads = {lbl.split(":", 1)[0] + ":" if ":" in lbl else "" for lbl in labels}
    return heads.pop() if len(heads) == 1 and "" not in heads else ""


def _deduplicate(labels: list[str], notes: list[Finding]) -> list[str]:
    seen: dict[str, int] = {}
    result = []
    for lbl in labels:
        seen[lbl] = seen.get(lbl, 0) + 1
        result.append(lbl if seen[lbl] == 1 else f"{lbl}_{seen[lbl]}")
    renamed = sorted(lbl for lbl, count in seen.items() if count > 1)
    if renamed:
        notes.append(warning(f"duplicate labels renamed with _2, _3, ...: {', '.join(renamed)}"))
    return result


def _length_factor(path: Path, raw: RawC3D, notes: list[Finding]) -> float:
    units = raw.get("POINT", "UNITS")
    unit = (units[0] if units else "").strip().lower()
    if not unit:
        notes.append(warning("POINT:UNITS missing; assuming millimetres", FindingKind.UNITS))
        return 1.0
    if unit not in LENGTH_UNITS_TO_MM:
        raise _fail(path, f"unknown POINT:UNITS {unit!r}; expected mm, cm or m")
    factor = LENGTH_UNITS_TO_MM[unit]
    if factor != 1.0:
        notes.append(Finding(FindingKind.UNITS, f"marker positions converted from {unit} to mm"))
    return factor


def _output_kinds(raw: RawC3D, labels: list[str], prefix: str) -> dict[str, str]:
    """Kind of every label that is a model output rather than a marker."""
    kinds: dict[str, str] = {}
    label_set = set(labels)
    listed_any = False
    for param, kind in _TYPE_LISTS.items():
        for name in raw.get("POINT", param) or []:
            listed_any = True
            name = name[len(prefix) :] if prefix and name.startswith(prefix) else name
            if name in label_set:
                kinds[name] = kind
    for lbl in labels:
        if lbl in kinds:
            continue
        if _SEGMENT_FRAME.match(lbl):
            kinds[lbl] = "segment_frame"
        elif not listed_any:
            for pattern, kind in _OUTPUT_SUFFIX:
                if pattern.search(lbl):
                    kinds[lbl] = kind
                    break
    return kinds


def _subject_name(raw: RawC3D) -> str:
    names = raw.get("SUBJECTS", "NAMES")
    return names[0] if names else ""


# =========================================================================== writing
def write_c3d(
    trial: Trial,
    path: str | os.PathLike[str],
    *,
    text_parameters: Mapping[str, Mapping[str, str]] | None = None,
    source: str | os.PathLike[str] | None = None,
) -> list[Finding]:
    """Write ``trial`` to a float C3D file at ``path``.

    Markers are written in mm with ``POINT:UNITS = mm`` (with ``source``: in its length
    unit); missing samples get a residual of -1, others 0 (computed) unless they are
    ``source``'s own unchanged. Model outputs follow Vicon's conventions (angles in degrees listed in
    ``POINT:ANGLES``, etc.). Labels carry ``trial.label_prefix``. Events beyond the
    255th go to ``EVENT:TIMES2``, ``LABELS2``, ... (C3D's ``POINT:LABELS2`` convention;
    the reader joins them). The file appears atomically: on any error nothing is left at ``path``.

    With ``source`` (the C3D file the trial was read from) everything of that file the
    writer does not change is carried over (:mod:`fuzzygait.io.c3d_writeback`): its analog
    channels (samples and ``ANALOG`` parameters, cut to the trial's frames), force
    platforms, the ``EVENT`` group when the trial's events are the file's, and every
    other parameter group and parameter, byte for byte; of its points, those the trial
    holds unchanged keep their residuals, and each its cameras and description.

    Args:
        text_parameters: more parameters, ``{GROUP: {NAME: text}}`` (e.g. ``{"FUZZYGAIT":
            {"MODEL": "cgm2.3"}}``), each a one-string character parameter; groups other
            than the standard ones are ignored by C3D readers that do not know them.
        source: the input C3D file to carry over (None: the trial alone is written).

    Returns:
        Findings for the user (:attr:`~fuzzygait.core.findings.FindingKind.OUTPUT_FILE`):
        one naming what of ``source`` could not be carried over and why ([] when
        everything was, or without ``source``).

    Raises:
        C3DError: the file cannot be written (names the path and the cause), ``path`` is
            not a ``.c3d`` file or is ``source`` itself.
    """
    path = Path(path)
    try:
        check_c3d_path(path, "the output")
        check_not_input(path, [source], "the output")
    except FuzzyGaitError as exc:
        raise _fail(path, str(exc).removeprefix(f"{path}: ")) from None
    prefix = trial.label_prefix
    too_long = [n for n in [*trial.marker_labels, *trial.outputs] if len(prefix + n) > _MAX_LABEL]
    if too_long:
        raise _fail(path, f"labels longer than {_MAX_LABEL} characters: {too_long}; shorten them")
    if source is None:
        _atomic_write(path, lambda tmp: _write_stage(tmp, trial, text_parameters))
        return []
    from fuzzygait.io.c3d_writeback import open_source, write_back

    back = open_source(Path(source), trial)

    def write_stage(target: Path, analogs: Analogs | None) -> None:
        _write_stage(target, trial, text_parameters, analogs, back.points)

    lost: list[str] = []
    _atomic_write(path, lambda tmp: lost.extend(write_back(tmp, path, back, trial, write_stage)))
    return [Finding(FindingKind.OUTPUT_FILE, line, Severity.WARNING) for line in lost]


def _write_stage(target: Path, trial: Trial, text_parameters: Mapping[str, Mapping[str, str]] | None,
                 analogs: Analogs | None = None, points: InputPoints | None = None) -> None:  # fmt: skip
    """ezc3d writes the trial to ``target`` (:func:`_ezc3d_trial`), the event icons and
    flags stored as integers (:func:`~fuzzygait.io.c3d_params.integer_event_records`);
    its blocks checked."""
    from fuzzygait.io.c3d_writeback import splice

    _write_with_ezc3d(_ezc3d_trial(trial, text_parameters, analogs, points), target)
    check_blocks(target)
    data = target.read_bytes()
    section = read_section(data)
    if integer_event_records(section):  # smaller records: the section still fits
        target.write_bytes(splice(data, section))


def _ezc3d_trial(
    trial: Trial,
    text_parameters: Mapping[str, Mapping[str, str]] | None,
    analogs: Analogs | None,
    points: InputPoints | None = None,
) -> _EzC3D:
    """``trial`` as an ezc3d object: points (residual -1 where missing, 0 where valid),
    output type lists, subject, first frame, ``text_parameters`` and events; with
    ``analogs``, the input's analog samples as stored (scale 1, offset 0: the input's
    ``ANALOG`` group replaces these parameters afterwards, :mod:`fuzzygait.io.c3d_writeback`).

    Positions (markers, modelled markers, segment frames) are in mm, or with ``points``
    (the input's point block) in the input's length unit, as its other parameters (force
    plates' corners and origin) are; its own points keep their residuals, cameras and
    descriptions (:func:`~fuzzygait.io.c3d_points.point_meta`)."""
    import ezc3d

    names = list(trial.marker_labels) + list(trial.outputs)
    labels = [trial.label_prefix + n for n in names]
    data = np.concatenate(
        [trial.markers, np.stack(list(trial.outputs.values()), axis=1)]
        if trial.outputs
        else [trial.markers],
        axis=1,
    )  # (frames, points, 3)
    unit = "mm"
    if points is not None and points.to_mm != 1.0:
        unit = points.unit
        lengths = [True] * trial.n_markers + [trial.output_kinds.get(n) in LENGTH_KINDS for n in trial.outputs]
        data = np.where(np.array(lengths)[None, :, None], data / points.to_mm, data)
    valid = np.all(np.isfinite(data), axis=2)
    block = np.zeros((4, data.shape[1], data.shape[0]))
    block[:3] = np.where(valid[:, :, None], data, 0.0).transpose(2, 1, 0)
    block[3] = 1.0
    if points is not None:
        from fuzzygait.io.c3d_points import point_meta

        residuals, masks, descriptions = point_meta(points, labels, data)
    else:
        residuals, masks = np.where(valid, 0.0, -1.0), np.zeros((7, data.shape[1], data.shape[0]), dtype=bool)
        descriptions = [""] * len(names)

    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = np.array([trial.rate])
    c["parameters"]["POINT"]["LABELS"]["value"] = labels
    c["parameters"]["POINT"]["DESCRIPTIONS"]["value"] = descriptions
    c["parameters"]["POINT"]["UNITS"]["value"] = [unit]
    if points is not None:  # a float file (negative scale) whose residuals are in the input's unit
        c["parameters"]["POINT"]["SCALE"]["value"] = np.array([-points.residual_scale])
    c["data"]["points"] = block
    c["data"]["meta_points"]["residuals"] = residuals.T[None]
    c["data"]["meta_points"]["camera_masks"] = masks
    _write_output_lists(c, trial)
    _write_subject(c, trial)
    _write_trial_frames(c, trial)
    for group, values in (text_parameters or {}).items():
        for name, text in values.items():
            c.add_parameter(group.upper(), name.upper(), [str(text)])
    for name, value in event_parameters(trial.events):  # beyond 255 events: TIMES2, LABELS2, ...
        c.add_parameter("EVENT", name, value)
    if analogs is not None:
        _write_stored_analogs(c, analogs, trial.rate)
    return c


def _write_stored_analogs(c: _EzC3D, analogs: Analogs, rate: float) -> None:
    """The input's analog samples as stored (placeholder labels, scale 1, offset 0) at
    ``analogs.per_frame`` samples a frame of ``rate`` Hz."""
    n = analogs.stored.shape[0]
    c["data"]["analogs"] = analogs.stored[None]  # (1, channels, samples)
    c.add_parameter("ANALOG", "LABELS", [f"A{i + 1}" for i in range(n)])
    c.add_parameter("ANALOG", "SCALE", np.ones(n))
    c.add_parameter("ANALOG", "RATE", np.array([analogs.per_frame * rate]))


def _write_with_ezc3d(c: _EzC3D, target: Path) -> None:
    """``c.write`` to ``target``: ezc3d appends ``.c3d`` to a name that does not end so
    (e.g. ``OUT.C3D``), so it writes beside it and the file is moved onto ``target``."""
    if target.name.endswith(".c3d"):
        c.write(str(target))
        return
    beside = target.with_name(target.name + ".c3d")
    try:
        c.write(str(beside))
        os.replace(beside, target)
    finally:
        beside.unlink(missing_ok=True)


def _write_output_lists(c: _EzC3D, trial: Trial) -> None:
    by_kind: dict[str, list[str]] = {}
    for name, kind in trial.output_kinds.items():
        by_kind.setdefault(kind, []).append(trial.label_prefix + name)
    type_groups = []
    for kind, list_name in _KIND_TO_LIST.items():
        if kind in by_kind:
            c.add_parameter("POINT", list_name, by_kind[kind])
            c.add_parameter("POINT", _KIND_UNIT_PARAM[kind], [OUTPUT_UNITS[kind]])
            type_groups += [list_name, list_name[:-1]]
    if type_groups:
        c.add_parameter("POINT", "TYPE_GROUPS", type_groups)


def _write_subject(c: _EzC3D, trial: Trial) -> None:
    for name, value in trial.parameters.items():
        c.add_parameter("PROCESSING", name, np.array([float(value)]))
    if trial.subject or trial.label_prefix:
        c.add_parameter("SUBJECTS", "USED", 1)
        c.add_parameter("SUBJECTS", "NAMES", [trial.subject or trial.label_prefix.rstrip(":")])
        c.add_parameter("SUBJECTS", "LABEL_PREFIXES", [trial.label_prefix])
        c.add_parameter("SUBJECTS", "USES_PREFIXES", 1 if trial.label_prefix else 0)


def _write_trial_frames(c: _EzC3D, trial: Trial) -> None:
    """Record the first frame number in the header (ezc3d counts from 0 there).

    Vicon's ``TRIAL:ACTUAL_START_FIELD`` is not written here: ezc3d's Python API can only
    store integer arrays as floats, which other readers reject for that parameter. An
    input file's ``TRIAL`` group is carried over as stored (frame fields moved to the
    trial's frames) by :mod:`fuzzygait.io.c3d_writeback`.
    """
    c["header"]["points"]["first_frame"] = int(trial.first_frame) - 1


def _atomic_write(path: Path, write: Callable[[Path], object]) -> None:
    try:
        with atomic_output(path) as tmp:
            write(tmp)
    except FuzzyGaitError as exc:
        raise _fail(path, str(exc).removeprefix(f"{path}: ")) from None
    except Exception as exc:
        raise _fail(path, f"cannot be written ({exc})") from exc
