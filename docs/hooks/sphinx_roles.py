"""MkDocs hook: the docstrings' Sphinx roles as links.

The package's docstrings refer to other objects the Sphinx way (``:func:`~a.b.c```,
``:class:`Title <a.b.C>```). mkdocstrings renders them as the role's name followed by
code; this hook turns each into a cross-reference that mkdocs-autorefs resolves to the
object's entry in the API reference (optional: a target that is not documented, e.g. a
private helper or another package's object, stays plain code without a warning).
``~`` shows the last component only, as in Sphinx.
"""

from __future__ import annotations

import html
import re
from typing import Any

ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|exc|obj|const):<code>(.*?)</code>", flags=re.DOTALL)
EXPLICIT = re.compile(r"(.*?)\s*<([^<>]+)>", flags=re.DOTALL)


def _reference(match: re.Match[str]) -> str:
    text = html.unescape(match[1]).strip()
    if explicit := EXPLICIT.fullmatch(text):
        title, target = explicit[1], explicit[2].strip().lstrip("~")
    else:
        target = text.lstrip("~")
        title = target.rsplit(".", 1)[-1] if text.startswith("~") else target
    target = target.lstrip(".").removesuffix("()")
    return (f'<autoref identifier="{html.escape(target)}" optional>'
            f"<code>{html.escape(title)}</code></autoref>")  # fmt: skip


def on_page_content(html_text: str, **kwargs: Any) -> str:
    """The page's HTML with every Sphinx role made an optional cross-reference."""
    return ROLE.sub(_reference, html_text)
