"""PDF copies of report pages: headless Chromium when present, matplotlib otherwise."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pytest

from fuzzygait.workflows import pdf

PAGE = """<!DOCTYPE html><html><head><title>t</title></head><body><nav>skip me</nav>
<h1>Trial walk01</h1><p>Some text about the angles.</p><table><tr><th>a</th><td>1</td></tr></table>
<figure><img src="walk_files/cycles.png"></figure></body></html>"""


@pytest.fixture
def page(tmp_path: Path) -> Path:
    (tmp_path / "walk_files").mkdir()
    figure, axes = plt.subplots()
    axes.plot([0, 1], [0, 1])
    figure.savefig(tmp_path / "walk_files" / "cycles.png")
    plt.close(figure)
    html = tmp_path / "walk.html"
    html.write_text(PAGE, encoding="utf-8")
    return html


def test_matplotlib_route(page: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("FUZZYGAIT_CHROMIUM", "none")
    target = page.with_suffix(".pdf")
    assert pdf.html_to_pdf(page, target) == "matplotlib"
    data = target.read_bytes()
    assert data[:5] == b"%PDF-" and data.count(b"/Type /Page") - data.count(b"/Type /Pages") == 2  # text + figure
    assert sorted(p.name for p in page.parent.iterdir()) == ["walk.html", "walk.pdf", "walk_files"]


def test_page_text_skips_navigation(page: Path) -> None:
    parser = pdf._PageText()
    parser.feed(page.read_text(encoding="utf-8"))
    assert parser.blocks[0] == ("h1", "Trial walk01") and all("skip me" not in t for _, t in parser.blocks)
    assert parser.images == ["walk_files/cycles.png"]


@pytest.mark.skipif(pdf.chromium() is None, reason="no headless Chromium installed")
def test_chromium_route(page: Path) -> None:
    target = page.with_suffix(".pdf")
    assert pdf.html_to_pdf(page, target) == "chromium"
    assert target.read_bytes()[:5] == b"%PDF-"
    assert sorted(p.name for p in page.parent.iterdir()) == ["walk.html", "walk.pdf", "walk_files"]
