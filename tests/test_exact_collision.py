"""Mesh-to-shape and mesh-to-mesh distances (geometry/exact_collision.py) against closed
forms, trimesh and brute force."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from dynfab.geometry.exact_collision import (
    exact_distance, hull_distance, mesh_set, placement_matrix, shape_bounding_radius, shape_geometry,
)
from dynfab.geometry.shapes import (
    Box, Capsule, Cylinder, Placement, Plane, Sphere, quaternion_from_normal, quaternion_from_rpy,
)


def pose(position: tuple[float, float, float], rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    return placement_matrix(Placement(position, quaternion_from_rpy(rpy)))


def box_point_distance(size: np.ndarray, point: np.ndarray) -> float:
    """Signed distance of a point to an axis-aligned centred box (closed form)."""
    q = np.abs(point) - 0.5 * size
    return float(np.linalg.norm(np.maximum(q, 0.0)) + min(max(q.max(), -np.inf), 0.0))


CUBE = mesh_set([trimesh.creation.box(extents=(0.2, 0.2, 0.2))])


@pytest.mark.parametrize("center", [(0.5, 0.0, 0.0), (0.3, 0.25, -0.2), (0.12, 0.05, 0.0), (0.0, 0.0, 0.05)])
def test_box_mesh_to_sphere_is_the_closed_form(center: tuple[float, float, float]) -> None:
    radius = 0.04
    expected = box_point_distance(np.array([0.2, 0.2, 0.2]), np.array(center)) - radius
    sphere = shape_geometry(Sphere(radius))
    assert exact_distance(CUBE, np.eye(4), sphere, pose(center)) == pytest.approx(expected, abs=1e-6)
    assert hull_distance(CUBE, np.eye(4), sphere, pose(center)) == pytest.approx(expected, abs=1e-6)


@pytest.mark.parametrize(("shape", "half_height"), [
    (Box((0.3, 0.4, 0.5)), 0.25), (Cylinder(0.2, 0.6), 0.3), (Capsule(0.1, 0.6), 0.4), (Sphere(0.15), 0.15)])
def test_shape_sizes_follow_shapes_py(shape: Box | Cylinder | Capsule | Sphere, half_height: float) -> None:
    """A cube 0.1 m above the shape's top along its z axis, in a rotated frame."""
    frame = pose((0.3, -0.2, 0.7), (0.4, -0.3, 1.0))
    above = frame @ pose((0.0, 0.0, half_height + 0.1 + 0.1))
    assert exact_distance(CUBE, above, shape_geometry(shape), frame) == pytest.approx(0.1, abs=1e-6)
    assert shape_bounding_radius(shape) >= half_height


def test_plane_is_a_solid_half_space() -> None:
    normal = (0.3, -0.2, 1.0)
    plane = Placement((0.1, 0.2, 0.3), quaternion_from_normal(normal))
    n = np.array(normal) / np.linalg.norm(normal)
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    body = mesh_set([mesh])
    for height in (0.4, 0.05, -0.02, -0.5):  # centre's height above the plane [m]
        where = np.eye(4)
        where[:3, 3] = np.array(plane.position) + height * n
        world = mesh.vertices + where[:3, 3]
        expected = float(np.min((world - plane.position) @ n))  # convex: the lowest vertex
        got = exact_distance(body, where, shape_geometry(Plane()), placement_matrix(plane))
        if expected > 0:
            assert got == pytest.approx(expected, abs=1e-6)
        else:  # in contact: minus the penetration depth of the hull
            assert got == pytest.approx(expected, abs=1e-6)
            assert got < 0.0


