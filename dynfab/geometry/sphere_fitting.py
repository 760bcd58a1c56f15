"""Spheres that cover a triangle mesh's surface: few, inside the body, bulging little.

The fit (deterministic for a given seed):

1. Sample the surface (area-weighted, seeded) plus every vertex; the samples ``s`` with
   their outward face normals ``n``.
2. Candidate centres on the inner medial axis by the *shrinking-ball* construction: for a
   sample ``p`` the largest ball tangent to the surface at ``p`` from inside (centre
   ``p - r n``) that holds no other sample; ``r`` is then about the distance of the centre
   to the surface.
3. Set cover: a candidate may reach ``R = min(r, d) + max_bulge`` with ``d`` the depth of
   its centre in the body (:func:`sphere_bulges`) and covers the samples with
   ``|s - c| <= R + target``, ``target = tolerance - check_edge / sqrt(3)`` (what step 5
   checks); take the one that covers most uncovered samples until all are covered and drop
   spheres whose samples others cover (:mod:`dynfab.geometry.set_cover`), or, with
   ``fewest``, solve for the fewest candidates that cover every sample.
4. Refine: shrink every sphere to the smallest radius that still covers the samples
   nearest to it (never above its ``R``).
5. Check on the vertices of the mesh subdivided to short edges (every surface point is
   near one); vertices found outside join the fit set and the fit is repeated (at most
   :data:`_ROUNDS` times, samples covered within ``target - _MARGIN``).
6. Misses left after the last round grow their nearest sphere, never beyond its ``R``;
   the check points still outside get spheres of their own (steps 2-4 with those points
   as the rows to cover). So every sphere keeps ``R <= d + max_bulge`` (the bulge bound
   always holds), and a check point no candidate can reach is reported as measured
   (:attr:`SphereFit.coverage` above ``tolerance``).

Coverage of a surface point ``s`` by spheres ``(c_i, R_i)``:

    outside(s) = max(0, min_i |s - c_i| - R_i)   [m]

and the *bulge* of a sphere whose centre lies inside the body at distance ``d`` from the
surface is ``max(0, R - d)`` [m], an upper bound of how far it reaches out of the body.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy import sparse
from scipy.spatial import cKDTree

from dynfab.geometry.set_cover import fewest_cover, greedy_cover, prune

__all__ = ["FittedSphere", "SphereFit", "SphereFitParameters", "check_points", "fit_spheres",
           "outside_distances", "sphere_bulges", "surface_samples"]

#: Shrinking-ball iterations; the radius converges in a handful.
_SHRINK_ITERATIONS = 30
#: Fit/verify rounds: a round adds the verification samples found outside to the fit set.
_ROUNDS = 2
#: The rounds cover their samples this much tighter than the check asks [m], so that most
#: check points between samples are covered too (fewer misses left to step 6).
_MARGIN = 0.001


@dataclass(frozen=True)
class SphereFitParameters:
    """How tightly spheres cover a mesh.

    Attributes:
        tolerance: Largest allowed distance of a surface point outside all spheres [m];
            the knob that trades sphere count for coverage.
        max_bulge: Largest allowed distance a sphere reaches out of the body [m].
        spacing: Mean distance between the surface samples the fit covers [m].
        check_edge: Coverage is checked on the vertices of the meshes subdivided to edges of
            at most this length [m]; every surface point lies within ``check_edge / sqrt(3)``
            of one of them, and the distance outside grows at most 1:1 with distance, so
            ``coverage = max over vertices + check_edge / sqrt(3)`` bounds every point.
        seed: Seed of the surface sampling.
        fewest: True: the fewest candidate spheres that cover the samples (an integer
            program, about 1-2 s per arm link) instead of the greedy cover, which needs
            about 1.2-1.4 times as many on arm links. Either way every sphere reaches at
            most ``max_bulge`` out of the body, so with ``fewest`` a larger
            ``max_bulge`` is what buys fewer spheres.
    """

    tolerance: float = 0.01
    max_bulge: float = 0.02
    spacing: float = 0.008
    check_edge: float = 0.004
    seed: int = 0
    fewest: bool = False

    def __post_init__(self) -> None:
        for name in ("tolerance", "max_bulge", "spacing", "check_edge"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0) or (name != "max_bulge" and value == 0.0):
                raise ValueError(f"sphere fitting: {name} must be a positive number, got {value!r}")
        if self.check_edge / np.sqrt(3.0) >= self.tolerance:
            raise ValueError(f"sphere fitting: check_edge must be below sqrt(3) x tolerance, "
                             f"got {self.check_edge!r}")


@dataclass(frozen=True)
class FittedSphere:
    """A sphere in the mesh's frame.

    Attributes:
        center: Centre [m].
        radius: Radius [m].
    """

    center: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class SphereFit:
    """Spheres fitted to one body and how well they cover it.

    Attributes:
        spheres: The spheres.
        coverage: Upper bound of the largest distance of a surface point outside all
            spheres [m] (see :attr:`SphereFitParameters.check_edge`).
        bulge: Largest bulge of a sphere out of the body [m].
        samples: Number of surface points the coverage was checked on.
    """

    spheres: tuple[FittedSphere, ...]
    coverage: float
    bulge: float
    samples: int


def fit_spheres(meshes: Sequence[trimesh.Trimesh],
                parameters: SphereFitParameters = SphereFitParameters()) -> SphereFit:
    """Fit spheres to the surface of one body made of ``meshes`` (same frame) [m].

    Raises:
        ValueError: No mesh, or meshes without triangles.
    """
    parts = _components(meshes)
    points, normals = surface_samples(parts, parameters.spacing, parameters.seed)
    check = check_points(parts, parameters.check_edge)
    target = parameters.tolerance - parameters.check_edge / np.sqrt(3.0)
    for _ in range(_ROUNDS):
        centers, radii, largest = _fit(parts, points, normals, points, parameters, target - _MARGIN)
        missed = outside_distances(check, centers, radii) > target
        if not missed.any():
            break
        points = np.vstack([points, check[missed]])
        normals = np.vstack([normals, _closest_normals(parts, check[missed])])
    radii = _grown(check, centers, radii, largest, target)
    missed = outside_distances(check, centers, radii) > target
    if missed.any():
        added, added_radii, _ = _fit(parts, points, normals, check[missed], parameters, target)
        centers, radii = np.vstack([centers, added]), np.concatenate([radii, added_radii])
    outside = outside_distances(check, centers, radii).max(initial=0.0) + parameters.check_edge / np.sqrt(3.0)
    bulges = sphere_bulges(parts, centers, radii)
    spheres = tuple(FittedSphere(tuple(float(x) for x in c), float(r))  # type: ignore[arg-type]
                    for c, r in zip(centers, radii))
    return SphereFit(spheres=spheres, coverage=float(outside),
                     bulge=float(bulges.max(initial=0.0)), samples=len(check))


def surface_samples(parts: Sequence[trimesh.Trimesh], spacing: float,
                    seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Points on the outer surface of a body made of overlapping closed ``parts``, with
    their outward unit normals; shapes (N, 3) and (N, 3).

    Each part gets seeded area-weighted samples about ``spacing`` [m] apart plus its
    vertices (one per cube of side ``spacing``); samples inside another closed part (faces buried in the body) are dropped.
    """
    rng = np.random.default_rng(seed)
    chunks = []
    for part in parts:
        count = int(np.clip(part.area / spacing**2, 50, 20000))
        points, faces = trimesh.sample.sample_surface(part, count, seed=int(rng.integers(2**31)))
        corners = _spread_vertices(part, spacing)
        chunks.append((np.vstack([points, part.vertices[corners]]),
                       np.vstack([part.face_normals[faces], part.vertex_normals[corners]])))
    kept_points, kept_normals = [], []
    for i, (points, normals) in enumerate(chunks):
        buried = np.zeros(len(points), dtype=bool)
        for j, other in enumerate(parts):
            if j != i and other.is_watertight:
                buried |= other.contains(points)
        kept_points.append(points[~buried])
        kept_normals.append(normals[~buried])
    return np.vstack(kept_points), np.vstack(kept_normals)


