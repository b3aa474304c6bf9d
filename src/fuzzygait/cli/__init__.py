"""The ``fuzzygait`` command line: :mod:`~fuzzygait.cli.app` (the typer app, errors and
exit codes, progress bars) and one module per command group, each command parsing its
arguments, making one workflow call (:mod:`fuzzygait.workflows`) and printing."""

from fuzzygait.cli.app import app, main

# The command modules register their commands on import, in this order (that of --help).
# isort: off
from fuzzygait.cli import gait  # noqa: F401
from fuzzygait.cli import marker_errors  # noqa: F401
from fuzzygait.cli import compare  # noqa: F401
from fuzzygait.cli import spatiotemporal  # noqa: F401
from fuzzygait.cli import normative  # noqa: F401
from fuzzygait.cli import simulate  # noqa: F401
from fuzzygait.cli import data  # noqa: F401

# isort: on

__all__ = ["app", "main"]
