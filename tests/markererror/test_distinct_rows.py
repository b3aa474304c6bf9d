"""Rows a compiled model computes once (:func:`~fuzzygait.markererror.row_kernel.distinct_rows`):
the blocks of one model screening the same random deviations at the same frames.

Truth: rows built as copies of known rows (the indices are known), rows that differ in one
entry by one unit in the last place, and the model's own values row by row.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.markererror.row_kernel import MIN_ROWS_TO_SHARE, distinct_rows


def copies(n: int = 400, repeats: int = 3) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    P, nodes = rng.normal(size=(n, 12)), rng.integers(0, 50, n)
    return np.tile(nodes, repeats), np.tile(P, (repeats, 1))


def test_repeated_rows_are_found_exactly() -> None:
    nodes, P = copies()
    first, inverse = distinct_rows(nodes, P)  # type: ignore[misc]
    assert first.size == 400
    np.testing.assert_array_equal(P[first[inverse]], P)
    np.testing.assert_array_equal(nodes[first[inverse]], nodes)


def test_rows_that_differ_by_one_ulp_are_not_merged() -> None:
    """The same deviations at another frame, or one entry one ulp away, are other rows."""
    nodes, P = copies()
    P[400:800, 5] = np.nextafter(P[400:800, 5], np.inf)
    nodes[800:] += 1
    assert distinct_rows(nodes, P) is None  # every row distinct: nothing to share


def test_no_sharing_where_it_cannot_pay_or_cannot_be_told() -> None:
    """Fewer than MIN_ROWS_TO_SHARE rows, a first row that does not repeat, or NaN rows."""
    nodes, P = copies(n=MIN_ROWS_TO_SHARE // 4, repeats=3)
    assert distinct_rows(nodes, P) is None
    nodes, P = copies()
    P[0, 0] += 1.0
    assert distinct_rows(nodes, P) is None
    nodes, P = copies()
    P[:, 3] = np.nan
    assert distinct_rows(nodes, P) is None
