"""`fuzzy-sim --workers N` (issue 18, Deliver 3): the Graph Follower's (α, bound) tracks
run side by side and their simulations on the workers; the hulls, extremisers and
counts are the same for 1 and 2 workers, bit for bit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support import run

from fuzzygait.uncertainty.storage import load_result


@pytest.mark.slow
def test_fuzzy_sim_hulls_do_not_depend_on_the_workers(tmp_path: Path) -> None:
    results = {}
    for workers in (1, 2):
        out = tmp_path / f"w{workers}.nc"
        done = run("fuzzy-sim", "swing", "--fuzzy", "E=10%,rho=5%", "--duration", "0.1", "--nodes", "6",
                   "--stride", "20", "--workers", str(workers), "--out", out)  # fmt: skip
        assert done.returncode == 0, done.stderr
        results[workers] = load_result(out)
    one, two = results[1], results[2]
    assert one.attrs["tracks"] == "side-by-side" and one.attrs["workers"] == 1 and two.attrs["workers"] == 2
    assert np.array_equal(one["hull"].values, two["hull"].values)
    assert np.array_equal(one["extremiser"].values, two["extremiser"].values)
    assert one.attrs["forward_simulations"] == two.attrs["forward_simulations"] > 1
    lower, upper = one["hull"].sel(alpha=0.0).values
    assert np.all(lower <= upper) and np.any(upper > lower)
