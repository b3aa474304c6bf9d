"""The documentation: the MkDocs site builds without a warning, the README stays a front
door (one screen, the Quick-start lines CI runs, links that lead somewhere) and the command
line page documents every command the ``fuzzygait`` app registers."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
import typer

from support import ROOT

README = ROOT / "README.md"
CLI_PAGE = ROOT / "docs" / "cli.md"
CI_SCRIPT = ROOT / ".ci" / "run"
MAX_README_LINES = 250
#: the Quick start's first line: install and run the demo
INSTALL_AND_DEMO = (
    "python3 -m venv .venv && .venv/bin/pip install -q -e . && .venv/bin/fuzzygait demo --out results/demo"
)
#: a Markdown link or image target: [text](target) or [text](target "title")
LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def registered_commands() -> list[str]:
    """The command names of the typer app, as ``fuzzygait --help`` lists them."""
    import fuzzygait.cli  # the command modules register their commands on import

    return sorted(typer.main.get_command(fuzzygait.cli.app).commands)


@pytest.mark.slow
def test_the_site_builds_strictly(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, f"mkdocs build --strict failed:\n{result.stdout}\n{result.stderr}"
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "cli" / "index.html").is_file()


def test_the_readme_fits_on_a_screen() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines (at most {MAX_README_LINES})"


def test_the_readme_shows_the_quick_start_lines_ci_runs() -> None:
    """The test line is the last line of ``.ci/run``, verbatim, and both set-up lines stand
    on lines of their own in the README."""
    ci_line = CI_SCRIPT.read_text(encoding="utf-8").strip().splitlines()[-1].strip()
    assert ci_line.startswith("python3 -m venv .venv && .venv/bin/pip install -q -e '.[test]'"), ci_line
    readme_lines = [line.strip() for line in README.read_text(encoding="utf-8").splitlines()]
    assert INSTALL_AND_DEMO in readme_lines
    assert ci_line in readme_lines


def test_the_cli_page_documents_every_command() -> None:
    commands = registered_commands()
    assert {"angles", "report", "normative", "simulate"} <= set(commands), commands
    page = CLI_PAGE.read_text(encoding="utf-8")
    headings = [line for line in page.splitlines() if line.startswith("#")]
    missing = []
    for command in commands:
        named = re.compile(rf"(?<![\w-]){re.escape(command)}(?![\w-])")
        if not any(named.search(h) for h in headings) and not re.search(rf"fuzzygait {re.escape(command)}(?![\w-])",
                                                                         page):  # fmt: skip
            missing.append(command)
    assert not missing, f"docs/cli.md does not document: {', '.join(missing)}"


def test_the_readme_links_lead_to_existing_files() -> None:
    targets = LINK.findall(README.read_text(encoding="utf-8"))
    relative = [t for t in targets if not re.match(r"^[a-z][a-z0-9+.-]*:", t) and not t.startswith("#")]
    assert relative, "the README links to no page of the docs"
    broken = [t for t in relative if not (ROOT / t.split("#")[0]).is_file()]
    assert not broken, f"README.md links to missing files: {broken}"
    assert any(t.startswith("docs/") for t in relative)
