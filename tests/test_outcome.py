"""A run's outcome keys say what did the work (docs/design.md section 5.5, scenario/outcome.py):
the planner alone, braking fallbacks, stall recovery (tests/test_stall_recovery.py),
guidance (tests/test_guidance.py) or, for the MPC, its fallback on failed solves; in the
kinematic simulator and under MuJoCo."""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import numpy as np
import pytest

from dynfab.fabric.planner import FabricPlanner
from dynfab.mpc.problem import MpcProblem
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict

#: The point robot crosses 2 m past a disc off its straight line.
POINT: dict[str, Any] = {
    "robot": "point", "planner": "static-fabric", "dt": 0.01, "duration": 8.0,
    "initial_state": {"q": [-1.0, 0.0]},
    "goal": [{"type": "position", "link": "point", "position": [1.0, 0.0], "tolerance": 0.05}],
    "obstacles": [{"type": "sphere", "position": [0.0, 0.3], "radius": 0.2}],
}
#: tests/test_mujoco_scenario.py's Panda among spheres, shortened.
PANDA: dict[str, Any] = {
    "robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 0.5,
    "initial_state": {"q": [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]},
    "goal": [{"type": "position", "link": "panda_hand", "position": [0.55, -0.35, 0.25], "tolerance": 0.05}],
    "obstacles": [{"type": "sphere", "position": [0.5, 0.15, 0.35], "radius": 0.15}],
}
#: every this many planner calls the output is made non-finite (injected_failures)
EVERY = 7


def _metrics(data: dict[str, Any], **changes: Any):
    return run_scenario(scenario_from_dict({**copy.deepcopy(data), **changes})).metrics


@pytest.fixture
def injected_failures(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Every fabric planner made from now on returns a non-finite output on every
    :data:`EVERY`-th call; the list counts the outputs spoiled."""
    spoiled: list[int] = []
    build = FabricPlanner.__init__

    def flaky_init(self: FabricPlanner, *args: Any, **kwargs: Any) -> None:
        build(self, *args, **kwargs)
        evaluate, calls = self._evaluate, [0]

        def flaky() -> None:
            evaluate()
            calls[0] += 1
            if calls[0] % EVERY == 0:
                self._output[:] = np.nan
                spoiled.append(calls[0])

        self._evaluate = flaky

    monkeypatch.setattr(FabricPlanner, "__init__", flaky_init)
    return spoiled


def test_a_success_of_the_fabric_alone_says_nothing_helped() -> None:
    metrics = _metrics(POINT)
    assert metrics.success and metrics.failure is None
    assert (metrics.guided, metrics.plans, metrics.plan_time_ms, metrics.recovered, metrics.fallbacks) == \
        (False, 0, None, 0, 0)


@pytest.mark.parametrize("simulator, guidance", [("kinematic", False), ("kinematic", True), ("mujoco", False),
                                                 ("mujoco", True)])
def test_every_braked_output_is_a_fallback(injected_failures: list[int], simulator: str, guidance: bool) -> None:
    metrics = _metrics(PANDA, simulator=simulator, guidance=guidance, recovery=False)
    assert len(injected_failures) >= 50 // EVERY   # 50 control periods
    assert metrics.fallbacks == len(injected_failures)
    assert metrics.guided is guidance and metrics.plans == int(guidance)


def test_the_mpc_counts_its_failed_solves_as_fallbacks(monkeypatch: pytest.MonkeyPatch) -> None:
    solve, solves = MpcProblem.solve, [0]

    def every_other_fails(self: MpcProblem, *args: Any, **kwargs: Any):
        result = solve(self, *args, **kwargs)
        solves[0] += 1
        return dataclasses.replace(result, success=result.success and solves[0] % 2 == 1)

    monkeypatch.setattr(MpcProblem, "solve", every_other_fails)
    metrics = _metrics(POINT, planner="mpc", duration=2.0)
    assert solves[0] == 20   # at 10 Hz
    assert (metrics.guided, metrics.plans, metrics.recovered, metrics.fallbacks) == (False, 0, 0, 10)


def test_a_clean_mpc_run_says_nothing_helped() -> None:
    metrics = _metrics(POINT, planner="mpc", duration=2.0)
    assert (metrics.guided, metrics.plans, metrics.plan_time_ms, metrics.recovered, metrics.fallbacks) == \
        (False, 0, None, 0, 0)
