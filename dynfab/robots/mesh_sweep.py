"""Mesh distances over a whole run: robot links vs obstacle shapes and checked link pairs.

Every sample of the run counts; nothing is skipped by a stride. Three tiers keep it fast:

1. a lower bound for every (sample, link, obstacle) and (sample, pair) from bounding
   spheres, in numpy: ``||c_a - c_b|| - R_a - R_b`` (for a plane, the signed height of
   the link's sphere centre above it minus ``R_a``; for a point cloud, the distance of the
   link's sphere centre to the nearest kept point minus ``R_a``, one KD-tree query);
2. the convex hulls' signed distance (:func:`~dynfab.geometry.exact_collision.hull_distance`),
   also a lower bound, a few microseconds each;
3. :func:`~dynfab.geometry.exact_collision.exact_distance` on the meshes.

Entries are visited in increasing order of their bound. Every entry whose bound is <= 0
is settled (so every contact is found), and the search for the minimum stops once the
bound exceeds the smallest exact distance found: the reported minima are exactly the
minima over all samples of tier 3.

Against a point cloud the distance is to its kept points, signed
(:mod:`dynfab.geometry.cloud_collision`), less the obstacle's :attr:`PlacedShape.lowering`
(the run's metrics: the cloud's voxel half-diagonal ``δ``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.exact_collision import (
    exact_distance, hull_distance, placement_matrix, shape_bounding_radius, shape_geometry,
)
from dynfab.geometry.shapes import Placement, Plane, PointCloud, Shape

from .mesh_collision import MeshCollisionModel

__all__ = ["Contact", "MeshSweep", "PlacedShape", "clearance_per_sample", "meshes_clear", "sweep_meshes"]


@dataclass(frozen=True)
class PlacedShape:
    """An obstacle over a run: its shape and where it is at each sample.

    Attributes:
        name: How reports name it, e.g. ``obstacles[2]``.
        shape: The obstacle's shape.
        placements: One placement per sample, or a single one for a static obstacle.
        lowering: subtracted from every distance to it [m] (>= 0): a point cloud's ``δ``
            in a run's metrics, the distance to the raw points it stands for being at least
            that to its kept points less ``δ``; 0 for the distance to the shape as given.
    """

    name: str
    shape: Shape
    placements: tuple[Placement, ...]
    lowering: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.lowering) and self.lowering >= 0.0):
            raise ValueError(f"{self.name}: lowering must be a finite number >= 0, got {self.lowering}")


@dataclass(frozen=True)
class Contact:
    """A link touching an obstacle or another link during some samples.

    Attributes:
        first: The robot link.
        second: The obstacle's name, or the other link.
        samples: Indices of the samples in contact, increasing.
        depth: Smallest distance over those samples [m] (<= 0; see ``exact_distance``).
    """

    first: str
    second: str
    samples: tuple[int, ...]
    depth: float


@dataclass(frozen=True)
class MeshSweep:
    """The mesh distances of a run.

    Attributes:
        clearance: min over samples, links and obstacles of the mesh distance [m]; None
            without obstacles.
        min_self_distance: min over samples and checked pairs [m]; None without pairs.
        obstacle_contacts: Every (link, obstacle) that touched, by first contact.
        self_contacts: Every checked link pair that touched, by first contact.
    """

    clearance: float | None
    min_self_distance: float | None
    obstacle_contacts: tuple[Contact, ...]
    self_contacts: tuple[Contact, ...]


def sweep_meshes(model: MeshCollisionModel, qs: ArrayLike, obstacles: Sequence[PlacedShape]) -> MeshSweep:
    """Measure a run's configurations against the obstacles and the robot itself.

    Args:
        model: The robot's mesh model.
        qs: Configurations, shape (T, dof).
        obstacles: Obstacles, each placed at every sample (or static).

    Raises:
        ValueError: An obstacle whose number of placements is neither 1 nor T.
    """
    poses, centers, radii = _link_spheres(model, qs)
    clearance, obstacle_contacts = None, []
    for obstacle in obstacles:
        bound, distance = _obstacle_distances(model, obstacle, poses, centers, radii)
        minimum, contacts = _search(bound, distance)
        clearance = minimum if clearance is None else min(clearance, minimum)
        obstacle_contacts += [Contact(model.links[link], obstacle.name, tuple(s for s, _ in found),
                                      min(d for _, d in found)) for link, found in contacts.items()]
    min_self_distance, self_contacts = None, []
    if model.pairs:
        min_self_distance, contacts = _search(*_pair_distances(model, poses, centers, radii))
        self_contacts = [Contact(model.links[model.pairs[p][0]], model.links[model.pairs[p][1]],
                                 tuple(s for s, _ in found), min(d for _, d in found))
                         for p, found in contacts.items()]
    return MeshSweep(clearance, min_self_distance, _by_first_sample(obstacle_contacts),
                     _by_first_sample(self_contacts))


def clearance_per_sample(model: MeshCollisionModel, qs: ArrayLike, obstacles: Sequence[PlacedShape],
                         cap: float = np.inf) -> NDArray[np.float64]:
    """The mesh clearance at each sample: ``min`` over links and obstacles of the mesh
    distance, shape (T,) [m] (inf without obstacles); its minimum is
    :attr:`MeshSweep.clearance` of the same run, for the same three tiers (module doc) are
    searched per sample, each to its exact minimum. With a ``cap`` [m], a clearance above
    it reads ``cap`` (nothing farther is measured: a caller that only needs to know the
    clearance up to a distance pays for the links nearer than it).

    Raises:
        ValueError: An obstacle whose number of placements is neither 1 nor T.
    """
    poses, centers, radii = _link_spheres(model, qs)
    columns = [_obstacle_distances(model, obstacle, poses, centers, radii) for obstacle in obstacles]
    clearance = np.full(poses.shape[0], float(cap))
    if not columns:
        return clearance
    bound = np.concatenate([column_bound for column_bound, _ in columns], axis=1)
    links = len(model.meshes)
    for t, row in enumerate(bound):
        for j in np.argsort(row, kind="stable"):
            if row[j] >= clearance[t]:
                break
            distance = columns[j // links][1]
            if distance(t, j % links, False) < clearance[t]:
                clearance[t] = min(clearance[t], distance(t, j % links, True))
    return clearance


def meshes_clear(model: MeshCollisionModel, qs: ArrayLike, obstacles: Sequence[PlacedShape], floor: float) -> bool:
    """Whether at every sample every link keeps a mesh distance ``≥ floor`` [m] from every
    obstacle and no checked link pair touches (distance ``≤ 0``): the same answer as
    :func:`sweep_meshes`' ``clearance ≥ floor and min_self_distance > 0``, found with the
    same three tiers but stopping at the first entry below the threshold, or once every
    bound left is above it (no exact minimum is sought).

    Raises:
        ValueError: An obstacle whose number of placements is neither 1 nor T.
    """
    poses, centers, radii = _link_spheres(model, qs)
    for obstacle in obstacles:
        if _any_below(*_obstacle_distances(model, obstacle, poses, centers, radii), floor):
            return False
    if not model.pairs:
        return True
    return not _any_below(*_pair_distances(model, poses, centers, radii), np.nextafter(0.0, 1.0))   # ≤ 0


def _link_spheres(model: MeshCollisionModel, qs: ArrayLike
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The links' poses (T, L, 4, 4), bounding-sphere centres (T, L, 3) [m] and radii (L,) [m]."""
    poses = model.link_poses(qs)
    centers = np.einsum("tlij,lj->tli", poses[:, :, :3, :3], np.array([m.center for m in model.meshes]))
    centers += poses[:, :, :3, 3]
    return poses, centers, np.array([m.radius for m in model.meshes])


