"""The inverse-kinematics residual evaluated through its CasADi buffer equals the
function's own evaluation, its Jacobian the finite differences, and results are not
overwritten by the next call."""

from __future__ import annotations

import numpy as np

from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget, ResidualFunction
from dynfab.robots import load_robot


def test_buffered_residual_equals_the_function_and_its_jacobian_the_differences() -> None:
    panda = load_robot("panda")
    targets = [PointTarget("panda_hand", (0.5, 0.2, 0.3), offset=(0.0, 0.0, 0.1)),
               AxisTarget("panda_hand", (0.0, 0.0, 1.0), (0.0, 0.0, -1.0))]
    residual = ResidualFunction(panda, targets)
    rng = np.random.default_rng(3)
    first = rng.uniform(-1.5, 1.5, panda.kinematics.dof)
    kept = residual(first)
    for _ in range(5):
        q = rng.uniform(-1.5, 1.5, panda.kinematics.dof)
        r, jacobian = residual(q)
        expected_r, expected_jacobian = residual.function(q)
        np.testing.assert_allclose(r, np.asarray(expected_r).ravel(), atol=1e-12)
        np.testing.assert_allclose(jacobian, np.asarray(expected_jacobian), atol=1e-12)
        step = 1e-6
        differences = np.stack([(residual(q + step * e)[0] - residual(q - step * e)[0]) / (2 * step)
                                for e in np.eye(q.size)], axis=1)
        np.testing.assert_allclose(jacobian, differences, atol=1e-6)
    np.testing.assert_allclose(kept[0], np.asarray(residual.function(first)[0]).ravel(), atol=1e-12)
