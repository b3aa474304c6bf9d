"""``python -m fuzzygait.synthetic [OUT_DIR]``: write the sample-data folder (default
``sample_data``) and list the written files."""

from __future__ import annotations

import sys
from pathlib import Path

from fuzzygait.synthetic.sample_data import write_sample_data


def main(argv: list[str] | None = None) -> int:
    """Write the sample data to ``argv[0]`` (default ``sample_data``); returns 0."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) > 1 or (args and args[0] in ("-h", "--help")):
        print("usage: python -m fuzzygait.synthetic [OUT_DIR]")
        return 0 if args and args[0] in ("-h", "--help") else 2
    out_dir = Path(args[0]) if args else Path("sample_data")
    for path in write_sample_data(out_dir):
        print(f"{path}  ({path.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