def _pair_distances(model: MeshCollisionModel, poses: NDArray[np.float64], centers: NDArray[np.float64],
                    radii: NDArray[np.float64]) -> tuple[NDArray[np.float64], Callable[[int, int, bool], float]]:
    """Tier 1's bounds (T, P) [m] of each checked link pair's distance, and the distance
    ``(t, pair, exact)`` of tiers 2 (``exact=False``) and 3."""
    first, second = (np.array(side) for side in zip(*model.pairs))
    bound = np.linalg.norm(centers[:, first] - centers[:, second], axis=-1) - radii[first] - radii[second]

    def distance(t: int, pair: int, exact: bool) -> float:
        measure = exact_distance if exact else hull_distance
        a, b = model.pairs[pair]
        return measure(model.meshes[a], poses[t, a], model.meshes[b], poses[t, b])

    return bound, distance


def _obstacle_distances(model: MeshCollisionModel, obstacle: PlacedShape, poses: NDArray[np.float64],
                        centers: NDArray[np.float64], radii: NDArray[np.float64]
                        ) -> tuple[NDArray[np.float64], Callable[[int, int, bool], float]]:
    """Tier 1's bounds (T, L) [m] of each link's distance to ``obstacle``, and the
    distance ``(t, link, exact)`` of tiers 2 (``exact=False``) and 3."""
    obstacle_poses = _obstacle_poses(obstacle, poses.shape[0])
    geometry = shape_geometry(obstacle.shape)

    def distance(t: int, link: int, exact: bool) -> float:
        measure = exact_distance if exact else hull_distance
        return measure(model.meshes[link], poses[t, link], geometry, obstacle_poses[t]) - obstacle.lowering

    return _obstacle_bound(obstacle.shape, obstacle_poses, centers, radii) - obstacle.lowering, distance


