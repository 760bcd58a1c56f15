"""The planner's focus on a point cloud near its goal: the split of the kept points, the
focused obstacles around the robot's spheres, the compiled checker's bound on them (never
above the distance to a measured point, closer to it than the whole cloud's grid near the
goal), guidance using it only where the whole cloud gives no plan (a cage grasp) and after
its first failed attempt there, bad settings refused."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial import cKDTree

from dynfab.geometry.focused_cloud import FocusedCloud, split_cloud
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.cloud_focus import CloudFocus, focused_obstacles
from dynfab.motion.configuration_checker import ConfigurationChecker, PlacedObstacle
from dynfab.motion.guidance import GuidanceError, JointGuidance, JointTarget
from dynfab.motion.guidance_settings import GuidanceSettings, counted_checks
from dynfab.robots.builtin import load_robot

ORIGIN = Placement((0.0, 0.0, 0.0))
START = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def _wall(rng: np.random.Generator, count: int = 20_000) -> np.ndarray:
    """Noisy points on a vertical wall x = 0.6 and a floor z = 0."""
    wall = np.column_stack([np.full(count, 0.6), rng.uniform(-0.4, 0.4, count), rng.uniform(0.0, 0.8, count)])
    floor = np.column_stack([rng.uniform(0.2, 0.8, count), rng.uniform(-0.4, 0.4, count), np.zeros(count)])
    return np.concatenate([wall, floor]) + rng.normal(0.0, 0.002, (2 * count, 3))


def test_the_split_partitions_the_kept_points_by_the_box_with_the_same_bound() -> None:
    cloud = PointCloud.from_points(_wall(np.random.default_rng(1)), voxel=0.01, source="wall.npy")
    low, high = np.array([0.5, -0.1, 0.2]), np.array([0.7, 0.1, 0.5])
    focused, rest = split_cloud(cloud, low, high, 0.004)
    assert isinstance(focused, FocusedCloud) and type(rest) is PointCloud
    assert np.all((focused.points >= low) & (focused.points <= high))
    assert not np.all((rest.points >= low) & (rest.points <= high), axis=1).any()
    assert len(focused.points) + len(rest.points) == len(cloud.points)
    merged = np.concatenate([focused.points, rest.points])
    assert np.array_equal(np.unique(merged, axis=0), np.unique(cloud.points, axis=0))
    assert focused.lowering == rest.lowering == cloud.lowering and focused.pitch == 0.004
    nowhere, everything = split_cloud(cloud, [5.0, 5.0, 5.0], [6.0, 6.0, 6.0], 0.004)
    assert nowhere is None and everything is not None and len(everything.points) == len(cloud.points)
    around, none = split_cloud(cloud, [-1.0, -1.0, -1.0], [2.0, 2.0, 2.0], 0.004)
    assert none is None and around is not None and len(around.points) == len(cloud.points)


@pytest.mark.parametrize(("low", "high", "pitch", "message"), [
    ([0.0, 0.0], [1.0, 1.0, 1.0], 0.004, "low and high must be 3 finite numbers"),
    ([0.0, np.nan, 0.0], [1.0, 1.0, 1.0], 0.004, "low and high must be 3 finite numbers"),
    ([1.0, 0.0, 0.0], [0.0, 1.0, 1.0], 0.004, "exceeds high"),
    ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0, "pitch must be a positive number"),
])
def test_a_bad_focus_box_or_pitch_is_refused(low: list, high: list, pitch: float, message: str) -> None:
    cloud = PointCloud.from_points(_wall(np.random.default_rng(2), 500), voxel=0.01, source="wall.npy")
    with pytest.raises(ValueError, match=message) as error:
        split_cloud(cloud, low, high, pitch)
    assert "wall.npy" in str(error.value)


@pytest.mark.parametrize(("field", "value"), [("reach", -0.1), ("reach", math.inf), ("pitch", 0.0),
                                              ("pitch", math.nan), ("whole_attempts", 0)])
def test_bad_focus_settings_are_refused_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"cloud focus {field}"):
        CloudFocus(**{field: value})


def test_focused_obstacles_split_clouds_around_the_spheres_in_the_cloud_frame() -> None:
    rng = np.random.default_rng(3)
    cloud = PointCloud.from_points(_wall(rng) - np.array([1.0, 0.0, 0.0]), voxel=0.01)  # the wall at x = -0.4
    placement = Placement((1.0, 0.0, 0.0))  # back at x = 0.6 in the world
    box = PlacedObstacle(Box((0.1, 0.1, 0.1)), Placement((0.0, 1.0, 0.0)))
    centres, radii = np.array([[0.5, 0.0, 0.4], [0.45, 0.05, 0.35]]), np.array([0.05, 0.03])
    focused = focused_obstacles([box, PlacedObstacle(cloud, placement)], centres, radii, CloudFocus(reach=0.1))
    assert focused[0] is box
    shapes = [o.shape for o in focused[1:]]
    assert [type(s) for s in shapes] == [FocusedCloud, PointCloud] and all(o.placement == placement for o in focused[1:])
    world = shapes[0].points + np.array([1.0, 0.0, 0.0])
    low, high = np.array([0.32, -0.15, 0.22]) - 1e-9, np.array([0.65, 0.18, 0.55]) + 1e-9  # spheres ± r ± reach
    assert np.all((world >= low) & (world <= high)) and world[:, 1].max() > 0.15
    assert len(shapes[0].points) + len(shapes[1].points) == len(cloud.points)
    # an empty cloud and a focused one stay as they are
    empty = PlacedObstacle(PointCloud(np.zeros((0, 3))), ORIGIN)
    again = PlacedObstacle(shapes[0], placement)
    assert focused_obstacles([empty, again], centres, radii, CloudFocus()) == (empty, again)


def test_the_checker_reads_the_focused_cloud_below_the_measured_distance_and_closer_to_it() -> None:
    robot = load_robot("panda")
    rng = np.random.default_rng(6)
    raw = _wall(rng)
    cloud = PointCloud.from_points(raw, voxel=0.01)
    whole = ConfigurationChecker(robot, [PlacedObstacle(cloud, ORIGIN)])
    goal = np.array([1.0, 0.26, -0.17, -2.8, 0.68, 2.22, 0.03])  # 9 mm from the measured points
    centres = np.asarray(robot.sphere_centers(goal), dtype=float).reshape(-1, 3)
    radii = np.asarray(robot.sphere_radii, dtype=float)
    focus = CloudFocus(reach=0.1, pitch=0.004)
    obstacles = focused_obstacles([PlacedObstacle(cloud, ORIGIN)], centres, radii, focus)
    assert any(isinstance(o.shape, FocusedCloud) for o in obstacles)
    near = ConfigurationChecker(robot, obstacles)
    qs = goal + rng.normal(0.0, 0.15, (300, robot.dof))
    tree = cKDTree(raw)
    exact = np.array([(tree.query(np.asarray(robot.sphere_centers(q), dtype=float).reshape(-1, 3))[0]
                       - radii).min() for q in qs])
    focused_bound, whole_bound = near.batch(qs)[:, 0], whole.batch(qs)[:, 0]
    assert (focused_bound <= exact + 1e-12).all()
    close = (exact > 0) & (exact < 0.05)
    assert close.sum() > 20
    shortfall, whole_shortfall = (exact - focused_bound)[close], (exact - whole_bound)[close]
    assert shortfall.max() < 2 * math.sqrt(3) * 0.004 + 2 * cloud.lowering
    assert np.median(shortfall) < np.median(whole_shortfall) - 0.002


def test_guidance_focuses_the_cloud_only_where_the_whole_cloud_gives_no_plan() -> None:
    robot = load_robot("panda")
    cloud = PointCloud.from_points(_wall(np.random.default_rng(7)), voxel=0.01)
    obstacles = [PlacedObstacle(cloud, ORIGIN)]
    guidance = JointGuidance(robot)
    guidance.plan(START, JointTarget((0.3, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785)), obstacles)
    assert guidance.checker.obstacles == tuple(obstacles)  # planned on the whole cloud


def _cage_problem() -> tuple[list[PlacedObstacle], np.ndarray, JointTarget]:
    """Training problem cage/0011 as a point cloud: its grasp goal reads in collision on the
    whole cloud's grid with no escape."""
    from dynfab.benchmarks.mbm.franka import franka
    from dynfab.benchmarks.mbm.problems import load_problems
    from dynfab.benchmarks.mbm.variants import prepare_case
    from dynfab.scenario.schema import scenario_from_dict

    problem = load_problems(("cage",), 1, skip=2)[0]
    assert problem.name == "cage/0011"
    scenario = scenario_from_dict(prepare_case(problem, "points", franka()).mapping)
    obstacles = [PlacedObstacle(o.shape, Placement(tuple(o.position), o.orientation)) for o in scenario.obstacles]
    return obstacles, np.asarray(scenario.initial_state.q), JointTarget(tuple(scenario.goals[0].position))


