"""Subject ``.mp`` files of either kind (:func:`read_mp` tells them apart): Vicon Nexus'
(``$LeftLegLength = 900`` lines; mm, kg, angles in degrees) and pyCGM2's (YAML, or the
older JSON: ``MandatoryParameters`` and ``OptionalParameters`` with ``LeftLegLength``
style names; mm, kg; no angles).  Both give :class:`~fuzzygait.io.subject.SubjectParameters`
through :func:`~fuzzygait.io.subject.subject_from_processing`;
:func:`fuzzygait.io.subject.read_subject` reads a ``.mp`` with :func:`read_mp`.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from pathlib import Path

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.subject import (
    ANGLE_FIELDS,
    PROCESSING_NAMES,
    VICON_SIDE_NAMES,
    SubjectParameters,
    _vicon_name,
    subject_from_processing,
)

#: What an ``.mp`` file that is neither kind is told to be (one line).
_MP_EXPECTED = ("expected Vicon Nexus' '$Name = value' lines (e.g. '$LeftLegLength = 900') or pyCGM2's "
                "'MandatoryParameters:' / 'OptionalParameters:' groups (YAML, or the older JSON)")  # fmt: skip

#: pyCGM2 ``.mp`` values read (mm, kg); the optional offsets (pyCGM2 computes them in the
#: static calibration, 0 = not given) are not: fuzzygait's static calibration sets them.
_MP_NAMES = {"Bodymass", "Height", "InterAsisDistance", "MarkerDiameter"} | {
    f"{side}{name}" for side in "LR" for name in ("LegLength", "KneeWidth", "AnkleWidth", "SoleDelta",
                                                  "AsisTrocanterDistance")}  # fmt: skip

#: Vicon Nexus ``.mp`` angles (degrees in the file, radians in SubjectParameters).
_NEXUS_MP_ANGLES = frozenset(side + VICON_SIDE_NAMES[name] for side in "LR" for name in ANGLE_FIELDS)
#: Nexus ``.mp`` parameters SubjectParameters has no field for (the Plug-in Gait upper
#: body, and the circumferences of older Vicon subject files): numbers, read and ignored.
_NEXUS_MP_IGNORED = frozenset({"HeadOffset"} | {
    side + name for side in "LR"
    for name in ("ShoulderOffset", "ElbowWidth", "WristWidth", "WristThickness", "HandWidth", "HandThickness",
                 "CircuitThigh", "CircuitShank")})  # fmt: skip
#: Nexus ``.mp`` measurements whose 0 means "not measured" (Plug-in Gait computes the
#: ASIS distances, the marker diameter defaults, a missing leg measurement is named).
_NEXUS_MP_ZERO_UNSET = frozenset({"InterAsisDistance", "MarkerDiameter"} | {
    side + name for side in "LR"
    for name in ("LegLength", "KneeWidth", "AnkleWidth", "AsisTrocanterDistance")})  # fmt: skip
#: One line of a Nexus ``.mp``: ``$Name = value``.
_NEXUS_MP_LINE = re.compile(r"\$\s*(?P<name>[A-Za-z_][A-Za-z0-9_]*)\s*=\s*(?P<value>.*?)\s*;?\s*")


def _mp_text(path: Path) -> str:
    """The text of an ``.mp`` file: UTF-16 with a byte-order mark, else UTF-8 (with or
    without one), else Latin-1 (Windows tools)."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such subject file; check the path") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the .mp file ({exc.strerror or exc})") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        return raw.decode("utf-16", errors="replace")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _meaningful_lines(text: str) -> list[tuple[int, str]]:
    """``(line number, stripped line)`` of the lines that are neither blank nor ``#`` comments."""
    return [(n, line.strip()) for n, line in enumerate(text.splitlines(), 1)
            if line.strip() and not line.strip().startswith("#")]  # fmt: skip


def _nexus_mp_values(path: Path, lines: Sequence[tuple[int, str]]) -> dict[str, float]:
    """The ``$Name = value`` lines of a Vicon Nexus ``.mp`` under ``PROCESSING`` names
    (:func:`read_mp`): angles converted to radians, unset zeros and ignored names left out."""
    values: dict[str, float] = {}
    for number, line in lines:
        match = _NEXUS_MP_LINE.fullmatch(line)
        if match is None:
            raise ParameterError(f"{path}: line {number} {line!r} of this Vicon Nexus .mp is not '$Name = value'")
        key, raw = match["name"], match["value"]
        name = _vicon_name(key)
        if name not in PROCESSING_NAMES and name not in _NEXUS_MP_IGNORED:
            continue  # another model's parameter
        try:
            value = float(raw)
        except ValueError:
            raise ParameterError(f"{path}: parameter {key} has non-numeric value {raw!r}") from None
        if name in _NEXUS_MP_IGNORED or (value == 0.0 and name in _NEXUS_MP_ZERO_UNSET):
            continue
        value = math.radians(value) if name in _NEXUS_MP_ANGLES else value
        if name in values and values[name] != value:
            raise ParameterError(f"{path}: parameter {name} is given twice with different values ({key})")
        values[name] = value
    return values


