"""Distances between the collision meshes of a robot's bodies over many configurations.

A *body* is a set of links that never move relative to each other (see
:func:`dynfab.robots.self_collision.bodies`). The distance of two bodies at ``q`` is the
smallest exact distance (:func:`dynfab.geometry.exact_collision.exact_distance`, <= 0 when
they touch) between a link mesh of one and a link mesh of the other [m]. Link pairs whose
bounding spheres are farther apart than ``reach`` are not measured: there the distance is
reported as ``inf`` (it is larger than ``reach``), which saves most of the mesh queries.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from dynfab.geometry.exact_collision import exact_distance, mesh_set

from .kinematics import Kinematics
from .link_meshes import LinkMeshError, link_collision_meshes
from .mesh_collision import MeshCollisionModel

__all__ = ["BodyMeshes", "body_meshes"]


@dataclass(frozen=True, eq=False)
class BodyMeshes:
    """The collision meshes of a robot's links, grouped by body.

    Attributes:
        model: The links with meshes, their meshes, and their poses.
        body_links: Body number -> indices into ``model.links`` of its links with meshes.
    """

    model: MeshCollisionModel
    body_links: Mapping[int, tuple[int, ...]]

    def distances(self, q: np.ndarray, pairs: Sequence[tuple[int, int]],
                  reach: float) -> dict[tuple[int, int], np.ndarray]:
        """Distance of each body pair at each row of ``q``, shape (N,) per pair [m]; ``inf``
        where the bodies' bounding spheres are more than ``reach`` apart. Pairs with a body
        without meshes are left out of the result."""
        poses = self.model.link_poses(q)  # (N, L, 4, 4)
        meshes = self.model.meshes
        centres = np.einsum("nlij,lj->nli", poses[:, :, :3, :3], np.array([m.center for m in meshes])) \
            + poses[:, :, :3, 3]
        radii = np.array([m.radius for m in meshes])
        result = {}
        for a, b in pairs:
            if a not in self.body_links or b not in self.body_links:
                continue
            distance = np.full(len(q), np.inf)
            for i in self.body_links[a]:
                for j in self.body_links[b]:
                    bounds = np.linalg.norm(centres[:, i] - centres[:, j], axis=1) - radii[i] - radii[j]
                    for n in np.flatnonzero(bounds < reach):
                        distance[n] = min(distance[n], exact_distance(meshes[i], poses[n, i], meshes[j], poses[n, j]))
            result[(a, b)] = distance
        return result


def body_meshes(kinematics: Kinematics, body_of: Mapping[str, int], wanted: set[int]) -> BodyMeshes:
    """The meshes of the links of the ``wanted`` bodies that have collision geometry; a
    link whose mesh file is missing or unreadable is left out (a body left without meshes
    is not in :attr:`BodyMeshes.body_links`)."""
    links, sets = [], []
    for link in kinematics.link_names:
        if body_of[link] not in wanted:
            continue
        try:
            meshes = link_collision_meshes(kinematics.model, link)
        except LinkMeshError:
            continue
        if meshes:
            links.append(link)
            sets.append(mesh_set(meshes))
    model = MeshCollisionModel(kinematics, tuple(links), tuple(sets), ())
    grouped: dict[int, list[int]] = {}
    for index, link in enumerate(links):
        grouped.setdefault(body_of[link], []).append(index)
    return BodyMeshes(model, {body: tuple(indices) for body, indices in grouped.items()})

