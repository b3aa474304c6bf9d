"""Writing result tables as CSV or Parquet (by file suffix), atomically.

What produced a table (the model version, the program) travels with it
(:func:`write_table`'s ``metadata``): in both formats as constant text columns added
last, so ``pd.read_csv(path)`` reads the file as it is (a ``#`` comment line would need
``comment="#"``); in Parquet also in the schema's key-value metadata (``fuzzygait.<key>``
for pyarrow and other readers) and as the frame's ``attrs`` for pandas.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.paths import check_table_path
from fuzzygait.io.atomic import atomic_output

#: Parquet schema metadata key prefix of :func:`write_table`'s ``metadata``.
METADATA_PREFIX = "fuzzygait."


def write_table(
    table: pd.DataFrame,
    path: str | os.PathLike[str],
    *,
    metadata: Mapping[str, str] | None = None,
    columns: tuple[str, ...] = (),
) -> Path:
    """Write ``table`` to ``path`` (.csv with '.' decimals, or .parquet).

    Args:
        metadata: text describing the table (e.g. ``{"model": "cgm2.3", "fuzzygait":
            "0.1.0"}``): in Parquet the schema metadata ``fuzzygait.<key>`` and the
            frame's ``attrs`` (``pd.read_parquet(path).attrs["model"]``).
        columns: keys of ``metadata`` also written as constant columns after the table's
            own (in both formats; the only place CSV has for them).
    """
    path = check_table_path(path)
    metadata = dict(metadata or {})
    unknown = [c for c in columns if c not in metadata]
    clashing = [c for c in columns if c in table.columns]
    if unknown or clashing:
        raise FuzzyGaitError(f"{path}: metadata columns {unknown or clashing} are "
                             f"{'not in the metadata' if unknown else 'already table columns'}")  # fmt: skip
    if columns:
        table = table.assign(**{c: metadata[c] for c in columns})
    with atomic_output(path) as tmp:
        if path.suffix.lower() == ".csv":
            table.to_csv(tmp, index=False, float_format="%.6f")
        else:
            _write_parquet(table, tmp, metadata)
    return path


def _write_parquet(table: pd.DataFrame, path: Path, metadata: Mapping[str, str]) -> None:
    import pyarrow as pa  # type: ignore[import-untyped]
    import pyarrow.parquet as pq  # type: ignore[import-untyped]

    arrow = pa.Table.from_pandas(table, preserve_index=False)
    existing = arrow.schema.metadata
    schema_metadata: dict[bytes, bytes] = dict(existing) if existing else {}
    schema_metadata.update({(METADATA_PREFIX + k).encode(): str(v).encode() for k, v in metadata.items()})
    attrs: dict[str, object] = {str(k): v for k, v in table.attrs.items()}
    attrs.update(metadata)
    if attrs:  # where pandas (>= 2.1) keeps DataFrame.attrs in Parquet
        schema_metadata[b"PANDAS_ATTRS"] = json.dumps(attrs, default=str).encode()
    pq.write_table(arrow.replace_schema_metadata(schema_metadata), str(path))
