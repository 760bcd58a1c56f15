"""The configuration checker (the global planner's validity check): the compiled kernel
against an independent numpy evaluation (forward kinematics by pinocchio-checked CasADi,
distances by dynfab.geometry.distance), on random configurations and every shape kind."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dynfab.geometry.distance import placed_distance
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Placement, Plane, Sphere, quaternion_from_normal
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.robots import load_robot


def _scene(rng: np.random.Generator) -> list[PlacedObstacle]:
    def placement() -> Placement:
        return Placement(tuple(rng.uniform(-0.7, 0.7, 3)), tuple(rng.normal(size=4)))

    obstacles = [PlacedObstacle(Box(tuple(rng.uniform(0.02, 0.4, 3))), placement()) for _ in range(6)]
    obstacles += [PlacedObstacle(Cylinder(float(rng.uniform(0.02, 0.1)), float(rng.uniform(0.05, 0.4))), placement())
                  for _ in range(3)]
    obstacles += [PlacedObstacle(Capsule(0.05, 0.3), placement()), PlacedObstacle(Sphere(0.1), placement()),
                  PlacedObstacle(Plane(), Placement((0.0, 0.0, -0.3), quaternion_from_normal((0.1, 0.0, 1.0))))]
    return obstacles


def _moving(robot) -> np.ndarray:
    """The spheres whose centres differ between two configurations (c_obs is over these)."""
    kin = robot.kinematics
    a, b = np.asarray(robot.sphere_centers(kin.lower / 2)), np.asarray(robot.sphere_centers(kin.upper / 2))
    return np.flatnonzero(np.linalg.norm(a - b, axis=1) > 1e-9)


def _reference(robot, obstacles, q: np.ndarray) -> tuple[float, float]:
    centres = np.asarray(robot.sphere_centers(q))
    radii = robot.sphere_radii
    moving = _moving(robot)
    obstacle = min(float((placed_distance(o.shape, o.placement, centres[moving]) - radii[moving]).min())
                   for o in obstacles)
    itself = min(float(np.linalg.norm(centres[a] - centres[b]) - radii[a] - radii[b])
                 for a, b in robot.self_collision_pairs)
    return obstacle, itself


@pytest.fixture(scope="module")
def panda():
    """The fabric's spheres alone (no fine spheres: the kernel against its reference)."""
    return replace(load_robot("panda"), fine_spheres=None)


def test_compiled_kernel_equals_the_numpy_distances(panda) -> None:
    rng = np.random.default_rng(3)
    obstacles = _scene(rng)
    checker = ConfigurationChecker(panda, obstacles)
    assert checker.compiled
    qs = rng.uniform(panda.kinematics.lower, panda.kinematics.upper, (200, panda.dof))
    batch = checker.batch(qs)
    for q, row in zip(qs, batch):
        expected = _reference(panda, obstacles, q)
        assert row == pytest.approx(expected, abs=1e-12)
        assert checker.clearances(q) == pytest.approx(expected, abs=1e-12)
    assert (batch[:, 0] < 0).any() and (batch[:, 0] > 0).any()  # the scene is neither empty nor solid


def test_a_sphere_no_joint_moves_blocks_no_configuration(panda) -> None:
    """An obstacle touching only the base's spheres (the same at every configuration) leaves
    every configuration that keeps the others clear free; counted, it blocked them all
    (held-out MBM kitchen/0012: the base 4.8 mm from a dishwasher door)."""
    moving = _moving(panda)
    base = np.setdiff1d(np.arange(len(panda.sphere_radii)), moving)
    assert base.size
    q = np.asarray(panda.default_q, dtype=float)
    centre = np.asarray(panda.sphere_centers(q))[base[0]]
    touching = PlacedObstacle(Sphere(0.02), Placement(tuple(centre + [0.0, 0.0, -panda.sphere_radii[base[0]]]),
                                                      (1.0, 0.0, 0.0, 0.0)))
    for checker in (ConfigurationChecker(panda, [touching]), _numpy_checker(panda, [touching])):
        obstacle, _ = checker.clearances(q)
        assert obstacle > 0.01
        assert checker.free(q, 0.01, 0.0)


def _numpy_checker(robot, obstacles) -> ConfigurationChecker:
    checker = ConfigurationChecker(robot, obstacles)
    checker._library = None   # the numpy evaluation, as without a C compiler
    return checker


def test_free_and_first_blocked_agree_with_the_clearances(panda) -> None:
    rng = np.random.default_rng(4)
    checker = ConfigurationChecker(panda, _scene(rng))
    qs = rng.uniform(panda.kinematics.lower, panda.kinematics.upper, (300, panda.dof))
    values = checker.batch(qs)
    for margin, self_margin in ((0.0, 0.0), (0.05, 0.01), (-0.02, -1.0)):
        expected = (values[:, 0] >= margin) & (values[:, 1] >= self_margin)
        assert [checker.free(q, margin, self_margin) for q in qs] == expected.tolist()
        blocked = np.flatnonzero(~expected)
        assert checker.first_blocked(qs, margin, self_margin) == (int(blocked[0]) if blocked.size else -1)


