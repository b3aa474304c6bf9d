"""Commands on the bundled data: sample-data."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fuzzygait.cli.app import app, out, user_errors


@app.command("sample-data", short_help="Regenerate the synthetic sample trials into a folder.")
def sample_data(
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Folder to write.")] = Path(
        "sample_data"
    ),
) -> None:
    """Regenerate the synthetic sample trials (deterministic) into a folder."""
    from fuzzygait.synthetic import write_sample_data

    with user_errors():
        written = write_sample_data(out_dir)
    for path in written:
        out.print(str(path), markup=False)
