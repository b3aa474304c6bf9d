"""Shared fixtures: where the reference data lives, and skipping when it does not."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_DATA = ROOT / "sample_data"
SHARED_DATA = ROOT.parent / "shared" / "data"
VICON = SHARED_DATA / "vicon"
C3D_FORMATS = SHARED_DATA / "c3d-formats"

needs_shared = pytest.mark.skipif(
    not SHARED_DATA.is_dir(),
    reason=f"reference data {SHARED_DATA} is absent (it sits beside the clone in CI)",
)


def shared_file(*parts: str) -> Path:
    """Path of a reference file; skips the calling test when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"reference file {path} is absent")
    return path
