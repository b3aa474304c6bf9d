"""Writing result tables as CSV or Parquet (by file suffix), atomically."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.atomic import atomic_output

TABLE_SUFFIXES = (".csv", ".parquet")


def check_table_path(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """``path`` if its suffix is a table format, else a clear error naming ``option``."""
    path = Path(path)
    if path.suffix.lower() not in TABLE_SUFFIXES:
        raise FuzzyGaitError(f"{path}: {option} must end in .csv or .parquet")
    return path


def write_table(table: pd.DataFrame, path: str | os.PathLike[str]) -> Path:
    """Write ``table`` to ``path`` (.csv with '.' decimals, or .parquet)."""
    path = check_table_path(path)
    with atomic_output(path) as tmp:
        if path.suffix.lower() == ".csv":
            table.to_csv(tmp, index=False, float_format="%.6f")
        else:
            table.to_parquet(tmp, index=False)
    return path