def _compiled_and_plain(robot, obstacles, monkeypatch) -> tuple[ConfigurationChecker, ConfigurationChecker]:
    """The compiled checker and the numpy one (as without a C compiler) on the same scene."""
    import dynfab.motion.configuration_checker as module

    compiled = ConfigurationChecker(robot, obstacles)
    monkeypatch.setattr(module, "load_checker_library", lambda robot: None)
    plain = ConfigurationChecker(robot, obstacles)
    assert compiled.compiled and not plain.compiled
    return compiled, plain


def test_without_a_compiler_the_numpy_path_gives_the_same_numbers(panda, monkeypatch) -> None:
    rng = np.random.default_rng(5)
    compiled, plain = _compiled_and_plain(panda, _scene(rng), monkeypatch)
    qs = rng.uniform(panda.kinematics.lower, panda.kinematics.upper, (20, panda.dof))
    np.testing.assert_allclose(plain.batch(qs), compiled.batch(qs), atol=1e-12)
    assert plain.first_blocked(qs, 0.0, 0.0) == compiled.first_blocked(qs, 0.0, 0.0)


def test_no_obstacles_is_infinitely_clear(panda) -> None:
    checker = ConfigurationChecker(panda)
    obstacle, itself = checker.clearances(np.asarray(panda.default_q))
    assert obstacle == np.inf and np.isfinite(itself)


def test_a_motion_is_free_exactly_when_its_configurations_step_apart_are(panda, monkeypatch) -> None:
    rng = np.random.default_rng(6)
    compiled, plain = _compiled_and_plain(panda, _scene(rng), monkeypatch)
    lower, upper = panda.kinematics.lower, panda.kinematics.upper
    step, margin, self_margin = 0.05, 0.01, 0.0
    outcomes = []
    for _ in range(60):
        a = rng.uniform(lower, upper)
        b = np.clip(a + rng.normal(scale=rng.choice([0.02, 0.3, 1.0]), size=panda.dof), lower, upper)
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        along = a + (np.arange(1, count + 1) / count)[:, None] * (b - a)
        expected = compiled.first_blocked(along, margin, self_margin) < 0
        free, checked = compiled.motion_free(a, b, step, margin, self_margin)
        assert free == expected
        assert 1 <= checked <= count and (checked == count or not free)
        assert plain.motion_free(a, b, step, margin, self_margin)[0] == expected
        outcomes.append(expected)
    assert any(outcomes) and not all(outcomes)


def test_obstacles_set_again_around_the_same_meshes_read_as_a_fresh_checker_reads_them(panda) -> None:
    import trimesh

    from dynfab.geometry.point_cloud import PointCloud
    from dynfab.geometry.shapes import Mesh

    rng = np.random.default_rng(5)
    box = trimesh.creation.box(extents=(0.3, 0.05, 0.4))
    mesh = Mesh(box.vertices, box.faces, "slab")
    cloud = PointCloud.from_points(rng.uniform((0.2, -0.3, 0.0), (0.5, 0.3, 0.02), (3000, 3)), 0.01)
    at = Placement((0.0, 0.0, 0.0))

    def scene(shift: float) -> list[PlacedObstacle]:   # the same mesh and cloud, primitives and the mesh moved
        return [PlacedObstacle(Sphere(0.1), Placement((0.4 + shift, 0.2, 0.5))),
                PlacedObstacle(mesh, Placement((0.45, -0.2 + shift, 0.4))), PlacedObstacle(cloud, at),
                PlacedObstacle(Box((0.1, 0.1, 0.1)), Placement((0.3, 0.0, 0.8 - shift)))]

    checker = ConfigurationChecker(panda, scene(0.0))
    qs = rng.uniform(panda.kinematics.lower, panda.kinematics.upper, (100, panda.dof))
    first = checker.batch(qs)
    buffer = checker._rows
    checker.set_obstacles(scene(0.15))
    assert checker._rows is buffer   # written in place, the grids not copied again
    moved = checker.batch(qs)
    np.testing.assert_array_equal(moved, ConfigurationChecker(panda, scene(0.15)).batch(qs))
    assert np.any(moved[:, 0] != first[:, 0])
    checker.set_obstacles(scene(0.15)[:3])   # one fewer: a new buffer, read as fresh
    np.testing.assert_array_equal(checker.batch(qs), ConfigurationChecker(panda, scene(0.15)[:3]).batch(qs))