def test_a_cage_goal_blocked_on_the_whole_cloud_is_planned_on_the_focused_one_and_reused() -> None:
    robot = load_robot("panda")
    obstacles, start, goal = _cage_problem()
    # one attempt, seed 0's escape samples (a later seed finds an escape on the whole cloud), 4 s of search
    # (counted in checks: the same on a loaded machine)
    one = counted_checks(GuidanceSettings(attempts=1, path=replace(GuidanceSettings().path, time_limit=4.0)))
    with pytest.raises(GuidanceError) as failure:
        JointGuidance(robot, replace(one, cloud_focus=None)).plan(start, goal, obstacles)
    assert failure.value.reason == "goal_in_collision"
    guidance = JointGuidance(robot, one)
    plan = guidance.plan(start, goal, obstacles)
    used = guidance.checker.obstacles
    assert any(isinstance(o.shape, FocusedCloud) for o in used) and plan.approach > 0.0
    guidance.plan(start, goal, obstacles, seed=1)
    assert guidance.checker.obstacles is used


def test_after_the_first_failed_whole_cloud_attempt_every_attempt_is_on_the_focus(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import dynfab.motion.guidance as guidance_module
    from dynfab.motion.joint_planning import NoPathError

    robot = load_robot("panda")
    cloud = PointCloud.from_points(_wall(np.random.default_rng(8)), voxel=0.01)
    obstacles = [PlacedObstacle(cloud, ORIGIN)]
    seen: list[tuple[bool, int]] = []

    def no_path(checker, start, goal, lower, upper, settings, seed, approach, leave=None):  # type: ignore[no-untyped-def]
        seen.append((any(isinstance(o.shape, FocusedCloud) for o in checker.obstacles), seed))
        raise NoPathError("no_path", "none")

    monkeypatch.setattr(guidance_module, "plan_joint_path", no_path)
    goal = JointTarget((0.3, -0.3, 0.0, -2.0, 0.0, 1.8, 0.785))
    settings = GuidanceSettings(attempts=3)
    with pytest.raises(GuidanceError):
        JointGuidance(robot, settings).plan(START, goal, obstacles, seed=5)
    assert seen == [(False, 5), (True, 5), (True, 6), (True, 7)]
    seen.clear()
    with pytest.raises(GuidanceError):
        JointGuidance(robot, replace(settings, cloud_focus=CloudFocus(whole_attempts=2))).plan(START, goal, obstacles)
    assert seen == [(False, 0), (False, 1), (True, 0), (True, 1), (True, 2)]
    seen.clear()
    with pytest.raises(GuidanceError):
        JointGuidance(robot, replace(settings, cloud_focus=None)).plan(START, goal, obstacles)
    assert seen == [(False, 0), (False, 1), (False, 2)]
