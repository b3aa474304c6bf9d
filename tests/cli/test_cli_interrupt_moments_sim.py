"""Issue 37: ``fuzzy-sim`` and ``frv-sim`` with two workers in a process group of their
own: nothing of them left in the group at exit, completed or interrupted; interrupted
at seeded random moments, the one line, no traceback, exit 130 / 143 (the checks of
``test_cli_interrupt_moments.py``, in a module of their own so that the two run side by
side)."""

from __future__ import annotations

from pathlib import Path

import pytest
from interrupt_harness import check_completes_with_an_empty_group, check_interrupted_cleanly

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")]
pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The inputs and runs of this module (an FRV study)."""
    return tmp_path_factory.mktemp("interrupt-work-sim")


def test_fuzzy_sim_with_workers_leaves_its_process_group_empty(work: Path) -> None:
    check_completes_with_an_empty_group("fuzzy-sim", work)


def test_fuzzy_sim_interrupted_at_random_moments(work: Path) -> None:
    check_interrupted_cleanly("fuzzy-sim", work)


def test_frv_sim_with_workers_leaves_its_process_group_empty(work: Path) -> None:
    check_completes_with_an_empty_group("frv-sim", work)


def test_frv_sim_interrupted_at_random_moments(work: Path) -> None:
    check_interrupted_cleanly("frv-sim", work)
