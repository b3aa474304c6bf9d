"""PDF copies of the report's pages (``fuzzygait report --pdf``): A4, readable in greyscale.

:func:`html_to_pdf` prints a page with headless Chromium when one is installed
(``chromium``, ``chromium-browser``, ``google-chrome``; or ``FUZZYGAIT_CHROMIUM``), with a
print style sheet added (A4 with 12 mm margins, figures scaled to the page width, black
text, tables with grey rules, no navigation bar); without Chromium it builds the PDF with
matplotlib: the page's headings and text first, then each figure scaled onto its own A4
page.  Either way the file appears whole or not at all.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import textwrap
from html.parser import HTMLParser
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.atomic import atomic_output

__all__ = ["PRINT_CSS", "chromium", "html_to_pdf"]

#: The style sheet added for printing (A4; greyscale-safe: black text, grey rules).
PRINT_CSS = """
@page { size: A4; margin: 12mm; }
@media print {
  html, body { background: #fff !important; color: #000 !important; font-size: 10pt; }
  nav { display: none !important; }
  img, svg { max-width: 100% !important; height: auto !important; page-break-inside: avoid; }
  table { border-collapse: collapse; page-break-inside: auto; }
  th, td { border-bottom: 0.5pt solid #777 !important; color: #000 !important; }
  tr { page-break-inside: avoid; }
  h1, h2, h3 { color: #000 !important; page-break-after: avoid; }
  a { color: #000 !important; text-decoration: underline; }
  .box { border: 0.5pt solid #555 !important; background: #fff !important; }
}
"""
_A4_INCH = (8.27, 11.69)
_CHROMIUM_TIMEOUT = 120.0


def chromium() -> str | None:
    """The headless browser used for printing, or None (``FUZZYGAIT_CHROMIUM``: a path,
    or ``none`` to force the matplotlib route)."""
    chosen = os.environ.get("FUZZYGAIT_CHROMIUM")
    if chosen:
        return None if chosen.lower() == "none" else chosen
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(name)
        if found:
            return found
    return None


def html_to_pdf(html: Path, pdf: Path) -> str:
    """Write ``pdf`` from the report page ``html`` (figures referenced relative to it);
    returns ``"chromium"`` or ``"matplotlib"``, the route taken."""
    browser = chromium()
    if browser is not None:
        try:
            _print_with_chromium(browser, html, pdf)
            return "chromium"
        except FuzzyGaitError:
            pass  # a broken browser: the matplotlib route still gives a PDF
    _build_with_matplotlib(html, pdf)
    return "matplotlib"


def _print_with_chromium(browser: str, html: Path, pdf: Path) -> None:
    text = html.read_text(encoding="utf-8")
    style = f"<style>{PRINT_CSS}</style>"
    text = text.replace("</head>", style + "\n</head>", 1) if "</head>" in text else style + text
    printable = html.with_name(f".{html.stem}.print.html")  # beside it: the figures' paths hold
    printable.write_text(text, encoding="utf-8")
    profile = html.with_name(f".{html.stem}.chromium")
    try:
        with atomic_output(pdf) as tmp:
            command = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                       "--disable-extensions", f"--user-data-dir={profile}", "--no-pdf-header-footer",
                       f"--print-to-pdf={tmp}", printable.resolve().as_uri()]  # fmt: skip
            try:
                done = subprocess.run(command, capture_output=True, timeout=_CHROMIUM_TIMEOUT, check=False)
            except (OSError, subprocess.TimeoutExpired) as exc:
                raise FuzzyGaitError(f"{browser}: could not print {html.name} ({exc})") from None
            if done.returncode != 0 or not tmp.is_file() or tmp.stat().st_size < 1000:
                raise FuzzyGaitError(f"{browser}: could not print {html.name} (exit code {done.returncode})")
    finally:
        printable.unlink(missing_ok=True)
        shutil.rmtree(profile, ignore_errors=True)


class _PageText(HTMLParser):
    """Headings, paragraphs, list items and table rows of a page, and its figures."""

    BLOCKS = ("h1", "h2", "h3", "p", "li", "tr", "figcaption", "caption")

    def __init__(self) -> None:
        super().__init__()
        self.blocks: list[tuple[str, str]] = []
        self.images: list[str] = []
        self._tag: str | None = None
        self._text: list[str] = []
        self._skip = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in ("style", "script", "nav"):
            self._skip += 1
        elif tag == "img":
            src = dict(attrs).get("src")
            if src and src.lower().endswith(".png"):
                self.images.append(src)
        elif tag in self.BLOCKS and self._tag is None:
            self._tag, self._text = tag, []
        elif tag in ("td", "th") and self._tag == "tr":
            self._text.append(" | ")

    def handle_endtag(self, tag: str) -> None:
        if tag in ("style", "script", "nav"):
            self._skip = max(0, self._skip - 1)
        elif tag == self._tag:
            text = " ".join("".join(self._text).split()).strip(" |")
            if text:
                self.blocks.append((tag, text))
            self._tag = None

    def handle_data(self, data: str) -> None:
        if self._tag is not None and not self._skip:
            self._text.append(data)


def _build_with_matplotlib(html: Path, pdf: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    parser = _PageText()
    parser.feed(html.read_text(encoding="utf-8"))
    lines: list[tuple[str, str]] = []
    for tag, text in parser.blocks:
        width = 70 if tag in ("h1", "h2", "h3") else 105
        for k, line in enumerate(textwrap.wrap(text, width) or [""]):
            lines.append((tag if k == 0 else "p", line))
    with atomic_output(pdf) as tmp, PdfPages(tmp) as document:
        per_page = 62
        for first in range(0, max(len(lines), 1), per_page):
            figure = plt.figure(figsize=_A4_INCH)
            y = 0.96
            for tag, line in lines[first:first + per_page]:
                size, weight = {"h1": (13, "bold"), "h2": (11, "bold"), "h3": (10, "bold")}.get(tag, (7.5, "normal"))
                figure.text(0.06, y, line, fontsize=size, fontweight=weight, color="black", va="top")
                y -= 0.0148 * (size / 7.5)
            document.savefig(figure)
            plt.close(figure)
        for src in parser.images:
            path = html.parent / src
            if not path.is_file():
                continue
            image = mpimg.imread(path)
            figure = plt.figure(figsize=_A4_INCH)
            axes = figure.add_axes((0.04, 0.04, 0.92, 0.92))
            axes.imshow(image)
            axes.set_axis_off()
            document.savefig(figure, dpi=200)
            plt.close(figure)
