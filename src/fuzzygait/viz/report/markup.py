"""HTML building blocks of the report pages: escaped text and a plain table."""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

__all__ = ["escape", "html_table"]


def escape(value: object) -> str:
    """``value`` as HTML text (quotes escaped too)."""
    return html.escape(str(value), quote=True)


def html_table(header: Sequence[tuple[str, bool]], rows: Iterable[Sequence[tuple[str, bool]]],
               row_classes: Sequence[str] | None = None) -> str:  # fmt: skip
    """``header``/cells are (html, numeric) pairs; the html must already be escaped."""
    num = ' class="num"'
    head = "".join(f'<th scope="col"{num if n else ""}>{h}</th>' for h, n in header)
    lines = []
    for i, row in enumerate(rows):
        rc = f' class="{row_classes[i]}"' if row_classes and row_classes[i] else ""
        cells = "".join(f"<td{num if n else ''}>{v}</td>" for v, n in row)
        lines.append(f"<tr{rc}>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(lines)}</tbody></table>"
