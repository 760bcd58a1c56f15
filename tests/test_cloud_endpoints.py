"""Blocked endpoints among point clouds: a goal's approach is not refused by its own floor
(the clearance read less ``δ`` and given back plus ``δ``, 1 nm of slack), and the tight round
(``tight_margin``) comes only on the clouds' focus, after the focus at the planner's margin,
never on the whole clouds' grids."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.focused_cloud import FocusedCloud
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Placement
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GuidanceError, JointGuidance, JointTarget
from dynfab.motion.guidance_settings import GuidanceSettings
from dynfab.robots.builtin import load_robot

ORIGIN = Placement((0.0, 0.0, 0.0))
START = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
GOAL = JointTarget((0.3, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785))


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def _wall(rng: np.random.Generator, count: int = 20_000) -> np.ndarray:
    """Noisy points (σ = 2 mm) on a vertical wall x = 0.6 and a floor z = 0."""
    wall = np.column_stack([np.full(count, 0.6), rng.uniform(-0.4, 0.4, count), rng.uniform(0.0, 0.8, count)])
    floor = np.column_stack([rng.uniform(0.2, 0.8, count), rng.uniform(-0.4, 0.4, count), np.zeros(count)])
    return np.concatenate([wall, floor]) + rng.normal(0.0, 0.002, (2 * count, 3))


def test_an_endpoint_passes_its_own_floor_on_the_meshes_among_clouds(panda) -> None:
    """``polyline_free`` at the endpoint's own clearance (the "no deeper than the endpoint"
    floor of its approach, read less ``δ`` and given back plus ``δ``) accepts the endpoint
    itself, and 1 µm above it refuses it: configurations beside the wall clear of
    themselves. (The ulp that the slack covers showed at MBM points cage/0056's goal on
    hP-points; none of these draws meets it without the slack.)"""
    cloud = PointCloud.from_points(_wall(np.random.default_rng(3)), voxel=0.01)
    guidance = JointGuidance(panda)
    guidance.checker.set_obstacles([PlacedObstacle(cloud, ORIGIN)])
    meshes = guidance._meshes()
    rng = np.random.default_rng(4)
    tried = 0
    for _ in range(60):
        q = START + rng.normal(0.0, 0.3, START.size)
        own, itself = meshes.clearance(q)
        if itself <= 0.0:   # touching itself: refused at any floor
            continue
        tried += 1
        assert meshes.polyline_free(np.vstack([q, q]), 0.015, own)
        assert not meshes.polyline_free(np.vstack([q, q]), 0.015, own + 1e-6)
    assert tried > 40


def test_the_tight_round_among_clouds_comes_on_the_focus_after_it_failed_at_the_margin(
        panda, monkeypatch: pytest.MonkeyPatch) -> None:
    import dynfab.motion.guidance as guidance_module
    from dynfab.motion.joint_planning import NoPathError

    cloud = PointCloud.from_points(_wall(np.random.default_rng(8)), voxel=0.01)
    seen: list[tuple[bool, float]] = []

    def blocked(checker, start, goal, lower, upper, settings, seed, approach,  # type: ignore[no-untyped-def]
                leave=None):
        seen.append((any(isinstance(o.shape, FocusedCloud) for o in checker.obstacles), settings.margin))
        raise NoPathError("goal_in_collision", "no escape")

    monkeypatch.setattr(guidance_module, "plan_joint_path", blocked)
    settings = GuidanceSettings(attempts=2)
    margin, tight = settings.path.margin, settings.tight_margin
    assert tight < margin
    with pytest.raises(GuidanceError) as failure:
        JointGuidance(panda, settings).plan(START, GOAL, [PlacedObstacle(cloud, ORIGIN)])
    assert failure.value.reason == "goal_in_collision"
    rounds = list(dict.fromkeys(seen))   # in order, each (focus, margin) once
    assert rounds == [(False, margin), (True, margin), (True, tight)]


def test_without_a_focus_no_tight_round_is_made_among_clouds(panda, monkeypatch: pytest.MonkeyPatch) -> None:
    from dataclasses import replace

    import dynfab.motion.guidance as guidance_module
    from dynfab.motion.joint_planning import NoPathError

    cloud = PointCloud.from_points(_wall(np.random.default_rng(8)), voxel=0.01)
    margins: list[float] = []

    def blocked(checker, start, goal, lower, upper, settings, seed, approach,  # type: ignore[no-untyped-def]
                leave=None):
        margins.append(settings.margin)
        raise NoPathError("goal_in_collision", "no escape")

    monkeypatch.setattr(guidance_module, "plan_joint_path", blocked)
    settings = replace(GuidanceSettings(attempts=2), cloud_focus=None)
    with pytest.raises(GuidanceError):
        JointGuidance(panda, settings).plan(START, GOAL, [PlacedObstacle(cloud, ORIGIN)])
    assert set(margins) == {settings.path.margin}
