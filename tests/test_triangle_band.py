"""The exact band of a mesh's distance grid: the compiled loop against numpy's, and both
against trimesh's closest points (an independent implementation)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from dynfab.geometry import triangle_band as band_module
from dynfab.geometry.triangle_band import numpy_triangle_band, triangle_band


@pytest.fixture(scope="module")
def mesh() -> trimesh.Trimesh:
    """A sphere, a thin board and a sliver triangle, so every Voronoi region of a triangle
    (vertex, edge, face) is somebody's nearest."""
    board = trimesh.creation.box(extents=(0.3, 0.2, 0.01)).apply_translation((0.25, 0.0, 0.0))
    sliver = trimesh.Trimesh([[0.0, 0.2, 0.1], [0.2, 0.2, 0.1], [0.1, 0.2001, 0.1]], [[0, 1, 2]])
    return trimesh.util.concatenate([trimesh.creation.icosphere(2, 0.08), board, sliver])


def _grid(mesh: trimesh.Trimesh, band: float) -> tuple[np.ndarray, float, tuple[int, int, int]]:
    pitch = 0.013
    origin = mesh.bounds[0] - band - 0.004
    shape = tuple(int(n) for n in np.ceil((mesh.bounds[1] - origin + band) / pitch) + 1)
    return origin, pitch, shape


def test_the_compiled_band_is_numpys(mesh: trimesh.Trimesh) -> None:
    if band_module._compiled() is None:
        pytest.skip("no C compiler: triangle_band is numpy's")
    origin, pitch, shape = _grid(mesh, 0.05)
    compiled = triangle_band(mesh.vertices[mesh.faces], origin, pitch, shape, 0.05)
    reference = numpy_triangle_band(mesh.vertices[mesh.faces], origin, pitch, shape, 0.05)
    assert np.array_equal(np.isfinite(compiled), np.isfinite(reference))
    finite = np.isfinite(reference)
    assert finite.sum() > 1000 and np.abs(compiled[finite] - reference[finite]).max() < 1e-12


def test_the_band_is_exact_within_band_and_never_below_the_distance(mesh: trimesh.Trimesh) -> None:
    band = 0.05
    origin, pitch, shape = _grid(mesh, band)
    exact = triangle_band(mesh.vertices[mesh.faces], origin, pitch, shape, band)
    nodes = origin + np.argwhere(np.ones(shape, dtype=bool)) * pitch
    _, truth, _ = trimesh.proximity.closest_point(mesh, nodes)
    values = exact.reshape(-1)
    within = truth <= band
    assert within.sum() > 1000
    np.testing.assert_allclose(values[within], truth[within], atol=1e-9)   # every node within band: exact
    reached = np.isfinite(values)
    assert (values[reached] >= truth[reached] - 1e-9).all()               # farther: never below (a min over some)
