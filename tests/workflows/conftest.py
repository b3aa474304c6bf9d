"""Fixtures of the workflow tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzygait.io import write_c3d
from fuzzygait.synthetic.cgm24 import make_cgm24_static, make_cgm24_walking


@pytest.fixture(scope="session")
def cgm24_session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The synthetic CGM 2.4 session (static with KNM/MED, 2-cycle walking) as C3D files:
    ``(static, walking)``."""
    folder = tmp_path_factory.mktemp("cgm24")
    walking, _ = make_cgm24_walking(n_cycles=2)
    write_c3d(make_cgm24_static(), folder / "static.c3d")
    write_c3d(walking, folder / "walking.c3d")
    return folder / "static.c3d", folder / "walking.c3d"
