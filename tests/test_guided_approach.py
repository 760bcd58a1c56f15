"""A grasp's approach under guidance: started from where the robot is when the obstacle
leaves hold it short of the planned one, its allowances over the whole segment, progress
on it judged on the distance to the goal rather than on the reference's clock, and for a
goal the spheres refuse and the robot's meshes find free, judged on the meshes instead of
the spheres (issue 19: such a goal must not be refused, and the spheres accept approaches
the meshes find inside a board)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
import dynfab.motion.guidance as guidance_module
from dynfab.motion.approach_segment import along_segment, leaf_buffers, segment_offset
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance, JointTarget
from dynfab.motion.joint_planning import (ApproachTest, JointPlannerSettings, NoPathError, approach_clear,
                                          plan_joint_path)
from dynfab.motion.mesh_goal_check import MeshGoalCheck, robot_mesh_model
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.scenario.guided_controller import make_scenario_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
from wall_scene import WALL, goal_near_the_wall
from coarse_panda import panda_on_planning_spheres

START = np.array([-1.3, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
DT = 0.01
FAST = JointPlannerSettings(time_limit=0.5)


@pytest.fixture(scope="module")
def panda():
    return panda_on_planning_spheres()


@pytest.fixture(scope="module")
def grasp(panda) -> np.ndarray:
    """The spheres 4 mm from the wall (the planner's margin is 10 mm): a goal that is
    escaped and approached."""
    return goal_near_the_wall(panda, 0.004)


@pytest.fixture(scope="module")
def touching(panda) -> np.ndarray:
    """The spheres touching the wall; the meshes are farther (a goal the spheres refuse and
    the meshes find free)."""
    return goal_near_the_wall(panda, 0.0)


def _turned(q: np.ndarray, by: float) -> np.ndarray:
    turned = q.copy()
    turned[0] += by
    return turned


def test_an_approach_is_clear_from_the_side_of_the_goal_and_not_through_the_wall(panda, grasp) -> None:
    checker = ConfigurationChecker(panda, [WALL])
    assert approach_clear(checker, _turned(grasp, -0.1), grasp)
    beyond = _turned(grasp, 1.8)   # the arm on the wall's other side
    assert checker.clearances(beyond)[0] > 0.0 and not approach_clear(checker, beyond, grasp)
    # the test is "no deeper than the goal": a segment to a goal deeper in the wall may reach that deep
    deeper = _turned(grasp, 0.02)
    assert checker.clearances(deeper)[0] < checker.clearances(grasp)[0]
    assert approach_clear(checker, _turned(grasp, -0.1), deeper, JointPlannerSettings())


def test_approach_from_times_the_straight_segment_from_the_robot_as_an_approach(panda, grasp) -> None:
    guidance = JointGuidance(panda)
    guidance.plan(START, JointTarget(tuple(grasp)), [WALL])   # sets the checker's obstacles
    here = _turned(grasp, -0.12)
    plan = guidance.approach_from(here, grasp)
    assert plan is not None and isinstance(plan.trajectory, PhasedTrajectory) and len(plan.trajectory.phases) == 1
    assert plan.approach_start == 0.0 and plan.approach == pytest.approx(0.12, abs=1e-9)
    np.testing.assert_allclose(plan.trajectory.evaluate(0.0).position, here, atol=1e-9)
    np.testing.assert_allclose(plan.trajectory.end, grasp, atol=1e-9)
    velocity = plan.trajectory.sample(np.linspace(0.0, plan.trajectory.duration, 501))[1]
    limit = guidance.settings.approach_speed * panda.limits.velocity
    assert (np.abs(velocity) <= limit + 1e-9).all()
    assert guidance.approach_from(_turned(grasp, 1.8), grasp) is None   # through the wall
    assert guidance.approach_from(grasp, grasp) is None   # already there


def test_approach_allowances_are_given_along_the_segment(panda, grasp) -> None:
    guidance = JointGuidance(panda)
    plan = guidance.plan(START, JointTarget(tuple(grasp)), [WALL])
    assert plan.approach > 0.0
    # a block beside the middle of the approach, where the goal is farther from it
    middle = 0.5 * (plan.trajectory.waypoints[-2] + grasp)
    hand = np.asarray(panda.kinematics.position(middle, "panda_hand")).ravel()
    block = PlacedObstacle(Box((0.02, 0.02, 0.02)), Placement(tuple(hand + np.array([0.0, 0.0, 0.12]))))
    buffers = [0.005, 0.005]
    segment, table = guidance.approach_allowances(plan, [WALL, block], buffers)
    np.testing.assert_allclose(segment[0], plan.trajectory.waypoints[-2], atol=1e-12)
    np.testing.assert_allclose(segment[-1], grasp, atol=1e-12)
    assert np.linalg.norm(np.diff(segment, axis=0), axis=1).max() <= guidance.settings.path.resolution + 1e-12
    np.testing.assert_allclose(table, [guidance.allowances(q, [WALL, block], buffers) for q in segment], atol=1e-12)
    assert table[:, 1].max() > table[-1, 1] and table[-1, 0] == table[:, 0].max()   # the block: mid-way; the wall: at the goal


def _guided(panda, goal: np.ndarray):
    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": DT, "duration": 5.0,
            "initial_state": {"q": START.tolist()}, "goal": [{"type": "joint", "position": goal.tolist()}],
            "obstacles": [{"type": "box", "position": [0.45, 0.0, 0.35], "size": [0.6, 0.04, 0.7]}]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=0.0).guided


def _follow_to_the_approach(guided) -> float:
    """Update with the robot exactly on the reference until its clock reaches the approach; the time."""
    plan = guided.plan
    t = 0.0
    while guided._tau < plan.approach_start:   # the clock of a perfectly tracking robot
        t += DT
        guided.update(t, plan.trajectory.evaluate(guided._tau).position.copy())
    return t


def _held_short(guided, grasp: np.ndarray) -> tuple[float, np.ndarray]:
    """Follow the plan to its approach, then hold the robot 0.06 rad short of the approach's
    start until guidance replans; the time and where the robot is held."""
    settings = guided.guidance.settings
    guided.set_goal(JointTarget(tuple(grasp)), 0.0, START)
    first = guided.plan
    t = _follow_to_the_approach(guided)
    held = _turned(first.trajectory.waypoints[-2], -0.06)   # short of the approach's start, on the goal's side
    assert np.linalg.norm(held - first.trajectory.waypoints[-2]) > settings.approach_lag_stop
    began = t
    while guided.plan is first:
        t += DT
        guided.update(t, held)
        assert t < began + settings.approach_hold_time + 0.1, "never replanned"
    assert t == pytest.approx(began + settings.approach_hold_time, abs=3 * DT)
    return t, held


def test_a_robot_held_short_of_the_approach_approaches_from_where_it_is(panda, grasp) -> None:
    guided = _guided(panda, grasp)
    t, held = _held_short(guided, grasp)
    assert guided.status.replans_stalled == 1 and guided.status.plans == 2
    plan = guided.plan
    assert plan.approach_start == 0.0 and plan.approach == pytest.approx(np.linalg.norm(grasp - held))
    np.testing.assert_allclose(plan.trajectory.evaluate(0.0).position, held, atol=1e-9)
    guided.update(t + DT, held)
    assert guided.approaching
    segment, table = guided.guidance.approach_allowances(plan, guided._static, leaf_buffers(guided.fabric.config, guided._static))
    np.testing.assert_allclose(guided.allowances(), table.max(axis=0))   # at the start: the whole segment's
    guided.update(t + 2 * DT, grasp)
    np.testing.assert_allclose(guided.allowances(), table[-2:].max(axis=0))   # at the goal: what is left of it
    assert guided.allowances()[0] > 0.0


def test_on_the_approach_a_robot_closing_in_slowly_does_not_stall_and_one_that_stops_does(panda, grasp) -> None:
    guided = _guided(panda, grasp)
    settings = guided.guidance.settings
    t, q = _held_short(guided, grasp)   # now on an approach from q, about 0.12 rad long
    direction = (grasp - q) / np.linalg.norm(grasp - q)
    speed = 1.5 * settings.stall_floor / settings.stall_window   # slower than the reference: its clock waits
    for _ in range(int(2.5 * settings.stall_window / DT)):
        t += DT
        q = q + speed * DT * direction
        guided.update(t, q)
    assert guided.approaching and guided._tau < guided.plan.trajectory.duration
    assert guided.status.replans_stalled == 1   # the clock waited, the robot kept closing in
    stopped = t
    while guided.status.replans_stalled == 1:
        t += DT
        guided.update(t, q)
        assert t < stopped + 2 * settings.stall_window, "never stalled"
    # within stall_window of the last stall_floor of progress, which came at most
    # stall_floor / speed before the robot stopped
    assert stopped + settings.stall_window - settings.stall_floor / speed - DT <= t <= stopped + settings.stall_window + DT


def _plan(panda, touching, approach: ApproachTest | None):
    checker = ConfigurationChecker(panda, [WALL])
    kin = panda.kinematics
    return plan_joint_path(checker, START, touching, kin.lower, kin.upper, FAST, 0, approach)


def test_an_approach_test_instead_of_the_spheres_decides_alone(panda, touching) -> None:
    assert _plan(panda, touching, None).escaped_goal   # the spheres accept an approach
    with pytest.raises(NoPathError) as refused:
        _plan(panda, touching, ApproachTest(lambda free, goal: False, instead_of_spheres=True))
    assert refused.value.reason == "goal_in_collision"
    asked = []
    path = _plan(panda, touching, ApproachTest(lambda free, goal: asked.append(free) is None, instead_of_spheres=True))
    np.testing.assert_array_equal(path.waypoints[-2], asked[0])   # the first it was asked about


def test_an_approach_test_beside_the_spheres_needs_both(panda, touching) -> None:
    with pytest.raises(NoPathError):
        _plan(panda, touching, ApproachTest(lambda free, goal: False))
    assert _plan(panda, touching, ApproachTest(lambda free, goal: True)).escaped_goal


def test_a_goal_free_on_the_meshes_is_approached_clear_of_them(panda, touching) -> None:
    guidance = JointGuidance(panda)
    plan = guidance.plan(START, JointTarget(tuple(touching)), [WALL])
    meshes = guidance._meshes()
    assert meshes is not None
    at_goal = meshes.clearance(touching)[0]
    assert at_goal >= meshes.margin and guidance.checker.clearances(touching)[0] < 0.0   # refused by the spheres alone
    assert plan.approach > 0.0
    approach = plan.trajectory.phases[-1].waypoints
    line = approach[0] + np.linspace(0.0, 1.0, 101)[:, None] * (approach[-1] - approach[0])
    floor = min(guidance.settings.approach_clearance, at_goal)
    assert meshes.clearance(line)[0] >= floor - 1e-4   # checked every path.resolution / 2, here every 1 % of it


def test_the_meshes_decide_the_approach_of_a_goal_they_find_free(panda, touching, monkeypatch) -> None:
    monkeypatch.setattr(MeshGoalCheck, "segment_free", lambda self, a, b, step, floor=None: False)
    with pytest.raises(GuidanceError) as refused:
        JointGuidance(panda, GuidanceSettings(mesh_escape=None)).plan(START, JointTarget(tuple(touching)),
                                                                      [WALL])   # (no last resort past the tests)
    assert refused.value.reason == "goal_in_collision"


def test_guidance_instances_of_one_robot_share_its_mesh_model(panda) -> None:
    first, second = JointGuidance(panda), JointGuidance(panda)
    first.checker.set_obstacles([WALL])
    second.checker.set_obstacles([WALL])
    model = robot_mesh_model(panda)
    assert model is not None and first._meshes().model is model and second._meshes().model is model


def test_a_goal_the_meshes_judge_is_escaped_with_mesh_escape_samples(panda, touching, monkeypatch) -> None:
    used = []

    def recording(checker, start, goal, lower, upper, settings, seed, approach, leave):
        used.append(settings.escape_samples)
        return plan_joint_path(checker, start, goal, lower, upper, settings, seed, approach, leave)

    monkeypatch.setattr(guidance_module, "plan_joint_path", recording)
    guidance = JointGuidance(panda, replace(GuidanceSettings(), mesh_escape_samples=777))
    guidance.plan(START, JointTarget(tuple(touching)), [WALL])   # free on the meshes: judged there
    assert used == [777]
    deep = goal_near_the_wall(panda, -0.03)   # the meshes within mesh_margin too: the spheres judge it
    assert guidance._meshes().clearance(deep)[0] < guidance.settings.mesh_margin
    guidance.plan(START, JointTarget(tuple(deep)), [WALL])
    assert used[-1] == guidance.settings.path.escape_samples


@pytest.fixture(scope="module")
def barely(panda) -> np.ndarray:
    """The meshes about 1.5 mm from the wall: free on them, by less than ``mesh_margin``."""
    return goal_near_the_wall(panda, -0.003)


def test_a_goal_the_meshes_clear_by_less_than_mesh_margin_is_approached_on_both(panda, barely) -> None:
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([WALL])
    meshes = guidance._meshes()
    assert 0.0 < meshes.clearance(barely)[0] < guidance.settings.mesh_margin
    (test,) = guidance._endpoint_tests(barely)
    assert test is not None and not test.instead_of_spheres   # the meshes' test beside the spheres'
    assert guidance._endpoint_tests(goal_near_the_wall(panda, -0.03)) == (None,)   # in collision on the meshes too


@pytest.mark.parametrize("meshes_accept", [True, False])
def test_an_approach_from_where_the_robot_is_passes_the_meshes_test_too(panda, barely, monkeypatch,
                                                                       meshes_accept: bool) -> None:
    """The straight approach made when the robot is held short of its plan's (held-out
    as-posed bookshelf_tall/0046: the spheres' test alone let it 6.9 mm into a can on the
    meshes) is judged as a plan's approach to that goal is: the segment, then (the goal
    under ``mesh_margin`` from the wall) its continuation past the goal, touching nothing."""
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([WALL])
    asked = []

    def judged(self, a, b, step, floor=None):
        asked.append(floor)
        return meshes_accept

    monkeypatch.setattr(MeshGoalCheck, "segment_free", judged)
    plan = guidance.approach_from(_turned(barely, -0.1), barely)
    assert (plan is not None) == meshes_accept and len(asked) == (2 if meshes_accept else 1)
    assert asked[0] == pytest.approx(guidance._meshes().clearance(barely)[0])   # no deeper than the goal
    assert asked[1:] == ([0.0] if meshes_accept else [])   # past the goal: not touching


def test_the_offset_from_a_segment_is_the_distance_to_its_nearest_point() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        a, b, q = rng.normal(size=(3, 7))
        segment = a + np.linspace(0.0, 1.0, 9)[:, None] * (b - a)
        dense = a + np.linspace(0.0, 1.0, 200001)[:, None] * (b - a)
        assert segment_offset(segment, q) == pytest.approx(np.linalg.norm(dense - q, axis=1).min(), abs=1e-7)
        s = along_segment(segment, q)
        assert 0.0 <= s <= 1.0
        assert np.linalg.norm(a + s * (b - a) - q) == pytest.approx(segment_offset(segment, q), abs=1e-12)


@pytest.mark.parametrize("beside", [0.002, 0.0045, 0.008])
def test_on_the_approach_the_clock_waits_for_a_robot_beside_the_segment(panda, grasp, beside: float) -> None:
    """Along the approach a lag is harmless; beside its checked segment the clock slows from
    ``approach_offset_slow`` and stops at ``approach_offset_stop`` (training as-posed
    box/0015: the robot 0.015-0.02 rad beside it touched the cube), though the lag rule alone
    would let it run."""
    guided = _guided(panda, grasp)
    settings = guided.guidance.settings
    t, q = _held_short(guided, grasp)   # now on an approach from q
    plan = guided.plan
    direction = (grasp - q) / np.linalg.norm(grasp - q)
    side = np.zeros(7)
    side[3] = 1.0
    side -= (side @ direction) * direction
    side /= np.linalg.norm(side)
    robot = plan.trajectory.evaluate(guided._tau).position + beside * side
    assert np.linalg.norm(robot - plan.trajectory.evaluate(guided._tau).position) < settings.approach_lag_slow
    before = guided._tau
    guided.update(t + DT, robot)
    expected = float(np.clip((settings.approach_offset_stop - beside)
                             / (settings.approach_offset_stop - settings.approach_offset_slow), 0.0, 1.0))
    assert guided._tau - before == pytest.approx(expected * DT, abs=1e-9)


def test_obstacles_replaced_on_the_approach_get_no_allowance_and_do_not_crash(panda, grasp) -> None:
    """A camera's scene is replaced every guidance period, also on an approach: the new
    obstacles' allowances are zero at every approach sample (a one-row table once made
    ``allowances`` reduce an empty slice: thrown seed 27 under a camera)."""
    guided = _guided(panda, grasp)
    t, held = _held_short(guided, grasp)
    guided.update(t + DT, held)
    guided.update(t + 2 * DT, grasp)   # at the goal: the table's last rows ahead
    assert guided.approaching and guided.allowances()[0] > 0.0
    guided.set_obstacles(guided._static)
    assert guided.allowances().tolist() == [0.0] * len(guided._static)


def test_among_primitives_a_goal_no_escape_reaches_is_planned_on_the_meshes(panda, touching, monkeypatch) -> None:
    # the last resort (mesh_escape_plan) among primitives since session 20 (among meshes since session 21)
    monkeypatch.setattr(MeshGoalCheck, "segment_free", lambda self, a, b, step, floor=None: False)
    guidance = JointGuidance(panda)
    plan = guidance.plan(START, JointTarget(tuple(touching)), [WALL])
    assert isinstance(plan.trajectory, PhasedTrajectory) and plan.approach > 0.0
    np.testing.assert_allclose(plan.trajectory.phases[-1].waypoints[-1], touching)
    meshes = guidance._meshes()
    qs = plan.trajectory.sample(np.linspace(0.0, plan.trajectory.duration, 400))[0]
    assert meshes.clearance(qs)[0] > 0.0   # the whole way clear of the wall on the meshes