def test_against_trimesh_closest_points_on_random_placements() -> None:
    mesh = trimesh.creation.capsule(height=0.3, radius=0.05)
    mesh.apply_transform(pose((0.0, 0.0, 0.0), (0.3, 0.2, 0.0)))
    body = mesh_set([mesh])
    rng = np.random.default_rng(3)
    centers = rng.uniform(-0.4, 0.4, (60, 3))
    outside = centers[~mesh.contains(centers)]
    _, gaps, _ = trimesh.proximity.closest_point(mesh, outside)
    radius = 0.02
    for center, gap in zip(outside, gaps):
        got = exact_distance(body, np.eye(4), shape_geometry(Sphere(radius)), pose(tuple(center)))
        assert got == pytest.approx(gap - radius, abs=1e-6)


def test_non_convex_mesh_is_exact_where_its_hull_is_not() -> None:
    """An L of two bars; a ball in the notch is inside the hull but 0.03 m from the L."""
    bar_x = trimesh.creation.box(extents=(0.4, 0.1, 0.1), transform=pose((0.2, 0.05, 0.0)))
    bar_y = trimesh.creation.box(extents=(0.1, 0.4, 0.1), transform=pose((0.05, 0.2, 0.0)))
    letter = mesh_set([trimesh.util.concatenate([bar_x, bar_y])])
    ball = shape_geometry(Sphere(0.02))
    where = pose((0.15, 0.15, 0.0))  # 0.05 m from each bar's inner face
    assert hull_distance(letter, np.eye(4), ball, where) < 0.0
    assert exact_distance(letter, np.eye(4), ball, where) == pytest.approx(0.03, abs=1e-6)
    touching = pose((0.15, 0.11, 0.0))  # 0.01 m into bar_x
    assert exact_distance(letter, np.eye(4), ball, touching) <= 0.0


def test_mesh_to_mesh_gap_and_penetration() -> None:
    other = mesh_set([trimesh.creation.box(extents=(0.2, 0.2, 0.2))])
    assert exact_distance(CUBE, np.eye(4), other, pose((0.35, 0.0, 0.0))) == pytest.approx(0.15, abs=1e-6)
    assert exact_distance(CUBE, np.eye(4), other, pose((0.17, 0.0, 0.0))) == pytest.approx(-0.03, abs=1e-6)
    tilted = pose((0.0, 0.0, 0.4), (0.0, 0.0, np.pi / 4))
    assert exact_distance(CUBE, np.eye(4), other, tilted) == pytest.approx(0.2, abs=1e-6)


def test_a_mesh_set_measures_its_nearest_part_and_bounds_every_vertex() -> None:
    near = trimesh.creation.box(extents=(0.1, 0.1, 0.1), transform=pose((0.0, 0.0, 0.0)))
    far = trimesh.creation.box(extents=(0.1, 0.1, 0.1), transform=pose((1.0, 0.0, 0.0)))
    body = mesh_set([near, far])
    sphere = shape_geometry(Sphere(0.05))
    assert exact_distance(body, np.eye(4), sphere, pose((1.2, 0.0, 0.0))) == pytest.approx(0.1, abs=1e-6)
    vertices = np.vstack([near.vertices, far.vertices])
    assert np.all(np.linalg.norm(vertices - body.center, axis=1) <= body.radius + 1e-12)
    with pytest.raises(ValueError, match="at least one mesh"):
        mesh_set([])


def test_a_solid_wholly_inside_a_mesh_touches_it() -> None:
    """No surfaces cross, yet the inner solid is in contact (ray-parity containment)."""
    small = mesh_set([trimesh.creation.box(extents=(0.04, 0.04, 0.04))])
    inner = pose((0.02, -0.03, 0.01), (0.2, 0.1, 0.3))
    assert exact_distance(CUBE, np.eye(4), small, inner) < 0.0
    assert exact_distance(small, inner, CUBE, np.eye(4)) < 0.0
    assert exact_distance(CUBE, np.eye(4), shape_geometry(Sphere(0.02)), inner) < 0.0
    assert exact_distance(CUBE, np.eye(4), small, pose((0.2, 0.0, 0.0))) == pytest.approx(0.08, abs=1e-6)
