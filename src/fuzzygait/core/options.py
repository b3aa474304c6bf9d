"""Settings a user gives, named in messages without knowing where the user gave them.

A message below the command line that tells the user what to change names the setting
by an :class:`Option`, not by a command-line flag::

    raise FuzzyGaitError(f"{path}: no static trial; give one ({Option.STATIC} STATIC.c3d)")

and the edge decides how it reads: ``--static STATIC.c3d`` when the ``fuzzygait`` command
runs (:func:`use_command_line_names`, which its entry point calls; worker processes it
starts inherit the choice through :data:`STYLE_VARIABLE`), ``static= STATIC.c3d`` — the
library's keyword — otherwise.
"""

from __future__ import annotations

import os
from enum import StrEnum

#: The environment variable that carries the naming style to worker processes.
STYLE_VARIABLE = "FUZZYGAIT_OPTION_NAMES"
_COMMAND_LINE = "command-line"


class Option(StrEnum):
    """A setting by its command-line name (without the dashes); ``str()`` and f-strings
    give it as the running edge names it."""

    ALPHAS = "alphas"
    C3D_OUT = "c3d-out"
    CYCLES = "cycles"
    DEBUG = "debug"
    DISC = "disc"
    DISTRIBUTION = "distribution"
    DT = "dt"
    DURATION = "duration"
    FLAT_FOOT = "flat-foot"
    FORCE = "force"
    FRV = "frv"
    FUZZY = "fuzzy"
    KINETICS = "kinetics"
    MARKER_DIAMETER = "marker-diameter"
    MODEL = "model"
    NO_FLAT_FOOT = "no-flat-foot"
    NODES = "nodes"
    NORMATIVE = "normative"
    OUT = "out"
    OVERWRITE = "overwrite"
    PER_SOURCE = "per-source"
    RRD = "rrd"
    SAMPLES = "samples"
    SAMPLING = "sampling"
    SCHEME = "scheme"
    SEED = "seed"
    SET = "set"
    STATIC = "static"
    STRIDE = "stride"
    SUBJECT = "subject"
    SUFFIX = "suffix"
    TARGET = "target"
    TOLERANCE = "tolerance"
    UNCERTAINTY = "uncertainty"
    VALUE = "value"

    @property
    def flag(self) -> str:
        """The command line's name: ``--static``."""
        return "-" * 2 + self.value

    @property
    def keyword(self) -> str:
        """The library's keyword argument: ``static``, ``subject_file``, ``values``."""
        return _KEYWORDS.get(self, self.value.replace("-", "_"))

    def __str__(self) -> str:
        if os.environ.get(STYLE_VARIABLE) == _COMMAND_LINE:
            return self.flag
        return _LIBRARY_TEXT.get(self, f"{self.keyword}=")

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


#: Where the library's keyword differs from the command-line name.
_KEYWORDS = {
    Option.C3D_OUT: "c3d",
    Option.SUBJECT: "subject_file",
    Option.SET: "values",
    Option.FRV: "parameters",
    Option.VALUE: "deterministic_value",
    Option.DEBUG: "strict",
    Option.NO_FLAT_FOOT: "flat_foot",
}

#: Switches: the library names the value too (``flat_foot=False`` for ``--no-flat-foot``).
_LIBRARY_TEXT = {
    Option.FLAT_FOOT: "flat_foot=True",
    Option.NO_FLAT_FOOT: "flat_foot=False",
    Option.KINETICS: "kinetics=True",
}


class Advice:
    """A piece of advice naming options, made once where it is defined and worded when
    it is shown (so a module-level constant follows the naming of the running edge)::

        FIX = Advice("start a new study (another {out}, or {overwrite})", out=Option.OUT,
                     overwrite=Option.OVERWRITE)
        raise StudyError(f"{path}: damaged; {FIX}")
    """

    def __init__(self, template: str, **options: Option) -> None:
        self.template, self.options = template, options

    def __str__(self) -> str:
        return self.template.format(**{name: str(option) for name, option in self.options.items()})

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


def use_command_line_names() -> None:
    """Name options as the ``fuzzygait`` command does (``--static``), in this process and
    in the processes it starts."""
    os.environ[STYLE_VARIABLE] = _COMMAND_LINE


__all__ = ["STYLE_VARIABLE", "Advice", "Option", "use_command_line_names"]
