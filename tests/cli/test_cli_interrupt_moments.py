"""Issue 37: ``uncertainty`` and ``report`` with two workers, each run in a process group
of its own (as a shell runs a command): at exit nothing of it is left in that group
(``ps -g PGID`` would list nothing), whether it completed or was interrupted; and,
interrupted at seeded random moments (start-up, the workers' spin-up, computing,
writing, shutdown), it prints the one interrupt line, no traceback, and exits 130 / 143.

``fuzzy-sim`` and ``frv-sim`` are in ``test_cli_interrupt_moments_sim.py`` (a module of
their own, so that the two run side by side); the full campaign, ten moments per
command, is ``benchmarks/interrupt_campaign.py``.  The runs and checks are in
``interrupt_harness.py``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from interrupt_harness import check_completes_with_an_empty_group, check_interrupted_cleanly

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")]
pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The inputs and runs of this module (a session folder)."""
    return tmp_path_factory.mktemp("interrupt-work")


def test_uncertainty_with_workers_leaves_its_process_group_empty(work: Path) -> None:
    check_completes_with_an_empty_group("uncertainty", work)


def test_uncertainty_interrupted_at_random_moments(work: Path) -> None:
    check_interrupted_cleanly("uncertainty", work)


def test_report_with_workers_leaves_its_process_group_empty(work: Path) -> None:
    check_completes_with_an_empty_group("report", work)


def test_report_interrupted_at_random_moments(work: Path) -> None:
    check_interrupted_cleanly("report", work)
