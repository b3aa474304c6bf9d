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

import math
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import escape as xml_escape

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Option
from fuzzygait.io.atomic import atomic_output
from fuzzygait.io.qtm_session import is_qtm_session, qtm_foot_flat, qtm_session_values
from fuzzygait.io.tomlfile import TomlData, load_toml, toml_text

if TYPE_CHECKING:  # at run time through __getattr__: fuzzygait.io.subject_mp imports this module
    from fuzzygait.io.subject_mp import read_mp as read_mp

#: Default marker diameter (mm) when a source does not give one.
DEFAULT_MARKER_DIAMETER = 14.0
#: Plausible body height (mm; 0 = unknown): a small child (0.5 m) to the tallest adults.
HEIGHT_RANGE = (500.0, 2600.0)
#: Plausible body mass (kg; 0 = unknown): an infant (2 kg) to 400 kg.
BODY_MASS_RANGE = (2.0, 400.0)


def asis_trochanter_regression(leg_length: float) -> float:
    """Plug-in Gait ASIS-trochanter distance (mm) from the leg length (mm)."""
    return 0.1288 * leg_length - 48.56


@dataclass(frozen=True)
class SideParameters:
    """Parameters of one leg (Vicon names without the ``L``/``R`` prefix).

    Attributes:
        leg_length: ASIS to medial malleolus, mm (``LegLength``).
        knee_width: mm (``KneeWidth``).
        ankle_width: mm (``AnkleWidth``).
        asis_trochanter_distance: mm (``AsisTrocanterDistance``); None: regression.
        tibial_torsion: rad (``TibialTorsion``).
        thigh_rotation: rad (``ThighRotation``), thigh-wand offset.
        shank_rotation: rad (``ShankRotation``), tibia-wand offset.
        ankle_abadd: rad (``AnkleAbAdd``).
        sole_delta: mm (``SoleDelta``), heel minus toe sole thickness (flat-foot option).
        static_plant_flex: rad (``StaticPlantFlex``), from static calibration.
        static_rot_off: rad (``StaticRotOff``), from static calibration.
    """

    leg_length: float
    knee_width: float
    ankle_width: float
    asis_trochanter_distance: float | None = None
    tibial_torsion: float = 0.0
    thigh_rotation: float = 0.0
    shank_rotation: float = 0.0
    ankle_abadd: float = 0.0
    sole_delta: float = 0.0
    static_plant_flex: float = 0.0
    static_rot_off: float = 0.0

    @property
    def asis_trochanter(self) -> float:
        """ASIS-trochanter distance in mm, from the regression when not given."""
        if self.asis_trochanter_distance is None or self.asis_trochanter_distance <= 0:
            return asis_trochanter_regression(self.leg_length)
        return self.asis_trochanter_distance


#: Vicon suffix of each SideParameters field.
_SIDE_NAMES = {
    "leg_length": "LegLength",
    "knee_width": "KneeWidth",
    "ankle_width": "AnkleWidth",
    "asis_trochanter_distance": "AsisTrocanterDistance",
    "tibial_torsion": "TibialTorsion",
    "thigh_rotation": "ThighRotation",
    "shank_rotation": "ShankRotation",
    "ankle_abadd": "AnkleAbAdd",
    "sole_delta": "SoleDelta",
    "static_plant_flex": "StaticPlantFlex",
    "static_rot_off": "StaticRotOff",
}
_REQUIRED_SIDE = ("leg_length", "knee_width", "ankle_width")

#: Every name Vicon writes to a C3D file's ``PROCESSING`` group for the subject
#: measurements (``Bodymass``, ``LLegLength``, ...), as ``to_processing`` writes them.
PROCESSING_NAMES = frozenset(
    {"Bodymass", "Height", "MarkerDiameter", "InterAsisDistance"}
    | {side + vicon for side in "LR" for vicon in _SIDE_NAMES.values()}
)
_ANGLE_FIELDS = {"tibial_torsion", "thigh_rotation", "shank_rotation", "ankle_abadd",
                 "static_plant_flex", "static_rot_off"}  # fmt: skip


