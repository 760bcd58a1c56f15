"""The built-in Panda's self-collision pairs see the finger contacts on Franka's meshes
that the uniform-sample selection missed (issue 19)."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.robots.body_distances import body_meshes
from dynfab.robots.builtin import panda_robot
from dynfab.robots.franka import DYNFAB_LINKS, franka_kinematics
from dynfab.robots.panda_spheres import PANDA_FITTED_SPHERES
from dynfab.robots.robot import CollisionSphere
from dynfab.robots.self_collision import (PairSelection, bodies, configurations_around, sample_configurations,
                                          sphere_centres)

#: Deepest samples of two runs where a finger went into the arm's base on the meshes while
#: the 123 pairs of the previous selection saw no overlap: (name, q, the two bodies).
#: exp2b seed 3, dynamic fabric, guidance on: the right finger 12 mm into panda_link1;
#: exp1 seed 1036, static fabric, guidance and recovery off: the left finger 13.6 mm
#: into panda_link0.
FINGER_CONTACTS = (
    ("exp2b seed 3", (0.7187, -0.1344, 0.5037, -2.9188, -0.3094, 1.2497, -0.1374), (1, 7)),
    ("exp1 seed 1036", (1.0719, -0.1063, 0.0435, -3.018, 0.3513, 1.607, 0.0149), (0, 7)),
)


def _kept_gaps(fingers: float, q: np.ndarray, body_pair: tuple[int, int]) -> np.ndarray:
    """Gaps of the kept pairs between the two bodies at each row of ``q``, shape (N, k) [m]."""
    kinematics = franka_kinematics(fingers)
    body_of = bodies(kinematics)
    franka_of = {dynfab: franka for franka, dynfab in DYNFAB_LINKS.items()}
    spheres = [CollisionSphere(franka_of[link], center, radius) for link, center, radius in PANDA_FITTED_SPHERES]
    depth = [body_of[s.link] for s in spheres]
    kept = np.array([(a, b) for a, b in panda_robot("fitted", fingers).self_collision_pairs
                     if (depth[a], depth[b]) == body_pair])
    assert len(kept), body_pair
    radii = np.array([s.radius for s in spheres])
    centres = sphere_centres(kinematics, spheres, q)
    distances = np.linalg.norm(centres[:, kept[:, 0]] - centres[:, kept[:, 1]], axis=2)
    return distances - radii[kept[:, 0]] - radii[kept[:, 1]]


@pytest.mark.parametrize(("name", "q", "body_pair"), FINGER_CONTACTS, ids=[c[0] for c in FINGER_CONTACTS])
def test_a_finger_inside_the_base_on_the_meshes_is_seen_by_a_kept_pair(
        name: str, q: tuple[float, ...], body_pair: tuple[int, int]) -> None:
    kinematics = franka_kinematics(0.04)
    meshes = body_meshes(kinematics, bodies(kinematics), set(body_pair))
    depth = meshes.distances(np.array([q]), [body_pair], 0.02)[body_pair][0]
    assert depth < -0.01, (name, depth)
    assert _kept_gaps(0.04, np.array([q]), body_pair).min() < 0.0, name


@pytest.mark.parametrize("fingers", [0.04, 0.0])
def test_near_self_contact_of_hand_and_base_every_deep_mesh_contact_has_an_overlapping_pair(fingers: float) -> None:
    """Fresh configurations near contact of the hand body (hand, fingers, link7) with
    panda_link0 and panda_link1, drawn as the selection draws (around uniform samples that
    come within 2 cm, 0.1 rad offsets) but from other seeds: wherever the meshes go more
    than 1 cm into each other (twice the spheres' 5 mm coverage: closer contacts may sit
    between spheres), some kept pair of the two bodies overlaps."""
    kinematics = franka_kinematics(fingers)
    body_of = bodies(kinematics)
    meshes = body_meshes(kinematics, body_of, {0, 1, 7})
    selection = PairSelection()
    rng = np.random.default_rng(4321)
    uniform = sample_configurations(kinematics, 3000, 98765)
    deep = 0
    for body_pair in ((0, 7), (1, 7)):
        close = uniform[meshes.distances(uniform, [body_pair], selection.margin)[body_pair] < selection.margin]
        assert len(close) > 10, body_pair
        q = configurations_around(close, kinematics, 600, selection.near_spread, rng)
        inside = meshes.distances(q, [body_pair], selection.margin)[body_pair] < -0.01
        deep += int(inside.sum())
        seen = _kept_gaps(fingers, q[inside], body_pair).min(axis=1)
        assert np.all(seen < 0.0), (body_pair, int(np.sum(seen >= 0.0)), float(seen.max()))
    assert deep > 100
