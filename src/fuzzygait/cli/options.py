"""Options shared by several commands and the parsers of their text values."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Annotated

import typer

from fuzzygait.core.errors import FuzzyGaitError

StaticOption = Annotated[Path | None, typer.Option("--static", help="Static trial for the calibration offsets.")]
SubjectOption = Annotated[
    Path | None,
    typer.Option("--subject", help="Subject parameters (.toml or .vsk); default: the file's PROCESSING group."),
]
ErrorsOption = Annotated[
    Path | None, typer.Option("--errors", help="Marker error sizes (.toml); default: thesis Table 3.1.")
]
SourcesOption = Annotated[str, typer.Option(help="Marker error sources to add up, comma-separated.")]
AlphasOption = Annotated[
    str, typer.Option(help="α-levels below 1, comma-separated (1, the measured curve, is always added).")
]
AnglesOption = Annotated[
    str | None, typer.Option("--angles", help="Angles to analyse, comma-separated (e.g. LKneeAngles); default: all.")
]
NoFilterOption = Annotated[bool, typer.Option("--no-filter", help="Do not low-pass the markers.")]
MaxGapOption = Annotated[int, typer.Option(help="Longest gap (frames) to fill.")]
CutoffOption = Annotated[float, typer.Option(help="Low-pass cutoff (Hz).")]
DEFAULT_SOURCES = "measurement,placement,sta"
DEFAULT_ALPHAS = "0,0.25,0.5,0.75"


def parse_angles(text: str | None) -> list[str] | None:
    """``"LKneeAngles,RKneeAngles"`` -> validated angle names (None: all)."""
    from fuzzygait.kinematics import ANGLE_NAMES

    if text is None:
        return None
    selected = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in selected if n not in ANGLE_NAMES]
    if unknown or not selected:
        raise FuzzyGaitError(f"--angles: unknown angle {', '.join(unknown) or repr(text)}; "
                             f"choose from {', '.join(ANGLE_NAMES)}")  # fmt: skip
    return selected


def parse_alphas(text: str) -> tuple[float, ...]:
    """``"0,0.25,0.5"`` -> sorted α-levels in [0, 1), plus 1 (the measured curve)."""
    message = f"--alphas must be comma-separated numbers from 0 to below 1, e.g. 0,0.5; got {text!r}"
    try:
        values = {float(v) for v in text.split(",") if v.strip()}
    except ValueError:
        raise FuzzyGaitError(message) from None
    values.discard(1.0)
    if not values or not all(0.0 <= v < 1.0 for v in values):
        raise FuzzyGaitError(message)
    return (*sorted(values), 1.0)


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
