"""How a run went, in its metrics: guidance, recovery, fallbacks and, for a failure, why
(docs/design.md section 5.5: ``guided``, ``plans``, ``plan_time_ms``, ``recovered``, ``fallbacks``,
``goal_moved``, ``failure``).

A ``success`` the fabric earned alone reads ``guided: false, recovered: 0, fallbacks: 0``.
Every controller a run can have fills these keys:

| controller | `guided` | `plans` | `recovered` | `fallbacks` |
|---|---|---|---|---|
| guided fabric (a path goal: the fabric follows the path, guidance takes over at its end) | true (false once guidance found no plan and the scenario's own fabric took over) | plans made: the first, replans, recovery paths (an attempt that found no plan is not counted; a failed first plan's wall time is `plan_time_ms`) | replans (blocked, stalled), recovery paths | braking actions, plus 1 if the fabric took over |
| fabric, with or without stall recovery | false | recovery paths | recovery paths | braking actions |
| MPC | false | 0 | 0 | failed solves (the last plan or braking executed) |

A replayed recording (no controller) leaves them ``None``: what helped is not recorded.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from dynfab.mpc import MpcController
from dynfab.scenario.controllers import Controller
from dynfab.scenario.camera_controller import CameraController
from dynfab.scenario.guided_controller import GuidedController
from dynfab.scenario.path_end import PathEndController
from dynfab.scenario.metrics import Metrics

__all__ = ["with_outcome"]


def with_outcome(metrics: Metrics, controller: Controller | None, goal_positions: np.ndarray,
                 goal_reference: np.ndarray) -> Metrics:
    """``metrics`` with the outcome fields of the run's controller (None for a replayed
    recording) and ``final_distance`` from the primary goal's coordinates (T, d) and its
    reference (T, d)."""
    final = float(np.linalg.norm(goal_positions[-1] - goal_reference[-1])) if len(goal_positions) else None
    outcome: dict[str, object] = {"final_distance": final, "failure": _failure(metrics)}
    if isinstance(controller, CameraController):  # fed by a camera: the outcome is its controller's
        controller = controller.inner
    if isinstance(controller, GuidedController | PathEndController):   # a path's end: guided after its time
        status = controller.status
        recoveries = len(controller.recovery_times)
        fell_back = controller.fallback is not None   # the first plan failed
        outcome.update(guided=status.guided and not fell_back,
                       plans=status.plans + recoveries, plan_time_ms=status.plan_time_ms,
                       recovered=status.replans_blocked + status.replans_stalled + status.refuges + recoveries,
                       fallbacks=controller.fallback_count + fell_back, goal_moved=status.goal_moved)
        if fell_back and not metrics.success:
            outcome["failure"] = status.failure
    elif isinstance(controller, MpcController):
        outcome.update(guided=False, plans=0, recovered=0, fallbacks=controller.failures, goal_moved=False)
    elif controller is not None:   # a fabric controller, with stall recovery or without
        recoveries = len(getattr(controller, "recovery_times", []))
        planner = getattr(controller, "planner", None)
        outcome.update(guided=False, plans=recoveries, recovered=recoveries,
                       fallbacks=int(getattr(planner, "fallback_count", 0)), goal_moved=False)
    return dataclasses.replace(metrics, **outcome)


def _failure(metrics: Metrics) -> str | None:
    if metrics.success:
        return None
    if metrics.collision:
        return "collision"
    if metrics.self_collision:
        return "self_collision"
    return "stalled"
