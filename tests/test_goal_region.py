"""Goals inside their tolerance (dynfab.motion.goal_region): nearby targets stay within the
fraction of the tolerances asked, a pose stays a frame, and a pose goal whose every exact
solution puts the hand into a block is planned to a free pose the goal still accepts."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dynfab.geometry.shapes import Box, Placement
from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.goal_region import nearby_targets, roomier_goal
from dynfab.motion.guidance import GuidanceError, GuidanceSettings, JointGuidance, JointTarget, Plan
from dynfab.motion.inverse_kinematics import AxisTarget, PointTarget
from dynfab.motion.plan_requests import PlanRequest, make_plan
from dynfab.robots import load_robot
from wall_scene import START, hand_pose_targets

#: The goal configuration: the hand above the block, pointing down [rad].
ABOVE = np.array([0.0, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785])
POSITION_TOLERANCE, ANGLE_TOLERANCE = 0.02, 0.1


def _pose(position_tolerance: float, angle_tolerance: float) -> list[PointTarget | AxisTarget]:
    rotation = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    return [PointTarget("panda_hand", (0.4, 0.1, 0.3), tolerance=position_tolerance),
            *(AxisTarget("panda_hand", tuple(np.eye(3)[k]), tuple(rotation[:, k]), angle_tolerance) for k in range(3))]


def test_nearby_targets_stay_within_the_fraction_and_a_pose_stays_a_frame() -> None:
    rng = np.random.default_rng(0)
    goal = _pose(POSITION_TOLERANCE, ANGLE_TOLERANCE)
    offsets, angles = [], []
    for _ in range(500):
        point, *axes = nearby_targets(goal, 0.5, rng)
        offsets.append(np.linalg.norm(np.subtract(point.position, goal[0].position)))
        frame = np.column_stack([axis.direction for axis in axes])
        np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-12)     # still orthonormal
        reference = np.column_stack([axis.direction for axis in goal[1:]])
        angles.append(Rotation.from_matrix(frame @ reference.T).magnitude())
    assert max(offsets) <= 0.5 * POSITION_TOLERANCE + 1e-12 and max(offsets) > 0.45 * POSITION_TOLERANCE
    assert max(angles) <= 0.5 * ANGLE_TOLERANCE + 1e-12 and max(angles) > 0.45 * ANGLE_TOLERANCE


def test_targets_without_tolerance_stay_where_they_are() -> None:
    goal = _pose(0.0, 0.0)
    assert nearby_targets(goal, 0.5, np.random.default_rng(1)) == goal


@pytest.fixture(scope="module")
def blocked() -> tuple[object, PlacedObstacle, list[PointTarget | AxisTarget]]:
    """The Panda, a block whose top is 3 mm above the lowest point of the hand's and the
    fingers' spheres at ABOVE, and the hand's pose there: every exact solution overlaps it."""
    panda = load_robot("panda")
    planning = panda.planning_robot
    centres = np.array(planning.sphere_centers(ABOVE)).astype(float)
    radii = np.asarray(planning.sphere_radii)
    hand = np.array([("hand" in s.link or "finger" in s.link) for s in planning.collision_spheres])
    lowest = float((centres[hand, 2] - radii[hand]).min())
    x, y = centres[hand, 0].mean(), centres[hand, 1].mean()
    block = PlacedObstacle(Box((0.12, 0.12, 0.1)), Placement((float(x), float(y), lowest + 0.003 - 0.05)))
    return panda, block, hand_pose_targets(panda, ABOVE)


def _tolerant(targets: list[PointTarget | AxisTarget]) -> list[PointTarget | AxisTarget]:
    return [replace(t, tolerance=POSITION_TOLERANCE if isinstance(t, PointTarget) else ANGLE_TOLERANCE)
            for t in targets]


def test_a_pose_whose_exact_solutions_overlap_a_block_is_solved_inside_its_tolerance(blocked) -> None:
    panda, block, exact = blocked
    guidance = JointGuidance(panda)
    guidance.set_obstacles([block])
    with pytest.raises(GuidanceError) as refused:
        guidance.goal_configuration(exact, START)
    assert refused.value.reason == "no_ik_solution"
    solution, moved = guidance.goal_solution(_tolerant(exact), START)
    assert moved
    assert guidance.checker.exact_free(solution, 0.0, guidance.settings.path.self_margin)
    moved = np.linalg.norm(panda.link_position(solution, "panda_hand") - np.asarray(exact[0].position))
    assert moved <= guidance.settings.goal_region * POSITION_TOLERANCE + 1e-6
    turned = np.asarray(panda.kinematics.transform(solution, "panda_hand"))[:3, :3]
    target = np.column_stack([t.direction for t in exact[1:]])
    assert Rotation.from_matrix(turned @ target.T).magnitude() <= guidance.settings.goal_region * ANGLE_TOLERANCE + 1e-4


def test_a_plan_request_to_a_pose_solved_inside_its_tolerance_says_the_goal_moved(blocked) -> None:
    """The plan requests of a guided fabric solve a task goal before planning to the joint
    configuration: the plan they return carries the moved target (its metrics' ``goal_moved``)."""
    panda, block, exact = blocked
    guidance = JointGuidance(panda)

    def outcome(goal):
        return make_plan(guidance, PlanRequest(0.0, START, goal, (block,), (), None, 0, False, (0.0,)))

    moved = outcome(_tolerant(exact))
    assert moved.plan is not None and moved.plan.goal_moved
    free_goal = _tolerant(hand_pose_targets(panda, START))   # the start's own pose, far above the block
    assert not outcome(free_goal).plan.goal_moved


def test_without_the_region_the_tolerant_pose_is_refused(blocked) -> None:
    panda, block, exact = blocked
    guidance = JointGuidance(panda, replace(GuidanceSettings(), goal_region_targets=0))
    guidance.set_obstacles([block])
    with pytest.raises(GuidanceError) as refused:
        guidance.goal_configuration(_tolerant(exact), START)
    assert refused.value.reason == "no_ik_solution"


@pytest.fixture(scope="module")
def wall_goal():
    """The Panda, guidance among the mesh wall, and a joint goal its meshes clear by 2.5 mm
    (the spheres overlap the wall there)."""
    from test_mesh_near_goals import GOAL_CLEARANCE
    from wall_scene import MESH_WALL, goal_near_the_wall
    panda = load_robot("panda")
    guidance = JointGuidance(panda)
    guidance.set_obstacles([MESH_WALL])
    meshes = guidance._meshes()
    return guidance, meshes, _meshes_clear_by(meshes, goal_near_the_wall(panda, 0.0), GOAL_CLEARANCE), MESH_WALL


def _meshes_clear_by(meshes, touching: np.ndarray, clearance: float) -> np.ndarray:
    """``touching`` (the spheres touching the wall) turned back about joint 1 until the
    meshes clear the wall by ``clearance`` [m] (bisection)."""
    far, close = touching.copy(), touching.copy()
    far[0] -= 0.06
    close[0] += 0.06
    for _ in range(40):
        middle = (far + close) / 2
        far, close = (middle, close) if meshes.clearance(middle)[0] > clearance else (far, middle)
    return far


def test_a_roomier_joint_goal_lies_inside_half_its_tolerance_farther_from_the_meshes(wall_goal) -> None:
    guidance, meshes, near, _ = wall_goal
    roomier = roomier_goal(JointTarget(tuple(near), 0.05), near, meshes, guidance.settings, guidance.bounds, 0)
    assert roomier is not None
    assert np.linalg.norm(roomier - near) <= guidance.settings.goal_region * 0.05 + 1e-12
    assert meshes.clearance(roomier)[0] > meshes.clearance(near)[0] + 1e-3
    assert meshes.free(roomier, guidance.settings.mesh_goal_floor)
    assert roomier_goal(JointTarget(tuple(near)), near, meshes, guidance.settings, guidance.bounds, 0) is None      # no tolerance: the goal as given


def test_a_joint_goal_nearer_the_meshes_than_their_margin_is_planned_to_a_roomier_one_at_once(wall_goal,
                                                                                                monkeypatch) -> None:
    # generated MBM seed 15 as posed, cage/0001: a goal 0.25 mm from the object, a finger 0.42 mm into it
    guidance, meshes, near, wall = wall_goal
    assert meshes.clearance(near)[0] < guidance.settings.mesh_margin
    tried: list[np.ndarray] = []

    def record(self, start, target, *args):
        tried.append(np.array(target))
        return Plan(None, np.array(target), 0.0, 0)

    monkeypatch.setattr(JointGuidance, "_plan_to", record)
    start = near.copy()
    start[0] = -2.2
    plan = guidance.plan(start, JointTarget(tuple(near), 0.05), [wall])
    assert len(tried) == 1 and np.linalg.norm(tried[0] - near) <= guidance.settings.goal_region * 0.05 + 1e-12
    assert meshes.clearance(tried[0])[0] > meshes.clearance(near)[0] and plan.goal_moved
    tried.clear()
    assert not guidance.plan(start, JointTarget(tuple(near)), [wall]).goal_moved   # no tolerance: as given
    np.testing.assert_array_equal(tried[0], near)


def test_a_joint_goal_with_no_way_in_is_planned_again_to_a_roomier_one(wall_goal, monkeypatch) -> None:
    guidance, meshes, _, wall = wall_goal
    near = _meshes_clear_by(meshes, wall_goal[2], guidance.settings.mesh_margin + 0.001)   # not moved at once
    tried: list[np.ndarray] = []

    def no_way_into_near(self, start, target, *args):
        tried.append(np.array(target))
        if np.allclose(target, near):
            raise GuidanceError("goal_in_collision", "no escape")
        return Plan(None, np.array(target), 0.0, 0)   # what is planned does not matter here

    monkeypatch.setattr(JointGuidance, "_plan_to", no_way_into_near)
    start = near.copy()
    start[0] = -2.2
    plan = guidance.plan(start, JointTarget(tuple(near), 0.05), [wall])
    assert len(tried) == 2 and np.linalg.norm(tried[1] - near) <= guidance.settings.goal_region * 0.05 + 1e-12
    np.testing.assert_array_equal(plan.goal, tried[1])
    assert plan.goal_moved   # the metrics say the goal was reached within its tolerance
    tried.clear()
    far = near.copy()
    far[0] -= 0.3
    assert not guidance.plan(start, JointTarget(tuple(far), 0.05), [wall]).goal_moved
    with pytest.raises(GuidanceError):
        guidance.plan(start, JointTarget(tuple(near)), [wall])


def test_a_nearby_target_keeps_the_meshes_floor_where_the_exact_pose_is_nearer(blocked) -> None:
    """A block 1.5 mm under the hand's meshes at ABOVE: every exact solution is nearer than
    ``mesh_goal_floor`` (2 mm), so searches 1-3 find none; a nearby target inside half of a
    3 mm tolerance lifts the hand past the floor (search 4 accepts the floor, as search 3
    does), where none can reach ``mesh_margin`` (3 mm)."""
    panda, block, exact = blocked
    guidance = JointGuidance(panda)
    meshes = None
    low, high = block.placement.position[2] - 0.05, block.placement.position[2]
    for _ in range(40):   # the block's height for 1 mm under the hand's meshes
        middle = 0.5 * (low + high)
        placed = PlacedObstacle(block.shape, Placement((*block.placement.position[:2], middle)))
        guidance.set_obstacles([placed])
        meshes = guidance._meshes()
        low, high = (middle, high) if meshes.clearance(ABOVE)[0] > 0.0015 else (low, middle)
    goal = [replace(t, tolerance=0.003) if isinstance(t, PointTarget) else t for t in exact]
    solution, moved = guidance.goal_solution(goal, START)
    assert moved and meshes.clearance(solution)[0] >= guidance.settings.mesh_goal_floor
    strict = JointGuidance(panda, replace(GuidanceSettings(), mesh_goal_floor=guidance.settings.mesh_margin))
    strict.set_obstacles([placed])
    with pytest.raises(GuidanceError) as refused:
        strict.goal_solution(goal, START)
    assert refused.value.reason == "no_ik_solution"
