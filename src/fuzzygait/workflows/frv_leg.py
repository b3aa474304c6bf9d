"""FRV-GFA of a leg scenario as a job (``fuzzygait frv-sim``, thesis §2.7, §5.7): one leg
parameter — or several, independent (``--frv E,rho``) — as fuzzy random variables about
their deterministic values, the study run (or extended) into a chunked zarr store by
:func:`fuzzygait.mechanics.fuzzy_dynamics.leg_frv_study`.

A study records the options it was made with (:func:`study_options`: the scenario, the
FRV, every fixed parameter value, the target and the simulation settings, all resolved).
Extending it takes the options not given from that record and refuses, in one line
naming the option, any given one that differs — two models are never mixed in a study.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Advice, Option
from fuzzygait.mechanics.leg import LEG_PARAMETERS, default_parameters
from fuzzygait.mechanics.scenarios import SCENARIOS
from fuzzygait.workflows.fuzzy_dynamics import LegSetup, named_fixes, time_simulation
from fuzzygait.workflows.progress import SILENT, StageProgress, announce, takes_estimates

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy
    from fuzzygait.workflows.work_estimate import SimulationTiming, WorkEstimate

__all__ = ["FRVRequest", "check_frv_parameter", "deterministic_value", "frv_parameters", "run_frv_leg",
           "study_options"]  # fmt: skip

#: the recorded options in the order they are compared (named as frv-sim's options)
OPTIONS = ("scenario", "frv", "value", "set", "target", "alphas", "distribution", "sampling", "seed", "disc", "nodes",
           "dt", "duration", "scheme")  # fmt: skip
#: options a study made before they existed is taken to have been made with
OPTION_DEFAULTS = {"sampling": "random"}
_NEW_STUDY = Advice("start a new study (another {out}, or {overwrite})", out=Option.OUT, overwrite=Option.OVERWRITE)


#: The deterministic value p_det (SI) of an FRV parameter in the thesis' FRV studies, where
#: it is not the scenario table's: the stance study of §5.7 (Table 5.3) takes the
#: reverse-engineered E = 59.958 GPa of Table 4.2, not Table 4.4's 0.6 GPa (under which
#: the FRV's low samples fold the blade: E = 0.35 GPa folds element 11 at t = 0.29 s).
FRV_STUDY_VALUES: dict[str, dict[str, float]] = {"stance": {"E": 59.958e9}}


def frv_parameters(parameter: str) -> tuple[str, ...]:
    """The FRV parameters of ``--frv``: one name or several, comma-separated (``"E,rho"``)."""
    return tuple(name.strip() for name in parameter.split(",") if name.strip())


def check_frv_parameter(parameter: str) -> None:
    """A :class:`FuzzyGaitError` unless ``parameter`` names leg parameters (one, or several
    distinct ones comma-separated)."""
    names = frv_parameters(parameter)
    if not names:
        raise FuzzyGaitError(f"{Option.FRV} {parameter!r}: name a leg parameter; known: {', '.join(LEG_PARAMETERS)}")
    for name in names:
        if name not in LEG_PARAMETERS:
            raise FuzzyGaitError(f"{Option.FRV} {name!r}: unknown parameter; known: {', '.join(LEG_PARAMETERS)}")
    if len(set(names)) != len(names):
        raise FuzzyGaitError(f"{Option.FRV} {parameter!r}: a parameter is named twice")


def _scenario_values(scenario: str) -> dict[str, float]:
    preset = SCENARIOS[scenario]
    defaults = default_parameters(preset.material, shank_mass=preset.shank_mass)
    return {name: float(v) for name, v in zip(LEG_PARAMETERS, defaults, strict=True)}


def deterministic_value(scenario: str, parameter: str, values: Mapping[str, float]) -> float:
    """``p_det`` of the FRV parameter: its value in ``values``, else the thesis' FRV
    study's (:data:`FRV_STUDY_VALUES`), else the scenario's."""
    if parameter in values:
        return values[parameter]
    return FRV_STUDY_VALUES.get(scenario, {}).get(parameter, _scenario_values(scenario)[parameter])


@dataclass(frozen=True)
class FRVRequest:
    """The FRV of an FRV-GFA study: the leg ``parameter`` (its deterministic value
    ``value``, else the setup's, else the scenario's) or several, comma-separated
    (independent FRVs with the same settings; each one's ``p_det`` from the setup or the
    scenario, ``value`` not allowed), ``samples`` samples (to draw, or to add to an
    existing study), ``disc`` grouping grid points (one count for every parameter, or one
    per parameter), the α-levels, the
    increments' ``distribution``, the peaks' ``sampling`` (``"random"`` or ``"lhs"``:
    Latin-hypercube per block of samples), the ``seed`` of the sample streams and the
    ``target`` output (None: the scenario's)."""

    parameter: str = "E"
    value: float | None = None
    samples: int = 10000
    disc: int | Sequence[int] = 100
    alphas: Sequence[float] = (0.0, 0.25, 0.5, 0.75, 1.0)
    distribution: str = "normal"
    seed: int = 0
    sampling: str = "random"
    target: str | None = None


def study_options(setup: LegSetup, frv: FRVRequest) -> dict[str, Any]:
    """What a study of ``frv`` on ``setup`` is made with, resolved (the scenario's values
    filled in) and JSON-compatible: the record a study keeps and an extension must match."""
    from fuzzygait.mechanics.fuzzy_dynamics import DEFAULT_TARGET

    settings = setup.settings
    values = {**_scenario_values(setup.scenario), **{k: float(v) for k, v in setup.values.items()}}
    names = frv_parameters(frv.parameter)
    if len(names) > 1 and frv.value is not None:
        raise FuzzyGaitError(f"{Option.VALUE} applies to one {Option.FRV} parameter; for {','.join(names)} give "
                             f"each p_det with {Option.SET} NAME=VALUE")  # fmt: skip
    for name in names:
        values[name] = (float(frv.value) if frv.value is not None
                        else deterministic_value(setup.scenario, name, setup.values))  # fmt: skip
    value: float | list[float] = values[names[0]] if len(names) == 1 else [values[n] for n in names]
    return {"scenario": setup.scenario, "frv": ",".join(names), "value": value, "set": values,
            "target": frv.target or DEFAULT_TARGET[setup.scenario], "alphas": [float(a) for a in frv.alphas],
            "distribution": frv.distribution, "sampling": frv.sampling, "seed": int(frv.seed),
            "disc": _disc_record(frv.disc), "nodes": int(setup.nodes), "dt": float(settings.dt),
            "duration": float(settings.steps * settings.dt if settings.duration is None else settings.duration),
            "scheme": settings.scheme}  # fmt: skip


def _disc_record(disc: int | Sequence[int]) -> int | list[int]:
    """``disc`` as a study records it: one count, or a list of one per parameter."""
    if isinstance(disc, int):
        return int(disc)
    counts = [int(n) for n in disc]
    return counts[0] if len(set(counts)) == 1 else counts


def _as_made(setup: LegSetup, frv: FRVRequest, stored: Mapping[str, Any],
             given: Collection[str]) -> tuple[LegSetup, FRVRequest]:  # fmt: skip
    """The request with every option not ``given`` taken from the ``stored`` record; the
    given ``--set`` values are laid over the stored ones."""
    values = {**stored["set"], **setup.values}
    solver = setup.settings.derive(**{k: stored[k] for k in ("dt", "duration", "scheme") if k not in given})
    setup = replace(setup, values=values, solver=solver, nodes=setup.nodes if "nodes" in given else stored["nodes"])
    taken: dict[str, Any] = {"parameter": stored["frv"]} if "frv" not in given else {}
    taken.update({k: stored[k] for k in ("disc", "alphas", "distribution", "sampling", "seed", "target")
                  if k not in given})  # fmt: skip
    if "value" not in given:
        taken["value"] = None  # p_det: the --set value, else the stored one
    return setup, replace(frv, **taken)


def _num(value: float) -> str:
    """Short, but exact: two different values never print alike."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def _show(key: str, value: Any) -> str:
    if key == "alphas":
        return ",".join(_num(a) for a in value)
    if key == "disc" and isinstance(value, list):
        return ",".join(str(n) for n in value)
    return _num(value) if isinstance(value, float) else str(value)


def _refuse_other_options(store: Path, made: Mapping[str, Any], asked: Mapping[str, Any],
                          given: Collection[str]) -> None:  # fmt: skip
    """One line naming the first option whose value differs from the study's record."""
    for key in OPTIONS:
        if made[key] == asked[key]:
            continue
        was, now = _show(key, made[key]), _show(key, asked[key])
        if key == "scenario":
            named, advice = "SCENARIO", f"give SCENARIO {was}"
        elif key == "set" or (key == "value" and key not in given):  # p_det given by --set
            pool = frv_parameters(asked["frv"]) if key == "value" else LEG_PARAMETERS
            name = next(n for n in pool if made["set"][n] != asked["set"][n])
            was, now = (f"{name}={_num(record['set'][name])}" for record in (made, asked))
            named, advice = f"{Option.SET}", f"leave {Option.SET} {name} out"
        else:
            named = f"{Option(key)}"
            advice = f"leave {named} out"
        raise FuzzyGaitError(f"{store}: this study was made with {named} {was}; given {now}. To extend it, {advice}, "
                             f"or {_NEW_STUDY}")  # fmt: skip


def run_frv_leg(
    setup: LegSetup,
    frv: FRVRequest,
    out_store: Path,
    *,
    workers: int = 2,
    scheduler: str | None = None,
    overwrite: bool = False,
    given: Collection[str] | None = None,
    progress: StageProgress = SILENT,
) -> FRVStudy:
    """Run the FRV-GFA of ``frv`` on the leg ``setup`` into ``out_store`` (an existing
    study is extended unless ``overwrite``), the forward simulations on ``workers`` local
    processes or the Dask ``scheduler``.  Returns the study (its ``counts`` say what was
    computed).

    Extending, the options not in ``given`` (names of :data:`OPTIONS`; None: all given)
    are the study's; a given one that differs from the study's record raises a
    :class:`FuzzyGaitError` naming it. A failed new study leaves nothing at ``out_store``
    (nor the folders made for it); a failed extension leaves the study as it was.
    """
    from fuzzygait.mechanics.fuzzy_dynamics import LegStudyModel, leg_frv_study
    from fuzzygait.mechanics.targets import TARGETS
    from fuzzygait.uncertainty.frv import FRVSpec, StudyOptions
    from fuzzygait.uncertainty.frv.store import read_meta

    extend = out_store.exists() and not overwrite
    if extend:
        made = read_meta(out_store).get("options") or {}
        made = {**OPTION_DEFAULTS, **made} if made else made
        if not all(key in made for key in OPTIONS):
            raise FuzzyGaitError(f"{out_store}: the study does not record the options it was made with (an older "
                                 f"version or the library made it): it cannot be extended; {_NEW_STUDY}")  # fmt: skip
        setup, frv = _as_made(setup, frv, made, OPTIONS if given is None else given)
    options = study_options(setup, frv)
    if options["target"] not in TARGETS:
        raise FuzzyGaitError(f"{Option.TARGET} {options['target']!r}: unknown target; choose one of "
                             f"{', '.join(TARGETS)}")  # fmt: skip
    if extend:
        _refuse_other_options(out_store, made, options, OPTIONS if given is None else given)
    names = frv_parameters(frv.parameter)
    specs = [FRVSpec(name, options["set"][name], alphas=tuple(frv.alphas), distribution=frv.distribution,
                     sampling=frv.sampling) for name in names]  # fmt: skip
    stage = f"{setup.scenario}: FRV-GFA ({frv.samples} samples)"
    announce(progress, _frv_work(setup, frv, specs, out_store if extend else None, stage, options["set"],
                                 None if scheduler is not None else workers, progress))  # fmt: skip
    made_folders = [p for p in (out_store.parent, *out_store.parent.parents) if not p.exists()]
    out_store.parent.mkdir(parents=True, exist_ok=True)
    progress.stage(stage)
    try:
        with named_fixes(setup):
            spec = specs[0] if len(specs) == 1 else specs
            leg = LegStudyModel(options["target"], options["set"], setup.nodes, setup.settings)
            made_with = StudyOptions(n_disc=frv.disc, seed=frv.seed, overwrite=overwrite, record=options)
            return leg_frv_study(setup.scenario, spec, frv.samples, out_store, leg=leg, study=made_with,
                                 workers=workers, scheduler=scheduler)  # fmt: skip
    except BaseException:
        for folder in made_folders:  # innermost first; only if still empty
            try:
                folder.rmdir()
            except OSError:
                break
        raise


def _frv_work(setup: LegSetup, frv: FRVRequest, specs: Sequence[FRVSpec], extended: Path | None, stage: str,
              values: Mapping[str, float], workers: int | None, progress: StageProgress) -> WorkEstimate:  # fmt: skip
    """The estimate of an FRV study (``extended``: the store of the study extended): its
    new forward simulations, one of them timed first when there are any and ``progress``
    takes estimates (at the full parameter ``values``, the FRVs at their p_det)."""
    from fuzzygait.mechanics.scenarios import LegSimulator
    from fuzzygait.uncertainty.frv.store import read_meta
    from fuzzygait.workflows.work_estimate import frv_work

    def timer() -> SimulationTiming | None:
        progress.stage(f"{setup.scenario}: timing a forward simulation")
        sim = LegSimulator(setup.scenario, nodes=setup.nodes)
        return time_simulation(sim, sim.parameters(**values), setup)

    meta = read_meta(extended) if extended is not None else None
    return frv_work(setup.scenario, specs, frv.disc, frv.samples, stage, meta=meta,
                    timer=timer if takes_estimates(progress) else None, workers=workers)  # fmt: skip
