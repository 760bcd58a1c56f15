"""A braking nearest-point leaf among meshes (dynfab.perception.surfaces): the feed looks as far
as each sphere's stopping distance, and of several meshes writes the one the leaf acts on most,
the least clearance left after a stop, not the nearest (MBM kitchen seed 12/0010, session 21:
a hand at 1.5 m/s toward a cupboard door kept a nearer surface beside it and met the door)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

import dynfab
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.leaves.surface_points import NearestSurfaceAvoidance
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.shapes import Placement
from dynfab.perception.surfaces import PlacedMesh, SurfaceFeed
from dynfab.robots.robot import CollisionSphere

ARM = Path(__file__).resolve().parents[1] / "examples" / "custom_urdf" / "arm.urdf"
RADII = np.array([0.06, 0.06, 0.05])
#: the guided fabric's leaf: range 0.1 m, braking at 4 m/s² (dynfab.scenario.guided_controller)
BRAKING = Barrier(geometry_gain=5.0, energy_gain=0.02, horizon=0.1, offset=0.005, braking=4.0)


@pytest.fixture(scope="module")
def arm() -> dynfab.Robot:
    spheres = [CollisionSphere("link1", (0.5, 0.0, 0.0), RADII[0]), CollisionSphere("link2", (0.4, 0.0, 0.0), RADII[1]),
               CollisionSphere("tool", (0.0, 0.0, 0.0), RADII[2])]
    return dynfab.robot_from_urdf(ARM, goal_link="tool", spheres=spheres)


def _slab(size: tuple[float, float, float], centre: np.ndarray, name: str) -> PlacedMesh:
    box = trimesh.creation.box(extents=size)
    return PlacedMesh(Mesh(np.asarray(box.vertices), np.asarray(box.faces), name), Placement(tuple(centre)))


def _feed(arm: dynfab.Robot) -> tuple[SurfaceFeed, dict]:
    leaf = NearestSurfaceAvoidance(spheres=(0, 1, 2), barrier=BRAKING)
    planner = dynfab.FabricPlanner(arm, dynfab.PlannerConfig(goals=(dynfab.GoalConfig(link="tool"),), leaves=(leaf,),
                                                             backend="vm"))
    views = planner.parameters.leaves["surfaces"]
    return SurfaceFeed(arm, leaf, views), views


def _stretched(arm: dynfab.Robot, feed: SurfaceFeed) -> tuple[np.ndarray, np.ndarray, float]:
    """The stretched arm (along x), its tool's centre [m] and the tool's speed along +y per
    rad/s of the first joint [m/rad]."""
    q = np.zeros(3)
    velocity = feed.sphere_velocities(q, np.array([1.0, 0.0, 0.0]))[2]
    assert velocity[1] > 0.0 and abs(velocity[0]) + abs(velocity[2]) < 1e-9 * velocity[1]
    return q, np.asarray(arm.sphere_centers(q))[2], float(velocity[1])


def _written_clearance(views: dict, centre: np.ndarray, sphere: int, radius: float) -> float:
    point = np.asarray(views["points"]).reshape(-1, 3)[sphere]
    normal = np.asarray(views["normals"]).reshape(-1, 3)[sphere]
    return float(normal @ (centre - point)) - radius


def test_a_fast_sphere_is_fed_the_mesh_ahead_of_it_not_the_nearer_one_beside_it(arm: dynfab.Robot) -> None:
    feed, views = _feed(arm)
    q, tool, speed = _stretched(arm, feed)   # the tool moves along +y at ``speed`` per rad/s of joint 1
    # a slab 0.15 m ahead of the tool's surface, another 0.10 m below it (nearer)
    door = _slab((0.4, 0.02, 0.4), tool + np.array([0.0, RADII[2] + 0.15 + 0.01, 0.0]), "door")
    counter = _slab((0.4, 0.4, 0.02), tool - np.array([0.0, 0.0, RADII[2] + 0.10 + 0.01]), "counter")
    qdot = np.array([1.5 / speed, 0.0, 0.0])   # the tool at 1.5 m/s toward the door: 0.28 m to stop at 4 m/s²
    feed.write(q, [counter, door], qdot=qdot)
    assert views["active"][2] == 1.0
    assert _written_clearance(views, tool, 2, RADII[2]) == pytest.approx(0.15, abs=0.02)   # the door
    feed.write(q, [counter, door])   # at rest: the nearest
    assert _written_clearance(views, tool, 2, RADII[2]) == pytest.approx(0.10, abs=0.02)   # the counter
    # moving away from the door: the nearer again
    feed.write(q, [counter, door], qdot=-qdot)
    assert _written_clearance(views, tool, 2, RADII[2]) == pytest.approx(0.10, abs=0.02)


def test_a_mesh_beyond_the_range_is_seen_by_a_sphere_moving_toward_it(arm: dynfab.Robot) -> None:
    feed, views = _feed(arm)
    q, tool, speed = _stretched(arm, feed)
    wall = _slab((0.3, 0.02, 0.3), tool + np.array([0.0, RADII[2] + 0.2 + 0.01, 0.0]), "wall")   # 0.2 m: twice the range
    feed.write(q, [wall])
    assert views["active"][2] == 0.0
    feed.write(q, [wall], qdot=np.array([1.2 / speed, 0.0, 0.0]))   # 1.2 m/s: 0.18 m to stop
    assert views["active"][2] == 1.0
    assert _written_clearance(views, tool, 2, RADII[2]) == pytest.approx(0.2, abs=0.02)
    assert not math.isnan(float(np.asarray(views["points"]).sum()))
