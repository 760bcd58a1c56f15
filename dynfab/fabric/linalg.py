"""Small symbolic linear algebra kernels that keep CasADi SX graphs short.

The planner's cost per step is the number of SX instructions it evaluates, so the two
operations it does most, the congruence ``Jᵀ M J`` of a pullback and the solve
``M⁻¹ b`` of the root, are written to exploit symmetry and structural sparsity.
"""

from __future__ import annotations

import casadi as ca


def congruence(jacobian: ca.SX, metric: ca.SX) -> ca.SX:
    """Return the symmetric product ``Jᵀ M J`` for a symmetric metric ``M``.

    Only the upper triangle is computed (``n(n+1)/2`` dot products instead of ``n²``) and
    columns of ``J`` that are structurally zero are skipped, so pulling a 1-D task through
    a selector row costs one multiplication.

    Args:
        jacobian: ``J`` of shape (m, n).
        metric: symmetric ``M`` of shape (m, m).

    Returns:
        The (n, n) symmetric matrix ``Jᵀ M J``.
    """
    n = jacobian.shape[1]
    metric_jacobian = ca.mtimes(metric, jacobian)
    columns = [jacobian[:, i] for i in range(n)]
    weighted = [metric_jacobian[:, j] for j in range(n)]
    used = [columns[i].nnz() > 0 for i in range(n)]
    result = ca.SX(n, n)
    for i in range(n):
        if not used[i]:
            continue
        for j in range(i, n):
            if not used[j]:
                continue
            entry = ca.dot(columns[i], weighted[j])
            result[i, j] = entry
            if i != j:
                result[j, i] = entry
    return result


def cholesky_solve(matrix: ca.SX, rhs: ca.SX) -> ca.SX:
    """Solve ``A y = b`` for a symmetric positive definite ``A`` by an unrolled Cholesky.

    ``A = L Lᵀ`` costs about n³/6 multiplications and n square roots; the two triangular
    solves about n² each. The caller guarantees positive definiteness (the planner adds a
    base metric ``c I`` with ``c > 0`` to every root metric).

    Args:
        matrix: SPD matrix ``A`` of shape (n, n).
        rhs: right-hand side ``b`` of shape (n, 1).

    Returns:
        ``y = A⁻¹ b`` of shape (n, 1).
    """
    n = matrix.shape[0]
    lower = [[ca.SX(0) for _ in range(n)] for _ in range(n)]
    inverse_diagonal = [ca.SX(0)] * n
    for j in range(n):
        diagonal = matrix[j, j] - sum((lower[j][k] ** 2 for k in range(j)), ca.SX(0))
        root = ca.sqrt(diagonal)
        lower[j][j] = root
        inverse_diagonal[j] = 1 / root
        for i in range(j + 1, n):
            off = matrix[i, j] - sum((lower[i][k] * lower[j][k] for k in range(j)), ca.SX(0))
            lower[i][j] = off * inverse_diagonal[j]
    forward = [ca.SX(0)] * n
    for i in range(n):
        forward[i] = (rhs[i] - sum((lower[i][k] * forward[k] for k in range(i)), ca.SX(0))) * inverse_diagonal[i]
    solution = [ca.SX(0)] * n
    for i in reversed(range(n)):
        solution[i] = (
            forward[i] - sum((lower[k][i] * solution[k] for k in range(i + 1, n)), ca.SX(0))
        ) * inverse_diagonal[i]
    return ca.vertcat(*solution)
