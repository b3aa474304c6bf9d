"""Every simulator command line the README shows (issue 18: "every command line in the
README runs to the end with its defaults"): the concrete lines of the README's
"Simulator commands that run" block are run as they are, their output folder moved to a
temporary one, and must exit 0 having written their output."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from support import run

README = Path(__file__).resolve().parents[2] / "README.md"
#: a concrete simulator line: no synopsis brackets or alternatives, output under results/
LINE = re.compile(r"^fuzzygait (simulate|fuzzy-sim|frv-sim) [^\[|#]*--out results/\S+(\s+#.*)?$")


def readme_lines() -> list[str]:
    return [line.strip() for line in README.read_text(encoding="utf-8").splitlines() if LINE.match(line.strip())]


def test_the_readme_shows_each_simulator_command() -> None:
    lines = readme_lines()
    shown = {tuple(shlex.split(line, comments=True)[1:3]) for line in lines}
    assert shown >= {("simulate", "swing"), ("simulate", "stance"), ("fuzzy-sim", "swing"),
                     ("fuzzy-sim", "stance"), ("frv-sim", "stance")}, lines  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("line", readme_lines())
def test_readme_simulator_command_runs_with_its_defaults(tmp_path: Path, line: str) -> None:
    words = [w.replace("results/", f"{tmp_path}/") for w in shlex.split(line, comments=True)[1:]]
    result = run(*words)
    assert result.returncode == 0, result.stderr
    out = Path(words[words.index("--out") + 1])
    assert out.exists() and (out.is_dir() or out.stat().st_size > 0)
    assert "Traceback" not in result.stderr
