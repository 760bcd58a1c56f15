"""Among moving obstacles a plan request makes ``moving_attempts`` attempts, not ``attempts``:
the scene changes within seconds, and a request that fails is made again as it changes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import dynfab.motion.guidance as guidance_module
from dynfab.geometry.shapes import Placement, Sphere
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance, JointTarget
from dynfab.motion.joint_planning import NoPathError
from dynfab.motion.placed_obstacle import any_moving
from dynfab.robots import load_robot

START = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
GOAL = START + np.array([0.6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
#: a sphere far from the arm, at rest and passing
RESTING = PlacedObstacle(Sphere(0.05), Placement((1.5, 0.0, 0.5)))
PASSING = replace(RESTING, velocity=(0.0, 0.3, 0.0))


def test_an_obstacle_moves_when_its_velocity_is_not_zero() -> None:
    assert not any_moving([]) and not any_moving([RESTING])
    assert any_moving([RESTING, PASSING]) and any_moving([replace(RESTING, velocity=(0.0, 0.0, -1e-9))])


@pytest.mark.parametrize("obstacles, moving_attempts, seeds", [((RESTING,), 1, [4, 5, 6]),
                                                               ((RESTING, PASSING), 1, [4]),
                                                               ((PASSING,), 2, [4, 5]),
                                                               ((PASSING,), 5, [4, 5, 6])])
def test_among_moving_obstacles_fewer_attempts_are_made(monkeypatch, obstacles, moving_attempts, seeds) -> None:
    tried: list[int] = []

    def finding_none(checker, start, goal, lower, upper, settings, seed, approach=None, leave=None):
        tried.append(seed)
        raise NoPathError("no_path", "none found")

    monkeypatch.setattr(guidance_module, "plan_joint_path", finding_none)
    monkeypatch.setattr(guidance_module, "escape_plan", lambda *args: None)
    settings = replace(GuidanceSettings(), moving_attempts=moving_attempts, tight_margin=0.01)   # no tight round
    guidance = JointGuidance(load_robot("panda"), settings)
    with pytest.raises(GuidanceError, match="none found"):
        guidance.plan(START, JointTarget(tuple(GOAL)), obstacles, seed=4)
    assert tried == seeds


def test_moving_attempts_must_be_at_least_one() -> None:
    with pytest.raises(ValueError, match="moving_attempts"):
        GuidanceSettings(moving_attempts=0)
