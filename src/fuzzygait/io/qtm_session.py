"""Qualisys Track Manager ``session.xml``: the subject file of a QTM session folder.

QTM's project (as pyCGM2's QTM workflow uses it) keeps the patient, the visit and its
measurements in one ``session.xml`` per session folder (UTF-16 or UTF-8)::

    <Subject Type="Patient">
      <Fields><First_name>..</First_name><Last_name>..</Last_name> ...</Fields>
      <Session Type="Clinical Gait Session">
        <Fields><Height>1.8</Height><Weight>70</Weight>
                <Leg_length_left>1.0</Leg_length_left> ... </Fields>
        <Subsession ...> ... <Measurement .../> ... </Subsession>
      </Session>
    </Subject>

The visit's anthropometry sits in the ``Session``'s ``Fields``, **in metres** (weight in
kg; QTM writes float32 values, 0.094999999 m).  :func:`qtm_session_values` returns it
under Vicon ``PROCESSING`` names in mm rounded to the micrometre, as
:func:`fuzzygait.io.subject.subject_from_processing` takes them:

=======================================  ====================================
session.xml field                         fuzzygait (Vicon) name, unit
=======================================  ====================================
``Height``                                ``Height``, mm
``Weight``                                ``Bodymass``, kg
``Leg_length_left`` / ``_right``          ``LLegLength`` / ``RLegLength``, mm
``Knee_width_left`` / ``_right``          ``LKneeWidth`` / ``RKneeWidth``, mm
``Ankle_width_left`` / ``_right``         ``LAnkleWidth`` / ``RAnkleWidth``, mm
``Sole_delta_left`` / ``_right``          ``LSoleDelta`` / ``RSoleDelta``, mm
``Marker_diameter``                       ``MarkerDiameter``, mm
=======================================  ====================================

A length of 0 is QTM's "not measured" (sole delta excepted: 0 is a value).

:func:`qtm_foot_flat` reads the subsession's ``Left_foot_normalised_to_static_trial`` /
``Right_…`` (``True``/``False``): pyCGM2's foot-flat option, Plug-in Gait's "foot flat"
(the sole parallel to the floor in the static trial).  It is the default of the static
calibration when both feet agree (a command's ``--flat-foot`` / ``--no-flat-foot``
overrides it; fuzzygait's foot flat is one setting for both feet).  Other fields
(upper-body widths, the CGM2 model choice, filter settings) are not read: those options
are the command's (``--model``, ``--cutoff``).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

from fuzzygait.core.errors import ParameterError

__all__ = ["QTM_SESSION_FILE", "is_qtm_session", "qtm_foot_flat", "qtm_session_values", "qtm_subject_name"]

#: The file name QTM gives a session's subject file.
QTM_SESSION_FILE = "session.xml"

#: session.xml length fields (metres) -> Vicon name (mm).
_LENGTHS = {"Height": "Height", "Marker_diameter": "MarkerDiameter"} | {
    f"{field}_{side}": f"{side[0].upper()}{name}"
    for field, name in (("Leg_length", "LegLength"), ("Knee_width", "KneeWidth"), ("Ankle_width", "AnkleWidth"),
                        ("Sole_delta", "SoleDelta"))
    for side in ("left", "right")
}  # fmt: skip
#: Longest plausible length in metres (a height of 3 m): a larger value is in mm already.
_MAX_METRES = 3.0


def is_qtm_session(path: Path) -> bool:
    """``path`` is named like a QTM session file (``session.xml``, any case)."""
    return path.name.lower() == QTM_SESSION_FILE


def _root(path: Path) -> ET.Element:
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such subject file; check the path") from None
    except (OSError, ET.ParseError) as exc:
        raise ParameterError(f"{path}: cannot read the QTM session.xml ({exc})") from None
    if root.tag != "Subject":
        raise ParameterError(f"{path}: not a QTM session.xml (its root element is <{root.tag}>, not <Subject>); "
                             "give a .toml, .vsk or .mp subject file instead")  # fmt: skip
    return root


def _number(path: Path, field: str, text: str | None) -> float:
    try:
        return float((text or "").strip())
    except ValueError:
        raise ParameterError(f"{path}: field {field} has non-numeric value {text!r}") from None


def qtm_session_values(path: str | os.PathLike[str]) -> dict[str, float]:
    """The anthropometry of a QTM ``session.xml`` under Vicon names, lengths in mm.

    The first ``Session`` element whose ``Fields`` hold a leg length is the visit read.

    Raises:
        ParameterError: a missing or unreadable file, another XML document, no session
            with a leg length, a non-numeric field, or a length that is not in metres
            (one line naming the file and the field).
    """
    path = Path(path)
    root = _root(path)
    sessions = [s.find("Fields") for s in root.iter("Session")]
    fields = next((f for f in sessions if f is not None and f.find("Leg_length_left") is not None), None)
    if fields is None:
        raise ParameterError(f"{path}: this session.xml has no <Session> with Leg_length_left; enter the "
                             "patient's leg lengths, knee and ankle widths in QTM's session, or give a .toml "
                             "subject file")  # fmt: skip
    values: dict[str, float] = {}
    weight = fields.find("Weight")
    if weight is not None and _number(path, "Weight", weight.text) > 0:
        values["Bodymass"] = _number(path, "Weight", weight.text)
    for field, name in _LENGTHS.items():
        element = fields.find(field)
        if element is None:
            continue
        metres = _number(path, field, element.text)
        if metres > _MAX_METRES:
            raise ParameterError(f"{path}: {field} = {metres:g} is not in metres (QTM's session.xml stores "
                                 f"lengths in m: {metres / 1000:g} if that is mm); correct it in QTM")  # fmt: skip
        if metres == 0.0 and not field.startswith("Sole_delta"):
            continue  # QTM's "not measured"
        values[name] = round(metres * 1000.0, 3)  # QTM writes float32 values: 0.094999999 m
    return values


def qtm_subject_name(path: str | os.PathLike[str]) -> str | None:
    """The patient's name of a QTM ``session.xml`` ("First Last"), None when it has none
    or cannot be read."""
    try:
        fields = _root(Path(path)).find("Fields")
    except ParameterError:
        return None
    if fields is None:
        return None
    parts = [(fields.findtext(tag) or "").strip() for tag in ("First_name", "Last_name")]
    return " ".join(p for p in parts if p) or None


#: The subsession fields of pyCGM2's foot-flat option, per side.
FOOT_FLAT_FIELDS = ("Left_foot_normalised_to_static_trial", "Right_foot_normalised_to_static_trial")


def qtm_foot_flat(path: str | os.PathLike[str]) -> bool | None:
    """The session's foot-flat setting: True/False when both feet's "foot normalised to
    static trial" fields say so, None when a field is absent, not True/False, or the two
    feet differ (then the command's own default, foot flat off, applies).

    Raises:
        ParameterError: a missing or unreadable file, another XML document.
    """
    for fields in _root(Path(path)).iter("Fields"):
        said = [(fields.findtext(tag) or "").strip().lower() for tag in FOOT_FLAT_FIELDS]
        if any(said):
            return said[0] == "true" if said[0] == said[1] and said[0] in ("true", "false") else None
    return None
