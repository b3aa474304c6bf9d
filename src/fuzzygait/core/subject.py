"""Subject (anthropometric) parameters of the Conventional Gait Model / Plug-in Gait:
what the model needs of the person, whichever file gives it
(:mod:`fuzzygait.io.subject` reads and writes them).

Units: lengths in mm, angles in **radians** (as Vicon stores them), mass in kg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from fuzzygait.core.errors import ParameterError

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
VICON_SIDE_NAMES = {
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
REQUIRED_SIDE = ("leg_length", "knee_width", "ankle_width")

#: Every name Vicon writes to a C3D file's ``PROCESSING`` group for the subject
#: measurements (``Bodymass``, ``LLegLength``, ...), as ``to_processing`` writes them.
PROCESSING_NAMES = frozenset(
    {"Bodymass", "Height", "MarkerDiameter", "InterAsisDistance"}
    | {side + vicon for side in "LR" for vicon in VICON_SIDE_NAMES.values()}
)
ANGLE_FIELDS = {"tibial_torsion", "thigh_rotation", "shank_rotation", "ankle_abadd",
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
            for name, vicon in VICON_SIDE_NAMES.items():
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
            for name in ANGLE_FIELDS:
                check_range(f"{prefix}{VICON_SIDE_NAMES[name]}", getattr(params, name), -math.pi, math.pi, "rad")
        if problems:
            where = f"{self.source}: " if self.source else ""
            raise ParameterError(
                f"{where}implausible subject parameters: {'; '.join(problems)}; "
                "lengths are in mm and angles in radians"
            )
        return self
