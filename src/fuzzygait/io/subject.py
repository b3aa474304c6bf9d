"""Subject (anthropometric) parameters of the Conventional Gait Model / Plug-in Gait.

These sources give the same :class:`SubjectParameters` (each for the fields it holds):

* a TOML file with Vicon ``PROCESSING`` names at top level (``LLegLength = 900.0``),
  see ``sample_data/subject.toml``;
* a Vicon ``.vsk`` subject file (XML; ``LeftLegLength`` / ``RightLegLength`` names);
* the ``PROCESSING`` group of a C3D file (``trial.parameters``);
* an ``.mp`` file of either kind (:func:`read_mp` in :mod:`fuzzygait.io.subject_mp`
  tells them apart): Vicon Nexus' (``$LeftLegLength = 900`` lines; mm, kg, angles in
  degrees) or pyCGM2's (YAML or JSON: ``MandatoryParameters`` and ``OptionalParameters``
  with ``LeftLegLength`` style names; mm, kg; no angles);
* a QTM ``session.xml`` (:mod:`fuzzygait.io.qtm_session`; lengths, widths, sole deltas,
  marker diameter, height and mass, no offsets).

:func:`write_subject` writes them back as TOML or ``.vsk`` (read back equal).

Units: lengths in mm, angles in **radians** (as Vicon stores them), mass in kg.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import escape as xml_escape

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.core.options import Option
from fuzzygait.core.paths import check_subject_input
from fuzzygait.core.subject import (  # the definitions; the names importable from here too
    ANGLE_FIELDS,
    DEFAULT_MARKER_DIAMETER,
    REQUIRED_SIDE,
    VICON_SIDE_NAMES,
    SideParameters,
    SubjectParameters,
)
from fuzzygait.core.subject import BODY_MASS_RANGE as BODY_MASS_RANGE
from fuzzygait.core.subject import HEIGHT_RANGE as HEIGHT_RANGE
from fuzzygait.core.subject import PROCESSING_NAMES as PROCESSING_NAMES
from fuzzygait.core.subject import asis_trochanter_regression as asis_trochanter_regression
from fuzzygait.io.atomic import atomic_output
from fuzzygait.io.qtm_session import is_qtm_session, qtm_foot_flat, qtm_session_values
from fuzzygait.io.tomlfile import TomlData, load_toml, toml_text

if TYPE_CHECKING:  # at run time through __getattr__: fuzzygait.io.subject_mp imports this module
    from fuzzygait.io.subject_mp import read_mp as read_mp


# ---------------------------------------------------------------------- constructors
def subject_from_processing(values: Mapping[str, float], source: str = "") -> SubjectParameters:
    """Build parameters from Vicon ``PROCESSING`` names (``LLegLength``, ...).

    Raises:
        ParameterError: when required values are missing (all of them named) or
            implausible.
    """
    needed = [f"{p}{VICON_SIDE_NAMES[n]}" for p in "LR" for n in REQUIRED_SIDE]
    missing = [name for name in needed if name not in values]
    if missing:
        where = f"{source}: " if source else ""
        raise ParameterError(
            f"{where}missing subject parameters {', '.join(missing)}; "
            f"give them in a subject file ({Option.SUBJECT} SUBJECT.toml or .vsk)"
        )

    def side(prefix: str) -> SideParameters:
        kwargs: dict[str, float | None] = {}
        for name, vicon in VICON_SIDE_NAMES.items():
            if prefix + vicon in values:
                kwargs[name] = float(values[prefix + vicon])
        return SideParameters(**kwargs)  # type: ignore[arg-type]

    inter_asis = values.get("InterAsisDistance")
    return SubjectParameters(
        left=side("L"),
        right=side("R"),
        body_mass=float(values.get("Bodymass", 0.0)),
        height=float(values.get("Height", 0.0)),
        marker_diameter=float(values.get("MarkerDiameter", DEFAULT_MARKER_DIAMETER)),
        inter_asis_distance=float(inter_asis) if inter_asis else None,
        source=source,
        marker_diameter_stated="MarkerDiameter" in values,
    ).validate()


def read_subject_toml(path: str | os.PathLike[str]) -> SubjectParameters:
    """Read a TOML subject file with Vicon ``PROCESSING`` names at top level."""
    path = Path(path)
    data = load_toml(path, "subject file")
    table = data.get("subject", data) if isinstance(data.get("subject"), dict) else data
    numbers = {k: v for k, v in table.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    given = [f"{k} = {v!r}" for k, v in table.items() if k in PROCESSING_NAMES and k not in numbers]
    if given:
        raise ParameterError(f"{path}: subject parameters must be numbers (mm, kg, rad), written without quotes, e.g. "
                             f"LLegLength = 900.0; got {', '.join(given)}")  # fmt: skip
    bad = [k for k, v in table.items() if not isinstance(v, (int, float, dict, str))]
    if bad:
        raise ParameterError(f"{path}: parameters {bad} must be numbers")
    return subject_from_processing(numbers, source=str(path))


#: The words of a ``[force_plates]`` table: the foot on the plate, none, or the automatic
#: assignment (the plate left out of the override).
_PLATE_FEET: dict[str, Side | None] = {"left": Side.LEFT, "right": Side.RIGHT, "none": None}
_PLATE_AUTO = "auto"


def read_force_plate_assignment(path: str | os.PathLike[str]) -> dict[int, Side | None]:
    """The foot on each force plate as a subject file's ``[force_plates]`` table states it
    (TOML subject files only; ``[subject.force_plates]`` too), e.g.::

        [force_plates]
        1 = "left"
        2 = "none"    # no foot's load: the contacts on plate 2 are not used
        3 = "auto"    # the automatic assignment (as if not listed)

    Returns plate number (1-based, as ``FORCE_PLATFORM``) -> :class:`Side`, None for
    ``"none"``; plates set to ``"auto"`` or not listed are left out (empty: no override,
    also for a file of another kind or without the table).

    Raises:
        ParameterError: a key that is not a plate number 1, 2, ... or a value other than
            ``"left"``, ``"right"``, ``"none"``, ``"auto"`` (one line naming the file and key).
    """
    path = Path(path)
    if path.suffix.lower() != ".toml":
        return {}
    data = load_toml(path, "subject file")
    nested = data.get("subject")
    table = data.get("force_plates", nested.get("force_plates") if isinstance(nested, dict) else None)
    if table is None:
        return {}
    if not isinstance(table, dict):
        raise ParameterError(f"{path}: force_plates must be a table of plate number = \"left\", \"right\", "
                             f"\"none\" or \"auto\"")  # fmt: skip
    out: dict[int, Side | None] = {}
    words = ", ".join(f'"{w}"' for w in [*_PLATE_FEET, _PLATE_AUTO])
    for key, value in table.items():
        if not (key.isdigit() and int(key) >= 1):
            raise ParameterError(f"{path}: force_plates.{key}: not a plate number; use 1, 2, ... as in the C3D")
        word = value.lower() if isinstance(value, str) else None
        if word != _PLATE_AUTO and word not in _PLATE_FEET:
            raise ParameterError(f"{path}: force_plates.{key} = {value!r}; use one of {words}")
        if word in _PLATE_FEET:
            out[int(key)] = _PLATE_FEET[word]
    return out


def read_vsk(path: str | os.PathLike[str]) -> SubjectParameters:
    """Read a Vicon ``.vsk`` subject file (``LeftLegLength`` style names)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such subject file; check the path") from None
    except ET.ParseError as exc:
        raise ParameterError(f"{path}: not a valid Vicon .vsk (XML) file ({exc})") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the subject file ({exc.strerror or exc})") from None
    values: dict[str, float] = {}
    for element in root.iter():
        if not element.tag.endswith("Parameter") or "NAME" not in element.attrib:
            continue
        raw = element.attrib.get("VALUE")
        if raw is None:
            continue  # Vicon leaves unset optional parameters without a VALUE
        name = _vicon_name(element.attrib["NAME"])
        try:
            values[name] = float(raw)
        except ValueError:
            raise ParameterError(f"{path}: parameter {name} has non-numeric value {raw!r}") from None
    return subject_from_processing(values, source=str(path))


