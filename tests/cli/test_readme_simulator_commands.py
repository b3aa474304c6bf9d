"""Every simulator command line the documentation shows (issue 18: "every command line in the
README runs to the end with its defaults"): the concrete lines of the "Defaults that run"
block of docs/simulator.md (which held it when it was the README's) and the README's own
simulator examples are run as they are, their output folder moved to a temporary one, and
must exit 0 having written their output."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from support import ROOT, run

#: the simulator page of the docs: its "Defaults that run" block shows each command
SIMULATOR_PAGE = ROOT / "docs" / "simulator.md"
#: every page whose concrete simulator lines must run: the simulator page and the README
PAGES = (SIMULATOR_PAGE, ROOT / "README.md")
#: a concrete simulator line: no synopsis brackets or alternatives, output under results/
LINE = re.compile(r"^fuzzygait (simulate|fuzzy-sim|frv-sim) [^\[|#]*--out results/\S+(\s+#.*)?$")


def page_lines(page: Path) -> list[str]:
    return [line.strip() for line in page.read_text(encoding="utf-8").splitlines() if LINE.match(line.strip())]


def shown_lines() -> list[str]:
    """The concrete simulator lines of every page, each command once (comments aside)."""
    lines: dict[tuple[str, ...], str] = {}
    for page in PAGES:
        for line in page_lines(page):
            lines.setdefault(tuple(shlex.split(line, comments=True)), line)
    return list(lines.values())


def test_the_docs_show_each_simulator_command() -> None:
    lines = page_lines(SIMULATOR_PAGE)
    shown = {tuple(shlex.split(line, comments=True)[1:3]) for line in lines}
    assert shown >= {("simulate", "swing"), ("simulate", "stance"), ("fuzzy-sim", "swing"),
                     ("fuzzy-sim", "stance"), ("frv-sim", "stance")}, lines  # fmt: skip


def test_the_readme_shows_simulator_commands_that_are_run() -> None:
    """The README's examples are concrete lines too (and so run by the test below)."""
    assert page_lines(ROOT / "README.md"), "the README shows no concrete simulator command line"


@pytest.mark.slow
@pytest.mark.parametrize("line", shown_lines())
def test_readme_simulator_command_runs_with_its_defaults(tmp_path: Path, line: str) -> None:
    words = [w.replace("results/", f"{tmp_path}/") for w in shlex.split(line, comments=True)[1:]]
    result = run(*words)
    assert result.returncode == 0, result.stderr
    out = Path(words[words.index("--out") + 1])
    assert out.exists() and (out.is_dir() or out.stat().st_size > 0)
    assert "Traceback" not in result.stderr
