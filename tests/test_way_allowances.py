"""Allowances along a plan's way (issue 19): guidance plans with tighter spheres than the
fabric avoids with (the Panda's links 5 and 6), so the fabric's leaves get, near where the
robot is on the plan, the allowance that lets them see what the plan's spheres kept."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import JointGuidance, Plan
from dynfab.motion.joint_trajectory import time_path
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.way_window import WAY_AHEAD, way_window
from dynfab.robots import load_robot

START = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.8, 0.8])
END = np.array([0.9, 0.1, 0.3, -1.7, 0.6, 2.0, 0.4])
BUFFER = 0.005


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _plan(robot, waypoints: np.ndarray, approach: np.ndarray | None = None) -> Plan:
    """A plan timed along ``waypoints`` (obstacles play no part), with an approach phase to
    ``approach`` if given."""
    limits = robot.limits
    way = time_path(waypoints, 0.5 * limits.velocity, 0.25 * limits.acceleration)
    if approach is None:
        return Plan(way, waypoints[-1], 0.0, 0)
    last = time_path(np.vstack([waypoints[-1], approach]), 0.1 * limits.velocity, 0.1 * limits.acceleration)
    return Plan(PhasedTrajectory((way, last)), approach, 0.0, 0, float(np.linalg.norm(approach - waypoints[-1])),
                way.duration)


def _box_near_link5(robot, q: np.ndarray, clearance: float) -> PlacedObstacle:
    """A 4 cm cube beside ``panda_link5`` at ``q``, its planning spheres ``clearance`` [m] from it."""
    centre = np.asarray(robot.link_position(q, "panda_link5"), dtype=float).ravel()
    checker = ConfigurationChecker(robot.planning_robot)
    near, far = 0.0, 0.4
    for _ in range(50):   # bisect the cube's offset along +x for the clearance wanted
        offset = 0.5 * (near + far)
        box = PlacedObstacle(Box((0.04, 0.04, 0.04)), Placement(tuple(centre + np.array([offset, 0.0, 0.0]))))
        checker.set_obstacles([box])
        near, far = (offset, far) if checker.clearances(q)[0] < clearance else (near, offset)
    return box


def test_way_allowances_let_the_fabric_see_what_the_planning_spheres_kept(panda) -> None:
    middle = 0.5 * (START + END)
    box = _box_near_link5(panda, middle, 0.014)
    guidance = JointGuidance(panda)
    way, table = guidance.way_allowances(_plan(panda, np.vstack([START, middle, END])), [box], [BUFFER])
    np.testing.assert_allclose(way[0], START, atol=1e-12)
    np.testing.assert_allclose(way[-1], END, atol=1e-12)
    assert np.linalg.norm(np.diff(way, axis=0), axis=1).max() <= guidance.settings.path.resolution + 1e-12
    fabric = ConfigurationChecker(panda, [box]).batch(way)[:, 0]
    planned = ConfigurationChecker(panda.planning_robot, [box]).batch(way)[:, 0]
    settings = guidance.settings
    expected = np.maximum(0.0, BUFFER + np.minimum(settings.way_clearance, planned - settings.sphere_coverage) - fabric)
    np.testing.assert_allclose(table[:, 0], expected, atol=1e-12)
    assert (planned >= fabric - 1e-12).all()   # the planning spheres lie inside the fabric's here
    at_middle = int(np.argmin(np.linalg.norm(way - middle, axis=1)))
    assert table[at_middle, 0] > 0.002 and table[0, 0] == 0.0   # given where link 5 passes the box only


def test_a_plans_approach_is_not_part_of_its_way(panda) -> None:
    grasp = END + 0.1
    guidance = JointGuidance(panda)
    box = _box_near_link5(panda, END, 0.012)
    way, table = guidance.way_allowances(_plan(panda, np.vstack([START, END]), approach=grasp), [box], [BUFFER])
    np.testing.assert_allclose(way[-1], END, atol=1e-12)
    assert table.shape == (len(way), 1) and table[-1, 0] > 0.0


def test_no_way_allowance_without_tighter_planning_spheres(panda) -> None:
    robot = replace(panda, planning_spheres=None, planning_pairs=())
    assert robot.planning_robot is robot
    box = _box_near_link5(panda, START, 0.001)
    way, table = JointGuidance(robot).way_allowances(_plan(robot, np.vstack([START, END])), [box], [BUFFER])
    assert table.shape == (len(way), 1) and not table.any()


def test_way_allowances_hold_from_before_the_robot_to_just_beyond_its_reference() -> None:
    way = np.linspace(0.0, 1.0, 21)[:, None] * np.ones((1, 3))
    table = np.zeros((21, 2))
    table[10, 0], table[4, 1] = 0.01, 0.02
    at = way[3] + 1e-4
    np.testing.assert_allclose(way_window(way, at, way[3]).allowances(table), [0.0, 0.02])   # 4 is ahead, 10 is not
    np.testing.assert_allclose(way_window(way, at, way[10 - WAY_AHEAD]).allowances(table), [0.01, 0.02])
    np.testing.assert_allclose(way_window(way, way[12], way[14]).allowances(table), [0.0, 0.0])   # both passed
    np.testing.assert_allclose(way_window(way, way[11], way[14]).allowances(table), [0.01, 0.0])  # the one before counts


def test_way_allowances_fade_as_the_robot_leaves_its_way() -> None:
    way = np.linspace(0.0, 1.0, 21)[:, None] * np.array([[1.0, 0.0, 0.0]])
    table = np.zeros((21, 1))
    table[10, 0] = 0.01
    off = np.array([0.0, 0.0, 1.0])   # across the way
    for distance, kept in ((0.0, 1.0), (0.1, 1.0), (0.15, 0.5), (0.2, 0.0), (0.5, 0.0)):
        q = way[10] + distance * off
        np.testing.assert_allclose(way_window(way, q, way[10], reach=0.1).allowances(table), [0.01 * kept], atol=1e-12)


def _guided_before_the_wall(panda):
    """The guided fabric of a scenario from before the wall to behind it (plans made at once)."""
    from dynfab.scenario.guided_controller import make_scenario_controller
    from dynfab.scenario.references import scenario_references
    from dynfab.scenario.schema import scenario_from_dict, validate_for_robot
    from wall_scene import GOAL, WALL_ENTRY
    from wall_scene import START as BEFORE_THE_WALL

    data = {"robot": "panda", "planner": "dynamic-fabric", "dt": 0.01, "duration": 5.0,
            "initial_state": {"q": BEFORE_THE_WALL.tolist()}, "goal": [{"type": "joint", "position": GOAL.tolist()}],
            "obstacles": [WALL_ENTRY]}
    scenario = validate_for_robot(scenario_from_dict(data), panda)
    return make_scenario_controller(scenario, panda, scenario_references(scenario, panda), plan_latency=0.0).guided


def test_a_guided_fabric_gives_its_plans_way_allowances_where_the_robot_is(panda, monkeypatch) -> None:
    from dynfab.motion.guidance import JointTarget
    from wall_scene import GOAL
    from wall_scene import START as BEFORE_THE_WALL

    guided = _guided_before_the_wall(panda)
    made = guided.guidance.way_allowances

    def marked(plan, obstacles, buffers):   # the plan's own way, an allowance at its middle tenth
        way, table = made(plan, obstacles, buffers)
        table = np.zeros_like(table)
        table[len(way) * 9 // 20:len(way) * 11 // 20, 0] = 0.007
        return way, table

    monkeypatch.setattr(guided.guidance, "way_allowances", marked)
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, BEFORE_THE_WALL)
    plan, way = guided.plan, guided._way
    assert guided.allowances() == pytest.approx([0.0])   # the robot at the start
    given = []
    for tau in np.arange(0.01, plan.trajectory.duration, 0.01):   # the robot on its reference
        q = plan.trajectory.evaluate(float(guided._tau)).position
        guided.update(float(tau), q)
        now = guided.allowances()
        window = way_window(way, q, guided._reference).allowances(guided._way_table)
        own = guided._own_way.way_at(q, guided._static, guided._buffers, [0])   # where the robot is
        np.testing.assert_allclose(now, np.minimum(window, own), atol=0.0)
        given.append(now[0])
    assert 0.0 < max(given) <= 0.007 and given[-1] == 0.0 and given[0] == 0.0


def _cube_at_link2(mesh: bool = False):
    """A 4 cm cube (a box, or a triangle ``mesh``) the planning spheres enter at ``Q`` and
    the meshes clear by about 6.5 mm."""
    import trimesh

    from dynfab.geometry.shapes import Mesh
    from test_mesh_goal_check import BESIDE_LINK2
    if not mesh:
        return PlacedObstacle(Box((0.04, 0.04, 0.04)), BESIDE_LINK2.placement)
    cube = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    return PlacedObstacle(Mesh(cube.vertices, cube.faces, "cube"), BESIDE_LINK2.placement)


def test_a_blocked_starts_way_out_lets_the_leaves_see_the_meshes_clearance_from_a_mesh(panda) -> None:
    from dynfab.motion.joint_planning import polyline_samples
    from dynfab.motion.mesh_escape_plan import LEAF_SLACK, mesh_allowances
    from test_mesh_goal_check import Q

    cube = _cube_at_link2(mesh=True)
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([cube])
    away = Q + np.array([0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])
    waypoints = np.vstack([Q, away, END])
    plain = _plan(panda, waypoints)
    leaving = replace(plain, departure=float(np.linalg.norm(away - Q)))
    way, before = guidance.way_allowances(plain, [cube], [BUFFER])
    same_way, table = guidance.way_allowances(leaving, [cube], [BUFFER])
    np.testing.assert_array_equal(way, same_way)
    rows = len(polyline_samples(waypoints[:2], guidance.settings.path.resolution))
    fabric = np.array([[guidance.obstacle_clearance(q, cube)] for q in way])
    meshes = guidance._meshes()
    expected = mesh_allowances(meshes.model, way[:rows], (cube,), (BUFFER,), fabric[:rows],
                               guidance.settings.goal_clearance)
    np.testing.assert_allclose(table[:rows], np.maximum(before[:rows], expected))
    np.testing.assert_array_equal(table[rows:], before[rows:])   # beyond the way out as without it
    seen = fabric[0, 0] + table[0, 0] - BUFFER   # what the leaf keeps positive at the start
    on_meshes = meshes.clearance(Q)[0]
    assert fabric[0, 0] < 0.0 < on_meshes
    assert seen == pytest.approx(min(guidance.settings.goal_clearance, on_meshes + LEAF_SLACK), abs=1e-6)
    box = _cube_at_link2()   # a box: its way out is left as any way (no slack past the meshes)
    np.testing.assert_array_equal(guidance.way_allowances(leaving, [box], [BUFFER])[1],
                                  guidance.way_allowances(plain, [box], [BUFFER])[1])


def test_a_plan_from_a_blocked_start_says_how_long_its_way_out_is(panda) -> None:
    from dynfab.motion.guidance import JointTarget
    from test_mesh_goal_check import Q

    cube = _cube_at_link2()
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([cube])
    margin = guidance.settings.path
    assert not guidance.checker.free(Q, margin.margin, margin.self_margin)
    goal = Q + np.array([0.0, 0.0, 0.0, 0.4, 0.0, 0.0, 0.0])
    assert guidance.plan(Q, JointTarget(tuple(goal)), [cube]).departure > 0.0
    assert guidance.checker.free(START, margin.margin, margin.self_margin)
    assert guidance.plan(START, JointTarget(tuple(END)), [cube]).departure == 0.0


def test_along_the_way_a_mesh_gets_what_the_planning_spheres_grid_kept_never_more_than_the_meshes(panda) -> None:
    """A mesh cube beside ``panda_link5`` halfway: its allowance is the formula's with ``p_k``
    the planning spheres' grid bound and ``c_k`` the fabric's exact clearance, and what the
    leaf then sees (``c_k + a_k − buffer``) never exceeds the robot's meshes' clearance."""
    import trimesh

    from dynfab.geometry.shapes import Mesh

    middle = 0.5 * (START + END)
    box = _box_near_link5(panda, middle, 0.014)
    cube = trimesh.creation.box(extents=box.shape.size)
    mesh = PlacedObstacle(Mesh(cube.vertices, cube.faces, "cube"), box.placement)
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([mesh])
    way, table = guidance.way_allowances(_plan(panda, np.vstack([START, middle, END])), [mesh], [BUFFER])
    settings = guidance.settings
    fabric = np.array([guidance.obstacle_clearance(q, mesh) for q in way])
    planned = ConfigurationChecker(panda.planning_robot, [mesh]).batch(way)[:, 0]
    expected = np.maximum(0.0, BUFFER + np.minimum(settings.way_clearance, planned - settings.sphere_coverage) - fabric)
    np.testing.assert_allclose(table[:, 0], expected, atol=1e-9)   # where it is not asked, it is 0 too
    given = table[:, 0] > 0.0
    assert given.any() and not given[0]
    meshes = guidance._meshes()
    on_meshes = np.array([meshes.clearance(q)[0] for q in way[given]])
    assert (fabric[given] + table[given, 0] - BUFFER <= on_meshes + 1e-6).all()


def test_near_its_way_or_off_it_an_allowance_lets_the_leaves_see_no_more_than_the_planning_spheres(
        panda, monkeypatch) -> None:
    """Wherever the robot is, the allowance of a way lets the fabric's spheres see at most
    what the planning spheres show less ``sphere_coverage`` (at most ``way_clearance``): a
    robot held 0.09 rad beside its way kept the 7-10 mm allowances of the way's
    configurations there and put a finger on MBM table_bars' bars (fresh seed 34, 0014,
    0016, 0019). Checked on independent checkers of both sphere sets, for a way whose
    every configuration is given 15 mm."""
    from dynfab.motion.guidance import JointTarget
    from wall_scene import GOAL, WALL
    from wall_scene import START as BEFORE_THE_WALL

    guided = _guided_before_the_wall(panda)
    made = guided.guidance.way_allowances
    settings = guided.guidance.settings

    def everywhere(plan, obstacles, buffers):
        way, table = made(plan, obstacles, buffers)
        return way, np.full_like(table, 0.015)

    monkeypatch.setattr(guided.guidance, "way_allowances", everywhere)
    guided.set_goal(JointTarget(tuple(GOAL)), 0.0, BEFORE_THE_WALL)
    fabric, planning = ConfigurationChecker(panda), ConfigurationChecker(panda.planning_robot)
    fabric.set_obstacles([WALL])
    planning.set_obstacles([WALL])
    buffer = guided._buffers[0]
    rng = np.random.default_rng(3)
    given, withheld = [], 0
    for k, q_way in enumerate(guided._way[::3]):
        step = rng.normal(size=panda.dof)
        q = q_way + 0.09 * step / np.linalg.norm(step)   # within way_reach: the way's 15 mm hold in full
        guided.update(0.01 * (k + 1), q)
        allowance = guided.allowances()[0]
        c, p = fabric.clearances(q)[0], planning.clearances(q)[0]
        assert allowance <= max(0.0, buffer + min(settings.way_clearance, p - settings.sphere_coverage) - c) + 1e-9
        given.append(allowance)
        withheld += allowance < 0.015
    assert max(given) > 0.0 and withheld > 0


def test_a_meshs_clearance_within_a_bound_is_its_exact_clearance_below_the_bound(panda) -> None:
    """``obstacle_clearance(q, mesh, within)`` asks coal only for the spheres the mesh's grid
    puts within the bound: below it the clearance is exact, above it it reads at least the bound."""
    from dynfab.motion.allowance_tables import AllowanceTables
    from dynfab.motion.guidance import GuidanceSettings
    from wall_scene import GOAL, MESH_WALL
    from wall_scene import START as BEFORE_THE_WALL

    tables = AllowanceTables(panda, GuidanceSettings())
    below = 0
    for s in np.linspace(0.0, 0.5, 26):   # from in front of the wall into it
        q = (1.0 - s) * BEFORE_THE_WALL + s * GOAL
        exact, bounded = tables.obstacle_clearance(q, MESH_WALL), tables.obstacle_clearance(q, MESH_WALL, 0.02)
        if exact < 0.02:
            assert bounded == exact
            below += 1
        else:
            assert 0.02 <= bounded <= exact
    assert 0 < below < 26
