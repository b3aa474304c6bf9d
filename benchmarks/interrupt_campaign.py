"""Interrupt campaign (issue 37): every command with workers, signalled at random moments.

For each of ``uncertainty``, ``report``, ``fuzzy-sim`` and ``frv-sim`` with ``--workers 2``
(small inputs: seconds per run) the script first runs the command to completion once, in
a process group of its own, and checks that nothing of it is left at exit; that run's
duration T sets the moments.  Then it runs the command ``--runs`` times (default 10),
each time signalling it at a seeded random moment in [0, 1.1 T] (one moment per tenth
of that span, so start-up, the workers' spin-up, computing, writing and shutdown are all
hit; T is lowered to the duration of a run that ended before its signal, and that run
made again): SIGINT to the whole process group (as Ctrl-C in a terminal sends it) in most runs,
SIGTERM to the command alone (``kill PID``) or to the group (``timeout``'s default) in
the others.  A run passes when

* it exits 130 (SIGINT) / 143 (SIGTERM) with exactly the one interrupt line on stderr,
  or exits 0 (the signal came after its work was done);
* there is no traceback anywhere in its output;
* no process of its group is left the moment it has exited (``waitpid`` returned; the
  group is read from ``/proc`` at once, zombies included);
* its private ``TMPDIR`` is empty (no ``fuzzygait-parallel-*``, no Dask scratch space).

Prints one line per run and the pass count per command.

    python benchmarks/interrupt_campaign.py                 # 4 commands x 10 runs, ~12 min on 2 cores
    python benchmarks/interrupt_campaign.py --runs 3 --commands fuzzy-sim,frv-sim
"""

from __future__ import annotations

import argparse
import shutil
import signal
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _setup import ROOT

sys.path.insert(0, str(ROOT / "tests" / "cli"))

from interrupt_harness import COMMANDS, Outcome, command_args, run_command  # noqa: E402

#: The signal and its target of a run, drawn with these weights.
DELIVERIES = [(signal.SIGINT, "group"), (signal.SIGTERM, "command"), (signal.SIGTERM, "group")]
WEIGHTS = [0.6, 0.2, 0.2]


def fractions(runs: int, rng: np.random.Generator) -> list[float]:
    """One random fraction in each of ``runs`` equal parts of [0, 1.1]: the moments, as
    fractions of the command's duration."""
    return [float(1.1 * (i + rng.uniform()) / runs) for i in range(runs)]


def campaign(name: str, runs: int, rng: np.random.Generator, work: Path) -> tuple[int, int, Outcome]:
    """The reference run and ``runs`` interrupted runs of one command; (passed, runs, reference).

    The moments are fractions of the command's duration, estimated by the reference run
    and lowered to the duration of any run that ended before its signal was sent (the
    machine is shared: durations vary); such a run is made again (up to three times)."""

    def one(index: str, moment: float | None, signum: int = signal.SIGINT, target: str = "group") -> Outcome:
        run = work / name / index
        run.mkdir(parents=True)
        args = command_args(name, work, run)
        return run_command(args, run / "tmp", moment=moment, signum=signum, target=target)

    reference = one("reference", None)
    problems = reference.problems() + ([] if reference.returncode == 0 else ["the reference run failed"])
    print(f"{name:12s} reference  {reference.describe()}: {'; '.join(problems) or 'clean'}", flush=True)
    if reference.returncode != 0:
        print(reference.stderr[-2000:], flush=True)
    duration = reference.seconds
    passed = 0
    for i, fraction in enumerate(fractions(runs, rng)):
        signum, target = DELIVERIES[int(rng.choice(len(DELIVERIES), p=WEIGHTS))]
        for attempt in range(4):
            outcome = one(f"run{i:02d}-{attempt}", fraction * duration, signum, target)
            if outcome.moment is not None or attempt == 3:
                break
            duration = min(duration, outcome.seconds)  # ended before the signal: faster than estimated
        problems = outcome.problems()
        passed += not problems
        print(f"{name:12s} run {i + 1:2d}/{runs}  {outcome.describe()}: {'; '.join(problems) or 'clean'}",
              flush=True)  # fmt: skip
        if problems:
            print("    stderr: " + outcome.stderr[-3000:].replace("\n", "\n    stderr: "), flush=True)
    return passed, runs, reference


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=10, help="interrupted runs per command (default 10)")
    parser.add_argument("--seed", type=int, default=37, help="seed of the moments and signals (default 37)")
    parser.add_argument("--commands", default=",".join(COMMANDS), help="comma-separated (default: all four)")
    parser.add_argument("--keep", action="store_true", help="keep the work folder (its path is printed)")
    options = parser.parse_args()
    names = [n.strip() for n in options.commands.split(",") if n.strip()]
    unknown = sorted(set(names) - set(COMMANDS))
    if unknown:
        parser.error(f"unknown command(s) {unknown}; choose from {list(COMMANDS)}")
    rng = np.random.default_rng(options.seed)
    work = Path(tempfile.mkdtemp(prefix="interrupt-campaign-"))
    start = time.monotonic()
    results = {}
    try:
        for name in names:
            results[name] = campaign(name, options.runs, rng, work)
    finally:
        if options.keep:
            print(f"work folder: {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    print(f"\npass counts (seed {options.seed}, {(time.monotonic() - start) / 60:.1f} min):")
    for name, (passed, runs, reference) in results.items():
        clean = "clean" if not reference.problems() and reference.returncode == 0 else "NOT clean"
        print(f"  {name:12s} {passed}/{runs} interrupted runs clean; reference run ({reference.seconds:.1f} s) {clean}")
    if any(p < r or reference.problems() for p, r, reference in results.values()):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
