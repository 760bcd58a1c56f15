"""Blocked endpoints judged on the robot's meshes (issue 20): a start the spheres refuse and
the meshes find free is left along a segment clear of the meshes (the mirror of a goal's
approach), and in a scene of meshes an endpoint free on the meshes is judged on them alone
(coal, mesh-mesh) where the spheres' test and theirs together find no escape, while one the
meshes refuse too keeps the spheres' test and fails with its reason."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import dynfab.motion.joint_planning as joint_planning
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance, JointTarget
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots import load_robot
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict
from wall_scene import AWAY, MESH_WALL, WALL, WALL_ENTRY, goal_near_the_wall


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def touching(panda) -> np.ndarray:
    """The spheres touching the wall; the meshes are farther (refused by the spheres, free
    on the meshes)."""
    return goal_near_the_wall(panda, 0.0)


def _first_segment(plan) -> np.ndarray:
    trajectory = plan.trajectory
    first = trajectory.phases[0] if hasattr(trajectory, "phases") else trajectory
    return first.waypoints[:2]


def test_a_start_free_on_the_meshes_is_left_clear_of_them(panda, touching) -> None:
    guidance = JointGuidance(panda)
    plan = guidance.plan(touching, JointTarget(tuple(AWAY)), [WALL])
    meshes = guidance._meshes()
    at_start = meshes.clearance(touching)[0]
    assert at_start >= meshes.margin and guidance.checker.clearances(touching)[0] < guidance.settings.path.margin
    a, b = _first_segment(plan)
    np.testing.assert_array_equal(a, touching)
    line = a + np.linspace(0.0, 1.0, 101)[:, None] * (b - a)
    assert meshes.clearance(line)[0] >= min(guidance.settings.approach_clearance, at_start) - 1e-4


def test_the_meshes_decide_the_way_out_of_a_start_they_find_free(panda, touching, monkeypatch) -> None:
    monkeypatch.setattr(MeshGoalCheck, "segment_free", lambda self, a, b, step, floor=None: False)
    with pytest.raises(GuidanceError) as refused:
        last_resorts_off = GuidanceSettings(mesh_escape=None, tight_margin=GuidanceSettings().path.margin)
        JointGuidance(panda, last_resorts_off).plan(touching, JointTarget(tuple(AWAY)), [WALL])
    assert refused.value.reason == "start_in_collision"


def test_among_meshes_the_meshes_alone_judge_endpoints_they_find_free(panda, touching, monkeypatch) -> None:
    # AWAY's spheres clear the wall by 12.0 mm; the mesh grid reads 9.5 mm there (its bound
    # between exact nodes): a margin of 5 mm keeps AWAY free, as the test needs
    settings = GuidanceSettings()
    guidance = JointGuidance(panda, replace(settings, path=replace(settings.path, margin=0.005)))
    guidance.checker.set_obstacles([MESH_WALL])
    assert guidance.checker.free(AWAY, 0.005, 0.0)
    assert guidance._meshes().free(touching)   # coal: the robot's meshes against the wall's triangles
    monkeypatch.setattr(joint_planning, "_no_deeper", lambda *args: False)   # the spheres refuse every segment
    to_wall = guidance.plan(AWAY, JointTarget(tuple(touching)), [MESH_WALL])
    assert to_wall.approach > 0.0
    from_wall = guidance.plan(touching, JointTarget(tuple(AWAY)), [MESH_WALL])
    np.testing.assert_array_equal(_first_segment(from_wall)[0], touching)


def test_among_meshes_an_endpoint_the_meshes_refuse_keeps_the_spheres_test(panda, monkeypatch) -> None:
    deep = goal_near_the_wall(panda, -0.04)
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([MESH_WALL])
    assert guidance._meshes().clearance(deep)[0] < guidance.settings.mesh_margin
    monkeypatch.setattr(joint_planning, "_no_deeper", lambda *args: False)
    with pytest.raises(GuidanceError) as refused:
        guidance.plan(AWAY, JointTarget(tuple(deep)), [MESH_WALL])
    assert refused.value.reason == "goal_in_collision"
    with pytest.raises(GuidanceError) as refused:
        guidance.plan(deep, JointTarget(tuple(AWAY)), [MESH_WALL])
    assert refused.value.reason == "start_in_collision"


def test_a_run_from_a_start_the_spheres_overlap_ends_clear_on_the_meshes(touching) -> None:
    """The fabric's leaves start with spheres inside their buffer (clamped, passive while
    the clearance grows): the robot leaves, reaches the goal and touches nothing."""
    scenario = scenario_from_dict({"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 12.0,
                                   "initial_state": {"q": [float(v) for v in touching]},
                                   "goal": [{"type": "joint", "position": [float(v) for v in AWAY],
                                             "tolerance": 0.01}],
                                   "obstacles": [WALL_ENTRY]})
    metrics = run_scenario(scenario).metrics
    assert metrics.guided and metrics.success and not metrics.collision
    assert metrics.clearance is not None and metrics.clearance > 0.0


@pytest.mark.parametrize("wall", [WALL, MESH_WALL], ids=["box", "mesh"])
def test_a_segment_test_stopping_early_agrees_with_the_exact_minimum(panda, touching, wall) -> None:
    """:meth:`MeshGoalCheck.segment_free` stops at the first configuration below its floor
    (:func:`~dynfab.robots.mesh_sweep.meshes_clear`); its answers are those of the exact
    minimum over the segment, on both sides of the floor."""
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([wall])
    meshes = guidance._meshes()
    rng = np.random.default_rng(5)
    answers = []
    for _ in range(12):
        free = touching + rng.normal(scale=0.15, size=touching.size)
        line = free + np.linspace(0.0, 1.0, 41)[:, None] * (touching - free)
        least, itself = meshes.clearance(line)
        for floor in (0.002, 0.01, least - 1e-4, least + 1e-4):
            expected = least >= floor and itself > 0.0
            assert meshes.segment_free(free, touching, np.linalg.norm(touching - free) / 40 + 1e-12, floor) == expected
            answers.append(expected)
    assert any(answers) and not all(answers)
