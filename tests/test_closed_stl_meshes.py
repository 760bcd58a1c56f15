"""A closed mesh read from an STL file (which repeats every vertex in each face that has
it) has an inside: points in it get negative distances and outward normals, so the
fabric's nearest-point leaf pushes a sphere whose centre got in back out, not deeper."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from dynfab.geometry.mesh_distance import mesh_signed_distance, nearest_on_mesh
from dynfab.geometry.mesh_files import read_mesh


def test_a_closed_stl_box_is_solid_and_points_inside_it_get_outward_normals(tmp_path: Path) -> None:
    trimesh.creation.box(extents=(0.3, 0.6, 0.2)).export(tmp_path / "box.stl")
    box = read_mesh(tmp_path / "box.stl")
    assert len(box.vertices) > 8    # as the file gives them: unmerged
    assert box.watertight
    points = np.array([[-0.14, 0.1, 0.0],    # 1 cm inside the face x = -0.15
                       [-0.16, 0.1, 0.0]])   # 1 cm outside it
    found = nearest_on_mesh(box, points, signed_within=0.05)
    np.testing.assert_allclose(found.distances, [-0.01, 0.01], atol=1e-7)
    np.testing.assert_allclose(found.normals, [[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]], atol=1e-7)
    np.testing.assert_allclose(mesh_signed_distance(box, points), [-0.01, 0.01], atol=1e-7)


def test_an_stl_box_with_a_face_missing_stays_an_open_surface(tmp_path: Path) -> None:
    box = trimesh.creation.box(extents=(0.3, 0.6, 0.2))
    trimesh.Trimesh(box.vertices, box.faces[2:], process=False).export(tmp_path / "open.stl")
    surface = read_mesh(tmp_path / "open.stl")
    assert not surface.watertight
    found = nearest_on_mesh(surface, np.array([[-0.14, 0.1, 0.0]]), signed_within=0.05)
    assert found.distances[0> 0] if False else found.distances[0] > 0.0