def check_points(parts: Sequence[trimesh.Trimesh], edge: float) -> np.ndarray:
    """Vertices of the parts subdivided until no edge is longer than ``edge`` [m], without
    those buried inside another closed part; shape (N, 3)."""
    kept = []
    for i, part in enumerate(parts):
        vertices, _ = trimesh.remesh.subdivide_to_size(part.vertices, part.faces, max_edge=edge,
                                                        max_iter=20)
        buried = np.zeros(len(vertices), dtype=bool)
        for j, other in enumerate(parts):
            if j != i and other.is_watertight:
                buried |= other.contains(vertices)
        kept.append(vertices[~buried])
    return np.vstack(kept)


def _spread_vertices(part: trimesh.Trimesh, spacing: float) -> np.ndarray:
    """Indices of the part's vertices, at most one per cube of side ``spacing``."""
    _, first = np.unique(np.floor(part.vertices / spacing).astype(np.int64), axis=0, return_index=True)
    return np.sort(first)


def outside_distances(points: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """``max(0, min_i |p - c_i| - R_i)`` for every point, shape (N,) [m]."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(centers) == 0:
        return np.full(len(points), np.inf)
    gaps = np.linalg.norm(points[:, None, :] - np.asarray(centers)[None, :, :], axis=2) - np.asarray(radii)
    return np.maximum(gaps.min(axis=1), 0.0)


def sphere_bulges(parts: Sequence[trimesh.Trimesh], centers: np.ndarray,
                  radii: np.ndarray) -> np.ndarray:
    """``max(0, R - d)`` per sphere [m]: an upper bound of how far it reaches out of the body.

    ``d`` is the centre's depth in the deepest part that holds it (distance to that part's
    surface, on the inner side of its nearest face), a lower bound of its depth in the body.
    """
    centers = np.asarray(centers, dtype=float).reshape(-1, 3)
    return np.maximum(np.asarray(radii) - _depths(parts, centers), 0.0)


def _depths(parts: Sequence[trimesh.Trimesh], centers: np.ndarray) -> np.ndarray:
    """Depth of each centre in the deepest part that holds it, 0 outside all [m]."""
    depth = np.zeros(len(centers))
    if len(centers) == 0:
        return depth
    for part in parts:
        closest, distance, faces = trimesh.proximity.closest_point(part, centers)
        inner = np.einsum("ij,ij->i", centers - closest, part.face_normals[faces]) < 0.0
        depth = np.maximum(depth, np.where(inner, distance, 0.0))
    return depth


def _components(meshes: Sequence[trimesh.Trimesh]) -> list[trimesh.Trimesh]:
    """The meshes' connected parts, vertices merged, normals outward."""
    parts = []
    for mesh in meshes:
        if len(mesh.faces) == 0:
            continue
        mesh = mesh.copy()
        mesh.merge_vertices()
        mesh.update_faces(mesh.nondegenerate_faces())
        for part in mesh.split(only_watertight=False):
            trimesh.repair.fix_normals(part)
            parts.append(part)
    if not parts:
        raise ValueError("sphere fitting: no triangles to fit")
    return parts


