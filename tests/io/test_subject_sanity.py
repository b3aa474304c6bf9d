"""Subject parameters and TOML files refused in one line naming the file and the
parameter (issue 17): a folder as the subject file, an impossible Height or
AsisTrocanterDistance, nan in a TOML file; InterAsisDistance = 0 means "measure it"
(as in Plug-in Gait)."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import SAMPLE_DATA

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.subject import read_subject
from fuzzygait.io.tomlfile import load_toml

SUBJECT = SAMPLE_DATA / "subject.toml"


def _subject_with(tmp_path: Path, name: str, value: str) -> Path:
    lines = [line for line in SUBJECT.read_text().splitlines() if not line.startswith(f"{name} =")]
    path = tmp_path / "subject.toml"
    path.write_text("\n".join([*lines, f"{name} = {value}"]) + "\n")
    return path


@pytest.mark.parametrize("suffix", [".toml", ".vsk", ".mp", ""])
def test_a_folder_as_the_subject_file_is_one_line(tmp_path, suffix):
    folder = tmp_path / f"subject{suffix}"
    folder.mkdir()
    with pytest.raises(ParameterError, match=r"subject[.a-z]*: is a folder, not a subject file; give the subject file"):
        read_subject(folder)


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [("Height", "-1679", "Height=-1679 (expected 500..2600 mm, or 0 when unknown)"),
     ("Height", "1.68", "Height=1.68 (expected 500..2600 mm, or 0 when unknown)"),
     ("Bodymass", "-70", "Bodymass=-70 (expected 2..400 kg, or 0 when unknown)"),
     ("LAsisTrocanterDistance", "-67", "LAsisTrocanterDistance=-67 (expected 20..300 mm, or 0 when unknown)"),
     ("InterAsisDistance", "-250", "InterAsisDistance=-250 (expected 100..500 mm)"),
     ("LLegLength", "nan", "LLegLength = nan is not a finite number")],
)  # fmt: skip
def test_impossible_parameters_are_named_with_the_file(tmp_path, name, value, expected):
    path = _subject_with(tmp_path, name, value)
    with pytest.raises(ParameterError) as caught:
        read_subject(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and expected in message and "\n" not in message


def test_zero_means_unknown_or_measure_it(tmp_path):
    """Plug-in Gait: InterAsisDistance 0 is measured from the ASIS markers,
    AsisTrocanterDistance 0 comes from the leg-length regression, Height/Bodymass 0 are
    unknown."""
    path = _subject_with(tmp_path, "InterAsisDistance", "0")
    text = path.read_text().replace("LAsisTrocanterDistance = 67.36", "LAsisTrocanterDistance = 0")
    path.write_text(text.replace("Height = 1780.0", "Height = 0").replace("Bodymass = 72.0", "Bodymass = 0"))
    subject = read_subject(path)
    assert subject.inter_asis_distance is None and subject.height == 0.0 and subject.body_mass == 0.0
    assert subject.left.asis_trochanter == pytest.approx(0.1288 * 900.0 - 48.56)


def test_nan_in_any_toml_names_the_file_and_the_key(tmp_path):
    path = tmp_path / "errors.toml"
    path.write_text("[markers.LASI]\nradius = nan\n[segments.pelvis]\nsta = [1.0, inf]\n")
    with pytest.raises(ParameterError, match=r"errors\.toml: markers\.LASI\.radius = nan is not a finite number"):
        load_toml(path, "errors file")
    path.write_text("[segments.pelvis]\nsta = [1.0, -inf]\n")
    with pytest.raises(ParameterError, match=r"errors\.toml: segments\.pelvis\.sta\[1\] = -inf is not a finite"):
        load_toml(path, "errors file")


def test_a_folder_as_any_toml_file_is_one_line(tmp_path):
    with pytest.raises(ParameterError, match=r": is a folder; give the errors file itself"):
        load_toml(tmp_path, "errors file")
