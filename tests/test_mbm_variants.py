"""MotionBenchMaker variants: the grasped object removed, invalid problems found on
Franka's meshes, and the moving sphere crossing the hand's straight path."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.moveit import SceneObject
from dynfab.benchmarks.mbm.moving_sphere import (CROSSING_TIMES, FIXED_LINKS, RADII, REACTION_TIME, SPEEDS,
                                                START_MARGIN)
from dynfab.benchmarks.mbm.problems import Problem, load_problems
from dynfab.benchmarks.mbm.variants import GRASPABLE_PREFIXES, prepare_case
from dynfab.geometry.shapes import Placement, Sphere
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes


@pytest.fixture(scope="module")
def table_pick() -> Problem:
    """table_pick/0009: a can to grasp among other graspable objects on a table."""
    return load_problems(["table_pick"], per_type=1)[0]


def test_object_removed_removes_exactly_the_object_to_grasp(table_pick: Problem) -> None:
    graspable = [o.id for o in table_pick.objects if o.id.startswith(GRASPABLE_PREFIXES)]
    assert len(graspable) > 1
    case = prepare_case(table_pick, "object-removed", franka())
    assert case.removed == "Can1"  # 10 mm from the open fingers at the goal; the others are >= 15 mm away
    names = [o.id for o in table_pick.objects]
    names.remove("Can1")
    assert list(case.obstacle_names) == names
    assert len(case.mapping["obstacles"]) == len(table_pick.objects) - 1
    assert case.invalid is None
    assert prepare_case(table_pick, "as-posed", franka()).removed is None


def test_invalid_problems_are_found(table_pick: Problem) -> None:
    robot = franka()
    beyond = dataclasses.replace(table_pick, goal=table_pick.goal[:3] + (-0.043,) + table_pick.goal[4:])
    expected = "goal: panda_joint4 = -0.043 is outside [-3.0718, -0.0698]"
    assert prepare_case(beyond, "as-posed", robot).invalid == expected
    rounded = dataclasses.replace(table_pick, goal=table_pick.goal[:3] + (-0.0698 + 5e-7,) + table_pick.goal[4:])
    case = prepare_case(rounded, "as-posed", robot)
    assert case.invalid is None and case.mapping["goal"][0]["position"][3] == -0.0698  # at the limit, clipped
    hand = robot.tcp(table_pick.start)
    block = SceneObject("block", "box", (0.15, 0.15, 0.15), tuple(hand), (1.0, 0.0, 0.0, 0.0))
    blocked = dataclasses.replace(table_pick, objects=table_pick.objects + (block,))
    invalid = prepare_case(blocked, "object-removed", robot).invalid
    assert invalid is not None and invalid.startswith("start: ") and "touches block" in invalid


def test_the_moving_sphere_crosses_the_hands_straight_path(table_pick: Problem) -> None:
    robot = franka()
    case = prepare_case(table_pick, "moving-sphere", robot, seed=3)
    sphere = case.mapping["obstacles"][-1]
    assert case.obstacle_names[-1] == "moving-sphere" and sphere["trajectory"]["type"] == "linear"
    assert RADII[0] <= sphere["radius"] <= RADII[1]
    start, velocity = np.array(sphere["trajectory"]["start"]), np.array(sphere["trajectory"]["velocity"])
    assert SPEEDS[0] <= np.linalg.norm(velocity) <= SPEEDS[1]
    a, b = robot.tcp(table_pick.start), robot.tcp(table_pick.goal)
    times = np.linspace(0.0, 10.0, 10001)
    centres = start + times[:, None] * velocity
    along = np.clip((centres - a) @ (b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    distances = np.linalg.norm(centres - (a + along[:, None] * (b - a)), axis=1)
    closest = int(np.argmin(distances))
    assert distances[closest] < 1e-3  # through the line, not beside it
    assert CROSSING_TIMES[0] - 0.01 <= times[closest] <= CROSSING_TIMES[1] + 0.01
    assert 0.3 < along[closest] < 0.7  # around the middle
    assert prepare_case(table_pick, "moving-sphere", robot, seed=3).mapping == case.mapping  # seeded
    assert prepare_case(table_pick, "moving-sphere", robot, seed=4).mapping != case.mapping


def test_the_moving_sphere_keeps_off_the_links_nothing_can_move_away() -> None:
    """bookshelf_thin/0016's first draw swept through the Panda's base (a collision no
    controller avoids); the sphere kept keeps START_MARGIN from link0 and link1 all run."""
    robot = franka()
    problem = load_problems(["bookshelf_thin"], per_type=1, skip=7)[0]
    assert problem.number == 16
    case = prepare_case(problem, "moving-sphere", robot, seed=0)
    sphere = case.mapping["obstacles"][-1]
    start, velocity = np.array(sphere["trajectory"]["start"]), np.array(sphere["trajectory"]["velocity"])
    times = np.arange(0.0, case.mapping["duration"] + 0.1, 0.1)
    grown = PlacedShape("sphere", Sphere(sphere["radius"] + START_MARGIN - 1e-3),
                        tuple(Placement(tuple(start + t * velocity)) for t in times))
    q = np.repeat(np.array([case.mapping["initial_state"]["q"]]), len(times), axis=0)
    touched = {contact.first for contact in sweep_meshes(robot.meshes, q, [grown]).obstacle_contacts}
    assert not touched & set(FIXED_LINKS)


def test_the_moving_sphere_leaves_the_arm_time_to_react() -> None:
    """Seed 14's table_under_pick/0100 drew a sphere 5 cm from the arm's shoulder coming at
    it at 0.46 m/s: it met panda_link2 at 0.25 s. The sphere kept keeps START_MARGIN from the
    arm at its start configuration over the first REACTION_TIME."""
    robot = franka()
    problem = load_problems(["table_under_pick"], per_type=1, skip=100 - 9)[0]
    assert problem.number == 100
    sphere = prepare_case(problem, "moving-sphere", robot, seed=14).mapping["obstacles"][-1]
    start, velocity = np.array(sphere["trajectory"]["start"]), np.array(sphere["trajectory"]["velocity"])

    def touches(radius: float, within: float) -> bool:
        times = np.arange(0.0, within + 1e-9, 0.05)
        grown = PlacedShape("sphere", Sphere(radius), tuple(Placement(tuple(start + t * velocity)) for t in times))
        q = np.repeat(np.array([problem.start]), len(times), axis=0)
        return bool(sweep_meshes(robot.meshes, q, [grown]).obstacle_contacts)

    assert not touches(sphere["radius"], 0.5)                                   # the old draw did at 0.25 s
    assert not touches(sphere["radius"] + START_MARGIN - 2e-3, REACTION_TIME)   # sampled every 0.1 s when drawn
    assert 0.0 < REACTION_TIME < CROSSING_TIMES[0]
