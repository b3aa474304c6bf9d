"""Options named at the edge (``fuzzygait.core.options``): one message, worded as the
command line names its options or as the library names its keywords; and no command-line
flag spelled out in a message below ``cli/``."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from fuzzygait.core.options import STYLE_VARIABLE, Advice, Option, use_command_line_names

SRC = Path(__file__).resolve().parents[2] / "src" / "fuzzygait"


def test_an_option_reads_as_the_edge_names_it(monkeypatch) -> None:
    monkeypatch.delenv(STYLE_VARIABLE, raising=False)
    message = f"give the static trial ({Option.STATIC} STATIC.c3d) or a subject file ({Option.SUBJECT} S.toml)"
    assert message == "give the static trial (static= STATIC.c3d) or a subject file (subject_file= S.toml)"
    fix = Advice("start a new study (another {out}, or {overwrite})", out=Option.OUT, overwrite=Option.OVERWRITE)
    assert str(fix) == "start a new study (another out=, or overwrite=)"
    use_command_line_names()  # what the fuzzygait command does; monkeypatch restores the variable
    assert f"({Option.STATIC} STATIC.c3d)" == "(--static STATIC.c3d)" and f"{fix}" == (
        "start a new study (another --out, or --overwrite)")  # fmt: skip
    assert Option.MARKER_DIAMETER.flag == "--marker-diameter" and Option.MARKER_DIAMETER.keyword == "marker_diameter"


def test_every_option_is_one_of_the_command_lines() -> None:
    """Each Option names an option some fuzzygait command really has."""
    flags = _command_line_flags()
    assert [o for o in Option if o.flag not in flags] == []


def _command_line_flags() -> set[str]:
    import typer

    import fuzzygait.cli  # the command modules register their commands on import

    found = set()

    def walk(command) -> None:  # noqa: ANN001 - a click command or group
        for param in command.params:
            found.update(o for o in [*param.opts, *param.secondary_opts] if o.startswith("--"))
        for sub in getattr(command, "commands", {}).values():
            walk(sub)

    walk(typer.main.get_command(fuzzygait.cli.app))
    return found


def test_no_message_below_the_command_line_spells_a_flag() -> None:
    """String constants below ``cli/`` (docstrings aside) name options through
    :class:`Option`, never as ``--flag`` text; a module's own ``__main__`` is an edge."""
    flags = sorted(_command_line_flags(), key=len, reverse=True)
    pattern = re.compile(r"(?<![\w-])(" + "|".join(map(re.escape, flags)) + r")(?![\w-])")
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith("cli/") or path.name == "__main__.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                      if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
                      and node.body and isinstance(node.body[0], ast.Expr)
                      and isinstance(node.body[0].value, ast.Constant)}  # fmt: skip
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
                    and (found := pattern.search(node.value))):  # fmt: skip
                offenders.append(f"{relative}:{node.lineno}: {found[0]} in {node.value[:80]!r}")
    assert offenders == [], "\n".join(offenders)


@pytest.mark.parametrize("option", list(Option))
def test_keywords_are_python_names(option: Option) -> None:
    assert option.keyword.isidentifier()


def test_no_flag_is_assembled_in_an_f_string() -> None:
    """Nor pieced together (``f"--{'no-' if on else ''}flat-foot"``): an f-string part below
    ``cli/`` that ends in ``--`` right before a substitution is a flag built as text."""
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith("cli/") or path.name == "__main__.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.JoinedStr):
                for part, following in zip(node.values, node.values[1:], strict=False):
                    if (isinstance(part, ast.Constant) and isinstance(following, ast.FormattedValue)
                            and re.search(r"(^|[\s(\"'`])--$", str(part.value))):  # fmt: skip
                        offenders.append(f"{relative}:{node.lineno}: {str(part.value)[-40:]!r}")
    assert offenders == [], "\n".join(offenders)