def _mp_groups(path: Path, text: str) -> dict[str, dict[str, str]]:
    """The ``Group: / Key: value`` lines of a pyCGM2 ``.mp`` file (its YAML subset; JSON
    written by older pyCGM2 versions has the same shape once braces and quotes go)."""
    groups: dict[str, dict[str, str]] = {"": {}}
    current = ""
    for raw in text.replace("{", "\n").replace("}", "\n").replace(",", "\n").splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        key, sep, value = (part.strip().strip("\"'") for part in line.partition(":"))
        if not sep or not key:
            raise ParameterError(f"{path}: neither a Vicon Nexus nor a pyCGM2 .mp file (line {raw.strip()!r}); "
                                 + _MP_EXPECTED)  # fmt: skip
        if value == "":
            current = key
            groups.setdefault(current, {})
        else:
            groups.setdefault(current, {})[key] = value
    return groups


def _pycgm2_mp_values(path: Path, text: str) -> dict[str, float]:
    """The values of a pyCGM2 ``.mp`` under ``PROCESSING`` names (:func:`read_mp`)."""
    groups = _mp_groups(path, text)
    known = {_vicon_name(key) for key in groups[""]} & _MP_NAMES
    if not known and not {"MandatoryParameters", "OptionalParameters"} & set(groups):
        raise ParameterError(f"{path}: neither a Vicon Nexus nor a pyCGM2 .mp file (no subject parameter in it); "
                             + _MP_EXPECTED)  # fmt: skip
    values: dict[str, float] = {}
    for group in ("", "MandatoryParameters", "OptionalParameters"):
        for key, raw in groups.get(group, {}).items():
            name = _vicon_name(key)
            if name not in _MP_NAMES or raw.lower() in ("null", "none", "~"):
                continue
            try:
                value = float(raw)
            except ValueError:
                raise ParameterError(f"{path}: parameter {key} has non-numeric value {raw!r}") from None
            if value == 0.0 and name not in ("LSoleDelta", "RSoleDelta"):
                continue  # pyCGM2's "not measured"
            values[name] = value
    return values


def read_mp(path: str | os.PathLike[str]) -> SubjectParameters:
    """Read an ``.mp`` subject file of either kind, told apart by its first line that is
    neither blank nor a ``#`` comment: ``$...`` is Vicon Nexus', anything else pyCGM2's.

    **Vicon Nexus** (Plug-in Gait's subject file, beside the ``.vsk``): one
    ``$Name = value`` per line, the ``.vsk``'s names (``$Bodymass`` kg, ``$Height`` mm,
    ``$MarkerDiameter`` mm, ``$InterAsisDistance`` mm; per side ``$LeftLegLength``,
    ``$LeftKneeWidth``, ``$LeftAnkleWidth``, ``$LeftAsisTrocanterDistance``,
    ``$LeftSoleDelta`` mm and ``$LeftTibialTorsion``, ``$LeftThighRotation``,
    ``$LeftShankRotation``, ``$LeftAnkleAbAdd``, ``$LeftStaticPlantFlex``,
    ``$LeftStaticRotOff`` in **degrees**, converted to radians; ``Right...`` alike) or
    their ``PROCESSING`` spelling (``$LLegLength``, as older Vicon files and tools have
    it).  ``$HeadOffset`` and the upper-body ``$LeftShoulderOffset``,
    ``$LeftElbowWidth``, ``$LeftWristWidth``, ``$LeftWristThickness``,
    ``$LeftHandWidth``, ``$LeftHandThickness`` (and the circumferences
    ``$LeftCircuitThigh``/``$LeftCircuitShank``) are read and ignored: the lower-body model
    has no use for them; names of other models are ignored.  A value 0 of a *measured*
    length means "not measured": ``InterAsisDistance`` is then measured from the ASIS
    markers, ``AsisTrocanterDistance`` comes from the leg-length regression,
    ``MarkerDiameter`` is 14 mm, and a leg length, knee or ankle width of 0 is named as
    missing; ``Bodymass``/``Height`` 0 are unknown; for the offsets (angles) and
    ``SoleDelta`` 0 is a real 0.

    **pyCGM2** (YAML, or the older JSON of the same shape): the groups
    ``MandatoryParameters`` (``Bodymass`` kg, ``Height`` mm, ``LeftLegLength``,
    ``LeftKneeWidth``, ``LeftAnkleWidth``, ``LeftSoleDelta``, the same for ``Right``; mm)
    and ``OptionalParameters`` (``InterAsisDistance``, ``LeftAsisTrocanterDistance``, ...
    mm; 0 means "not measured").  Its optional angular offsets are not read: the static
    calibration computes them.

    Raises:
        ParameterError: one line naming the file: a missing or unreadable file, a file of
            neither kind (saying what was expected), a bad line or non-numeric value, a
            parameter given twice, missing or implausible parameters.
    """
    path = Path(path)
    text = _mp_text(path)
    lines = _meaningful_lines(text)
    if lines and lines[0][1].startswith("$"):
        values = _nexus_mp_values(path, lines)
    elif lines:
        values = _pycgm2_mp_values(path, text)
    else:
        raise ParameterError(f"{path}: the .mp file is empty; {_MP_EXPECTED}")
    return subject_from_processing(values, source=str(path))
