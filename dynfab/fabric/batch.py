"""Evaluate a planner function on many inputs at once (one row per environment).

The rows of a C-contiguous ``(N, m)`` array lie in memory exactly like the columns of the
``(m, N)`` column-major matrix CasADi's ``map`` takes, so the batch is handed to a mapped
function (``Function.map(N, "thread", threads)``) through buffers, without a copy. With the
C backend each row costs one call of the compiled code.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


#: mapped functions kept per evaluator (one per batch size and thread count)
_KEPT = 8


class BatchEvaluator:
    """Rows ``z = [q, q̇, p, previous command]`` (N, m) ↦ commands (N, k) for a planner
    function ``F: R^m → R^k``.

    The mapped functions are kept for the last few ``(N, threads)``; building one takes
    about a millisecond.
    """

    def __init__(self, function: ca.Function, n: int, nv: int, parameters: int) -> None:
        """``n`` configuration, ``nv`` velocity and ``parameters`` parameter entries per row."""
        self._function = function
        self._sections = (n, n + nv, n + nv + parameters, function.numel_in(0))
        self._mapped: dict[tuple[int, int], ca.Function] = {}

    def pack(self, template: np.ndarray, q: np.ndarray, qdot: np.ndarray, p: np.ndarray | None,
             previous: np.ndarray | None) -> np.ndarray:
        """The rows ``z`` (N, m): ``q`` (N, n), ``q̇`` (N, nv), ``p`` (N, parameters) and
        ``previous`` (N, nv); a ``None`` takes that part of ``template`` in every row.

        Raises:
            ValueError: for a wrong shape, or a non-finite entry (naming its row and part).
        """
        n, state, end, total = self._sections
        q = np.asarray(q, dtype=float)
        rows = q.shape[0] if q.ndim == 2 else -1
        z = np.empty((max(rows, 0), total))
        parts = (("Q", q, 0, n), ("Qdot", qdot, n, state), ("P", p, state, end), ("previous", previous, end, total))
        for name, part, first, last in parts:
            if part is None:
                z[:, first:last] = template[first:last]
                continue
            part = np.asarray(part, dtype=float)
            if part.shape != (rows, last - first):
                raise ValueError(f"{name} must have shape (N, {last - first}) with N rows like Q, got {part.shape}")
            z[:, first:last] = part
        finite = np.isfinite(z)
        if not finite.all():
            row, column = np.argwhere(~finite)[0]
            name = next(name for name, _, first, last in parts if first <= column < last)
            raise ValueError(f"row {row}: {name} contains NaN or infinity")
        return z

    def __call__(self, z: np.ndarray, threads: int) -> np.ndarray:
        """``F`` on every row of ``z`` (N, m) (C-contiguous floats), on ``threads`` threads."""
        if threads < 1:
            raise ValueError(f"threads must be >= 1, got {threads}")
        rows = z.shape[0]
        out = np.empty((rows, self._function.numel_out(0)))
        if rows == 0:
            return out
        threads = min(threads, rows)
        mapped = self._mapped.get((rows, threads))
        if mapped is None:
            if len(self._mapped) >= _KEPT:
                self._mapped.clear()
            mapped = self._mapped[(rows, threads)] = self._function.map(rows, "thread", threads)
        buffer, evaluate = mapped.buffer()
        buffer.set_arg(0, memoryview(z))
        buffer.set_res(0, memoryview(out))
        evaluate()
        return out
