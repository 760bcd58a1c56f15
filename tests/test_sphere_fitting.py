"""Sphere fitting on primitives, checked against their exact geometry (not the fitter's samples)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from dynfab.geometry.sphere_fitting import SphereFitParameters, fit_spheres, outside_distances


def _box_surface(size: np.ndarray, step: float) -> np.ndarray:
    """A grid on every face of the box centred at 0 (corners and edges included)."""
    half = size / 2
    points = []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        gu = np.linspace(-half[u], half[u], int(np.ceil(size[u] / step)) + 1)
        gv = np.linspace(-half[v], half[v], int(np.ceil(size[v] / step)) + 1)
        uu, vv = np.meshgrid(gu, gv)
        for sign in (-1.0, 1.0):
            face = np.zeros((uu.size, 3))
            face[:, u], face[:, v], face[:, axis] = uu.ravel(), vv.ravel(), sign * half[axis]
            points.append(face)
    return np.vstack(points)


def _cylinder_surface(radius: float, length: float, step: float) -> np.ndarray:
    """A grid on the side and both caps of the true (round) cylinder along z."""
    angles = np.linspace(0, 2 * np.pi, int(2 * np.pi * radius / step) + 1)
    heights = np.linspace(-length / 2, length / 2, int(length / step) + 1)
    aa, hh = np.meshgrid(angles, heights)
    side = np.column_stack([radius * np.cos(aa.ravel()), radius * np.sin(aa.ravel()), hh.ravel()])
    rings = np.linspace(0, radius, int(radius / step) + 1)
    rr, ca = np.meshgrid(rings, angles)
    disc = np.column_stack([rr.ravel() * np.cos(ca.ravel()), rr.ravel() * np.sin(ca.ravel())])
    caps = [np.column_stack([disc, np.full(len(disc), z)]) for z in (-length / 2, length / 2)]
    return np.vstack([side, *caps])


def test_box_is_covered_within_tolerance_by_spheres_inside_it() -> None:
    size = np.array([0.30, 0.12, 0.08])
    fit = fit_spheres([trimesh.creation.box(extents=size)])
    centers = np.array([s.center for s in fit.spheres])
    radii = np.array([s.radius for s in fit.spheres])
    outside = outside_distances(_box_surface(size, 0.002), centers, radii)
    assert outside.max() <= 0.01 + 5e-4
    assert np.all(np.abs(centers) < size / 2)  # centres inside the box
    depth = (size / 2 - np.abs(centers)).min(axis=1)  # exact distance to the box surface
    # the reported bulge is the exact one, and it keeps the bound even at the corners (which
    # therefore need spheres of their own: 20 here, 14 when the last step could grow a
    # sphere 1 cm beyond it)
    assert fit.bulge == pytest.approx(max((radii - depth).max(), 0.0), abs=1e-6)
    assert fit.bulge <= SphereFitParameters().max_bulge + 1e-12
    assert fit.coverage <= 0.01 + 1e-9
    # a sphere centred at depth <= 0.04 m reaching <= 0.06 m covers a disc of radius
    # <= sqrt(0.06^2 - 0.04^2) = 0.045 m of the 0.30 x 0.12 m top face: at least 4 are needed
    assert 4 <= len(fit.spheres) <= 24


def test_cylinder_is_covered_within_tolerance() -> None:
    radius, length = 0.05, 0.40
    mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=64)
    fit = fit_spheres([mesh])
    centers = np.array([s.center for s in fit.spheres])
    radii = np.array([s.radius for s in fit.spheres])
    # the tessellation lies within radius (1 - cos(pi / 64)) = 0.06 mm of the round surface
    assert outside_distances(_cylinder_surface(radius, length, 0.002), centers, radii).max() <= 0.01 + 5e-4
    depth = np.minimum(radius - np.hypot(centers[:, 0], centers[:, 1]), length / 2 - np.abs(centers[:, 2]))
    assert np.all(depth > 0)
    assert fit.bulge == pytest.approx(max((radii - depth).max(), 0.0), abs=2e-3)  # 64-gon vs circle
    assert fit.bulge <= 0.03
    # a covering sphere of radius <= r + 0.02 m spans at most 2 sqrt(0.08^2 - 0.05^2) = 0.125 m of
    # the side, so at least 4 are needed for 0.4 m
    assert 4 <= len(fit.spheres) <= 8


def test_sphere_is_fitted_by_one_sphere_at_its_centre() -> None:
    fit = fit_spheres([trimesh.creation.icosphere(subdivisions=3, radius=0.07)])
    assert len(fit.spheres) == 1
    (sphere,) = fit.spheres
    # the farthest point of the round sphere of radius 0.07 m is |c| + 0.07 from the centre
    assert np.linalg.norm(sphere.center) + 0.07 - sphere.radius <= 0.01
    assert sphere.radius <= 0.07 + 0.02


def test_a_looser_tolerance_needs_fewer_spheres() -> None:
    mesh = trimesh.creation.cylinder(radius=0.04, height=0.5, sections=48)
    tight = fit_spheres([mesh], SphereFitParameters(tolerance=0.005))
    loose = fit_spheres([mesh], SphereFitParameters(tolerance=0.03))
    assert len(loose.spheres) < len(tight.spheres)
    assert tight.coverage <= 0.005 + 1e-12 and loose.coverage <= 0.03 + 1e-12


def test_fit_is_deterministic() -> None:
    mesh = trimesh.creation.box(extents=(0.2, 0.1, 0.1))
    assert fit_spheres([mesh]) == fit_spheres([mesh])


def test_invalid_parameters_name_the_field() -> None:
    with pytest.raises(ValueError, match="tolerance"):
        SphereFitParameters(tolerance=0.0)
    with pytest.raises(ValueError, match="no triangles"):
        fit_spheres([])


def test_fewest_spheres_cover_an_l_shape_with_fewer_spheres_than_greedy() -> None:
    arm = trimesh.creation.box(extents=(0.3, 0.06, 0.06))
    leg = trimesh.creation.box(extents=(0.06, 0.3, 0.06)).apply_translation((0.12, 0.12, 0.0))
    greedy = fit_spheres([arm, leg], SphereFitParameters(max_bulge=0.04))
    fewest = fit_spheres([arm, leg], SphereFitParameters(max_bulge=0.04, fewest=True))
    assert len(fewest.spheres) < len(greedy.spheres)
    surface = np.vstack([_box_surface(np.array([0.3, 0.06, 0.06]), 0.003),
                         _box_surface(np.array([0.06, 0.3, 0.06]), 0.003) + (0.12, 0.12, 0.0)])
    centers = np.array([s.center for s in fewest.spheres])
    radii = np.array([s.radius for s in fewest.spheres])
    assert outside_distances(surface, centers, radii).max() <= 0.01 + 5e-4
    assert fewest.coverage <= 0.01 + 1e-9 and fewest.bulge <= 0.05


def test_tight_fit_of_overlapping_boxes_keeps_both_bounds() -> None:
    """Four overlapping small boxes (a Franka finger's collision geometry) at 5 mm coverage
    and 1 cm bulge: the surface is covered within 5 mm and no sphere reaches more than
    1 cm out of the union (a centre's depth in its deepest box, trimesh's signed distance,
    is at most its depth in the union, so ``radius - depth`` bounds the reach)."""
    boxes = []
    for size, offset in (((0.022, 0.015, 0.020), (0.0, 0.0185, 0.011)), ((0.022, 0.0088, 0.0038), (0.0, 0.0068, 0.0022)),
                         ((0.0175, 0.007, 0.0235), (0.0, 0.0159, 0.02835)), ((0.0175, 0.0152, 0.0185), (0.0, 0.0076, 0.04525))):
        box = trimesh.creation.box(extents=size)
        box.apply_translation(offset)
        boxes.append(box)
    parameters = SphereFitParameters(tolerance=0.005, max_bulge=0.01, check_edge=0.002, fewest=True)
    fit = fit_spheres(boxes, parameters)
    centers = np.array([s.center for s in fit.spheres])
    radii = np.array([s.radius for s in fit.spheres])
    surface = np.vstack([trimesh.sample.sample_surface(box, 4000, seed=5)[0] for box in boxes])
    exposed = ~np.any([box.contains(surface) for box in boxes], axis=0)
    assert outside_distances(surface[exposed], centers, radii).max() <= 0.005 + 1e-9
    depth = np.max([np.maximum(trimesh.proximity.signed_distance(box, centers), 0.0) for box in boxes], axis=0)
    assert np.all(radii - depth <= 0.01 + 1e-9), radii - depth
    assert fit.bulge <= 0.01 + 1e-12 and fit.coverage <= 0.005 + 1e-9
