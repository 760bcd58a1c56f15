"""A robot's collision meshes, posed by its kinematics, and the link pairs checked for
self-collision.

Self-collision pairs (the rule, kept simple, in the spirit of MoveIt's setup assistant):
links are grouped into *bodies* — links welded together by fixed joints are one body —
and a pair of links is checked unless

1. both links belong to the same body,
2. their bodies are *adjacent*: joined by one movable joint, or through bodies that have
   no collision geometry at all (as MoveIt does), or
3. their meshes touch (distance <= :data:`DEFAULT_CONTACT_MARGIN`) at the robot's
   default configuration — pairs that are always in contact (a shoulder cover over the
   base) are in contact there too; a robot started at its default configuration is
   therefore never in self-collision by construction.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.exact_collision import MeshSet, exact_distance, mesh_set

from .kinematics import Kinematics
from .link_meshes import link_collision_meshes

__all__ = ["DEFAULT_CONTACT_MARGIN", "MeshCollisionModel", "adjacent_links", "mesh_collision_model", "moving_part"]

#: Two links closer than this at the default configuration are never checked [m].
DEFAULT_CONTACT_MARGIN = 1e-3


@dataclass(frozen=True, eq=False)
class MeshCollisionModel:
    """Collision meshes of the links that have any, and the pairs checked among them.

    Attributes:
        kinematics: The robot's kinematics (poses the links).
        links: Links with collision geometry, in the kinematics' depth-first order.
        meshes: Their meshes, ``meshes[i]`` in the frame of ``links[i]``.
        pairs: Index pairs ``(i, j)``, ``i < j``, into ``links`` checked for self-collision.
    """

    kinematics: Kinematics
    links: tuple[str, ...]
    meshes: tuple[MeshSet, ...]
    pairs: tuple[tuple[int, int], ...]

    def link_poses(self, qs: ArrayLike) -> NDArray[np.float64]:
        """Poses of :attr:`links` at each configuration, shape (T, L, 4, 4).

        Args:
            qs: Configurations, shape (T, dof) (or (dof,) for one).
        """
        configurations = np.atleast_2d(np.asarray(qs, dtype=float))
        q = ca.SX.sym("q", self.kinematics.dof)
        stacked = ca.vertcat(*[self.kinematics.transform(q, link) for link in self.links])
        function = ca.Function("link_poses", [q], [ca.reshape(stacked.T, 16 * len(self.links), 1)])
        flat = np.array(function.map(configurations.shape[0])(configurations.T)).T
        # CasADi reshapes column-major: entry 16 l + 4 i + j of the column is T_l[i, j]
        return flat.reshape(configurations.shape[0], len(self.links), 4, 4)


def mesh_collision_model(kinematics: Kinematics, default_q: ArrayLike,
                         link_meshes: Mapping[str, Sequence[trimesh.Trimesh]] | None = None
                         ) -> MeshCollisionModel | None:
    """The mesh model of a robot; None if none of its links has collision geometry.

    Args:
        kinematics: Kinematics of a URDF robot (its ``model`` gives the meshes).
        default_q: Default configuration, where touching pairs are left out (module doc).
        link_meshes: The meshes of each link in its frame, instead of the URDF's (a
            built-in robot whose description has none: :mod:`dynfab.robots.builtin_meshes`).

    Raises:
        LinkMeshError: A collision mesh that is missing or unreadable (names link and URI).
    """
    links, meshes = [], []
    for link in kinematics.link_names:
        found = (link_collision_meshes(kinematics.model, link) if link_meshes is None
                 else list(link_meshes.get(link, ())))
        if found:
            links.append(link)
            meshes.append(mesh_set(found))
    if not links:
        return None
    model = MeshCollisionModel(kinematics, tuple(links), tuple(meshes), ())
    adjacent = adjacent_links(kinematics, set(links))
    poses = model.link_poses(default_q)[0]
    pairs = tuple(
        (i, j) for i, j in itertools.combinations(range(len(links)), 2)
        if frozenset((links[i], links[j])) not in adjacent
        and exact_distance(meshes[i], poses[i], meshes[j], poses[j]) > DEFAULT_CONTACT_MARGIN)
    return MeshCollisionModel(kinematics, tuple(links), tuple(meshes), pairs)


def moving_part(model: MeshCollisionModel) -> MeshCollisionModel:
    """``model``'s links that some joint moves (not welded to the root), without pairs: a
    configuration's distances to obstacles that can differ from another's (a base link's
    is the same at every configuration)."""
    body = _bodies(model.kinematics)
    root = body[model.kinematics.root_link]
    kept = [i for i, link in enumerate(model.links) if body[link] != root]
    return MeshCollisionModel(model.kinematics, tuple(model.links[i] for i in kept),
                              tuple(model.meshes[i] for i in kept), ())


def adjacent_links(kinematics: Kinematics, with_geometry: set[str]) -> set[frozenset[str]]:
    """Pairs of links never checked against each other by rules 1 and 2 (module doc).

    Args:
        kinematics: The robot's kinematics (its tree below ``root_link``).
        with_geometry: The links that have collision geometry.

    Returns:
        Unordered pairs of link names, each a frozenset of two names.
    """
    body = _bodies(kinematics)
    members: dict[str, list[str]] = {}
    for link, root in body.items():
        members.setdefault(root, []).append(link)
    solid = {root for root, links in members.items() if with_geometry.intersection(links)}
    neighbours: dict[str, set[str]] = {root: set() for root in members}
    for joint in kinematics.model.joints:
        if joint.parent in body and joint.child in body and body[joint.parent] != body[joint.child]:
            neighbours[body[joint.parent]].add(body[joint.child])
            neighbours[body[joint.child]].add(body[joint.parent])
    adjacent_bodies: set[frozenset[str]] = set()
    for root in solid:  # walk through bodies without geometry to the next solid ones
        seen, frontier = {root}, [root]
        while frontier:
            current = frontier.pop()
            for other in neighbours[current] - seen:
                seen.add(other)
                if other in solid:
                    adjacent_bodies.add(frozenset((root, other)))
                else:
                    frontier.append(other)
    pairs: set[frozenset[str]] = set()
    for a, b in itertools.combinations(sorted(body), 2):
        if body[a] == body[b] or frozenset((body[a], body[b])) in adjacent_bodies:
            pairs.add(frozenset((a, b)))
    return pairs


def _bodies(kinematics: Kinematics) -> dict[str, str]:
    """Each link of the tree -> the top link of its body (links welded by fixed joints)."""
    body = {kinematics.root_link: kinematics.root_link}
    for link in kinematics.link_names[1:]:  # depth-first: a parent comes before its children
        joint = kinematics.model.parent_joint(link)
        body[link] = body[joint.parent] if joint.type == "fixed" else link
    return body