def _vicon_name(name: str) -> str:
    """``LeftLegLength`` -> ``LLegLength`` (Vicon's long side prefixes shortened)."""
    for long, short in (("Left", "L"), ("Right", "R")):
        if name.startswith(long):
            return short + name[len(long) :]
    return name


def is_subject_file(path: Path) -> bool:
    """``path`` is a subject file a session folder may hold: ``.toml``, ``.vsk``, ``.mp``
    (Vicon Nexus' or pyCGM2's) or QTM's ``session.xml`` (other XML files of a folder are
    not subject files)."""
    suffix = path.suffix.lower()
    return suffix in (".toml", ".vsk", ".mp") or is_qtm_session(path)


def read_qtm_session(path: str | os.PathLike[str]) -> SubjectParameters:
    """Read a Qualisys Track Manager ``session.xml`` (:mod:`fuzzygait.io.qtm_session`:
    the session's leg lengths, knee and ankle widths, sole deltas, marker diameter,
    height in metres and weight in kg; its "foot normalised to static trial" setting
    as ``flat_foot``)."""
    subject = subject_from_processing(qtm_session_values(path), source=str(path))
    return replace(subject, flat_foot=qtm_foot_flat(path))


def read_subject(path: str | os.PathLike[str]) -> SubjectParameters:
    """Read a subject file by extension: ``.toml``, ``.vsk``, ``.mp`` (Vicon Nexus' or
    pyCGM2's: :func:`read_mp`) or a QTM ``session.xml`` (any ``.xml`` is read as one).

    Raises:
        ParameterError: a folder, a missing or unreadable file, another extension, or
            implausible parameters (one line naming the file and the parameter).
    """
    suffix = check_subject_input(path).suffix.lower()
    from fuzzygait.io.subject_mp import read_mp  # imports this module: here, not at the top

    readers = {".toml": read_subject_toml, ".vsk": read_vsk, ".mp": read_mp, ".xml": read_qtm_session}
    return readers[suffix](path)


