"""``FabricPlanner.compute_batch``: every row equals ``compute`` (VM and C), per-row
parameters and previous commands, the fallback per row, errors naming the row."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dynfab.fabric.c_backend import find_compiler
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot

PANDA = load_robot("panda")
CONFIG = PlannerConfig(goals=(GoalConfig(link="panda_hand"),), obstacle_slots=2)
BACKENDS = ["vm", pytest.param("c", marks=pytest.mark.skipif(find_compiler() is None, reason="no C compiler"))]


def _states(rows: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return PANDA.default_q + rng.normal(0, 0.4, (rows, 7)), rng.normal(0, 0.5, (rows, 7))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("threads", [1, 2])
def test_rows_equal_single_calls_with_per_row_parameters(backend: str, threads: int) -> None:
    planner = FabricPlanner(PANDA, dataclasses.replace(CONFIG, backend=backend))
    rng = np.random.default_rng(0)
    q, qdot = _states(37, rng)
    p = np.tile(planner._input[14:], (37, 1))  # goal (3), weight, 2 obstacle centres (6), 2 radii
    p[:, :3] = rng.uniform(-0.6, 0.6, (37, 3))
    p[:, 4:10] = rng.uniform(-0.8, 0.8, (37, 6))
    p[:, 10:] = rng.uniform(0.05, 0.2, (37, 2))
    batch = planner.compute_batch(q, qdot, p, threads=threads)
    assert batch.shape == (37, 7)
    for i in range(37):
        planner._input[14:] = p[i]
        np.testing.assert_allclose(batch[i], planner.compute(q[i], qdot[i]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_without_parameters_every_row_uses_the_current_ones(backend: str) -> None:
    planner = FabricPlanner(PANDA, dataclasses.replace(CONFIG, backend=backend))
    planner.parameters.goal_position[0][:] = [0.5, -0.3, 0.4]
    planner.parameters.obstacle_position[0] = [0.4, 0.2, 0.5]
    planner.parameters.obstacle_radius[0] = 0.15
    q, qdot = _states(5, np.random.default_rng(1))
    batch = planner.compute_batch(q, qdot)
    np.testing.assert_allclose(batch, [planner.compute(a, b) for a, b in zip(q, qdot)], rtol=0, atol=1e-12)


def test_jerk_limited_rows_take_their_own_previous_command() -> None:
    limits = dataclasses.replace(PANDA.limits, jerk=np.full(7, 50.0))  # binds: 0.5 rad/s^2 per period
    planner = FabricPlanner(PANDA, dataclasses.replace(CONFIG, limits=limits))
    rng = np.random.default_rng(2)
    q, qdot = _states(6, rng)
    previous = rng.normal(0, 3.0, (6, 7))
    batch = planner.compute_batch(q, qdot, previous=previous)
    for i in range(6):
        planner._previous_command[:] = previous[i]
        np.testing.assert_allclose(batch[i], planner.compute(q[i], qdot[i]), rtol=0, atol=1e-12)
    planner._previous_command[:] = 0.0
    assert not np.allclose(planner.compute_batch(q, qdot), batch)


def test_non_finite_rows_get_the_fallback_and_others_do_not() -> None:
    planner = FabricPlanner(PANDA, dataclasses.replace(CONFIG, bound_command=False))
    q, qdot = _states(4, np.random.default_rng(3))
    qdot[2] = 1e200  # finite input whose fabric command overflows
    batch = planner.compute_batch(q, qdot)
    assert np.isfinite(batch).all() and planner.fallback_count == 1
    np.testing.assert_allclose(batch[2], -planner.config.fallback_braking * qdot[2])
    np.testing.assert_allclose(batch[1], planner.compute(q[1], qdot[1]), rtol=0, atol=1e-12)


def test_bad_rows_and_shapes_are_named() -> None:
    planner = FabricPlanner(PANDA, CONFIG)
    q, qdot = _states(3, np.random.default_rng(4))
    qdot[1, 3] = np.nan
    with pytest.raises(ValueError, match="row 1: Qdot contains NaN or infinity"):
        planner.compute_batch(q, qdot)
    with pytest.raises(ValueError, match=r"P must have shape \(N, 12\)"):
        planner.compute_batch(q, np.zeros((3, 7)), np.zeros((3, 11)))
    assert planner.compute_batch(np.zeros((0, 7)), np.zeros((0, 7))).shape == (0, 7)
