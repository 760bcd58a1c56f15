"""Set cover: the greedy cover and the fewest cover on instances with known optima."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import sparse

from dynfab.geometry.set_cover import fewest_cover, greedy_cover, prune


def _matrix(rows: int, columns: list[set[int]]) -> sparse.csc_matrix:
    dense = np.zeros((rows, len(columns)), dtype=np.float32)
    for j, column in enumerate(columns):
        dense[sorted(column), j] = 1.0
    return sparse.csc_matrix(dense)


def _covers(cover: sparse.csc_matrix, chosen: list[int]) -> bool:
    return bool(np.all(np.asarray(cover[:, chosen].sum(axis=1)).ravel() > 0))


def test_greedy_is_fooled_where_the_fewest_cover_is_not() -> None:
    # rows 0..13; the optimum is the two halves, but greedy takes the 8-row column first and
    # then needs two more, none of them redundant
    halves = [set(range(7)), set(range(7, 14))]
    decoys = [{0, 1, 2, 3, 7, 8, 9, 10}, {4, 5, 11, 12}, {6, 13}]
    cover = _matrix(14, decoys + halves)
    greedy = prune(cover, greedy_cover(cover))
    assert sorted(greedy) == [0, 1, 2]
    assert fewest_cover(cover) == [3, 4]


def test_fewest_cover_matches_brute_force_on_random_instances() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        rows, columns = 12, 10
        dense = (rng.random((rows, columns)) < 0.3).astype(np.float32)
        dense[:, 0] += np.where(dense.sum(axis=1) == 0, 1.0, 0.0)  # every row coverable
        cover = sparse.csc_matrix(dense)
        best = next(size for size in range(1, columns + 1)
                    if any(_covers(cover, list(c)) for c in itertools.combinations(range(columns), size)))
        chosen = fewest_cover(cover)
        assert _covers(cover, chosen) and len(chosen) == best
        assert len(chosen) <= len(prune(cover, greedy_cover(cover)))


def test_rows_no_column_covers_are_ignored() -> None:
    cover = _matrix(4, [{0, 1}, {1, 2}])  # row 3 is coverable by nothing
    assert fewest_cover(cover) == [0, 1]
    assert sorted(prune(cover, greedy_cover(cover))) == [0, 1]


def test_costs_choose_the_cheaper_of_equally_small_covers() -> None:
    # both {0, 2} and {1, 2} cover; column 0 costs more
    cover = _matrix(4, [{0, 1}, {0, 1}, {2, 3}])
    assert fewest_cover(cover) == [0, 2]
    assert fewest_cover(cover, costs=np.array([1.5, 1.0, 1.0])) == [1, 2]
    # a cheap pair of columns beats one expensive column
    cover = _matrix(2, [{0, 1}, {0}, {1}])
    assert fewest_cover(cover, costs=np.array([3.0, 1.0, 1.0])) == [1, 2]


def test_a_matrix_too_large_to_reduce_keeps_the_greedy_cover(monkeypatch: pytest.MonkeyPatch) -> None:
    halves = [set(range(7)), set(range(7, 14))]
    decoys = [{0, 1, 2, 3, 7, 8, 9, 10}, {4, 5, 11, 12}, {6, 13}]
    cover = _matrix(14, decoys + halves)
    monkeypatch.setattr("dynfab.geometry.set_cover.DENSE_LIMIT", 14 * 5 - 1)
    assert fewest_cover(cover) == [0, 1, 2]
