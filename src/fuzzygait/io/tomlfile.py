"""Reading small TOML configuration files with one clear error per problem."""

from __future__ import annotations

import os
import tomllib
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
