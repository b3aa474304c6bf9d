"""How long-running workflows report progress: a sequence of stages, each with an
optional total, and the work done in the current one.  The command line shows them as
progress bars; library callers may pass nothing."""

from __future__ import annotations

from typing import Protocol


class StageProgress(Protocol):
    """Receives the progress of a workflow."""

    def stage(self, description: str, total: int | None = None) -> None:
        """A new stage begins (the previous one is over); ``total`` None: unknown."""

    def update(self, completed: int, total: int | None = None) -> None:
        """``completed`` units of the current stage are done (``total`` when known now)."""


class NoProgress:
    """Progress that goes nowhere (the default of every workflow)."""

    def stage(self, description: str, total: int | None = None) -> None:
        """Ignored."""

    def update(self, completed: int, total: int | None = None) -> None:
        """Ignored."""


#: The progress of a caller that does not want any.
SILENT = NoProgress()


class Prefixed:
    """The stages of ``progress`` with ``prefix`` before each description (e.g. the trial
    of a batch: ``"walking.c3d: fuzzy angles"``)."""

    def __init__(self, progress: StageProgress, prefix: str) -> None:
        self.progress, self.prefix = progress, prefix

    def stage(self, description: str, total: int | None = None) -> None:
        """A new stage of ``progress``, its description prefixed."""
        self.progress.stage(self.prefix + description, total)

    def update(self, completed: int, total: int | None = None) -> None:
        """As ``progress.update``."""
        self.progress.update(completed, total)
