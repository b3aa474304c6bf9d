"""Reading small TOML configuration files with one clear error per problem, and writing
them (:func:`toml_text`: values, arrays and nested tables)."""

from __future__ import annotations

import json
import math
import os
import re
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TypeAlias

from fuzzygait.core.errors import ParameterError


def load_toml(path: str | os.PathLike[str], kind: str) -> dict[str, Any]:
    """The TOML document at ``path``.

    Args:
        kind: what the file is, for messages (e.g. ``"subject file"``).

    Raises:
        ParameterError: missing file, a folder, invalid TOML or a NaN/infinite number
            (which no configuration means), naming the file (and the key).
    """
    path = Path(path)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such {kind}; check the path") from None
    except IsADirectoryError:
        raise ParameterError(f"{path}: is a folder; give the {kind} itself") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the {kind} ({exc.strerror or exc})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: not a valid TOML file ({exc})") from None
    bad = _non_finite(document)
    if bad is not None:
        raise ParameterError(f"{path}: {bad} is not a finite number; give a number (nan and inf are not values)")
    return document


def _non_finite(value: Any, key: str = "") -> str | None:
    """``"key = nan"`` of the first NaN or infinite float in a TOML document (dotted
    keys, ``[i]`` for array items), or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{key} = {value}"
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for name, item in items:
        sub = f"{key}[{name}]" if isinstance(name, int) else f"{key}.{name}" if key else str(name)
        found = _non_finite(item, sub)
        if found is not None:
            return found
    return None


#: A TOML scalar :func:`toml_text` writes.
TomlValue = str | bool | int | float
#: What :func:`toml_text` writes: scalars, arrays of them (nested arrays too) and tables.
TomlData: TypeAlias = "TomlValue | Sequence[TomlData] | Mapping[str, TomlData]"

#: Keys written without quotes.
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key, ensure_ascii=False)


def _toml_value(key: str, value: TomlData) -> str:
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # JSON strings are TOML basic strings
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) and math.isfinite(value):
        return repr(value)  # the shortest text that reads back to the same float
    if isinstance(value, Sequence) and not isinstance(value, Mapping):
        items = [_toml_value(f"{key}[{i}]", item) for i, item in enumerate(value)]
        if any(isinstance(item, Sequence) and not isinstance(item, str) for item in value):
            return "[\n" + "".join(f"    {item},\n" for item in items) + "]"  # an array of arrays: a row a line
        return "[" + ", ".join(items) + "]"
    raise ParameterError(
        f"{key}: cannot write {value!r} to TOML (finite numbers, text, true/false and arrays of them only)"
    )


def _toml_table(name: str, table: Mapping[str, TomlData]) -> list[str]:
    """``[name]`` and its values, then its sub-tables (``[name.sub]``); the header is left
    out when the table has sub-tables only."""
    values = {k: v for k, v in table.items() if not isinstance(v, Mapping)}
    lines = []
    if values or len(values) == len(table):
        lines += ["", f"[{name}]"] + [f"{_toml_key(k)} = {_toml_value(f'{name}.{k}', v)}" for k, v in values.items()]
    for key, sub in table.items():
        if isinstance(sub, Mapping):
            lines += _toml_table(f"{name}.{_toml_key(key)}", sub)
    return lines


def toml_text(document: Mapping[str, TomlData], comments: Sequence[str] = ()) -> str:
    """TOML text of ``document``: ``comments`` as ``#`` lines, then its values in order,
    then its tables (``[name]``, its values, then its sub-tables ``[name.sub]``); floats
    exactly (they read back equal), arrays of arrays one row a line.

    Raises:
        ParameterError: a value TOML cannot hold (NaN, infinity, another type).
    """
    lines = [f"# {line}".rstrip() for line in comments]
    if lines:
        lines.append("")
    lines += [f"{_toml_key(key)} = {_toml_value(key, value)}" for key, value in document.items()
              if not isinstance(value, Mapping)]  # fmt: skip
    for name, table in document.items():
        if isinstance(table, Mapping):
            lines += _toml_table(_toml_key(name), table)[1 if not lines or not lines[-1] else 0 :]
    return "\n".join(lines) + "\n"