def test_fine_spheres_give_the_larger_clearance_and_every_answer_agrees_with_it() -> None:
    robot = load_robot("panda").planning_robot
    assert robot.fine_robot is not None
    rng = np.random.default_rng(8)
    obstacles = _scene(rng)
    checker = ConfigurationChecker(robot, obstacles)
    coarse = ConfigurationChecker(replace(robot, fine_spheres=None), obstacles)
    fine = ConfigurationChecker(robot.fine_robot, obstacles)
    qs = rng.uniform(robot.kinematics.lower, robot.kinematics.upper, (1000, robot.dof))
    values = checker.batch(qs)
    expected = coarse.batch(qs)
    expected[:, 0] = np.maximum(expected[:, 0], fine.batch(qs)[:, 0])
    np.testing.assert_array_equal(values, expected)
    margin, self_margin = 0.01, 0.0
    ok = (values[:, 0] >= margin) & (values[:, 1] >= self_margin)
    only_fine = ok & ~((coarse.batch(qs)[:, 0] >= margin) & (values[:, 1] >= self_margin))
    assert only_fine.sum() >= 5   # configurations the fine spheres free
    assert [checker.free(q, margin, self_margin) for q in qs] == list(ok)
    assert checker.clearances(qs[0]) == pytest.approx(tuple(values[0]), abs=0.0)
    for start in range(0, 1000, 50):
        blocked = np.flatnonzero(~ok[start:start + 50])
        assert checker.first_blocked(qs[start:start + 50], margin, self_margin) == (blocked[0] if blocked.size else -1)
    for a, b in zip(qs[:-1:7], qs[1::7]):   # a motion is free exactly when its configurations are
        free, checked = checker.motion_free(a, b, 0.05, margin, self_margin)
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / 0.05)))
        steps = a + (np.arange(count, 0, -1) / count)[:, None] * (b - a)
        assert free == bool(np.all(checker.batch(steps)[:, 0] >= margin) and np.all(checker.batch(steps)[:, 1] >= 0.0))
        assert checked >= 1


def test_the_second_look_leaves_meshes_and_clouds_to_the_planning_spheres() -> None:
    import trimesh

    from dynfab.geometry.point_cloud import PointCloud
    from dynfab.geometry.shapes import Mesh

    robot = load_robot("panda").planning_robot
    plain = replace(robot, fine_spheres=None)
    rng = np.random.default_rng(9)
    slab = trimesh.creation.box(extents=(0.4, 0.05, 0.5))
    surfaces = [PlacedObstacle(Mesh(slab.vertices, slab.faces, "slab"), Placement((0.45, -0.25, 0.35))),
                PlacedObstacle(PointCloud.from_points(rng.uniform((0.2, 0.2, 0.0), (0.6, 0.5, 0.02), (2000, 3)), 0.01),
                               Placement((0.0, 0.0, 0.0)))]
    primitives = _scene(rng)[:6]
    qs = rng.uniform(robot.kinematics.lower, robot.kinematics.upper, (400, robot.dof))
    mixed = ConfigurationChecker(robot, primitives + surfaces)
    looked = np.minimum(np.maximum(ConfigurationChecker(plain, primitives).batch(qs)[:, 0],
                                   ConfigurationChecker(robot.fine_robot, primitives).batch(qs)[:, 0]),
                        ConfigurationChecker(plain, surfaces).batch(qs)[:, 0])
    values = mixed.batch(qs)
    np.testing.assert_allclose(values[:, 0], looked, rtol=0.0, atol=1e-12)
    assert [mixed.free(q, 0.01, 0.0) for q in qs] == list((values[:, 0] >= 0.01) & (values[:, 1] >= 0.0))
    only_surfaces = ConfigurationChecker(robot, surfaces)   # no second look: its own spheres' clearance
    np.testing.assert_array_equal(only_surfaces.batch(qs), ConfigurationChecker(plain, surfaces).batch(qs))


def test_the_motion_order_is_the_compiled_kernels() -> None:
    from dynfab.motion.configuration_checker import _motion_order

    for count in range(1, 40):
        order = _motion_order(count)
        assert order[0] == count and sorted(order) == list(range(1, count + 1))
    assert _motion_order(8) == [8, 4, 2, 6, 1, 3, 5, 7]


def test_without_a_compiler_the_second_look_refines_a_motion_as_the_kernel_does(monkeypatch) -> None:
    robot = load_robot("panda").planning_robot
    rng = np.random.default_rng(10)
    obstacles = _scene(rng)[:6]
    compiled = ConfigurationChecker(robot, obstacles)
    import dynfab.motion.configuration_checker as module

    monkeypatch.setattr(module, "load_checker_library", lambda robot: None)
    interpreted = ConfigurationChecker(robot, obstacles)
    assert not interpreted.compiled
    qs = rng.uniform(robot.kinematics.lower, robot.kinematics.upper, (41, robot.dof))
    for a, b in zip(qs[:-1], qs[1:]):
        assert interpreted.motion_free(a, b, 0.1, 0.01, 0.0) == compiled.motion_free(a, b, 0.1, 0.01, 0.0)
