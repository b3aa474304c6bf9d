"""A subject file value that is not a number is named with what was given (audit item 8),
not reported as missing."""

from __future__ import annotations

import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.subject import read_subject
from support import SAMPLE_DATA


@pytest.mark.parametrize(("line", "shown"), [('LLegLength = "900"', "LLegLength = '900'"),
                                             ("Height = true", "Height = True")])  # fmt: skip
def test_a_quoted_subject_value_must_be_a_number(tmp_path, line, shown) -> None:
    name = line.split(" ")[0]
    text = "\n".join(line if row.startswith(f"{name} ") else row
                     for row in (SAMPLE_DATA / "subject.toml").read_text().splitlines())  # fmt: skip
    path = tmp_path / "subject.toml"
    path.write_text(text)
    needle = rf"subject\.toml: subject parameters must be numbers \(mm, kg, rad\), written without quotes, e\.g\. " \
             rf"LLegLength = 900\.0; got {shown}$"  # fmt: skip
    with pytest.raises(ParameterError, match=needle):
        read_subject(path)
    assert read_subject(SAMPLE_DATA / "subject.toml").left.leg_length == 900.0