@dataclass(frozen=True)
class SubjectParameters:
    """All subject parameters the lower-body model needs.

    Attributes:
        left, right: per-leg parameters.
        body_mass: kg (``Bodymass``); 0 when unknown (not needed for kinematics).
        height: mm (``Height``); 0 when unknown.
        marker_diameter: mm (``MarkerDiameter``).
        inter_asis_distance: mm (``InterAsisDistance``); None: measure it from the
            static trial (or, failing that, from the dynamic trial's ASIS markers).
        source: where the values came from, for messages.
        flat_foot: the subject file's own foot-flat setting for the static calibration
            (a QTM session.xml's "foot normalised to static trial"); None: the file has
            none. A command's ``--flat-foot`` / ``--no-flat-foot`` overrides it.
        marker_diameter_stated: the source states ``MarkerDiameter`` (False: the
            default :data:`DEFAULT_MARKER_DIAMETER` stands in for it, and the angle
            pipeline recovers it from the trial's own model outputs where it can,
            :mod:`fuzzygait.kinematics.marker_size`).
    """

    left: SideParameters
    right: SideParameters
    body_mass: float = 0.0
    height: float = 0.0
    marker_diameter: float = DEFAULT_MARKER_DIAMETER
    inter_asis_distance: float | None = None
    source: str = field(default="", compare=False)
    flat_foot: bool | None = field(default=None, compare=False)
    marker_diameter_stated: bool = field(default=False, compare=False)

    @property
    def marker_radius(self) -> float:
        """Marker radius in mm."""
        return self.marker_diameter / 2.0

    def side(self, side: str) -> SideParameters:
        """Parameters of ``"L"`` or ``"R"``."""
        if side not in ("L", "R"):
            raise ParameterError(f"side must be 'L' or 'R'; got {side!r}")
        return self.left if side == "L" else self.right

    def with_side(self, side: str, **changes: float) -> SubjectParameters:
        """A copy with fields of one side replaced (e.g. static offsets)."""
        changed = replace(self.side(side), **changes)
        return replace(self, left=changed) if side == "L" else replace(self, right=changed)

    def to_processing(self) -> dict[str, float]:
        """The parameters under Vicon ``PROCESSING`` names (for C3D output and TOML)."""
        out: dict[str, float] = {
            "Bodymass": self.body_mass,
            "Height": self.height,
            "MarkerDiameter": self.marker_diameter,
        }
        if self.inter_asis_distance is not None:
            out["InterAsisDistance"] = self.inter_asis_distance
        for prefix, params in (("L", self.left), ("R", self.right)):
            for name, vicon in _SIDE_NAMES.items():
                value = getattr(params, name)
                out[prefix + vicon] = params.asis_trochanter if value is None else float(value)
        return out

    # ------------------------------------------------------------------ validation
    def validate(self) -> SubjectParameters:
        """Check plausibility; returns self.

        Raises:
            ParameterError: naming every implausible value (negative widths, lengths that
                look like metres, angles that look like degrees, ...).
        """
        problems = []

        def check_range(name: str, value: float | None, low: float, high: float, unit: str) -> None:
            if value is None:
                return
            if not math.isfinite(value) or not low <= value <= high:
                problems.append(f"{name}={value:g} (expected {low:g}..{high:g} {unit})")

        def check_known(name: str, value: float | None, low: float, high: float, unit: str) -> None:
            if value != 0.0:  # 0: unknown (Vicon's "not measured")
                check_range(name, value, low, high, unit + ", or 0 when unknown")

        check_range("MarkerDiameter", self.marker_diameter, 1, 40, "mm")
        check_range("InterAsisDistance", self.inter_asis_distance, 100, 500, "mm")
        check_known("Bodymass", self.body_mass, *BODY_MASS_RANGE, "kg")
        check_known("Height", self.height, *HEIGHT_RANGE, "mm")
        for prefix, params in (("L", self.left), ("R", self.right)):
            check_range(f"{prefix}LegLength", params.leg_length, 300, 1400, "mm")
            check_known(f"{prefix}AsisTrocanterDistance", params.asis_trochanter_distance, 20, 300, "mm")
            check_range(f"{prefix}KneeWidth", params.knee_width, 40, 250, "mm")
            check_range(f"{prefix}AnkleWidth", params.ankle_width, 30, 200, "mm")
            check_range(f"{prefix}SoleDelta", params.sole_delta, -100, 100, "mm")
            for name in _ANGLE_FIELDS:
                check_range(f"{prefix}{_SIDE_NAMES[name]}", getattr(params, name), -math.pi, math.pi, "rad")
        if problems:
            where = f"{self.source}: " if self.source else ""
            raise ParameterError(
                f"{where}implausible subject parameters: {'; '.join(problems)}; "
                "lengths are in mm and angles in radians"
            )
        return self


# ---------------------------------------------------------------------- constructors
def subject_from_processing(values: Mapping[str, float], source: str = "") -> SubjectParameters:
    """Build parameters from Vicon ``PROCESSING`` names (``LLegLength``, ...).

    Raises:
        ParameterError: when required values are missing (all of them named) or
            implausible.
    """
    missing = [f"{p}{_SIDE_NAMES[n]}" for p in "LR" for n in _REQUIRED_SIDE if f"{p}{_SIDE_NAMES[n]}" not in values]
    if missing:
        where = f"{source}: " if source else ""
        raise ParameterError(
            f"{where}missing subject parameters {', '.join(missing)}; "
            f"give them in a subject file ({Option.SUBJECT} SUBJECT.toml or .vsk)"
        )

    def side(prefix: str) -> SideParameters:
        kwargs: dict[str, float | None] = {}
        for name, vicon in _SIDE_NAMES.items():
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
    bad = [k for k, v in table.items() if not isinstance(v, (int, float, dict, str))]
    if bad:
        raise ParameterError(f"{path}: parameters {bad} must be numbers")
    return subject_from_processing(numbers, source=str(path))


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


_KINDS = ".toml, .vsk, a Vicon Nexus or pyCGM2 .mp or a QTM session.xml"


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
    if Path(path).is_dir():
        raise ParameterError(f"{path}: is a folder, not a subject file; give the subject file itself ({_KINDS})")
    suffix = Path(path).suffix.lower()
    from fuzzygait.io.subject_mp import read_mp  # imports this module: here, not at the top

    readers = {".toml": read_subject_toml, ".vsk": read_vsk, ".mp": read_mp, ".xml": read_qtm_session}
    if suffix not in readers:
        raise ParameterError(f"{path}: unknown subject file type {suffix!r}; use {_KINDS}")
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
        for name, vicon in _SIDE_NAMES.items():
            value = getattr(params, name)
            if value is not None:
                out[prefix + vicon] = float(value)
    return out


def _vsk_parameters(subject: SubjectParameters) -> dict[str, tuple[float, str]]:
    """``{VSK name: (value, QUANTITY)}``: ``LeftLegLength`` style names; mm, rad, kg."""
    angles = {v for k, v in _SIDE_NAMES.items() if k in _ANGLE_FIELDS}
    out: dict[str, tuple[float, str]] = {}
    for name, value in subject_values(subject).items():
        vicon = name
        if name[0] in "LR" and name[1:] in _SIDE_NAMES.values():
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
