"""``viz`` builds figures, pages and recording contents; it writes no file (issue 38).

The rule: no module under ``src/fuzzygait/viz/`` calls anything that writes to disk --
``savefig``, ``write_text``, ``write_bytes``, ``to_netcdf``, ``to_zarr``, ``to_csv`` with
a path, any ``.save(...)`` (``rr.save``, ``rec.save``, ``np.save``), ``atomic_output``,
``replace_path``, ``mkdir``, ``os.replace``/``os.rename``, ``shutil.rmtree``/``copy`` or
``open(...)`` in a writing mode (``"w"``, ``"wb"``, ``"a"``, ``"x"``, ``"+"``).  A viz
function returns a :class:`~matplotlib.figure.Figure`, page text or logs into a Rerun
stream it is given; the files are written in ``io`` (generic:
:mod:`fuzzygait.io.figure_files`, :mod:`fuzzygait.io.rerun_files`) or ``workflows``
(what needs the viz builders: :mod:`fuzzygait.workflows.report_folder`,
:mod:`fuzzygait.workflows.report_entries`, :mod:`fuzzygait.workflows.rerun_recordings`).
So a figure can be shown in a notebook, tested without a disk, and every output keeps
the atomic all-or-nothing writing of the layers that own it.

The check parses the source with :mod:`ast` (calls, not text: a docstring may name
``savefig``).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

VIZ = Path(__file__).resolve().parents[1] / "src" / "fuzzygait" / "viz"

#: Methods or functions that write, whatever they are called on.
WRITING_CALLS = frozenset({
    "savefig", "write_text", "write_bytes", "to_netcdf", "to_zarr", "save", "savez", "savez_compressed",
    "atomic_output", "replace_path", "replace_folder", "temporary_folder", "mkdir", "makedirs", "mkdtemp",
    "rmtree", "copyfile", "copytree", "write_entry", "write_table", "dump",
})  # fmt: skip
#: ``module.name`` calls that write (``os.replace``, ``shutil.copy``, ...).
WRITING_MODULE_CALLS = frozenset({("os", "replace"), ("os", "rename"), ("os", "remove"), ("os", "unlink"),
                                  ("shutil", "copy"), ("shutil", "copy2"), ("shutil", "move")})  # fmt: skip


def _name(func: ast.expr) -> str | None:
    if isinstance(func, ast.Name):
        return func.id
    if isinstance(func, ast.Attribute):
        return func.attr
    return None


def _open_mode(call: ast.Call) -> str | None:
    """The mode of ``open(path, mode)`` / ``path.open(mode)`` when it is a literal."""
    name = _name(call.func)
    if name != "open":
        return None
    position = 1 if isinstance(call.func, ast.Name) or (
        isinstance(call.func, ast.Attribute) and isinstance(call.func.value, ast.Name)
        and call.func.value.id in {"io", "os", "gzip", "bz2", "lzma", "codecs"}) else 0  # fmt: skip
    mode: ast.expr | None = call.args[position] if len(call.args) > position else None
    for keyword in call.keywords:
        if keyword.arg == "mode":
            mode = keyword.value
    if mode is None:
        return "r"
    return mode.value if isinstance(mode, ast.Constant) and isinstance(mode.value, str) else "?"


def writes(source: str) -> list[tuple[int, str]]:
    """``(line, call)`` of every call in ``source`` that writes a file."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call):
            continue
        name = _name(node.func)
        if name in WRITING_CALLS:
            found.append((node.lineno, name))
        elif isinstance(node.func, ast.Attribute) and isinstance(node.func.value, ast.Name) and \
                (node.func.value.id, node.func.attr) in WRITING_MODULE_CALLS:  # fmt: skip
            found.append((node.lineno, f"{node.func.value.id}.{node.func.attr}"))
        elif name == "to_csv" and (node.args or any(k.arg in ("path_or_buf", None) for k in node.keywords)):
            found.append((node.lineno, "to_csv"))
        else:
            mode = _open_mode(node)
            if mode is not None and (mode == "?" or set(mode) & set("wax+")):
                found.append((node.lineno, f"open(..., {mode!r})"))
    return found


def viz_modules() -> list[Path]:
    return sorted(VIZ.rglob("*.py"))


def test_viz_writes_no_file() -> None:
    assert len(viz_modules()) > 20  # the package is where it is expected
    found = [f"{path.relative_to(VIZ.parent)}:{line}: {call}"
             for path in viz_modules() for line, call in writes(path.read_text(encoding="utf-8"))]  # fmt: skip
    assert not found, "viz writes files (build the figure/page there, write it in io/ or workflows/):\n" + \
        "\n".join(found)  # fmt: skip


@pytest.mark.parametrize(("source", "expected"), [
    ("fig.savefig(path, dpi=100)", [(1, "savefig")]),
    ("Path(p).write_text(html)", [(1, "write_text")]),
    ("p.write_bytes(b'')", [(1, "write_bytes")]),
    ("ds.to_netcdf(p)", [(1, "to_netcdf")]),
    ("ds.to_zarr(p)", [(1, "to_zarr")]),
    ("rec.save(tmp, default_blueprint=None)", [(1, "save")]),
    ("rr.save(p)", [(1, "save")]),
    ("with atomic_output(p) as tmp:\n    pass", [(1, "atomic_output")]),
    ("open(p, 'w')", [(1, "open(..., 'w')")]),
    ("open(p, mode='wb')", [(1, "open(..., 'wb')")]),
    ("path.open('a')", [(1, "open(..., 'a')")]),
    ("open(p, m)", [(1, "open(..., '?')")]),
    ("os.replace(a, b)", [(1, "os.replace")]),
    ("table.to_csv(path)", [(1, "to_csv")]),
    # reading and building are fine
    ("open(p)\nopen(p, 'rb')\npath.open()\nio.open(p, 'r')", []),
    ("table.to_csv()\nfig.canvas.draw()\nplt.close(fig)\n'savefig'", []),
])  # fmt: skip
def test_the_check_finds_writing_calls(source: str, expected: list[tuple[int, str]]) -> None:
    assert writes(source) == expected
