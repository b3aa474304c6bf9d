"""The package's structure: layers that import only downward, and modules of a size a
reader can hold (docs/architecture.md, "Layout")."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "fuzzygait"

#: Rank of each top-level part; a module may import only parts of a lower rank (and its
#: own part). Parts of equal rank are independent of each other.
LAYERS = {
    "core": 0,
    "io": 1,
    "mocap": 2,
    "kinematics": 2,
    "uncertainty": 2,
    "mechanics": 3,  # models for the engine: may import uncertainty
    "kinetics": 3,  # force plates and inverse dynamics: may import mocap (filtering)
    "gait": 4,
    "markererror": 4,
    "synthetic": 4,
    "testing": 4,
    "viz": 5,
    "workflows": 6,
    "cli": 7,
    "__main__": 8,
}
MAX_LINES = 500  # issue 38: one responsibility per module (benchmarks/code_size.py lists the rest)


def modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def part_of(path: Path) -> str:
    relative = path.relative_to(PACKAGE)
    return relative.parts[0].removesuffix(".py") if len(relative.parts) > 1 or relative.stem != "__init__" else ""


def imported_parts(path: Path) -> set[tuple[str, int]]:
    """(part, line) of every ``fuzzygait.<part>`` import in the module, at any depth
    (function-level and TYPE_CHECKING imports are dependencies too)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names if node.module == "fuzzygait"]
        for name in names:
            parts = name.split(".")
            if parts[0] == "fuzzygait" and len(parts) > 1:
                found.add((parts[1], node.lineno))
    return found


def test_every_part_has_a_layer() -> None:
    parts = {part_of(p) for p in modules()} - {""}
    assert parts <= set(LAYERS), sorted(parts - set(LAYERS))


def test_layers_import_only_downward() -> None:
    violations = []
    for path in modules():
        part = part_of(path)
        if not part:  # the package's __init__: version only
            continue
        for target, line in imported_parts(path):
            if target == part or target == "__version__":
                continue
            if target not in LAYERS or LAYERS[target] >= LAYERS[part]:
                violations.append(f"{path.relative_to(PACKAGE)}:{line} ({part}, layer {LAYERS[part]}) imports "
                                  f"{target} (layer {LAYERS.get(target)})")  # fmt: skip
    assert not violations, "\n".join(violations)


def test_the_engine_knows_no_markers_or_beams() -> None:
    forbidden = {"mechanics", "markererror", "kinematics", "mocap", "gait", "viz", "workflows", "cli"}
    for path in (PACKAGE / "uncertainty").rglob("*.py"):
        bad = {t for t, _ in imported_parts(path)} & forbidden
        assert not bad, f"{path.relative_to(PACKAGE)} imports {sorted(bad)}"


@pytest.mark.parametrize("path", modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_size(path: Path) -> None:
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(PACKAGE)} has {lines} lines (at most {MAX_LINES})"
