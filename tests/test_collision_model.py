"""Automatic collision models of real arms: coverage against the meshes, pairs, cache."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh

from dynfab.geometry.sphere_fitting import outside_distances
from dynfab.robots import Kinematics, load_urdf
from dynfab.robots.builtin import panda_robot
from dynfab.robots.collision_model import CollisionModel, auto_collision_model
from dynfab.robots.link_meshes import LinkMeshError, link_collision_meshes
from dynfab.robots.panda_spheres import PANDA_FITTED_SPHERES
from dynfab.robots.robot import CollisionSphere
from dynfab.robots.self_collision import PairSelection, bodies, select_pairs, sphere_centres
from robot_files import arm_urdf

ARMS = ("ur5", "kinova", "xarm7", "panda")
#: Sphere count a typical arm link may need (the brief says about 10); the UR5's 0.55 m upper
#: arm and Kinova's upper arm need more (see the report in the test below).
TYPICAL_LINK_SPHERES = 10
LONGEST_LINK_SPHERES = 20


@pytest.fixture(scope="session")
def cache(request: pytest.FixtureRequest) -> Path:
    """pytest's persistent cache folder: fits are keyed by content, so reusing them across
    sessions is exactly what the cache is for."""
    return Path(request.config.cache.mkdir("dynfab-collision-models"))


@pytest.fixture(scope="session", params=ARMS)
def arm(request: pytest.FixtureRequest, cache: Path) -> tuple[str, CollisionModel]:
    return request.param, auto_collision_model(arm_urdf(request.param), cache=cache)


def _independent_surface(meshes: list[trimesh.Trimesh]) -> np.ndarray:
    """Vertices plus a dense seeded sample other than the fitter's (about 1 per 4 mm^2)."""
    return np.vstack([np.vstack([m.vertices, trimesh.sample.sample_surface(m, int(m.area / 4e-6) + 100,
                                                                          seed=987)[0]])
                      for m in meshes])


def test_spheres_cover_every_link_mesh_within_1_cm(arm: tuple[str, CollisionModel]) -> None:
    name, model = arm
    urdf = load_urdf(arm_urdf(name))
    counts = {}
    for fit in model.links:
        meshes = link_collision_meshes(urdf, fit.link)
        centres = np.array([s.center for s in fit.spheres])
        radii = np.array([s.radius for s in fit.spheres])
        outside = outside_distances(_independent_surface(meshes), centres, radii)
        # buried faces of overlapping parts need no cover; every such point of these arms is
        # still within 1 cm, so the check is on all of the surface
        assert outside.max() <= 0.01 + 1e-9, (name, fit.link, outside.max())
        assert fit.coverage <= 0.01 + 1e-9
        assert fit.bulge <= 0.035, (name, fit.link, fit.bulge)
        counts[fit.link] = len(fit.spheres)
    assert np.median(list(counts.values())) <= TYPICAL_LINK_SPHERES, counts
    assert max(counts.values()) <= LONGEST_LINK_SPHERES, counts
    moving = {link.name for link in urdf.links if link.collisions}
    assert set(counts) == moving


def test_pairs_skip_same_and_adjacent_bodies(arm: tuple[str, CollisionModel]) -> None:
    name, model = arm
    kinematics = Kinematics(load_urdf(arm_urdf(name)))
    body_of = bodies(kinematics)
    spheres = model.spheres
    parent_body = {}
    for link in kinematics.link_names:
        joint = kinematics.model.parent_joint(link)
        if joint is not None:
            parent_body[body_of[link]] = body_of[joint.parent]
    for a, b in model.self_collision_pairs:
        first, second = body_of[spheres[a].link], body_of[spheres[b].link]
        assert first != second
        assert parent_body.get(first) != second and parent_body.get(second) != first
    assert model.self_collision_pairs, name


def test_every_kept_pair_can_meet(arm: tuple[str, CollisionModel]) -> None:
    """For each body pair kept, some sampled configuration brings its spheres within the
    margin; and for at least one pair a configuration where the spheres overlap exists."""
    name, model = arm
    kinematics = Kinematics(load_urdf(arm_urdf(name)))
    q = np.random.default_rng(0).uniform(np.where(np.isfinite(kinematics.lower), kinematics.lower, -np.pi),
                                         np.where(np.isfinite(kinematics.upper), kinematics.upper, np.pi),
                                         size=(3000, kinematics.dof))
    centres = sphere_centres(kinematics, model.spheres, q)
    radii = np.array([s.radius for s in model.spheres])
    pairs = np.array(model.self_collision_pairs)
    gaps = (np.linalg.norm(centres[:, pairs[:, 0]] - centres[:, pairs[:, 1]], axis=2)
            - radii[pairs[:, 0]] - radii[pairs[:, 1]])
    assert np.all(gaps.min(axis=0) < PairSelection().margin)
    assert (gaps.min(axis=0) < 0.0).any()


