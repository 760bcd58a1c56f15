"""The planner's focus on a mesh near the robot's ends: the clip of the surface to a box, the
carved grid of the rest, their bound in the compiled checker (never above the exact
distance to the triangles, closer to it than the whole mesh's grid inside the focus), the
focused obstacles around the robot's spheres, bad boxes and settings refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dynfab.geometry.distance_grid import distance_grid, point_triangle_distances
from dynfab.geometry.focused_mesh import CarvedMesh, FocusedMesh, carved, carved_grid, clip_mesh
from dynfab.geometry.mesh_shape import Mesh
from dynfab.geometry.shapes import Placement, Sphere
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle, mesh_grid
from dynfab.motion.mesh_focus import MeshFocus, focused_meshes
from dynfab.robots.builtin import load_robot

ORIGIN = Placement((0.0, 0.0, 0.0))
Q = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def _shelf() -> Mesh:
    """A board z = 0.3 and a wall x = 0.7, two large triangles each (one panel's size)."""
    board = [[0.2, -0.4, 0.3], [0.9, -0.4, 0.3], [0.9, 0.4, 0.3], [0.2, 0.4, 0.3]]
    wall = [[0.7, -0.4, 0.0], [0.7, 0.4, 0.0], [0.7, 0.4, 0.9], [0.7, -0.4, 0.9]]
    return Mesh(np.array(board + wall), np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]), "shelf")


def _exact(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    return np.min([point_triangle_distances(points, t) for t in mesh.vertices[mesh.faces]], axis=0)


def test_the_clipped_piece_is_the_surface_inside_the_box() -> None:
    mesh = _shelf()
    low, high = np.array([0.4, -0.1, 0.2]), np.array([0.8, 0.2, 0.5])
    piece = clip_mesh(mesh, low, high, 0.003)
    assert isinstance(piece, FocusedMesh) and piece.pitch == 0.003
    assert np.all(piece.vertices >= low - 1e-12) and np.all(piece.vertices <= high + 1e-12)
    corners = piece.vertices[piece.faces]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert area == pytest.approx(0.3 * 0.4 + 0.3 * 0.3)   # the board's 0.4 x 0.3, the wall's 0.3 x 0.3
    points = np.random.default_rng(0).uniform(low, high, (3000, 3))
    assert np.allclose(np.minimum(_exact(piece, points), _exact(mesh, points)), _exact(mesh, points))
    assert clip_mesh(mesh, [2.0, 2.0, 2.0], [3.0, 3.0, 3.0], 0.003) is None


def test_the_pieces_bound_the_distance_from_below_and_closer_than_the_whole_grid_inside() -> None:
    mesh = _shelf()
    low, high = np.array([0.4, -0.15, 0.15]), np.array([0.8, 0.15, 0.45])
    piece = clip_mesh(mesh, low, high, 0.003)
    rest = carved(mesh, [(low, high)])
    assert isinstance(rest, CarvedMesh) and piece is not None
    whole = distance_grid(mesh)
    rest_grid = carved_grid(whole, rest.holes)
    assert np.all(rest_grid.values >= whole.values)
    rng = np.random.default_rng(3)
    points = rng.uniform([0.1, -0.5, -0.1], [1.0, 0.5, 1.0], (20_000, 3))
    bound = np.minimum(distance_grid(piece, pitch=piece.pitch, margin=0.05).lower_bound(points),
                       rest_grid.lower_bound(points))
    exact = _exact(mesh, points)
    assert np.all(bound <= exact + 1e-9)
    inside = np.all((points > low + 0.05) & (points < high - 0.05), axis=1) & (exact < 0.04)
    assert inside.sum() > 100
    assert np.all(exact[inside] - bound[inside] <= 0.003 * math.sqrt(3) + 1e-9)
    assert np.mean(exact[inside] - whole.lower_bound(points[inside])) > 2 * np.mean(exact[inside] - bound[inside])


def test_the_checker_reads_the_focused_obstacles_between_the_whole_grid_and_the_exact_distance() -> None:
    robot = load_robot("panda")
    mesh = _shelf()
    centres = np.asarray(robot.sphere_centers(Q), dtype=float)
    radii = np.asarray(robot.sphere_radii, dtype=float)
    hand = int(np.argmax(centres[:, 0]))                       # the sphere farthest out
    placement = Placement((centres[hand, 0] + radii[hand] + 0.004 - 0.7, 0.0, 0.0))   # wall 4 mm off it
    obstacles = (PlacedObstacle(mesh, placement), PlacedObstacle(Sphere(0.05), Placement((-1.0, 0.0, 0.0))))
    focused = focused_meshes(obstacles, [centres], radii, mesh_grid, MeshFocus(reach=0.05, pitch=0.002))
    kinds = [type(o.shape) for o in focused]
    assert kinds == [FocusedMesh, CarvedMesh, Sphere]
    whole = ConfigurationChecker(robot, obstacles).clearances(Q)[0]
    fine = ConfigurationChecker(robot, focused).clearances(Q)[0]
    exact = min(float(np.min(_exact(mesh, placement.to_local(centres)) - radii)), whole + 1.0)
    assert whole <= fine <= exact + 1e-9
    assert fine >= exact - 0.002 * math.sqrt(3) - 1e-9
    far = (PlacedObstacle(mesh, Placement((2.0, 0.0, 0.0))),)
    assert focused_meshes(far, [centres], radii, mesh_grid, MeshFocus()) == far


@pytest.mark.parametrize(("low", "high", "message"), [
    ([0.0, 0.0], [1.0, 1.0, 1.0], "low and high must be 3 finite numbers"),
    ([0.0, np.inf, 0.0], [1.0, 1.0, 1.0], "low and high must be 3 finite numbers"),
    ([1.0, 0.0, 0.0], [0.0, 1.0, 1.0], "exceeds high"),
])
def test_a_bad_focus_box_is_refused(low: list, high: list, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        clip_mesh(_shelf(), low, high, 0.004)
    with pytest.raises(ValueError, match=message):
        carved(_shelf(), [(low, high)])


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"reach": -0.1}, "mesh focus reach"), ({"reach": math.nan}, "mesh focus reach"),
    ({"pitch": 0.0}, "mesh focus pitch"), ({"pitch": math.inf}, "mesh focus pitch"),
])
def test_bad_focus_settings_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        MeshFocus(**kwargs)
    with pytest.raises(ValueError, match="pitch must be a positive number"):
        FocusedMesh(_shelf().vertices, _shelf().faces, "shelf", 0.0)
