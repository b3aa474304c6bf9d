"""No source file of the package loads data in a way that can run code (issue 37): no
pickle, marshal, shelve, dill, cloudpickle or jsonpickle import, no ``eval``/``exec``,
no ``yaml.load`` without a safe loader, no ``np.load(..., allow_pickle=True)``, no
``torch.load``, ``pd.read_pickle`` or ``joblib.load``.

Checked on the syntax tree (imports and calls), so words in comments and docstrings
("evaluate", "pickled") and methods of our own named ``eval`` are not matched.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "fuzzygait"

#: Modules whose import is refused (their loading runs code by design).
UNSAFE_MODULES = frozenset({"pickle", "cPickle", "_pickle", "pickletools", "marshal", "shelve", "dill", "cloudpickle",
                            "jsonpickle", "copyreg"})  # fmt: skip
#: Builtins that run code given as data.
UNSAFE_BUILTINS = frozenset({"eval", "exec", "__import__"})
#: ``module.function`` calls that unpickle (by the last two parts of the dotted name).
UNSAFE_CALLS = frozenset({"torch.load", "pd.read_pickle", "pandas.read_pickle", "joblib.load", "yaml.unsafe_load",
                          "yaml.full_load", "yaml.load_all", "numpy.load_pickle"})  # fmt: skip
SAFE_YAML_LOADERS = frozenset({"SafeLoader", "CSafeLoader", "BaseLoader", "CBaseLoader"})


def _dotted(node: ast.expr) -> str:
    """``a.b.c`` of a name or attribute chain ("" for anything else)."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value)
        return f"{base}.{node.attr}" if base else ""
    return ""


def _keyword(call: ast.Call, name: str) -> ast.expr | None:
    return next((k.value for k in call.keywords if k.arg == name), None)


def _call_problem(call: ast.Call) -> str | None:
    name = _dotted(call.func)
    last_two = ".".join(name.split(".")[-2:])
    if name in UNSAFE_BUILTINS or name.split(".")[0] in UNSAFE_MODULES:
        return f"{name}()"
    if last_two in UNSAFE_CALLS or name.endswith(".read_pickle"):
        return f"{name}()"
    if name in ("importlib.import_module", "import_module") and call.args:
        target = call.args[0]
        if isinstance(target, ast.Constant) and str(target.value).split(".")[0] in UNSAFE_MODULES:
            return f"{name}({target.value!r})"
    if last_two in ("np.load", "numpy.load"):
        flag = _keyword(call, "allow_pickle")
        if flag is not None and not (isinstance(flag, ast.Constant) and flag.value is False):
            return f"{name}(allow_pickle={ast.unparse(flag)})"
    if last_two == "yaml.load":
        loader = _keyword(call, "Loader") or (call.args[1] if len(call.args) > 1 else None)
        if loader is None or _dotted(loader).split(".")[-1] not in SAFE_YAML_LOADERS:
            return f"{name}() without a safe Loader"
    return None


def unsafe_uses(source: str, filename: str = "<source>") -> list[str]:
    """``file:line: what`` of every unsafe import or call in ``source``."""
    found = []
    for node in ast.walk(ast.parse(source, filename)):
        problem = None
        if isinstance(node, ast.Import):
            bad = [a.name for a in node.names if a.name.split(".")[0] in UNSAFE_MODULES]
            problem = f"import {', '.join(bad)}" if bad else None
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            root = node.module.split(".")[0]
            names = {a.name for a in node.names}
            if root in UNSAFE_MODULES or (root in ("torch", "joblib") and "load" in names):
                problem = f"from {node.module} import {', '.join(sorted(names))}"
            elif root in ("builtins",) and names & UNSAFE_BUILTINS:
                problem = f"from builtins import {', '.join(sorted(names & UNSAFE_BUILTINS))}"
        elif isinstance(node, ast.Call):
            problem = _call_problem(node)
        if problem:
            found.append(f"{filename}:{node.lineno}: {problem}")
    return found


def test_the_package_loads_no_data_that_can_run_code() -> None:
    files = sorted(PACKAGE.rglob("*.py"))
    assert len(files) > 50
    root = PACKAGE.parents[1]
    found = [hit for p in files for hit in unsafe_uses(p.read_text(encoding="utf-8"), str(p.relative_to(root)))]
    assert not found, "unsafe loading in the package:\n" + "\n".join(found)


UNSAFE_SNIPPETS = [
    "import pickle", "import pickle as p", "from pickle import loads", "import marshal", "import shelve",
    "import dill", "from cloudpickle import dumps", "x = eval('1')", "exec(code)", "__import__('os')",
    "np.load(f, allow_pickle=True)", "numpy.load(f, allow_pickle=flag)", "torch.load(f)", "from torch import load",
    "pd.read_pickle(f)", "frame.read_pickle(f)", "joblib.load(f)", "yaml.load(text)",
    "yaml.load(text, Loader=yaml.Loader)", "yaml.load(text, yaml.FullLoader)", "yaml.unsafe_load(text)",
    "importlib.import_module('pickle')", "from builtins import eval", "marshal.loads(b)",
]  # fmt: skip
SAFE_SNIPPETS = [
    '"""Evaluate the model; the results were pickled once (not any more)."""',
    "# eval(x) and import pickle in a comment", "model.eval()", "evaluator.evaluate(x)", "np.load(f)",
    "np.load(f, allow_pickle=False)", "yaml.load(text, Loader=yaml.SafeLoader)", "yaml.safe_load(text)",
    "text = 'exec(code) import pickle'", "import json", "from fuzzygait.workflows.pickle_free import x",
]  # fmt: skip


@pytest.mark.parametrize("snippet", UNSAFE_SNIPPETS)
def test_unsafe_snippets_are_found_with_their_line(snippet: str) -> None:
    assert unsafe_uses(f"import numpy as np\n{snippet}\n", "mod.py") != []
    assert unsafe_uses(f"import numpy as np\n{snippet}\n", "mod.py")[0].startswith("mod.py:2: ")


@pytest.mark.parametrize("snippet", SAFE_SNIPPETS)
def test_safe_snippets_are_not_found(snippet: str) -> None:
    assert unsafe_uses(snippet) == []