def test_pair_rules_on_a_chain_of_three_links() -> None:
    """A planar chain base -> a -> b -> c of 1 m links: adjacent bodies are skipped, a pair
    that is always in contact is skipped, a pair that can fold onto each other is kept."""
    kinematics = Kinematics(load_urdf(Path(__file__).parent / "data" / "three_links.urdf"))
    spheres = [CollisionSphere("base", (0.0, 0, 0), 1.2),  # b's origin is always 1 m away: always in contact
               CollisionSphere("a", (0.5, 0, 0), 0.1), CollisionSphere("b", (0.0, 0, 0), 0.1),
               CollisionSphere("c", (0.5, 0, 0), 0.1)]
    pairs = select_pairs(kinematics, spheres)
    assert set(pairs) == {(0, 3), (1, 3)}
    # a and c really meet: with the elbows folded c's sphere lies on a's
    centres = sphere_centres(kinematics, spheres, np.array([[0.0, 3.0, 3.0]]))[0]
    assert np.linalg.norm(centres[1] - centres[3]) < 0.2


def test_cache_is_used_and_a_changed_urdf_refits(tmp_path: Path) -> None:
    source = arm_urdf("ur5")
    robot_dir = tmp_path / "ur_description"
    shutil.copytree(source.parents[1], robot_dir)
    urdf = robot_dir / source.parent.name / source.name
    first = auto_collision_model(urdf, cache=tmp_path / "cache")
    again = auto_collision_model(urdf, cache=tmp_path / "cache")
    assert not first.from_cache and again.from_cache
    assert again.spheres == first.spheres and again.self_collision_pairs == first.self_collision_pairs
    assert len(list((tmp_path / "cache").iterdir())) == 1
    text = urdf.read_text()
    urdf.write_text(text.replace('upper="3.14159265"', 'upper="3.0"', 1) if 'upper="3.14159265"' in text
                    else text.replace("<robot ", "<robot  ", 1))
    changed = auto_collision_model(urdf, cache=tmp_path / "cache")
    assert not changed.from_cache
    assert len(list((tmp_path / "cache").iterdir())) == 2


def test_cache_dir_comes_from_the_environment(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from dynfab.robots.collision_model import cache_dir

    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path))
    assert cache_dir() == tmp_path
    monkeypatch.delenv("DYNFAB_CACHE_DIR")
    assert cache_dir() == Path(os.path.expanduser("~")) / ".cache" / "dynfab"


def test_missing_mesh_of_a_moving_link_names_the_link(tmp_path: Path) -> None:
    urdf = tmp_path / "arm.urdf"
    urdf.write_text((Path(__file__).parent / "data" / "three_links.urdf").read_text()
                    .replace("<!--MESH-->", '<collision><geometry><mesh filename="gone.stl"/></geometry></collision>'))
    with pytest.raises(LinkMeshError, match="link 'c'.*gone.stl"):
        auto_collision_model(urdf, cache=tmp_path)


def test_builtin_panda_spheres_cover_frankas_meshes() -> None:
    """The built-in Panda's fitted table (panda_spheres.py) against example-robot-data's
    meshes; the hand and the closed fingers are placed in dynfab's panda_hand frame, which is
    example-robot-data's panda_hand moved 0.1034 m along its z axis."""
    urdf = load_urdf(arm_urdf("panda"))
    kinematics = Kinematics(urdf, joints=[f"panda_joint{i}" for i in range(1, 8)])
    centres = np.array([center for _, center, _ in PANDA_FITTED_SPHERES])
    radii = np.array([radius for _, _, radius in PANDA_FITTED_SPHERES])
    links = np.array([link for link, _, _ in PANDA_FITTED_SPHERES])
    hand = ("panda_hand", "panda_leftfinger", "panda_rightfinger")
    for link in [f"panda_link{i}" for i in range(8)] + list(hand):
        surface = _independent_surface(link_collision_meshes(urdf, link))
        if link in hand:
            transform = np.array(kinematics.transform(np.zeros(7), link, parent="panda_hand"))
            surface = surface @ transform[:3, :3].T + transform[:3, 3] - [0.0, 0.0, 0.1034]
        mine = links == ("panda_hand" if link in hand else link)
        outside = outside_distances(surface, centres[mine], radii[mine])
        assert outside.max() <= 0.01 + 1e-9, (link, outside.max())


def test_fitted_panda_pairs_follow_the_rules_and_are_apart_at_the_default() -> None:
    panda = panda_robot("fitted")
    spheres, pairs = panda.collision_spheres, panda.self_collision_pairs
    depth = {f"panda_link{i}": i for i in range(8)} | {"panda_hand": 7}  # link7 + hand: one body
    assert len(set(pairs)) == len(pairs) > 50
    assert all(abs(depth[spheres[a].link] - depth[spheres[b].link]) >= 2 for a, b in pairs)
    centres, radii = panda.sphere_centers(panda.default_q), panda.sphere_radii
    gaps = [np.linalg.norm(centres[a] - centres[b]) - radii[a] - radii[b] for a, b in pairs]
    assert min(gaps) > 0.01
    with pytest.raises(ValueError, match="sphere_model"):
        panda_robot("guessed")