def __getattr__(name: str) -> object:
    """:func:`read_mp` (:mod:`fuzzygait.io.subject_mp`, which builds on this module) is
    importable from here too, imported on first use so that neither import is circular."""
    if name == "read_mp":
        from fuzzygait.io.subject_mp import read_mp

        return read_mp
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# ---------------------------------------------------------------------- writers
def subject_values(subject: SubjectParameters) -> dict[str, float]:
    """The parameters under Vicon ``PROCESSING`` names as they are: unlike
    :meth:`SubjectParameters.to_processing`, values left to a regression or to the static
    trial (``AsisTrocanterDistance``, ``InterAsisDistance`` None) are left out, so that a
    file written from them reads back equal."""
    out: dict[str, float] = {"Bodymass": subject.body_mass, "Height": subject.height,
                             "MarkerDiameter": subject.marker_diameter}  # fmt: skip
    if subject.inter_asis_distance is not None:
        out["InterAsisDistance"] = subject.inter_asis_distance
    for prefix, params in (("L", subject.left), ("R", subject.right)):
        for name, vicon in VICON_SIDE_NAMES.items():
            value = getattr(params, name)
            if value is not None:
                out[prefix + vicon] = float(value)
    return out


def _vsk_parameters(subject: SubjectParameters) -> dict[str, tuple[float, str]]:
    """``{VSK name: (value, QUANTITY)}``: ``LeftLegLength`` style names; mm, rad, kg."""
    angles = {v for k, v in VICON_SIDE_NAMES.items() if k in ANGLE_FIELDS}
    out: dict[str, tuple[float, str]] = {}
    for name, value in subject_values(subject).items():
        vicon = name
        if name[0] in "LR" and name[1:] in VICON_SIDE_NAMES.values():
            vicon = ("Left" if name[0] == "L" else "Right") + name[1:]
        quantity = "mass" if name == "Bodymass" else "angle" if name[1:] in angles else "length"
        out[vicon] = (float(value), quantity)
    return out


def _vsk_comment(comments: Sequence[str]) -> str:
    return " " + " ".join(comments).replace("--", "- -") + " "


def subject_vsk_text(subject: SubjectParameters, comments: Sequence[str] = (), template: str | None = None) -> str:
    """A Vicon ``.vsk`` (XML) with the parameters (``StaticParameter`` elements with
    Nexus' names, ``LeftLegLength``, ...; mm, rad, kg) and ``comments`` as an XML comment.

    With ``template`` (the text of the subject's own ``.vsk``, as Nexus wrote it) the
    result is that file with each parameter's ``VALUE`` set (added where Nexus left it
    unset, new ``StaticParameter`` elements for parameters it lacks) and every other byte
    kept: its skeleton, marker set and model stay as Nexus needs them.  Without one the
    file holds the parameters only (no skeleton or marker set).
    """
    parameters = _vsk_parameters(subject)
    if template is not None:
        return _update_vsk(template, parameters, comments)
    root = ET.Element("KinematicModel", MODEL="PlugInGait", VERSION="3.2")
    if comments:
        root.append(ET.Comment(_vsk_comment(comments)))
    element = ET.SubElement(root, "Parameters")
    for vicon, (value, quantity) in parameters.items():
        ET.SubElement(element, "StaticParameter", NAME=vicon, VALUE=repr(value), PRIOR=repr(value), QUANTITY=quantity)
    ET.indent(root, space="\t")
    return '<?xml version="1.0" encoding="UTF-8" standalone="no"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


