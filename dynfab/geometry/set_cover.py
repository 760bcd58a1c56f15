"""Set cover: choose few columns of a boolean matrix so that every row has a chosen column.

Rows are things to cover (surface samples, near-contact configurations), columns the
candidates that may cover them (spheres, sphere pairs); ``cover[i, j]`` is true when
candidate ``j`` covers row ``i``. Two solvers:

- :func:`greedy_cover` then :func:`prune`: take the candidate that covers most uncovered
  rows until all are covered, then drop candidates the others make redundant; fast, at
  most ``H(max column size)`` times the optimum (about 1.2-1.4 times on the meshes here);
- :func:`fewest_cover`: the minimum number (or total cost ``w``) of columns, as the
  integer program

      minimise  Σ_j w_j x_j   subject to   cover x >= 1,   x_j in {0, 1}

  solved by HiGHS (``scipy.optimize.milp``) within a time limit on the reduced problem:
  a column whose rows another column also covers is dropped (some optimum never needs
  it), then a row whose columns include all columns of another row (covering that one
  covers it). The greedy solution is kept whenever the solver returns nothing better.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.optimize import Bounds, LinearConstraint, milp

__all__ = ["fewest_cover", "greedy_cover", "prune"]

#: Largest cover matrix (rows x columns) that :func:`fewest_cover` reduces as a dense
#: float32 array (160 MB); larger problems keep the greedy cover.
DENSE_LIMIT = 40_000_000


def greedy_cover(cover: sparse.csc_matrix, costs: np.ndarray | None = None) -> list[int]:
    """Columns, best first (most newly covered rows per cost), until every coverable row
    is covered."""
    uncovered = np.ones(cover.shape[0], dtype=np.float32)
    chosen: list[int] = []
    while uncovered.any():
        gains = cover.T @ uncovered if costs is None else (cover.T @ uncovered) / costs
        best = int(np.argmax(gains))
        if gains[best] <= 0.0:
            break
        chosen.append(best)
        uncovered[cover[:, best].indices] = 0.0
    return chosen


def prune(cover: sparse.csc_matrix, chosen: list[int]) -> list[int]:
    """Drop chosen columns (latest first) whose rows the other chosen columns cover."""
    kept = list(chosen)
    counts = np.asarray(cover[:, kept].sum(axis=1)).ravel()
    for candidate in reversed(chosen):
        rows = cover[:, candidate].indices
        if np.all(counts[rows] >= 2):
            kept.remove(candidate)
            counts[rows] -= 1
    return kept


def fewest_cover(cover: sparse.csc_matrix, costs: np.ndarray | None = None,
                 time_limit: float = 20.0) -> list[int]:
    """The fewest columns (or the cheapest, with positive ``costs`` per column) that cover
    every coverable row, sorted; the pruned greedy cover if the solver finds nothing
    better within ``time_limit`` [s] or the matrix exceeds :data:`DENSE_LIMIT` entries."""
    weights = np.ones(cover.shape[1]) if costs is None else np.asarray(costs, dtype=float)
    greedy = prune(cover, greedy_cover(cover, weights))
    coverable = np.flatnonzero(np.asarray(cover.sum(axis=1)).ravel() > 0)
    if not greedy or (costs is None and len(greedy) == 1) or len(coverable) * cover.shape[1] > DENSE_LIMIT:
        return sorted(greedy)
    columns = _kept(sparse.csc_matrix(cover[coverable], dtype=np.float32), keep_largest=True, costs=weights)
    reduced = sparse.csc_matrix(cover[coverable][:, columns], dtype=np.float32)
    rows = _kept(reduced.T.tocsc(), keep_largest=False)
    matrix = sparse.csr_matrix(reduced[rows], dtype=float)
    result = milp(weights[columns], constraints=LinearConstraint(matrix, lb=1.0),
                  integrality=np.ones(len(columns)), bounds=Bounds(0.0, 1.0),
                  options={"time_limit": time_limit})
    if result.x is None:
        return sorted(greedy)
    chosen = [int(columns[j]) for j in np.flatnonzero(result.x > 0.5)]
    return sorted(chosen) if weights[chosen].sum() < weights[greedy].sum() - 1e-9 else sorted(greedy)


def _kept(sets: sparse.csc_matrix, keep_largest: bool, costs: np.ndarray | None = None) -> np.ndarray:
    """Indices of the columns of ``sets`` (each column a set of rows) that are kept when
    every column inside a larger one (``keep_largest``) or holding a smaller one (not
    ``keep_largest``) is dropped; of equal columns the first is kept. With ``costs``, a
    column is only dropped for one that costs no more."""
    dense = sets.toarray().astype(np.float32)
    overlap = dense.T @ dense  # dense BLAS: these matrices are a third full or more
    size = np.diag(overlap)
    index = np.arange(len(size))
    if keep_largest:  # drop j if j lies inside k, k larger or an earlier equal
        related = overlap >= size[:, None] - 0.5
        ranked = (size[None, :] > size[:, None]) | ((size[None, :] == size[:, None]) & (index[None, :] < index[:, None]))
    else:  # drop j if k lies inside j, k smaller or an earlier equal
        related = overlap >= size[None, :] - 0.5
        ranked = (size[None, :] < size[:, None]) | ((size[None, :] == size[:, None]) & (index[None, :] < index[:, None]))
    dominated = related & ranked
    if costs is not None:
        dominated &= costs[None, :] <= costs[:, None]
    return np.flatnonzero(~dominated.any(axis=1))
