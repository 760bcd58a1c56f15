"""Guidance's last resort among meshes (issue 20): the validity that asks the meshes where the
spheres refuse, the path it plans, the cut of that path into the way and the approach, and
the approach's measures along a polyline."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.motion.approach_segment import across_segment, allowances_ahead, along_segment, segment_offset
from dynfab.motion.configuration_checker import ConfigurationChecker
from dynfab.motion.mesh_escape import MeshEscapeSettings, SpheresOrMeshes, mesh_path
from dynfab.motion.mesh_escape_plan import _split
from dynfab.motion.mesh_goal_check import MeshGoalCheck
from dynfab.robots import load_robot
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.mesh_collision import mesh_collision_model
from dynfab.robots.mesh_contact import MeshContactCheck
from test_mesh_goal_check import BESIDE_LINK2, Q   # a cube the spheres touch at Q, the meshes clear by 1.7 cm



@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def model(panda):
    built = mesh_collision_model(panda.kinematics, panda.default_q, builtin_collision_meshes(panda))
    assert built is not None
    return built


def _validity(panda, model, obstacles, margin: float) -> SpheresOrMeshes:
    contact = MeshContactCheck(model, margin)
    contact.set_obstacles(obstacles)
    return SpheresOrMeshes(ConfigurationChecker(panda, obstacles), contact, 0.005, 0.0, 7)


def test_the_meshes_decide_where_the_spheres_refuse(panda, model) -> None:
    obstacles = (BESIDE_LINK2,)
    assert ConfigurationChecker(panda, obstacles).clearances(Q)[0] < 0.0   # the spheres refuse Q
    validity = _validity(panda, model, obstacles, 0.003)
    assert validity.free(Q) and validity.meshes.checks == 1   # the meshes clear it by 1.7 cm
    assert not _validity(panda, model, obstacles, 0.03).free(Q)   # not by 3 cm
    far = Q + np.array([0.0, 0.8, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert ConfigurationChecker(panda, obstacles).clearances(far)[0] > 0.05
    assert validity.free(far) and validity.meshes.checks == 1   # the spheres alone accept it
    assert validity.checks == 2


def test_an_end_nearer_the_meshes_keeps_its_own_margin_only_near_it(panda, model) -> None:
    obstacles = (BESIDE_LINK2,)
    wide, narrow = MeshContactCheck(model, 0.03), MeshContactCheck(model, 0.003)
    for check in (wide, narrow):
        check.set_obstacles(obstacles)
    checker = ConfigurationChecker(panda, obstacles)
    near = SpheresOrMeshes(checker, wide, 0.005, 0.0, 7, ((Q, narrow),), 0.3)
    assert near.free(Q)   # 1.7 cm from the cube: refused at 3 cm, accepted near its end at 3 mm
    away = Q + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
    far = SpheresOrMeshes(checker, wide, 0.005, 0.0, 7, ((away, narrow),), 0.3)
    assert not far.free(Q)
    assert (wide.checks, narrow.checks) == (2, 1) and near.mesh_checks == 3   # the shared checks, each asked


def test_a_path_from_a_goal_only_the_meshes_accept_keeps_the_meshes_clear(panda, model) -> None:
    obstacles = (BESIDE_LINK2,)
    validity = _validity(panda, model, obstacles, 0.003)
    start = Q + np.array([0.3, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0])
    lower, upper = panda.kinematics.lower, panda.kinematics.upper
    way = mesh_path(validity, start, Q, lower, upper, MeshEscapeSettings(checks=2000), seed=1)
    assert way is not None
    np.testing.assert_allclose(way[0], start)
    np.testing.assert_allclose(way[-1], Q)
    exact = MeshGoalCheck(model, 0.0)
    exact.set_obstacles(obstacles)
    assert exact.polyline_free(way, 0.005, 0.0015)
    blocked = _validity(panda, model, obstacles, 0.03)   # Q refused: no path
    assert mesh_path(blocked, start, Q, lower, upper, MeshEscapeSettings(checks=200)) is None


def test_the_way_ends_at_the_last_configuration_the_spheres_accept() -> None:
    way = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    cruise, approach = _split(way, lambda q: q[1] <= 0.5, 0.1)
    np.testing.assert_allclose(cruise, [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5]])
    np.testing.assert_allclose(approach, [[1.0, 0.5], [1.0, 1.0]])
    cruise, approach = _split(way, lambda q: False, 0.1)
    assert cruise is None and approach is way


def test_a_bent_approach_is_measured_on_its_nearest_piece() -> None:
    straight = np.linspace([0.0, 0.0], [2.0, 0.0], 5)
    q = np.array([0.5, 0.3])
    assert along_segment(straight, q) == pytest.approx(0.25)
    assert segment_offset(straight, q) == pytest.approx(0.3)
    np.testing.assert_allclose(across_segment(straight, q), [0.0, -0.3])
    bent = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    on_second = np.array([1.2, 0.5])
    assert along_segment(bent, on_second) == pytest.approx(0.75)
    assert segment_offset(bent, on_second) == pytest.approx(0.2)
    np.testing.assert_allclose(across_segment(bent, on_second), [-0.2, 0.0])   # not toward the chord


def test_a_bent_approach_allows_only_what_is_near_the_robot() -> None:
    bent = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0], [2.0, 3.0], [2.0, 4.0]])
    table = np.array([[0.0], [0.01], [0.0], [0.0], [0.0], [0.0], [0.05]])   # (k, one obstacle) [m]
    assert allowances_ahead(bent, table, np.array([0.1, 0.0]))[0] == pytest.approx(0.01)   # not the end's 5 cm
    assert allowances_ahead(bent, table, np.array([2.0, 3.9]))[0] == pytest.approx(0.05)
    straight = np.linspace([0.0, 0.0], [6.0, 0.0], 7)
    assert allowances_ahead(straight, table, np.array([0.1, 0.0]))[0] == pytest.approx(0.05)   # as before


def test_bad_settings_are_refused_by_name() -> None:
    for name in ("checks", "step", "resolution", "budget", "coverage"):
        with pytest.raises(ValueError, match=f"mesh_escape.{name}"):
            MeshEscapeSettings(**{name: -1.0})
    with pytest.raises(ValueError, match=r"mesh_escape.clearances\[1\]"):
        MeshEscapeSettings(clearances=(0.006, float("nan")))
