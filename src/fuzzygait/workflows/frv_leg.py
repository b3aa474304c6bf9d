"""FRV-GFA of a leg scenario as a job (``fuzzygait frv-sim``, thesis §2.7, §5.7): one leg
parameter as a fuzzy random variable about its deterministic value, the study run (or
extended) into a chunked zarr store by
:func:`fuzzygait.mechanics.fuzzy_dynamics.leg_frv_study`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.mechanics.leg import LEG_PARAMETERS, default_parameters
from fuzzygait.mechanics.scenarios import SCENARIOS
from fuzzygait.workflows.fuzzy_dynamics import LegSetup
from fuzzygait.workflows.progress import SILENT, StageProgress

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv import FRVStudy

__all__ = ["FRVRequest", "check_frv_parameter", "deterministic_value", "run_frv_leg"]


def check_frv_parameter(parameter: str) -> None:
    """A :class:`FuzzyGaitError` unless ``parameter`` is a leg parameter."""
    if parameter not in LEG_PARAMETERS:
        raise FuzzyGaitError(f"--frv {parameter!r}: unknown parameter; known: {', '.join(LEG_PARAMETERS)}")


def deterministic_value(scenario: str, parameter: str, values: Mapping[str, float]) -> float:
    """``p_det`` of the FRV parameter: its value in ``values``, else the scenario's."""
    if parameter in values:
        return values[parameter]
    preset = SCENARIOS[scenario]
    defaults = default_parameters(preset.material, shank_mass=preset.shank_mass)
    return float(defaults[LEG_PARAMETERS.index(parameter)])


@dataclass(frozen=True)
class FRVRequest:
    """The FRV of an FRV-GFA study: the leg ``parameter`` (its deterministic value
    ``value``, else the setup's, else the scenario's), ``samples`` samples (to draw, or to
    add to an existing study), ``disc`` grouping grid points, the α-levels, the increments'
    ``distribution`` and the ``seed`` of the sample streams."""

    parameter: str = "E"
    value: float | None = None
    samples: int = 10000
    disc: int = 100
    alphas: Sequence[float] = (0.0, 0.25, 0.5, 0.75, 1.0)
    distribution: str = "normal"
    seed: int = 0


def run_frv_leg(
    setup: LegSetup,
    frv: FRVRequest,
    out_store: Path,
    *,
    target: str | None = None,
    workers: int = 2,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: StageProgress = SILENT,
) -> FRVStudy:
    """Run the FRV-GFA of ``frv`` on the leg ``setup`` into ``out_store`` (an existing
    study is extended unless ``overwrite``), the forward simulations on ``workers`` local
    processes or the Dask ``scheduler``.  Returns the study (its ``counts`` say what was
    computed)."""
    from fuzzygait.mechanics.fuzzy_dynamics import leg_frv_study
    from fuzzygait.uncertainty.frv import FRVSpec

    fixed = dict(setup.values)
    if frv.value is not None:
        fixed[frv.parameter] = frv.value
    spec = FRVSpec(frv.parameter, deterministic_value(setup.scenario, frv.parameter, fixed),
                   alphas=tuple(frv.alphas), distribution=frv.distribution)  # fmt: skip
    out_store.parent.mkdir(parents=True, exist_ok=True)
    progress.stage(f"{setup.scenario}: FRV-GFA ({frv.samples} samples)")
    return leg_frv_study(setup.scenario, spec, frv.samples, out_store, target=target, base_overrides=fixed,
                         n_disc=frv.disc, seed=frv.seed, nodes=setup.nodes, dt=setup.dt, duration=setup.duration,
                         scheme=setup.scheme, workers=workers, scheduler=scheduler, overwrite=overwrite)  # fmt: skip
