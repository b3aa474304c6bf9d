"""Bad marker-error settings get one clear ParameterError naming the setting (audit item
3): unknown keywords, impossible α-levels, angle selections, workers and methods; and an
analysis of angles the run did not compute says so."""

from __future__ import annotations

import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind, Severity
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run
from support import sparse_angles_run


def test_create_refuses_an_unknown_keyword_and_lists_the_accepted_ones() -> None:
    with pytest.raises(ParameterError, match=r"unknown keyword argument alpha; it takes errors_file, .*alphas"):
        MarkerErrorSettings.create(alpha=(0.0, 0.5))  # type: ignore[call-arg]


@pytest.mark.parametrize("alphas", [0.5, (), (1.0,), (0.0, 1.5), (-0.1,), (float("nan"),), ("0",), (True,)])
def test_impossible_alpha_levels_are_refused_by_both_constructors(alphas) -> None:
    needle = r"alphas must be α-levels from 0 to below 1, e\.g\. \(0, 0\.5\).*; got "
    with pytest.raises(ParameterError, match=needle):
        MarkerErrorSettings.create(alphas=alphas)
    with pytest.raises(ParameterError, match=needle):
        MarkerErrorSettings(alphas=alphas)


@pytest.mark.parametrize("field", ["angles", "allowable_angles"])
@pytest.mark.parametrize(
    ("value", "needle"),
    [
        ("LKneeAngles", r"must be a list of one or more angle names or components, e\.g\. \['LKneeAngles'.*got "
                        r"'LKneeAngles'"),
        ([], r"must be a list of one or more angle names or components, .*got \[\]"),
        (["LKneeAngles", "LKneeAngle", "LKneeAngles_Q"], r"unknown angle 'LKneeAngle', 'LKneeAngles_Q'; give angle "
                                                         r"names such as LPelvisAngles"),
    ],
)  # fmt: skip
def test_bad_angle_selections_are_refused(field, value, needle) -> None:
    with pytest.raises(ParameterError, match=rf"^{field}"):
        MarkerErrorSettings.create(**{field: value})
    with pytest.raises(ParameterError, match=needle):
        MarkerErrorSettings(**{field: value})


@pytest.mark.parametrize("workers", [0, -2, 1.5, True])
def test_workers_must_be_a_whole_number_of_at_least_one(workers) -> None:
    with pytest.raises(ParameterError, match=rf"workers must be a whole number of processes >= 1.*got {workers!r}"):
        MarkerErrorSettings(workers=workers)


def test_an_unknown_method_is_refused() -> None:
    with pytest.raises(ParameterError, match=r"method must be one of cartesian, spherical; got 'polar'"):
        MarkerErrorSettings.create(method="polar")


def test_good_settings_are_kept() -> None:
    settings = MarkerErrorSettings.create(alphas=[0, 0.5, 1.0], angles=["LKneeAngles", "RHipAngles_X"], workers=2,
                                          allowable_angles=("LKneeAngles_X",), method="spherical")  # fmt: skip
    assert settings.alphas == (0.0, 0.5, 1.0)
    assert settings.angles == ("LKneeAngles", "RHipAngles_X")
    assert settings.allowable_angles == ("LKneeAngles_X",)
    assert settings.workers == 2 and settings.method == "spherical"
    assert MarkerErrorSettings().angles is None and MarkerErrorSettings(workers=None).workers is None


# ------------------------------------------------------------------ f: angles not computed
def test_angles_the_run_did_not_compute_are_named_in_a_note(angles_run) -> None:
    run = sparse_angles_run(angles_run, 3)
    settings = MarkerErrorSettings(alphas=(0.0,), angles=("LKneeAngles_X", "LForeFootAngles"), workers=1,
                                   tolerance=None, per_source=False)  # fmt: skip
    analysis = analyse_run(run, settings)
    assert [str(c) for c in analysis.fuzzy["component"].to_numpy()] == ["LKneeAngles_X"]
    notes = [n for n in analysis.notes if "LForeFootAngles" in n.message]
    assert len(notes) == 1 and notes[0].kind is FindingKind.UNCERTAINTY and notes[0].severity is Severity.WARNING
    assert "not analysed" in notes[0].message and "cgm1.0 run did not compute" in notes[0].message


def test_no_requested_angle_computed_names_the_requested_and_the_computed(angles_run) -> None:
    settings = MarkerErrorSettings(alphas=(0.0,), angles=("LForeFootAngles", "RForeFootAngles_X"), workers=1)
    with pytest.raises(ParameterError, match=r"walking\.c3d: none of the requested angles \(LForeFootAngles, "
                                             r"RForeFootAngles_X\) was computed by this cgm1\.0 run; it computed "
                                             r"LPelvisAngles, .*LKneeAngles"):  # fmt: skip
        analyse_run(angles_run, settings)
