"""What ezc3d's child process sends back (issue 37): an ``.npz`` archive of arrays and a
JSON document, read with ``allow_pickle=False`` -- the same :class:`RawC3D` as ezc3d in
this process, every field and every parameter; a pickle on its stdout is never loaded."""

from __future__ import annotations

import dataclasses
import io
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fuzzygait.io.c3d_backends import BackendError, RawC3D, _decode_ezc3d
from fuzzygait.io.c3d_child import ChildError, _archive, decode_isolated, decode_raw, encode_raw
from support import SAMPLE_DATA


def assert_same_raw(back: RawC3D, raw: RawC3D) -> None:
    """Every field of the dataclass (a field added later is compared too) and every
    parameter's value with its type and dtype."""
    for field in dataclasses.fields(RawC3D):
        if field.name == "get":
            continue
        a, b = getattr(back, field.name), getattr(raw, field.name)
        if isinstance(b, np.ndarray):
            assert a.dtype == b.dtype and a.shape == b.shape, field.name
            np.testing.assert_array_equal(a, b, err_msg=field.name)
        else:
            assert a == b and type(a) is type(b), field.name
    for group, names in raw.parameter_names.items():
        for name in names:
            a, b = back.get(group, name), raw.get(group, name)
            assert type(a) is type(b), (group, name)
            if isinstance(b, np.ndarray):
                assert a.dtype == b.dtype and a.shape == b.shape, (group, name)
                np.testing.assert_array_equal(a, b, err_msg=f"{group}:{name}")
            else:
                assert a == b, (group, name)
    assert back.get("NO", "SUCH") is None


@pytest.mark.parametrize("name", ["walking.c3d", "static.c3d"])
def test_encoded_raw_reads_back_as_ezc3d_read_it(name: str) -> None:
    raw = _decode_ezc3d(SAMPLE_DATA / name)
    assert_same_raw(decode_raw(encode_raw(raw)), raw)


def test_parameter_values_of_every_kind_read_back() -> None:
    values: dict[tuple[str, str], Any] = {
        ("A", "STRINGS"): ["LASI", "RASI"], ("A", "EMPTY"): [], ("A", "FLOAT"): np.array([[1.5, np.nan]]),
        ("A", "INT"): np.arange(3, dtype=np.int16), ("A", "TEXT"): np.array(["ab", "c"]),
        ("A", "NUMBERS"): [1, 2.5, np.float32(3.0)], ("A", "NONE"): None,
        ("A", "OBJECT"): np.array(["x", 1], dtype=object),
    }  # fmt: skip
    raw = RawC3D(np.zeros((2, 1, 3)), ["LASI"], 100.0, 1, [("Foot Strike", 0.5)], lambda g, p: values.get((g, p)),
                 {"A": [p for _, p in values]}, "ezc3d", ["a note"], None)  # fmt: skip
    back = decode_raw(encode_raw(raw))
    for (group, name), value in values.items():
        got = back.get(group, name)
        if isinstance(value, np.ndarray):
            assert got.dtype == value.dtype, name
            np.testing.assert_array_equal(got, value)
        else:
            assert got == (None if value is None else [float(v) if isinstance(v, np.generic) else v for v in value])
    assert back.header_events == [("Foot Strike", 0.5)] and back.analog_per_frame is None


def test_the_childs_refusal_is_its_one_line() -> None:
    with pytest.raises(ChildError, match="^not a C3D file$"):
        decode_raw(_archive({"kind": "error", "message": "not a C3D file"}, {}))


def test_a_pickle_on_the_childs_stdout_is_never_loaded(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"

    class Planted:
        def __reduce__(self) -> tuple[Any, tuple[str, str]]:
            return (open, (str(marker), "w"))

    for payload in (pickle.dumps(("ok", Planted())), _npz_with_pickled_array(Planted())):
        with pytest.raises(ValueError):
            decode_raw(payload)
    assert not marker.exists()


def _npz_with_pickled_array(planted: object) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array([planted], dtype=object))
    return buffer.getvalue()


def test_ezc3d_in_a_child_process_reads_what_ezc3d_reads(tmp_path: Path) -> None:
    path = SAMPLE_DATA / "walking.c3d"
    assert_same_raw(decode_isolated(path), _decode_ezc3d(path))
    (tmp_path / "bad.c3d").write_bytes(b"not a c3d file" * 100)
    with pytest.raises(BackendError):
        decode_isolated(tmp_path / "bad.c3d")
