"""The replan reasons' timers and tally, on a straight joint-space reference of the Panda."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.motion.guidance import GuidanceSettings, JointGuidance, Plan
from dynfab.motion.guidance_status import GuidanceStatus
from dynfab.motion.joint_trajectory import time_path
from dynfab.motion.replan_reasons import ReplanWatch, counted
from dynfab.robots import load_robot

SETTINGS = GuidanceSettings()
START, GOAL = np.zeros(7), np.array([1.0, 0, 0, 0, 0, 0, 0])


@pytest.fixture(scope="module")
def guidance() -> JointGuidance:
    return JointGuidance(load_robot("panda"), SETTINGS)


@pytest.fixture(scope="module")
def plan() -> Plan:
    trajectory = time_path(np.vstack([START, GOAL]), np.ones(7), np.ones(7), SETTINGS.timing)
    return Plan(trajectory, GOAL, 0.0, 0, 0.0, trajectory.duration)


@pytest.mark.parametrize(("reason", "count"), [("held", "replans_stalled"), ("short", "replans_stalled"),
                                               ("stalled", "replans_stalled"), ("refuge", "refuges"),
                                               ("blocked", "replans_blocked")])
def test_each_reason_counts_once_where_it_belongs(reason: str, count: str) -> None:
    status = counted(GuidanceStatus(), reason)
    assert getattr(status, count) == 1
    assert status.replans_stalled + status.refuges + status.replans_blocked == 1


def test_no_replan_and_a_return_count_nothing() -> None:
    assert counted(GuidanceStatus(), None) == GuidanceStatus()
    assert counted(GuidanceStatus(), "return") == GuidanceStatus()


def test_a_robot_lagging_on_the_way_is_held_after_stall_lag_time_and_a_restart_forgets_it(guidance, plan) -> None:
    watch = ReplanWatch(SETTINGS)
    lag = 2 * SETTINGS.lag_slow
    tau = 0.1 * plan.trajectory.duration   # the reference running, its clock advancing
    assert watch.reason(0.0, START, lag, plan, tau, False, guidance, None, ()) is None
    assert watch.reason(0.5 * SETTINGS.stall_lag_time, START, lag, plan, tau + 0.01, False, guidance, None, ()) is None
    late = 1.1 * SETTINGS.stall_lag_time
    assert watch.reason(late, START, lag, plan, tau + 0.02, False, guidance, None, ()) == "held"
    watch.restart(late, pause=False)
    assert watch.reason(late + 0.01, START, lag, plan, tau + 0.03, False, guidance, None, ()) is None


def test_after_the_reference_ended_a_robot_at_the_goal_waits_and_one_short_of_it_stalls(guidance, plan) -> None:
    ended = plan.trajectory.duration
    later = SETTINGS.stall_window + 0.1
    at_goal, short = ReplanWatch(SETTINGS), ReplanWatch(SETTINGS)
    near = GOAL - 0.5 * SETTINGS.stall_floor * np.eye(7)[0]
    away = GOAL - 0.3 * np.eye(7)[0]
    for watch, q in ((at_goal, near), (short, away)):
        assert watch.reason(0.0, q, 0.0, plan, ended, False, guidance, None, ()) is None
    assert at_goal.reason(later, near, 0.0, plan, ended, False, guidance, None, ()) is None
    assert short.reason(later, away, 0.0, plan, ended, False, guidance, None, ()) == "stalled"
