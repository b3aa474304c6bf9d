"""Every notebook in ``notebooks/`` runs from top to bottom without error.

The notebooks are executed with nbclient in a kernel that is guaranteed to be *this*
interpreter (the venv the tests run in, with fuzzygait installed): the test writes a
private ``python3`` kernel spec whose ``argv`` is ``sys.executable`` into a temporary
folder and hands nbclient a kernel manager that only looks there. A ``python3`` spec
registered by the user or the system (possibly pointing at another Python) is thereby
never picked up. The kernel runs in a temporary working directory, so nothing is written
into the repository.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import nbformat
import pytest

import fuzzygait
from ipykernel.kernelspec import write_kernel_spec
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import AsyncKernelManager
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
KERNEL_NAME = "python3"  # the name ipykernel-aware managers give an in-memory history
CHECK_MARKER = "kernel-check:"


@pytest.fixture(scope="module")
def kernel_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding one kernel spec that launches ``sys.executable``."""
    root = tmp_path_factory.mktemp("kernels")
    write_kernel_spec(root / KERNEL_NAME)  # argv: [sys.executable, -m, ipykernel_launcher, ...]
    return root


def execute(path: Path, kernel_dir: Path, workdir: Path) -> nbformat.NotebookNode:
    """Run the notebook at ``path`` (plus a cell reporting the kernel's interpreter)."""
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(
        nbformat.v4.new_code_cell(
            "import sys, fuzzygait\n"
            f"print({CHECK_MARKER!r}, sys.prefix)\n"
            f"print({CHECK_MARKER!r}, fuzzygait.__file__)"
        )
    )
    specs = KernelSpecManager(kernel_dirs=[str(kernel_dir)], ensure_native_kernel=False)
    km = AsyncKernelManager(kernel_name=KERNEL_NAME, kernel_spec_manager=specs)
    client = NotebookClient(nb, km=km, timeout=300, resources={"metadata": {"path": str(workdir)}})
    client.execute(cleanup_kc=True)  # we passed the manager in: still shut the kernel down
    return nb


def stream_text(nb: nbformat.NotebookNode) -> str:
    """Everything the code cells printed to stdout."""
    return "".join(
        output.get("text", "")
        for cell in nb.cells
        if cell.cell_type == "code"
        for output in cell.outputs
        if output.output_type == "stream" and output.name == "stdout"
    )


def test_notebooks_exist() -> None:
    assert NOTEBOOKS, "no notebooks found in notebooks/"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stored_without_outputs(path: Path) -> None:
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.outputs, f"{path.name}: clear the outputs before committing"
            assert cell.execution_count is None, f"{path.name}: clear the execution counts"


@pytest.mark.slow  # each notebook runs in its own kernel
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path: Path, kernel_dir: Path, tmp_path: Path) -> None:
    before = sorted(p.name for p in (ROOT / "notebooks").iterdir())
    nb = execute(path, kernel_dir, tmp_path)  # raises CellExecutionError on any failing cell
    text = stream_text(nb)

    # the kernel was this interpreter, importing the same fuzzygait as the tests
    reported = [line.split(CHECK_MARKER, 1)[1].strip() for line in text.splitlines() if CHECK_MARKER in line]
    assert reported[0] == sys.prefix
    assert Path(reported[1]).resolve() == Path(fuzzygait.__file__).resolve()
    # nothing was written beside the notebooks (the kernel ran in tmp_path)
    assert sorted(p.name for p in (ROOT / "notebooks").iterdir()) == before

    if path.name == "01_graph_follower_pendulum.ipynb":
        check_pendulum(text)
    if path.name == "03_frv_stance.ipynb":
        check_frv_stance(text)


def check_pendulum(text: str) -> None:
    """The Graph Follower hulls match dense sampling and need far fewer simulations."""
    error = re.search(r"max hull error: ([0-9.eE+-]+) % of the amplitude", text)
    assert error, "the notebook no longer prints its max hull error line"
    assert float(error.group(1)) < 0.5
    counts = re.search(r"model evaluations: Graph Follower (\d+), dense sampling (\d+)", text)
    assert counts, "the notebook no longer prints its evaluation counts"
    assert int(counts.group(1)) < int(counts.group(2))
    assert "loaded result equals the computed one" in text


def check_frv_stance(text: str) -> None:
    """The FRV-GFA study needs far fewer intervals than possible and adding samples to the
    stored study needs (almost) no new forward simulations; the Monte Carlo check ran."""
    intervals = re.search(r"possible intervals \(Eq. 2.32\): (\d+)\n\s+occurring intervals: (\d+)", text)
    assert intervals, "the notebook no longer prints its interval counts"
    assert int(intervals.group(2)) < int(intervals.group(1))
    added = re.search(r"new forward simulations when adding 1000 samples: (\d+) \(first run: (\d+)\)", text)
    assert added, "the notebook no longer prints the forward simulations of the added samples"
    assert int(added.group(1)) <= 2 < int(added.group(2))
    assert len(re.findall(r"KS statistic [0-9.]+, p = [0-9.]+", text)) == 8
