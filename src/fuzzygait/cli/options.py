"""Options shared by several commands and the parsers of their text values.

Single shared options are ``Annotated`` aliases (``static: StaticOption = None``); options
that always come together are an option group, a dataclass of such fields: a command
decorated with :func:`with_option_groups` declares one parameter of the group's type,
typer sees the group's options in its place, and the command gets the group.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, get_type_hints

import typer

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.paths import check_c3d_input, check_subject_input

if TYPE_CHECKING:
    from rich.progress import Progress

    from fuzzygait.workflows.angles import Preprocessing
    from fuzzygait.workflows.progress import Announced

StaticOption = Annotated[Path | None, typer.Option("--static", help="Static trial for the calibration offsets.")]
SubjectOption = Annotated[
    Path | None,
    typer.Option("--subject", help="Subject parameters (.toml, .vsk, pyCGM2 .mp or QTM session.xml); "
                 "default: the file's PROCESSING group."),
]
MarkerDiameterOption = Annotated[
    float | None,
    typer.Option(
        "--marker-diameter", metavar="MM",
        help="Marker diameter in mm, overriding the subject's MarkerDiameter (Nexus keeps it in the "
        "pipeline, not in the C3D: give it for e.g. 16 mm markers); default: the subject file's, else 14.",
    ),
]  # fmt: skip
FlatFootOption = Annotated[
    bool | None,
    typer.Option("--flat-foot/--no-flat-foot", help="Static calibration with Plug-in Gait's foot flat (uses "
                 "SoleDelta); default: the subject file's setting (a QTM session.xml's), else off."),
]
KneeAnkleCentresOption = Annotated[
    str | None,
    typer.Option(
        "--knee-ankle-centres", metavar="RULE",
        help="Cluster models (cgm2.3, cgm2.4): where the static calibration puts the knee and ankle centres: "
        "medial (on the KNE-KNM / ANK-MED lines), chord (Plug-in Gait's, with THI/TIB) or pycgm2 (the chord "
        "with THAP/TIAP as pyCGM2's CGM 2.3 does); default: medial when the static trial has KNM/MED, else chord.",
    ),
]  # fmt: skip

ModelOption = Annotated[
    str,
    typer.Option(
        "--model",
        help="Model version of the angles and of their marker-error model: cgm1.0 (Plug-in Gait), cgm1.1, cgm2.1, "
        "cgm2.3 (clusters; their static calibration held fixed, needs --static or a --subject written by "
        "`calibrate`), cgm2.4 (also the forefoot) or auto: the richest the markers support.",
    ),
]


def check_model(model: str) -> None:
    """One clear error, before any work, for an unknown ``--model``."""
    from fuzzygait.kinematics.versions import MODEL_CHOICES, model_version

    if model != "auto":
        try:
            model_version(model)
        except FuzzyGaitError:
            raise FuzzyGaitError(f"--model {model!r}: choose one of {', '.join(MODEL_CHOICES)}") from None


def check_knee_ankle_centres(rule: str | None) -> None:
    """One clear error, before any work, for an unknown ``--knee-ankle-centres``."""
    from fuzzygait.kinematics.knee_ankle import KNEE_ANKLE_CENTRES

    if rule is not None and rule not in KNEE_ANKLE_CENTRES:
        raise FuzzyGaitError(f"--knee-ankle-centres {rule!r}: choose one of {', '.join(KNEE_ANKLE_CENTRES)}")


ErrorsOption = Annotated[
    Path | None, typer.Option("--errors", help="Marker error sizes (.toml); default: thesis Table 3.1.")
]
SourcesOption = Annotated[str, typer.Option(help="Marker error sources to add up, comma-separated.")]
AlphasOption = Annotated[
    str, typer.Option(help="α-levels below 1, comma-separated (1, the measured curve, is always added); at most 20.")
]
AnglesOption = Annotated[
    str | None, typer.Option("--angles", help="Angles to analyse, comma-separated (e.g. LKneeAngles); default: all.")
]
ToleranceOption = Annotated[
    float,
    typer.Option(
        "--tolerance", metavar="DEG",
        help="Angle tolerance, ± degrees, for the allowable-marker-error table (the largest marker error for "
        "which each angle stays within it); 0 turns it off.",
    ),
]  # fmt: skip
PerSourceOption = Annotated[
    bool,
    typer.Option(
        "--per-source/--no-per-source",
        help="Also the hip/knee/ankle flexion bands of each error source alone (measurement, placement, "
        "soft-tissue artefact) at the smallest α-level, so the report shows which one dominates (thesis Fig. 5.9); "
        "one Graph Follower run per source and flexion component more.",
    ),
]
SchedulerOption = Annotated[
    str | None, typer.Option(help="Address of an existing Dask scheduler (e.g. tcp://host:8786).")
]
NoFilterOption = Annotated[bool, typer.Option("--no-filter", help="Do not low-pass the markers.")]
MaxGapOption = Annotated[int, typer.Option(help="Longest gap (frames) to fill.")]
CutoffOption = Annotated[float, typer.Option(help="Low-pass cutoff (Hz).")]
DEFAULT_SOURCES = "measurement,placement,sta"
DEFAULT_ALPHAS = "0,0.25,0.5,0.75"
DEFAULT_TOLERANCE = 2.5


@dataclass(frozen=True)
class MarkerErrorOptions:
    """``--errors``, ``--sources``, ``--alphas``, ``--angles`` (text, as given),
    ``--tolerance`` and ``--per-source/--no-per-source``."""

    errors: ErrorsOption = None
    sources: SourcesOption = DEFAULT_SOURCES
    alphas: AlphasOption = DEFAULT_ALPHAS
    angle_names: AnglesOption = None
    tolerance: ToleranceOption = DEFAULT_TOLERANCE
    per_source: PerSourceOption = True

    def tolerance_deg(self) -> float | None:
        """``--tolerance`` checked: degrees, None for 0 (no allowable-error table)."""
        return parse_tolerance(self.tolerance)


@dataclass(frozen=True)
class PreprocessingOptions:
    """``--no-filter``, ``--max-gap`` and ``--cutoff`` of the commands computing angles."""

    no_filter: NoFilterOption = False
    max_gap: MaxGapOption = 10
    cutoff: CutoffOption = 6.0

    def preprocessing(self) -> Preprocessing:
        """The pre-processing these options ask for (default gap-filling method)."""
        from fuzzygait.workflows.angles import Preprocessing

        return Preprocessing(max_gap=self.max_gap, cutoff=self.cutoff, filter=not self.no_filter)


@dataclass(frozen=True)
class CalibrationOptions:
    """``--static``, ``--subject``, ``--marker-diameter`` and ``--flat-foot``: where the
    subject parameters and the static offsets come from."""

    static: StaticOption = None
    subject: SubjectOption = None
    marker_diameter: MarkerDiameterOption = None
    flat_foot: FlatFootOption = None

    def check_files(self) -> None:
        """One line, before any work, for a ``--static`` or ``--subject`` that is not there."""
        check_calibration_files(self.static, self.subject)


def check_calibration_files(static: Path | None, subject: Path | None) -> None:
    """One line, before any work, for a static trial or subject file given but not there."""
    if static is not None:
        check_c3d_input(static)
    if subject is not None:
        check_subject_input(subject)


DEFAULT_CALIBRATION = CalibrationOptions()
DEFAULT_MARKER_ERRORS = MarkerErrorOptions()
DEFAULT_PREPROCESSING = PreprocessingOptions()


def with_option_groups(command: Callable[..., None]) -> Callable[..., None]:
    """``command`` as typer should see it: every parameter annotated with an option group
    replaced, in place, by the group's options (their defaults those of the parameter's
    default group), which are gathered back into the group when the command is called."""
    hints = get_type_hints(command, include_extras=True)
    groups: dict[str, tuple[type[Any], list[str]]] = {}
    parameters = []
    for parameter in inspect.signature(command).parameters.values():
        group = hints[parameter.name]
        if not (isinstance(group, type) and dataclasses.is_dataclass(group)):
            parameters.append(parameter.replace(annotation=group))
            continue
        names = [field.name for field in dataclasses.fields(group)]
        options = get_type_hints(group, include_extras=True)
        defaults = parameter.default if isinstance(parameter.default, group) else group()
        groups[parameter.name] = (group, names)
        parameters += [
            inspect.Parameter(name, parameter.kind, default=getattr(defaults, name), annotation=options[name])
            for name in names
        ]

    @functools.wraps(command)
    def expanded(**values: Any) -> None:
        for name, (group, members) in groups.items():
            values[name] = group(**{member: values.pop(member) for member in members})
        command(**values)

    signature = inspect.Signature(parameters, return_annotation=None)
    expanded.__signature__ = signature  # type: ignore[attr-defined]
    expanded.__annotations__ = {p.name: p.annotation for p in parameters} | {"return": None}
    return expanded


def parse_angles(text: str | None) -> list[str] | None:
    """``"LKneeAngles,RKneeAngles"`` -> validated angle names (None: all; the CGM 2.4
    ``L/RForeFootAngles`` included)."""
    from fuzzygait.kinematics import ALL_ANGLE_NAMES

    if text is None:
        return None
    selected = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in selected if n not in ALL_ANGLE_NAMES]
    if unknown or not selected:
        raise FuzzyGaitError(f"--angles: unknown angle {', '.join(unknown) or repr(text)}; "
                             f"choose from {', '.join(ALL_ANGLE_NAMES)}")  # fmt: skip
    return selected


def parse_tolerance(value: float) -> float | None:
    """``--tolerance``: degrees > 0, or None for 0 (off); one clear error otherwise."""
    if not math.isfinite(value) or value < 0:
        raise FuzzyGaitError(f"--tolerance must be a number of degrees ≥ 0 (0 turns the allowable-error table "
                             f"off), e.g. 2.5; got {value:g}")  # fmt: skip
    return None if value == 0 else float(value)


def parse_alphas(text: str) -> tuple[float, ...]:
    """``"0,0.25,0.5"`` -> sorted α-levels in [0, 1), plus 1 (the measured curve); at most
    :data:`~fuzzygait.workflows.work_estimate.MAX_ALPHA_LEVELS` below 1."""
    from fuzzygait.workflows.work_estimate import check_alpha_count

    message = f"--alphas must be comma-separated numbers from 0 to below 1, e.g. 0,0.5; got {text!r}"
    try:
        values = {float(v) for v in text.split(",") if v.strip()}
    except ValueError:
        raise FuzzyGaitError(message) from None
    values.discard(1.0)
    if not values or not all(0.0 <= v < 1.0 for v in values):
        raise FuzzyGaitError(message)
    check_alpha_count(tuple(values))
    return (*sorted(values), 1.0)


def parse_disc(text: str, parameters: str) -> int | tuple[int, ...]:
    """``--disc``: ``"100"`` (every FRV parameter) or one count per ``--frv`` parameter,
    ``"59,30"`` for ``E,rho``; each at least 2."""
    names = [n for n in parameters.split(",") if n.strip()]
    message = (f"--disc must be one whole number of at least 2, or one per --frv parameter ({','.join(names)}), "
               f"e.g. 60,30; got {text!r}")  # fmt: skip
    try:
        counts = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise FuzzyGaitError(message) from None
    if not counts or len(counts) not in (1, len(names)) or min(counts) < 2:
        raise FuzzyGaitError(message)
    return counts[0] if len(counts) == 1 else tuple(counts)


def parse_overrides(texts: Sequence[str]) -> dict[str, float]:
    """``["E=6e5,eta=2", "rho=1700"]`` -> ``{"E": 6e5, "eta": 2.0, "rho": 1700.0}``."""
    from fuzzygait.mechanics.leg import LEG_PARAMETERS

    values: dict[str, float] = {}
    for text in texts:
        for item in (part.strip() for part in text.split(",")):
            if not item:
                continue
            name, sep, value = (s.strip() for s in item.partition("="))
            if not sep or not name:
                raise FuzzyGaitError(f"--set: expected name=value, got {item!r}")
            if name not in LEG_PARAMETERS:
                raise FuzzyGaitError(f"--set: unknown parameter {name!r}; known: {', '.join(LEG_PARAMETERS)}")
            try:
                number = float(value)
            except ValueError:
                raise FuzzyGaitError(f"--set: {name}={value!r} is not a number (SI units, e.g. {name}=1.5e6)") from None
            if name in values:
                raise FuzzyGaitError(f"--set: {name} is given twice")
            values[name] = number
    return values


def estimated_stages(bars: Progress) -> Announced:
    """A workflow's stages on ``bars`` with its work estimate (issue 37): the estimate's
    line printed on stdout before the work starts, its labels on the stages' bars."""
    from fuzzygait.cli.app import StageBars, out
    from fuzzygait.workflows.progress import Announced

    return Announced(StageBars(bars), lambda line: out.print(line, markup=False))
