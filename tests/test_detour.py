"""A way that winds (longer than ``detour_ratio`` times the distance between its ends) is
planned again with the next seeds, and the quickest reference kept."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import dynfab.motion.guidance as guidance_module
from dynfab.motion.guidance import GuidanceSettings, JointGuidance, JointTarget
from dynfab.motion.joint_planning import JointPath
from dynfab.robots import load_robot

START = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
GOAL = START + np.array([0.6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
#: a way that winds: out 1 rad along joint 3 and back, then to the goal (winding 1 + 2/0.6)
WINDING = np.array([START, START + [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0], START, GOAL])
#: a way that winds less: out 0.5 rad and back
LESS = np.array([START, START + [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0], START, GOAL])
STRAIGHT = np.array([START, GOAL])


def _path(waypoints: np.ndarray, escaped_goal: bool = False) -> JointPath:
    return JointPath(waypoints, 0.0, 10, False, escaped_goal)


def test_the_winding_of_a_way_is_its_length_over_its_ends_distance_between_the_escapes() -> None:
    assert _path(STRAIGHT).winding == pytest.approx(1.0)
    assert _path(WINDING).winding == pytest.approx((2.0 + 0.6) / 0.6)
    escaped = _path(np.vstack([WINDING, GOAL + 0.01]), escaped_goal=True)   # the approach is not the way
    assert escaped.winding == pytest.approx((2.0 + 0.6) / 0.6)
    np.testing.assert_array_equal(escaped.inner, WINDING)
    assert _path(np.array([START, START])).winding == 1.0


@pytest.mark.parametrize("first, then, kept", [(WINDING, [LESS, STRAIGHT], STRAIGHT),
                                               (WINDING, [STRAIGHT, LESS], STRAIGHT),
                                               (LESS, [WINDING, WINDING], LESS),
                                               (STRAIGHT, [WINDING], STRAIGHT)])
def test_a_detour_is_planned_again_with_the_next_seeds_and_the_quickest_kept(monkeypatch, first, then,
                                                                             kept) -> None:
    panda = load_robot("panda")
    seeds: list[int] = []
    ways = [first, *then]

    def planned(checker, start, goal, lower, upper, settings, seed, approach=None, leave=None) -> JointPath:
        seeds.append(seed)
        return _path(ways[len(seeds) - 1])

    monkeypatch.setattr(guidance_module, "plan_joint_path", planned)
    guidance = JointGuidance(panda, replace(GuidanceSettings(), detour_tries=len(then)))
    plan = guidance.plan(START, JointTarget(tuple(GOAL)), [], seed=5)
    np.testing.assert_allclose(plan.trajectory.waypoints, kept)
    winds = _path(first).winding > guidance.settings.detour_ratio
    assert seeds == ([5, 6, 7][:1 + len(then)] if winds else [5])   # the next seeds, only after a detour
    assert plan.checks == 10 * len(seeds)
