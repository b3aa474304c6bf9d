"""Fixtures of the kinematics tests."""

from __future__ import annotations

import pytest

from fuzzygait.io.subject import SubjectParameters
from support import SAMPLE_DATA


@pytest.fixture(scope="module")
def subject() -> SubjectParameters:
    """sample_data/subject.toml."""
    from fuzzygait.io.subject import read_subject

    return read_subject(SAMPLE_DATA / "subject.toml")
