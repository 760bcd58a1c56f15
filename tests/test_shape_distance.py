"""Distances from points to obstacle shapes: exact numpy ones against brute force, the
smoothed CasADi ones against the exact ones and their stated bounds."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.geometry.distance import placed_distance, shape_distance
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Placement, Plane, Sphere, quaternion_from_rpy
from dynfab.geometry.smooth_distance import (
    box_smoothing_bound,
    cylinder_smoothing_bound,
    quaternion_rotation,
    smooth_box_distance,
    smooth_capsule_distance,
    smooth_cylinder_distance,
    smooth_plane_distance,
    smooth_sphere_distance,
)

RNG = np.random.default_rng(11)
BOX = Box((0.4, 0.2, 0.3))
CYLINDER = Cylinder(0.15, 0.5)
CAPSULE = Capsule(0.1, 0.4)
EPSILON = 0.01


def _surface_samples(shape: Box | Cylinder | Capsule, spacing: float) -> np.ndarray:
    """Points on the surface no farther than ``spacing`` apart."""
    if isinstance(shape, Box):
        half = np.array(shape.size) / 2
        points = []
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            gu = np.linspace(-half[u], half[u], int(2 * half[u] / spacing) + 2)
            gv = np.linspace(-half[v], half[v], int(2 * half[v] / spacing) + 2)
            grid_u, grid_v = np.meshgrid(gu, gv)
            for sign in (-1.0, 1.0):
                face = np.zeros((grid_u.size, 3))
                face[:, u], face[:, v], face[:, axis] = grid_u.ravel(), grid_v.ravel(), sign * half[axis]
                points.append(face)
        return np.vstack(points)
    angles = np.linspace(0, 2 * np.pi, int(2 * np.pi * shape.radius / spacing) + 2)
    half = shape.length / 2
    if isinstance(shape, Cylinder):
        heights = np.linspace(-half, half, int(shape.length / spacing) + 2)
        side = np.stack(np.meshgrid(angles, heights), -1).reshape(-1, 2)
        points = [np.column_stack([shape.radius * np.cos(side[:, 0]), shape.radius * np.sin(side[:, 0]), side[:, 1]])]
        radii = np.linspace(0, shape.radius, int(shape.radius / spacing) + 2)
        disc = np.stack(np.meshgrid(angles, radii), -1).reshape(-1, 2)
        for z in (-half, half):
            points.append(np.column_stack([disc[:, 1] * np.cos(disc[:, 0]), disc[:, 1] * np.sin(disc[:, 0]),
                                           np.full(len(disc), z)]))
        return np.vstack(points)
    # capsule: the side of a cylinder and two hemispherical caps
    heights = np.linspace(-half, half, int(shape.length / spacing) + 2)
    side = np.stack(np.meshgrid(angles, heights), -1).reshape(-1, 2)
    points = [np.column_stack([shape.radius * np.cos(side[:, 0]), shape.radius * np.sin(side[:, 0]), side[:, 1]])]
    polar = np.linspace(0, np.pi / 2, int(np.pi * shape.radius / spacing) + 2)
    cap = np.stack(np.meshgrid(angles, polar), -1).reshape(-1, 2)
    unit = np.column_stack([np.sin(cap[:, 1]) * np.cos(cap[:, 0]), np.sin(cap[:, 1]) * np.sin(cap[:, 0]),
                            np.cos(cap[:, 1])])
    for sign in (-1.0, 1.0):
        points.append(shape.radius * unit * [1.0, 1.0, sign] + [0.0, 0.0, sign * half])
    return np.vstack(points)


def _brute_force(shape: Box | Cylinder | Capsule, points: np.ndarray, spacing: float) -> np.ndarray:
    """Unsigned distance to the nearest surface sample."""
    surface = _surface_samples(shape, spacing)
    return np.min(np.linalg.norm(points[:, None, :] - surface[None, :, :], axis=-1), axis=1)


@pytest.mark.parametrize("shape", [BOX, CYLINDER, CAPSULE], ids=["box", "cylinder", "capsule"])
def test_exact_distance_matches_brute_force_sampling(shape: Box | Cylinder | Capsule) -> None:
    spacing = 0.006
    points = RNG.uniform(-0.5, 0.5, (200, 3))
    exact = shape_distance(shape, points)
    brute = _brute_force(shape, points, spacing)
    # sampling over-estimates the unsigned distance by at most half a sample diagonal
    np.testing.assert_array_less(np.abs(exact), brute + 1e-9)
    np.testing.assert_array_less(brute, np.abs(exact) + spacing)
    assert (exact < 0).any() and (exact > 0).any()


def test_sign_inside_and_simple_values() -> None:
    assert shape_distance(BOX, [[0.0, 0.0, 0.0]]) == pytest.approx(-0.1)
    assert shape_distance(BOX, [[0.5, 0.0, 0.0]]) == pytest.approx(0.3)
    assert shape_distance(BOX, [[0.3, 0.2, 0.0]]) == pytest.approx(np.hypot(0.1, 0.1))
    assert shape_distance(CYLINDER, [[0.0, 0.0, 0.0]]) == pytest.approx(-0.15)
    assert shape_distance(CYLINDER, [[0.25, 0.0, 0.35]]) == pytest.approx(np.hypot(0.1, 0.1))
    assert shape_distance(CAPSULE, [[0.0, 0.0, 0.5]]) == pytest.approx(0.2)
    assert shape_distance(Plane(), [[3.0, -2.0, 0.25]]) == pytest.approx(0.25)
    assert shape_distance(Sphere(0.2), [[0.0, 0.3, 0.4]]) == pytest.approx(0.3)


def test_placed_distance_rotates_and_translates() -> None:
    placement = Placement((1.0, 2.0, 0.5), quaternion_from_rpy((0.0, 0.0, np.pi / 2)))
    # the box's long x edge now lies along world y
    assert placed_distance(BOX, placement, [[1.0, 2.5, 0.5]]) == pytest.approx(0.3)
    assert placed_distance(BOX, placement, [[1.5, 2.0, 0.5]]) == pytest.approx(0.4)
    floor = Placement((0.0, 0.0, -0.1), quaternion_from_rpy((np.pi / 2, 0.0, 0.0)))  # normal along -y
    assert placed_distance(Plane(), floor, [[0.0, -0.3, 5.0]]) == pytest.approx(0.3)


def _smooth(kind: str) -> ca.Function:
    x = ca.SX.sym("x", 3)
    if kind == "box":
        d = smooth_box_distance(x, ca.DM(BOX.size), EPSILON)
    elif kind == "cylinder":
        d = smooth_cylinder_distance(x, CYLINDER.radius, CYLINDER.length, EPSILON)
    elif kind == "capsule":
        d = smooth_capsule_distance(x, CAPSULE.radius, CAPSULE.length)
    elif kind == "sphere":
        d = smooth_sphere_distance(x, 0.2)
    else:
        d = smooth_plane_distance(x)
    return ca.Function(kind, [x], [d])


SHAPES = {"box": (BOX, box_smoothing_bound(EPSILON)), "cylinder": (CYLINDER, cylinder_smoothing_bound(EPSILON)),
          "capsule": (CAPSULE, 1e-6), "sphere": (Sphere(0.2), 1e-6), "plane": (Plane(), 0.0)}


@pytest.mark.parametrize("kind", list(SHAPES))
def test_smoothed_distance_is_conservative_within_its_bound(kind: str) -> None:
    shape, bound = SHAPES[kind]
    points = RNG.uniform(-0.6, 0.6, (4000, 3))
    # many points near edges, corners and rims, where smoothing acts
    points[:1000] = RNG.uniform(-0.02, 0.02, (1000, 3)) + np.sign(RNG.normal(size=(1000, 3))) * 0.5 * np.array(
        BOX.size if kind == "box" else (CYLINDER.radius,) * 2 + (CYLINDER.length,))
    exact = shape_distance(shape, points)
    smooth = np.array(_smooth(kind).map(len(points))(points.T)).ravel()
    outside = exact >= 0
    assert outside.sum() > 500 and (~outside).sum() > 20
    np.testing.assert_array_less(smooth[outside], exact[outside] + 1e-12)          # never over-estimates
    np.testing.assert_array_less(exact - bound - 1e-12, smooth)                   # under by at most δ
    np.testing.assert_array_less(smooth[~outside], 1e-6)                          # inside stays inside
    if kind in ("box", "cylinder"):
        assert bound == pytest.approx(np.sqrt(3 if kind == "box" else 2) / 2 * EPSILON, abs=2e-6)
        assert np.max(exact[outside] - smooth[outside]) > 0.5 * bound  # the bound is nearly attained


@pytest.mark.parametrize("kind", ["box", "cylinder"])
def test_smoothed_distance_equals_exact_minus_bound_away_from_edges(kind: str) -> None:
    shape, bound = SHAPES[kind]
    # points in front of a face (or the cylinder's side/cap), > 5 cm from every edge plane
    if kind == "box":
        points = np.column_stack([RNG.uniform(0.25, 0.5, 200), RNG.uniform(-0.05, 0.05, 200),
                                  RNG.uniform(-0.1, 0.1, 200)])
    else:
        angle = RNG.uniform(0, 2 * np.pi, 200)
        rho = RNG.uniform(0.2, 0.5, 200)
        points = np.column_stack([rho * np.cos(angle), rho * np.sin(angle), RNG.uniform(-0.2, 0.2, 200)])
    exact = shape_distance(shape, points)
    smooth = np.array(_smooth(kind).map(len(points))(points.T)).ravel()
    np.testing.assert_allclose(smooth, exact - bound, atol=EPSILON**2 / (4 * 0.05) + 1e-9)


@pytest.mark.parametrize("kind", ["capsule", "sphere", "plane"])
def test_unsmoothed_distances_are_exact(kind: str) -> None:
    shape, _ = SHAPES[kind]
    points = RNG.uniform(-0.6, 0.6, (500, 3))
    smooth = np.array(_smooth(kind).map(len(points))(points.T)).ravel()
    np.testing.assert_allclose(smooth, shape_distance(shape, points), atol=2e-6)


def test_smoothed_distances_have_finite_derivatives_everywhere() -> None:
    x = ca.SX.sym("x", 3)
    for kind in SHAPES:
        d = _smooth(kind)(x)
        hessian = ca.Function("h", [x], [ca.hessian(d, x)[0], ca.gradient(d, x)])
        for point in ([0, 0, 0], [0, 0, 0.5], [0.2, 0.1, 0.15], [0.0, 0.0, 0.25], [0.15, 0.0, 0.25]):
            for value in hessian(point):
                assert np.isfinite(np.array(value)).all(), (kind, point)


def test_quaternion_rotation_matches_numpy_and_normalises() -> None:
    q = ca.SX.sym("q", 4)
    rotation = ca.Function("r", [q], [quaternion_rotation(q)])
    quaternion = quaternion_from_rpy((0.3, -0.7, 1.9))
    expected = Placement((0, 0, 0), quaternion).rotation
    np.testing.assert_allclose(np.array(rotation(quaternion)), expected, atol=1e-12)
    np.testing.assert_allclose(np.array(rotation(3.0 * np.array(quaternion))), expected, atol=1e-9)
    np.testing.assert_allclose(np.array(rotation([0, 0, 0, 0])), np.eye(3))


def test_closed_form_box_derivatives_equal_automatic_differentiation() -> None:
    from dynfab.geometry.smooth_distance import smooth_box_distance, smooth_box_distance_derivatives

    x, v, size = ca.SX.sym("x", 3), ca.SX.sym("v", 3), ca.SX.sym("s", 3)
    d = smooth_box_distance(x, size, 0.01)
    gradient = ca.gradient(d, x)
    automatic = ca.Function("ad", [x, v, size], [d, gradient, ca.dot(v, ca.mtimes(ca.hessian(d, x)[0], v))])
    closed = ca.Function("cf", [x, v, size], list(smooth_box_distance_derivatives(x, v, size, 0.01)))
    rng = np.random.default_rng(4)
    for _ in range(200):  # points around a box, many near its faces, edges and corners
        box = rng.uniform(0.05, 0.4, 3)
        point = rng.uniform(-0.6, 0.6, 3) * np.where(rng.random(3) < 0.3, box / 1.2, 1.0)
        velocity = rng.normal(size=3)
        for a, b in zip(automatic(point, velocity, box), closed(point, velocity, box)):
            np.testing.assert_allclose(np.array(b), np.array(a), rtol=1e-9, atol=1e-12)
