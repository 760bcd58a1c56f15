"""Guidance's last resort among primitives (and meshes, if asked; issues 19 and 20): where it
searches, the margins it searches, wider first, the budget of wall time it keeps, and the plan
it makes keeping the wider margin on the meshes."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
import trimesh

import dynfab.motion.mesh_escape_plan as escape_module
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Mesh, Placement, Sphere
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance
from dynfab.motion.guidance_settings import counted_checks
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.mesh_escape import MeshEscapeSettings
from dynfab.motion.phased_trajectory import PhasedTrajectory
from dynfab.motion.plan_values import Plan
from dynfab.motion.mesh_escape_plan import LEAF_SLACK, EscapeScene, escape_plan, mesh_allowances, search_margins
from test_mesh_goal_check import BESIDE_LINK2, Q   # a cube the spheres touch at Q, the meshes clear by 1.7 cm
from coarse_panda import panda_on_planning_spheres

START = Q + np.array([0.3, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0])
#: a few points beside the cube
_CLOUD = PlacedObstacle(PointCloud.from_points(np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]]), voxel=0.01),
                        Placement((0.6, 0.6, 0.6)))

#: a sphere passing far from the arm (the scene changes before a search ends)
_PASSING = PlacedObstacle(Sphere(0.05), Placement((1.5, 0.0, 0.5)), (0.0, 0.3, 0.0))


@pytest.fixture(scope="module")
def panda():
    return panda_on_planning_spheres()


def _scene(panda, escape: MeshEscapeSettings) -> EscapeScene:
    guidance = JointGuidance(panda, GuidanceSettings(mesh_escape=escape))
    guidance.checker.set_obstacles((BESIDE_LINK2,))
    meshes = guidance._meshes()
    assert meshes is not None
    return EscapeScene(guidance.checker, meshes, guidance.settings, panda.limits, panda.kinematics.lower,
                       panda.kinematics.upper, guidance._approach_timed)


def test_the_wider_margins_come_first_and_mesh_margin_last() -> None:
    assert search_margins(MeshEscapeSettings(), 0.003) == (0.006, 0.003)
    assert search_margins(MeshEscapeSettings(clearances=(0.005, 0.008, 0.002)), 0.003) == (0.008, 0.005, 0.003)
    assert search_margins(MeshEscapeSettings(clearances=()), 0.003) == (0.003,)


def test_the_wider_margin_is_searched_first_then_mesh_margin_with_every_seed(panda, monkeypatch) -> None:
    margins = []

    def finding_none(validity, start, goal, lower, upper, settings, seed, seconds):
        margins.append((validity.meshes.margin, seed))
        assert 0.0 < seconds <= settings.budget
        return None

    monkeypatch.setattr(escape_module, "mesh_path", finding_none)
    scene = _scene(panda, MeshEscapeSettings())
    assert escape_plan(scene, START, Q, (4, 5, 6), time.perf_counter()) is None
    assert margins == [(0.006, 4), (0.003, 4), (0.003, 5), (0.003, 6)]   # the wider one with the first seed
    margins.clear()
    scene = _scene(panda, MeshEscapeSettings(wide_searches=2))
    assert escape_plan(scene, START, Q, (4, 5, 6), time.perf_counter()) is None
    assert margins == [(0.006, 4), (0.006, 5), (0.003, 4), (0.003, 5), (0.003, 6)]


def test_among_meshes_it_searches_unless_told_not_to_and_never_among_point_clouds_or_what_moves(
        panda, monkeypatch) -> None:
    searched = []

    def finding_none(validity, start, goal, lower, upper, settings, seed, seconds):
        searched.append(seed)
        return None

    monkeypatch.setattr(escape_module, "mesh_path", finding_none)
    cube_mesh = trimesh.creation.box(extents=BESIDE_LINK2.shape.size)
    mesh = PlacedObstacle(Mesh(cube_mesh.vertices, cube_mesh.faces, "cube"), BESIDE_LINK2.placement)
    for escape, obstacles, searches in ((MeshEscapeSettings(among_meshes=False), (mesh,), 0),
                                        (MeshEscapeSettings(among_meshes=False), (BESIDE_LINK2, mesh), 0),
                                        (MeshEscapeSettings(), (mesh,), 2),
                                        (MeshEscapeSettings(), (BESIDE_LINK2, mesh), 2),
                                        (MeshEscapeSettings(), (BESIDE_LINK2, _CLOUD), 0),
                                        (MeshEscapeSettings(), (BESIDE_LINK2, _PASSING), 0),
                                        (MeshEscapeSettings(), (BESIDE_LINK2, replace(_PASSING, velocity=(0.0,) * 3)),
                                         2)):
        scene = _scene(panda, escape)
        scene.checker.set_obstacles(obstacles)
        searched.clear()
        assert escape_plan(scene, START, Q, (7,), time.perf_counter()) is None
        assert len(searched) == searches   # the wider margin, then mesh_margin


def test_a_spent_budget_of_time_fails_by_name(panda, monkeypatch) -> None:
    monkeypatch.setattr(escape_module, "mesh_path", lambda *args: pytest.fail("searched after the budget"))
    scene = _scene(panda, MeshEscapeSettings(budget=5.0))
    with pytest.raises(GuidanceError, match="5 s;") as failure:
        escape_plan(scene, START, Q, (0,), time.perf_counter() - 6.0)
    assert failure.value.reason == "mesh_escape_budget"
    simulated = _scene(panda, MeshEscapeSettings(budget=5.0))   # bounded by checks: ten times the time
    simulated = replace(simulated, settings=counted_checks(simulated.settings))
    monkeypatch.setattr(escape_module, "mesh_path", lambda *args: None)
    assert escape_plan(simulated, START, Q, (0,), time.perf_counter() - 6.0) is None


def test_the_searches_share_one_budget_of_mesh_checks(panda, monkeypatch) -> None:
    given = []

    def spending(validity, start, goal, lower, upper, settings, seed, seconds):
        given.append(settings.checks)
        validity.meshes.checks += 700   # as if the search checked 700 configurations on the meshes
        return None

    monkeypatch.setattr(escape_module, "mesh_path", spending)
    scene = _scene(panda, MeshEscapeSettings(checks=1000, total_checks=2000))
    with pytest.raises(GuidanceError, match="2000 mesh checks") as failure:
        escape_plan(scene, START, Q, (0, 1, 2), time.perf_counter())
    assert failure.value.reason == "mesh_escape_budget"
    assert given == [1000, 1000, 600]   # the third search is given what is left


def test_the_plan_runs_from_the_start_to_the_goal_clear_of_the_meshes(panda) -> None:
    scene = _scene(panda, MeshEscapeSettings(checks=2000, clearances=(0.012,)))
    plan = escape_plan(scene, START, Q, (1,), time.perf_counter())
    assert plan is not None
    np.testing.assert_allclose(plan.goal, Q)
    times = np.linspace(0.0, plan.trajectory.duration, 400)
    reference = plan.trajectory.sample(times)[0]
    np.testing.assert_allclose(reference[0], START, atol=1e-9)
    np.testing.assert_allclose(reference[-1], Q, atol=1e-9)
    assert scene.meshes.clearance(reference)[0] >= scene.meshes.clearance(Q)[0] - 1e-4   # nearest at the goal


def test_along_the_plans_polyline_the_leaves_see_the_meshes_clearance_at_most_goal_clearance(panda) -> None:
    scene = _scene(panda, MeshEscapeSettings())
    meshes = scene.meshes.clearance(Q)[0]   # 16.5 mm from the cube; its spheres 2.6 mm inside it
    spheres = np.array([[scene.checker.clearances(Q)[0]]])
    assert 0.01 < meshes < 0.03 and spheres[0, 0] < 0.0
    wide = mesh_allowances(scene.meshes.model, Q[None], (BESIDE_LINK2,), (0.02,), spheres, 0.05)
    assert wide[0, 0] == pytest.approx(0.02 + meshes + LEAF_SLACK - spheres[0, 0], abs=1e-6)   # the meshes' clearance
    narrow = mesh_allowances(scene.meshes.model, Q[None], (BESIDE_LINK2,), (0.02,), spheres, 0.01)
    assert narrow[0, 0] == pytest.approx(0.02 + 0.01 - spheres[0, 0])   # by goal_clearance where that is less
    assert mesh_allowances(scene.meshes.model, Q[None], (), (), np.zeros((1, 0)), 0.01).shape == (1, 0)


def test_guidance_gives_a_polyline_approach_the_meshes_allowances_and_a_straight_one_its_own(panda) -> None:
    cube = PlacedObstacle(Box((0.04, 0.04, 0.04)), BESIDE_LINK2.placement)   # 1 cm nearer Q on every side
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles((cube,))
    bent = np.array([Q + [0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0], Q + [0.0, 0.05, 0.05, 0.0, 0.0, 0.0, 0.0], Q])

    def plan_of(waypoints: np.ndarray) -> Plan:
        trajectory = PhasedTrajectory((guidance._approach_timed(waypoints),))
        return Plan(trajectory, Q, 0.0, 0, float(np.sum(np.linalg.norm(np.diff(waypoints, axis=0), axis=1))), 0.0)

    settings = guidance.settings
    segment, table = guidance.approach_allowances(plan_of(bent), (cube,), (0.02,))
    meshes = guidance._meshes()
    at_goal = meshes.clearance(Q)[0]
    assert 0.0 < at_goal < settings.goal_clearance - LEAF_SLACK - 0.002   # the meshes' clearance decides there
    spheres = guidance.checker.batch(segment)[:, :1]
    np.testing.assert_allclose(table, mesh_allowances(meshes.model, segment, (cube,), (0.02,), spheres,
                                                      settings.goal_clearance))
    np.testing.assert_allclose(table[-1, 0], 0.02 + at_goal + LEAF_SLACK - spheres[-1, 0], atol=1e-6)
    straight, as_before = guidance.approach_allowances(plan_of(bent[[0, 2]]), (cube,), (0.02,))   # a grasp's
    guidance.checker.set_obstacles((cube,))
    grid = guidance.checker.batch(straight)[:, 0]
    np.testing.assert_allclose(as_before[:, 0], np.maximum(0.0, 0.02 + settings.goal_clearance - grid))