#: A ``StaticParameter`` element of a VSK (one tag, attributes in any order).
_STATIC_PARAMETER = re.compile(r"<StaticParameter\b[^>]*?/?>")


def _update_vsk(template: str, parameters: Mapping[str, tuple[float, str]], comments: Sequence[str]) -> str:
    """``template`` with the ``VALUE`` of each of ``parameters`` set (see
    :func:`subject_vsk_text`)."""
    pending = dict(parameters)

    def set_value(match: re.Match[str]) -> str:
        tag = match.group(0)
        name = re.search(r'\bNAME="([^"]*)"', tag)
        if name is None or name.group(1) not in pending:
            return tag
        value = xml_escape(repr(pending.pop(name.group(1))[0]), {'"': "&quot;"})
        if re.search(r'\bVALUE="[^"]*"', tag):
            return re.sub(r'\bVALUE="[^"]*"', f'VALUE="{value}"', tag, count=1)
        return tag.replace(name.group(0), f'{name.group(0)} VALUE="{value}"', 1)

    text = _STATIC_PARAMETER.sub(set_value, template)
    end = text.find("</Parameters>")
    if end < 0:
        raise ParameterError("the template .vsk has no <Parameters> element; give a Vicon Nexus subject file")
    if pending:  # before the line of </Parameters>, one level deeper than it
        line_start = text.rfind("\n", 0, end) + 1
        indent = text[line_start:end] if not text[line_start:end].strip() else ""
        added = "".join(
            f'{indent}\t<StaticParameter NAME="{name}" VALUE="{value!r}" PRIOR="{value!r}" QUANTITY="{quantity}"/>\n'
            for name, (value, quantity) in pending.items()
        )
        at = line_start if indent or line_start == end else end
        text = text[:at] + added + text[at:]
    if comments:
        opening = re.search(r"<KinematicModel\b[^>]*>", text)
        if opening is None:
            raise ParameterError("the template .vsk has no <KinematicModel> element; give a Vicon Nexus subject file")
        text = text[: opening.end()] + f"<!--{_vsk_comment(comments)}-->" + text[opening.end() :]
    return text


def write_subject(
    subject: SubjectParameters,
    path: str | os.PathLike[str],
    *,
    comments: Sequence[str] = (),
    metadata: Mapping[str, TomlData] | None = None,
    vsk_template: str | os.PathLike[str] | None = None,
) -> Path:
    """Write the parameters to ``path`` by its extension, atomically (complete or not at
    all): ``.toml`` (``PROCESSING`` names at top level, ``comments`` as ``#`` lines,
    ``metadata`` as a ``[calibration]`` table (sub-tables and arrays allowed), which
    :func:`read_subject_toml` ignores) or ``.vsk`` (:func:`subject_vsk_text`; the scalars
    of ``metadata`` go into the comment, its tables and arrays nowhere; with
    ``vsk_template``, the subject's own Nexus ``.vsk`` with the values updated).  Returns
    the path.

    Raises:
        ParameterError: another extension, implausible parameters, an unreadable template.
        FuzzyGaitError: the folder does not exist.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".vsk"):
        raise ParameterError(f"{path}: unknown subject file type {suffix!r}; use .toml or .vsk")
    subject.validate()
    if suffix == ".toml":
        document: dict[str, TomlData] = dict(subject_values(subject))
        if metadata:
            document["calibration"] = dict(metadata)
        text = toml_text(document, comments)
    else:
        scalars = {k: v for k, v in (metadata or {}).items() if isinstance(v, (str, int, float))}
        details = [f"{key} = {value}" for key, value in scalars.items()]
        template = None
        if vsk_template is not None:
            try:
                template = Path(vsk_template).read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise ParameterError(f"{vsk_template}: cannot read the .vsk template ({exc})") from None
        text = subject_vsk_text(
            subject, [*comments, *(["(" + "; ".join(details) + ")"] if details else [])], template=template
        )
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