def _obstacle_poses(obstacle: PlacedShape, samples: int) -> NDArray[np.float64]:
    """The obstacle's 4x4 pose at each sample, shape (T, 4, 4)."""
    count = len(obstacle.placements)
    if count not in (1, samples):
        raise ValueError(f"{obstacle.name}: {count} placements for a run of {samples} samples")
    matrices = np.array([placement_matrix(p) for p in obstacle.placements])
    return np.broadcast_to(matrices, (samples, 4, 4)) if count == 1 else matrices


def _obstacle_bound(shape: Shape, poses: NDArray[np.float64], centers: NDArray[np.float64],
                    radii: NDArray[np.float64]) -> NDArray[np.float64]:
    """Lower bound of each link's distance to the obstacle, shape (T, L) [m]."""
    offsets = centers - poses[:, None, :3, 3]
    if isinstance(shape, Plane):  # height above the plane z_s = 0 along its normal
        return np.einsum("tli,ti->tl", offsets, poses[:, :3, 2]) - radii
    if isinstance(shape, PointCloud):  # the nearest kept point to each centre, in the cloud's frame
        if shape.empty:
            return np.full(offsets.shape[:2], np.inf)
        local = np.einsum("tji,tlj->tli", poses[:, :3, :3], offsets)
        gaps, _ = shape.tree.query(np.ascontiguousarray(local.reshape(-1, 3)))
        return gaps.reshape(offsets.shape[:2]) - radii
    return np.linalg.norm(offsets, axis=-1) - radii - shape_bounding_radius(shape)


def _search(bound: NDArray[np.float64], distance: Callable[[int, int, bool], float]
            ) -> tuple[float, dict[int, list[tuple[int, float]]]]:
    """Exact minimum over all (t, j) of ``distance(t, j, exact=True)`` and the entries <= 0.

    Args:
        bound: Lower bounds of the distances, shape (T, P).
        distance: ``(t, j, exact)``: the exact distance, or (``exact=False``) a cheaper
            lower bound of it that is at least ``bound[t, j]``.

    Returns:
        The minimum [m] and, per column j with contacts, the (t, distance) in contact.
    """
    best = np.inf
    contacts: dict[int, list[tuple[int, float]]] = {}
    columns = bound.shape[1]
    for flat in np.argsort(bound, axis=None, kind="stable"):
        t, j = divmod(int(flat), columns)
        if bound[t, j] > max(best, 0.0):
            break
        cheap = distance(t, j, False)
        if cheap > 0.0 and cheap >= best:
            continue
        value = distance(t, j, True)
        best = min(best, value)
        if value <= 0.0:
            contacts.setdefault(j, []).append((t, value))
    for found in contacts.values():
        found.sort()
    return float(best), contacts


def _any_below(bound: NDArray[np.float64], distance: Callable[[int, int, bool], float], threshold: float) -> bool:
    """Whether ``distance(t, j, exact=True) < threshold`` for some (t, j), visiting entries in
    increasing order of ``bound`` (lower bounds, shape (T, P)) and skipping those whose
    cheaper bound ``distance(t, j, exact=False)`` is not below it (:func:`_search`)."""
    columns = bound.shape[1]
    for flat in np.argsort(bound, axis=None, kind="stable"):
        t, j = divmod(int(flat), columns)
        if bound[t, j] >= threshold:
            return False
        if distance(t, j, False) < threshold and distance(t, j, True) < threshold:
            return True
    return False


def _by_first_sample(contacts: list[Contact]) -> tuple[Contact, ...]:
    return tuple(sorted(contacts, key=lambda c: (c.samples[0], c.first, c.second)))
