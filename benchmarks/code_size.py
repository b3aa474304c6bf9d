"""Sizes of the package's source: modules, functions and signatures over the limits of issue 38.

Run:  .venv/bin/python benchmarks/code_size.py   (from the repository root; under a second)

The limits (issue 38, acceptance), so that a reader can hold a module or a function at once:

* a module (``src/fuzzygait/**/*.py``) has at most 500 lines (every line, blank and comment
  lines included);
* a function or method has at most 80 lines, from its ``def`` line to its last line
  (decorators not counted, nested functions counted in their enclosing function too);
* a signature has at most 8 parameters (positional-only, ordinary, keyword-only, ``*args``
  and ``**kwargs`` each count one), not counting ``self`` or ``cls``.

Prints the three lists (largest first) and exits with 1 when anything exceeds its limit,
0 otherwise.
"""

from __future__ import annotations

import ast
import pathlib
import sys

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "fuzzygait"
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80
MAX_PARAMETERS = 8


def parameter_count(args: ast.arguments) -> int:
    """Parameters of a signature, ``self``/``cls`` not counted."""
    count = len(args.posonlyargs) + len(args.args) + len(args.kwonlyargs) + bool(args.vararg) + bool(args.kwarg)
    first = (args.posonlyargs + args.args)[:1]
    if first and first[0].arg in ("self", "cls"):
        count -= 1
    return count


def measure(src: pathlib.Path = SRC) -> tuple[list[tuple[int, str]], list[tuple[int, str]], list[tuple[int, str]]]:
    """(lines, module), (lines, function), (parameters, function) over the limits."""
    modules, functions, signatures = [], [], []
    for path in sorted(src.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        name = path.relative_to(src).as_posix()
        lines = len(text.splitlines())
        if lines > MAX_MODULE_LINES:
            modules.append((lines, name))
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                assert node.end_lineno is not None
                length = node.end_lineno - node.lineno + 1
                where = f"{name}:{node.lineno} {node.name}"
                if length > MAX_FUNCTION_LINES:
                    functions.append((length, where))
                count = parameter_count(node.args)
                if count > MAX_PARAMETERS:
                    signatures.append((count, where))
    return (sorted(modules, reverse=True), sorted(functions, reverse=True), sorted(signatures, reverse=True))


def main() -> int:
    modules, functions, signatures = measure()
    for title, rows, unit in (
        (f"modules over {MAX_MODULE_LINES} lines", modules, "lines"),
        (f"functions over {MAX_FUNCTION_LINES} lines", functions, "lines"),
        (f"signatures over {MAX_PARAMETERS} parameters", signatures, "parameters"),
    ):
        print(f"{title}: {len(rows)}")
        for size, where in rows:
            print(f"  {size:5d} {unit:<10} {where}")
    return 1 if modules or functions or signatures else 0


if __name__ == "__main__":
    sys.exit(main())