def _closest_normals(parts: Sequence[trimesh.Trimesh], points: np.ndarray) -> np.ndarray:
    """Normals of the faces nearest to ``points`` over all parts."""
    best = np.full(len(points), np.inf)
    normals = np.zeros((len(points), 3))
    for part in parts:
        _, distance, faces = trimesh.proximity.closest_point(part, points)
        closer = distance < best
        best[closer] = distance[closer]
        normals[closer] = part.face_normals[faces[closer]]
    return normals


def _fit(parts: Sequence[trimesh.Trimesh], points: np.ndarray, normals: np.ndarray, rows: np.ndarray,
         parameters: SphereFitParameters, target: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Spheres covering ``rows`` within ``target`` [m]: shrinking-ball candidates of the
    samples ``points`` (outward ``normals``) reaching at most ``min(r, depth) + max_bulge``,
    a set cover of the rows (greedy and pruned, or the fewest), then radii shrunk to what
    the rows nearest to each sphere need; centres (k, 3), radii (k,) and the largest
    radii the bulge bound allows (k,) [m]."""
    centers, inner = _medial_balls(points, normals)
    reach = np.minimum(inner, _depths(parts, centers)) + parameters.max_bulge
    cover = _cover_matrix(rows, centers, reach + target)
    chosen = fewest_cover(cover) if parameters.fewest else prune(cover, greedy_cover(cover))
    centers, largest = centers[chosen], reach[chosen]
    gaps = np.linalg.norm(rows[:, None, :] - centers[None, :, :], axis=2)
    owner = np.argmin(gaps - largest, axis=1)
    needed = np.array([gaps[owner == k, k].max(initial=0.0) - target for k in range(len(chosen))])
    return centers, np.minimum(np.maximum(needed, target), largest), largest


def _grown(points: np.ndarray, centers: np.ndarray, radii: np.ndarray, largest: np.ndarray,
           tolerance: float) -> np.ndarray:
    """Radii grown so that every point is at most ``tolerance`` outside its nearest sphere,
    each at most to its ``largest`` radius (a point that needs more stays outside)."""
    gaps = np.linalg.norm(points[:, None, :] - centers[None, :, :], axis=2) - radii
    owner = np.argmin(gaps, axis=1)
    grown = radii.copy()
    for k in range(len(radii)):
        grown[k] += max(gaps[owner == k, k].max(initial=-np.inf) - tolerance, 0.0)
    return np.minimum(grown, largest)


def _medial_balls(points: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inner shrinking balls, one per sample: centres (N, 3) and radii (N,) [m].

    Start from a ball larger than the body; while the nearest other sample ``q`` to the
    centre ``p - r n`` is inside the ball, shrink it to the ball through ``p`` and ``q``:
    ``r = |p - q|^2 / (2 n . (p - q))``.
    """
    tree = cKDTree(points)
    span = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    radii = np.full(len(points), span)
    floor = 1e-4 * span
    for _ in range(_SHRINK_ITERATIONS):
        centers = points - radii[:, None] * normals
        _, index = tree.query(centers, k=3)
        index = np.minimum(index, len(points) - 1)
        separate = np.linalg.norm(points[index] - points[:, None, :], axis=2) > 1e-9 * span
        nearest = index[np.arange(len(points)), np.argmax(separate, axis=1)]
        delta = points - points[nearest]
        gap = np.linalg.norm(centers - points[nearest], axis=1)
        inside = gap < radii * (1.0 - 1e-9)
        if not inside.any():
            break
        along = np.einsum("ij,ij->i", normals, delta)
        proposal = np.where(along > 1e-12, np.einsum("ij,ij->i", delta, delta) / (2.0 * np.maximum(along, 1e-12)),
                            floor)
        radii = np.where(inside, np.clip(proposal, floor, radii), radii)
    return points - radii[:, None] * normals, radii


def _cover_matrix(points: np.ndarray, centers: np.ndarray, reach: np.ndarray) -> sparse.csc_matrix:
    """Boolean (samples x candidates): sample within ``reach`` of a candidate's centre."""
    tree = cKDTree(points)
    lists = tree.query_ball_point(centers, reach)
    rows = np.concatenate([np.asarray(rows, dtype=np.int64) for rows in lists])
    cols = np.repeat(np.arange(len(centers)), [len(rows) for rows in lists])
    data = np.ones(len(rows), dtype=np.float32)
    return sparse.csc_matrix((data, (rows, cols)), shape=(len(points), len(centers)))
