"""Which collision-sphere pairs of a robot to keep apart, found by sampling configurations.

As MoveIt's setup assistant does for links, at the level of *bodies* (links welded by
fixed or locked joints): skip a body against itself and against its neighbours in the
kinematic tree (bodies without spheres in between are looked through), sample
configurations uniformly within the joint limits, skip body pairs whose spheres touch in
more than ``always_fraction`` of them, and of the rest keep every sphere pair that is the
closest pair of its two bodies in a sample where their clearance

    d_ij(q) = |c_i(q) - c_j(q)| - r_i - r_j   [m]

comes below ``margin``: whenever two bodies come close in the sample, the pair that
would touch first is kept apart. Pairs that never come that close are left out: they
cannot meet (or meet too rarely for the sample to see; raise ``samples``).

That is the rule with ``PairSelection(meshes=False, cover_slack=None)``. By default two
refinements apply (:class:`PairSelection`; on the UR5 of example-robot-data they cut its
pairs from about 180 to 53 and turned the 6 deadlocks of the ``arms`` experiment, a
shoulder held off the base by a pair of bulging spheres, into successes):

- ``meshes``: whether two bodies touch or come close is decided on their collision meshes
  (exact distances, :mod:`dynfab.robots.body_distances`) instead of their spheres. Spheres
  that reach out of the meshes make bodies look close that never meet (a Panda's wrist
  and forearm spheres overlap in configurations where the meshes are centimetres apart);
  on the meshes only body pairs that really can meet are kept, as MoveIt does.
- ``cover_slack``: instead of every closest pair, the fewest sphere pairs such that in
  every near sample some kept pair's clearance is at most ``cover_slack`` more than the
  bodies' distance (meshes or spheres; at least the closest pair qualifies)
  (:func:`dynfab.geometry.set_cover.fewest_cover`): then no sampled configuration where
  the bodies come close lets the kept pairs see them more than ``cover_slack`` farther
  apart than they are. Of equally few pairs, those that overlap least where the bodies
  are apart (sphere bulge that would block reachable configurations) are preferred: a
  pair costs ``1 + f`` with ``f`` the share of far samples in which it overlaps.
- ``near_samples``: uniform samples seldom bring two bodies close (a Panda's finger comes
  within 2 cm of its base in about 1.6 % of them), so a cover chosen on them alone left
  contacts unseen (issue 19: a finger 12-14 mm into ``panda_link1`` and ``panda_link0``
  while every kept pair of those bodies stayed apart). Each body pair that came close is
  sampled again around its close samples, ``q' = clip(q + N(0, near_spread^2))`` [rad],
  ``near_samples`` times, and the cover is chosen on both sets. The built-in Panda's
  pairs went from 123 to 268 (373 for its planning spheres); the ``auto`` models of
  example-robot-data's UR5, Kinova j2s6s200, xArm7 and Panda now keep 95, 104, 132 and
  111 pairs (default fits, as tests/test_collision_model.py makes them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy import sparse

from dynfab.geometry.set_cover import fewest_cover

from .body_distances import BodyMeshes, body_meshes
from .joint_bounds import finite_joint_bounds
from .kinematics import Kinematics
from .robot import CollisionSphere
from .urdf import Joint

__all__ = ["PairSelection", "bodies", "configurations_around", "sample_configurations", "select_pairs",
           "sphere_centres"]


@dataclass(frozen=True)
class PairSelection:
    """How self-collision pairs are chosen.

    Attributes:
        samples: Random configurations [-].
        margin: A body pair counts as close in a sample if its clearance is below this [m].
        always_fraction: Body pairs in contact in more than this share of the samples are
            skipped (they touch by design) [-].
        seed: Seed of the configuration sampling.
        meshes: Decide contact and closeness of two bodies on their collision meshes
            instead of their spheres (on the spheres where a body has no meshes).
        cover_slack: None: keep the closest sphere pair of every near sample; a number
            [m]: keep the fewest pairs such that in every near sample one of them sees
            the bodies at most this much farther apart than they are (see the module).
        near_samples: Configurations drawn per body pair around its close samples (see
            the module); 0: uniform samples only [-].
        near_spread: Standard deviation of the joint offsets of those draws [rad or m].
    """

    samples: int = 3000
    margin: float = 0.02
    always_fraction: float = 0.95
    seed: int = 0
    meshes: bool = True
    cover_slack: float | None = 0.02
    near_samples: int = 3000
    near_spread: float = 0.1

    def __post_init__(self) -> None:
        if self.samples < 1:
            raise ValueError(f"PairSelection.samples must be >= 1, got {self.samples}")
        if self.cover_slack is not None and not (np.isfinite(self.cover_slack) and self.cover_slack >= 0):
            raise ValueError(f"PairSelection.cover_slack must be None or >= 0, got {self.cover_slack}")
        if self.near_samples < 0:
            raise ValueError(f"PairSelection.near_samples must be >= 0, got {self.near_samples}")
        if not (np.isfinite(self.near_spread) and self.near_spread > 0):
            raise ValueError(f"PairSelection.near_spread must be > 0, got {self.near_spread}")


def select_pairs(kinematics: Kinematics, spheres: Sequence[CollisionSphere],
                 selection: PairSelection = PairSelection()) -> tuple[tuple[int, int], ...]:
    """Index pairs ``(i, j)``, ``i < j``, of ``spheres`` to keep apart (see the module).

    With ``selection.meshes``, a body pair where one body has no (readable) collision
    meshes is judged on its spheres.
    """
    body_of = bodies(kinematics)
    sphere_body = np.array([body_of[s.link] for s in spheres])
    carriers = set(sphere_body.tolist())
    neighbours = _neighbours(kinematics, body_of, carriers)
    q = sample_configurations(kinematics, selection.samples, selection.seed)
    radii = np.array([s.radius for s in spheres])
    ordered = sorted(carriers)
    body_pairs = [(a, b) for i, a in enumerate(ordered) for b in ordered[i + 1:] if b not in neighbours[a]]
    meshes = body_meshes(kinematics, body_of, carriers) if selection.meshes else None
    gauge = _BodyGauge(sphere_body, radii, meshes, selection.margin)
    centres = sphere_centres(kinematics, spheres, q)
    rng = np.random.default_rng(selection.seed + 1)
    pairs: list[tuple[int, int]] = []
    for a, b in body_pairs:
        gaps, distance = gauge.pair(q, centres, a, b)
        if np.mean(distance <= 0.0) > selection.always_fraction:
            continue
        close = distance < selection.margin
        if not close.any():
            continue
        if selection.near_samples:
            around = configurations_around(q[close], kinematics, selection.near_samples, selection.near_spread, rng)
            more_gaps, more_distance = gauge.pair(around, sphere_centres(kinematics, spheres, around), a, b)
            gaps, distance = np.vstack([gaps, more_gaps]), np.concatenate([distance, more_distance])
            close = distance < selection.margin
        near = gaps[close]
        if selection.cover_slack is None:
            cells = np.unique(np.argmin(near, axis=1))
        else:
            bound = np.maximum(distance[close] + selection.cover_slack, near.min(axis=1))
            phantom = np.mean(gaps[~close] < 0.0, axis=0) if (~close).any() else np.zeros(gaps.shape[1])
            cells = fewest_cover(sparse.csc_matrix(near <= bound[:, None]), costs=1.0 + phantom)
        first, second = np.flatnonzero(sphere_body == a), np.flatnonzero(sphere_body == b)
        for cell in cells:
            u, v = divmod(int(cell), len(second))
            pairs.append((int(min(first[u], second[v])), int(max(first[u], second[v]))))
    return tuple(sorted(pairs))


@dataclass(frozen=True, eq=False)
class _BodyGauge:
    """Sphere gaps and body distances of body pairs at many configurations.

    Attributes:
        sphere_body: Body number of each sphere.
        radii: Radius of each sphere [m].
        meshes: The bodies' meshes, or None to judge bodies on their spheres.
        reach: Mesh distances beyond this may be reported as ``inf`` [m].
    """

    sphere_body: np.ndarray
    radii: np.ndarray
    meshes: BodyMeshes | None
    reach: float

    def pair(self, q: np.ndarray, centres: np.ndarray, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        """Bodies ``a`` and ``b`` at the rows of ``q`` (sphere ``centres`` there, see
        :func:`sphere_centres`): the gaps ``d_ij(q)`` of all their sphere pairs, shape
        (N, |a| |b|) (row-major over a's, then b's spheres), and the bodies' distance,
        shape (N,): on the meshes where both have meshes, else the smallest gap [m]."""
        first = np.flatnonzero(self.sphere_body == a)
        second = np.flatnonzero(self.sphere_body == b)
        gaps = (np.linalg.norm(centres[:, first, None, :] - centres[:, None, second, :], axis=3)
                - self.radii[first, None] - self.radii[None, second]).reshape(len(q), -1)
        on_meshes = self.meshes.distances(q, [(a, b)], self.reach) if self.meshes is not None else {}
        return gaps, on_meshes.get((a, b), gaps.min(axis=1))


def configurations_around(close: np.ndarray, kinematics: Kinematics, count: int, spread: float,
                          rng: np.random.Generator) -> np.ndarray:
    """``count`` configurations ``clip(q + N(0, spread^2))``, each ``q`` a row of ``close``
    drawn at random, within the limits (see :func:`sample_configurations`), shape
    (count, dof); ``spread`` in rad (m for prismatic joints)."""
    lower, upper = finite_joint_bounds(kinematics.lower, kinematics.upper)
    picks = close[rng.integers(len(close), size=count)]
    return np.clip(picks + rng.normal(scale=spread, size=picks.shape), lower, upper)


def bodies(kinematics: Kinematics) -> dict[str, int]:
    """Body number of every link of the tree: links joined by fixed joints, or by movable
    joints that are neither active nor follow an active joint, share a body."""
    active = set(kinematics.joint_names)
    body_of: dict[str, int] = {}
    for link in kinematics.link_names:
        joint = kinematics.model.parent_joint(link)
        if link == kinematics.root_link or joint is None:
            body_of[link] = len(set(body_of.values()))
        elif _rigid(joint, active):
            body_of[link] = body_of[joint.parent]
        else:
            body_of[link] = max(body_of.values()) + 1
    return body_of


def sample_configurations(kinematics: Kinematics, count: int, seed: int) -> np.ndarray:
    """``count`` configurations uniform within the limits (unlimited joints: [-pi, pi]),
    shape (count, dof)."""
    lower, upper = finite_joint_bounds(kinematics.lower, kinematics.upper)
    return np.random.default_rng(seed).uniform(lower, upper, size=(count, kinematics.dof))


def sphere_centres(kinematics: Kinematics, spheres: Sequence[CollisionSphere],
                   q: np.ndarray) -> np.ndarray:
    """Root-frame centres of ``spheres`` at each row of ``q``, shape (N, k, 3) [m]."""
    q = np.atleast_2d(q)
    symbol = ca.SX.sym("q", kinematics.dof)
    points = kinematics.positions(symbol, [(s.link, s.center) for s in spheres])
    function = ca.Function("centres", [symbol], [ca.vec(points)]).map(len(q))
    values = np.array(function(q.T))  # (3k, N), column-major (k, 3) per sample
    return values.T.reshape(len(q), 3, len(spheres)).transpose(0, 2, 1)


def _rigid(joint: Joint, active: set[str]) -> bool:
    """True if ``joint`` never moves with ``q``."""
    if joint.type == "fixed":
        return True
    mimic = joint.mimic
    leader = joint.name if mimic is None else mimic.joint
    return leader not in active


def _neighbours(kinematics: Kinematics, body_of: dict[str, int], carriers: set[int]) -> dict[int, set[int]]:
    """Bodies with spheres next to each body with spheres, looking through bodies without."""
    links: dict[int, set[int]] = {body: set() for body in body_of.values()}
    for link in kinematics.link_names:
        joint = kinematics.model.parent_joint(link)
        if joint is not None and link != kinematics.root_link and body_of[link] != body_of[joint.parent]:
            links[body_of[link]].add(body_of[joint.parent])
            links[body_of[joint.parent]].add(body_of[link])
    neighbours: dict[int, set[int]] = {}
    for start in carriers:
        seen, frontier = {start}, [start]
        while frontier:
            body = frontier.pop()
            for other in links[body] - seen:
                seen.add(other)
                if other not in carriers:
                    frontier.append(other)
        neighbours[start] = seen - {start}
    return neighbours
