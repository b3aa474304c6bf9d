"""How long-running workflows report progress: a sequence of stages, each with an
optional total, and the work done in the current one.  The command line shows them as
progress bars; library callers may pass nothing.

A workflow that estimates its work before starting
(:class:`~fuzzygait.workflows.work_estimate.WorkEstimate`) hands the estimate to
:func:`announce`: a progress that takes estimates (:class:`Announced`, and
:class:`Prefixed` around one) says its line and labels its stages' bars with it; any other
ignores it (:func:`takes_estimates` tells a workflow whether timing a simulation for it
is worth its cost)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from fuzzygait.workflows.work_estimate import WorkEstimate


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

    def estimate(self, estimate: WorkEstimate) -> None:
        """Pass ``estimate`` on, its stage labels prefixed as the stages are."""
        announce(self.progress, estimate.prefixed(self.prefix))

    @property
    def takes_estimates(self) -> bool:
        return takes_estimates(self.progress)


class Announced:
    """The stages of ``progress``, with the work estimates a workflow announces: each
    estimate's line goes to ``say`` (e.g. printed), and the stages it labels get the
    label after their description (``"stance: α-level optimisations (≤ 337 forward
    simulations)"``)."""

    def __init__(self, progress: StageProgress, say: Callable[[str], None]) -> None:
        self.progress, self.say = progress, say
        self.labels: dict[str, str] = {}

    def estimate(self, estimate: WorkEstimate) -> None:
        """Say the estimate's line; label its stages from now on."""
        self.say(estimate.line())
        self.labels.update(estimate.stages)

    def stage(self, description: str, total: int | None = None) -> None:
        """A new stage of ``progress``, with its label when an estimate gave one."""
        label = self.labels.get(description)
        if label is not None:  # "FRV-GFA (20 samples)" -> "FRV-GFA (20 samples, 7 forward simulations)"
            description = f"{description[:-1]}, {label})" if description.endswith(")") else f"{description} ({label})"
        self.progress.stage(description, total)

    def update(self, completed: int, total: int | None = None) -> None:
        """As ``progress.update``."""
        self.progress.update(completed, total)

    takes_estimates = True


def takes_estimates(progress: StageProgress) -> bool:
    """Whether ``progress`` does something with a work estimate (:func:`announce`)."""
    return bool(getattr(progress, "takes_estimates", False))


def announce(progress: StageProgress, estimate: WorkEstimate) -> None:
    """Give ``progress`` a workflow's work estimate, made before the work starts, when it
    takes one (:class:`Announced`; :class:`Prefixed` passes it on); others ignore it."""
    receive: Callable[[WorkEstimate], None] | None = getattr(progress, "estimate", None)
    if receive is not None and takes_estimates(progress):
        receive(estimate)
