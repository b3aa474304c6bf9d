"""The C3D ``ANALYSIS`` group (Nexus' spatio-temporal parameters) with both readers,
files without it, odd groups, and the flat ``EVENT:TIMES`` layout of Nexus 1.4."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from support import C3D_FORMATS, SHARED_DATA, needs_shared, shared_file
from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import messages
from fuzzygait.core.trial import AnalysisValue, Trial
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.c3d import _interpret
from fuzzygait.io.c3d_backends import _decode_c3d, _decode_ezc3d


@needs_shared
@pytest.mark.parametrize("decode", [_decode_ezc3d, _decode_c3d], ids=["ezc3d", "c3d"])
def test_nexus_analysis_group_with_either_reader(decode) -> None:  # type: ignore[no-untyped-def]
    path = shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d")
    trial = _interpret(path, decode(path))
    assert len(trial.analysis) == 22
    first = trial.analysis[0]
    assert (first.name, first.context, first.unit, first.subject) == ("Cadence", "Left", "steps/min", "BELT_C")
    assert first.value == pytest.approx(116.50485, rel=1e-6)
    by_key = {(v.name, v.context): v for v in trial.analysis}
    assert by_key[("Stride Length", "Right")].unit == "m"
    assert by_key[("Stride Length", "Right")].value == pytest.approx(1.157305, rel=1e-6)
    assert by_key[("Single Support", "Left")].unit == "s"


@needs_shared
def test_workstation_analysis_group_keeps_its_own_units() -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    assert len(trial.analysis) == 21
    units = {(v.name, v.context): v.unit for v in trial.analysis}
    assert units[("Cadence", "Left")] == "1/s" and units[("Step Length", "Right")] == "mm"
    assert ("Single Support", "Left") not in units  # Workstation wrote none for that side


@needs_shared
def test_files_without_analysis_values_give_an_empty_list() -> None:
    for path in [*sorted((SHARED_DATA / "vicon").glob("*.c3d")), *sorted(C3D_FORMATS.glob("*"))]:
        if path.name in ("gait-pig.c3d",) or path.suffix.lower() != ".c3d":
            continue
        try:
            trial = read_c3d(path)
        except C3DError:  # the corrupt sample: one clear error, as before
            continue
        assert trial.analysis == [], path.name  # USED = 0 or no group at all
        assert not [n for n in messages(trial.notes) if "ANALYSIS" in n]


@needs_shared
def test_nexus_14_flat_event_times_are_minute_second_pairs() -> None:
    trial = read_c3d(shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d"))
    strikes = [(e.context, round(e.time, 4)) for e in trial.events if e.label == "Foot Strike"]
    assert strikes == [("Right", 1.53), ("Left", 2.02), ("Right", 2.54), ("Left", 3.05),
                       ("Right", 3.57), ("Left", 4.05), ("Right", 4.59)]  # fmt: skip
    first, last = trial.times[0], trial.times[-1]
    assert all(first <= e.time <= last for e in trial.events)


def _with_analysis(tmp_path: Path, **parameters: object) -> Path:
    import ezc3d

    path = tmp_path / "trial.c3d"
    write_c3d(Trial(markers=np.ones((20, 1, 3)), marker_labels=["LTOE"], rate=100.0), path)
    c = ezc3d.c3d(str(path))
    for name, value in parameters.items():
        c.add_parameter("ANALYSIS", name, value)
    c.write(str(path))
    return path


def test_a_short_analysis_group_gives_what_it_holds_and_a_note(tmp_path: Path) -> None:
    path = _with_analysis(tmp_path, USED=3, NAMES=["Cadence", "Stride Time"], CONTEXTS=["Left"],
                          UNITS=["steps/min", "s"], VALUES=np.array([110.0, 1.1]))  # fmt: skip
    trial = read_c3d(path)
    assert trial.analysis == [AnalysisValue("Cadence", "Left", "steps/min", 110.0),
                              AnalysisValue("Stride Time", "General", "s", pytest.approx(1.1))]  # fmt: skip
    assert any("ANALYSIS:USED says 3 values but the group holds 2" in n for n in messages(trial.notes))


def test_an_analysis_group_without_values_is_ignored_with_a_note(tmp_path: Path) -> None:
    trial = read_c3d(_with_analysis(tmp_path, USED=2, NAMES=["Cadence", "Stride Time"]))
    assert trial.analysis == []
    assert any("ANALYSIS group without NAMES/VALUES" in n for n in messages(trial.notes))
