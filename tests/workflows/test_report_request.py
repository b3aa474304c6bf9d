"""The batch report's typed request: each impossible field is one clear error, before
any file is read or written; sequences and paths are normalised."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.workflows.angles import Preprocessing
from fuzzygait.workflows.batch_report import BatchReportRequest
from fuzzygait.workflows.marker_uncertainty import DEFAULT_SETTINGS
from fuzzygait.workflows.trial_job import FAST_ALPHAS

SESSION = Path("visit-1")


def test_request_normalises_paths_and_sequences(tmp_path: Path) -> None:
    (tmp_path / "s.c3d").write_bytes(bytes(512))  # a static trial must be there (its reading is a trial's)
    request = BatchReportRequest([str(tmp_path / "a.c3d")], str(tmp_path / "out"), static=str(tmp_path / "s.c3d"))  # type: ignore[list-item, arg-type]
    assert request.inputs == (tmp_path / "a.c3d",) and request.out_dir == tmp_path / "out"
    assert request.static == tmp_path / "s.c3d" and request.subject_file is None and request.normative is None
    assert request.workers == 1 and request.model == "auto" and request.uncertainty == "full"
    assert isinstance(request.inputs, tuple)  # frozen: the caller's list cannot change it afterwards
    assert request.analysis() is DEFAULT_SETTINGS
    assert BatchReportRequest([SESSION], tmp_path, uncertainty="none").analysis() is None
    fast = BatchReportRequest([SESSION], tmp_path, uncertainty="fast").analysis()
    assert fast is not None and fast.alphas == FAST_ALPHAS and fast.tolerance is None and not fast.per_source
    assert BatchReportRequest([SESSION], tmp_path, model="2.3").model == "2.3"  # as run_angles takes it


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("inputs", [], "inputs must be a non-empty list"), ("inputs", "visit-1", "inputs must be a non-empty list"),
     ("marker_diameter", 0.0, "marker_diameter must be a finite number of mm > 0"),
     ("marker_diameter", float("nan"), "marker_diameter must be a finite number of mm > 0"),
     ("marker_diameter", True, "marker_diameter must be a finite number of mm > 0"),
     ("workers", 0, "workers must be a whole number ≥ 1"), ("workers", 1.5, "workers must be a whole number ≥ 1"),
     ("preprocessing", 6.0, "preprocessing must be a Preprocessing"),
     ("settings", {"alphas": (0.0,)}, "settings must be MarkerErrorSettings"),
     ("uncertainty", "slow", "uncertainty= 'slow': choose one of none, fast, full"),
     ("model", "cgm9", "model must be one of auto, cgm1.0"), ("model", None, "model must be one of")],
)  # fmt: skip
def test_request_rejects_each_impossible_field(tmp_path: Path, field: str, value: object, message: str) -> None:
    arguments: dict[str, object] = {"inputs": [SESSION], "out_dir": tmp_path / "out", field: value}
    with pytest.raises(ParameterError, match=f"^{message}") as raised:
        BatchReportRequest(**arguments)  # type: ignore[arg-type]
    assert "\n" not in str(raised.value) and not (tmp_path / "out").exists()


@pytest.mark.parametrize(("field", "name", "message"), [
    ("static", "absent.c3d", "absent.c3d: no such file; check the path"),
    ("subject_file", "absent.vsk", "absent.vsk: no such subject file; check the path"),
    ("subject_file", "notes.txt", "notes.txt: unknown subject file type '.txt'"),
    ("normative", "absent.csv", "absent.csv: no such normative file; check the path (normative=)"),
])  # fmt: skip
def test_request_refuses_a_file_that_is_not_there(tmp_path: Path, field: str, name: str, message: str) -> None:
    """Once an internal error of the report's re-run check (the static trial's digest)."""
    with pytest.raises(FuzzyGaitError) as raised:
        BatchReportRequest([SESSION], tmp_path / "out", **{field: tmp_path / name})  # type: ignore[arg-type]
    assert str(raised.value).startswith(str(tmp_path / message.split(":")[0])) and message in str(raised.value)
    assert "\n" not in str(raised.value) and not (tmp_path / "out").exists()


def test_request_keeps_the_options_it_is_given(tmp_path: Path) -> None:
    cut = Preprocessing(cutoff=5.0)
    request = BatchReportRequest((SESSION,), tmp_path, marker_diameter=14, flat_foot=True, preprocessing=cut,
                                 pdf=True, workers=3, scheduler="tcp://host:8786", force=True, strict=True)  # fmt: skip
    assert (request.marker_diameter, request.flat_foot, request.preprocessing, request.workers) == (14, True, cut, 3)
    assert (request.pdf, request.scheduler, request.force, request.strict) == (True, "tcp://host:8786", True, True)
