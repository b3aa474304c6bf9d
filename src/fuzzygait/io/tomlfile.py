"""Reading small TOML configuration files with one clear error per problem, and writing
flat ones (:func:`toml_text`)."""

from __future__ import annotations

import json
import math
import os
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fuzzygait.core.errors import ParameterError


def load_toml(path: str | os.PathLike[str], kind: str) -> dict[str, Any]:
    """The TOML document at ``path``.

    Args:
        kind: what the file is, for messages (e.g. ``"subject file"``).

    Raises:
        ParameterError: missing file or invalid TOML, naming the file.
    """
    path = Path(path)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such {kind}; check the path") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: not a valid TOML file ({exc})") from None


#: What :func:`toml_text` writes: a value, or a table of values one level deep.
TomlValue = str | bool | int | float


def _toml_value(key: str, value: TomlValue) -> str:
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # JSON strings are TOML basic strings
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) and math.isfinite(value):
        return repr(value)  # the shortest text that reads back to the same float
    raise ParameterError(f"{key}: cannot write {value!r} to TOML (finite numbers, text and true/false only)")


def toml_text(
    document: Mapping[str, TomlValue | Mapping[str, TomlValue]], comments: Sequence[str] = ()
) -> str:
    """TOML text of ``document``: ``comments`` as ``#`` lines, then its values in order,
    then its tables (``[name]``, values only); floats exactly (they read back equal).

    Raises:
        ParameterError: a value TOML cannot hold (NaN, infinity, another type).
    """
    lines = [f"# {line}".rstrip() for line in comments]
    if lines:
        lines.append("")
    tables = {k: v for k, v in document.items() if isinstance(v, Mapping)}
    lines += [f"{key} = {_toml_value(key, value)}" for key, value in document.items()
              if not isinstance(value, Mapping)]  # fmt: skip
    for name, table in tables.items():
        lines += ["", f"[{name}]"] + [f"{key} = {_toml_value(f'{name}.{key}', value)}" for key, value in table.items()]
    return "\n".join(lines) + "\n"
