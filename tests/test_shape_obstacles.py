"""Shape obstacle leaves in the fabric: the leaf map's derivatives, the parameter slots,
the instruction budget and the behaviour of a planner with box and plane slots."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.leaves.shape_obstacle import ShapeObstacleAvoidance
from dynfab.fabric.parameters import SHAPE_DIMENSIONS, ParameterError, ParameterLayout, ShapeSlots
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.geometry.distance import placed_distance
from dynfab.geometry.shapes import Box, Capsule, Cylinder, Placement, Plane, quaternion_from_rpy
from dynfab.robots import load_robot
from dynfab.robots.builtin import panda_robot

RNG = np.random.default_rng(3)
DIMENSIONS = {"box": [0.3, 0.2, 0.4], "cylinder": [0.1, 0.3], "capsule": [0.08, 0.25], "plane": []}
GEOMETRY = {"box": Box((0.3, 0.2, 0.4)), "cylinder": Cylinder(0.1, 0.3), "capsule": Capsule(0.08, 0.25),
            "plane": Plane()}
SPHERE_RADIUS = 0.05


def _leaf_map(kind: str, dims: int) -> tuple[ca.Function, np.ndarray, Placement]:
    """``(p_rel, ṗ_rel, slot parameters) ↦ (x, J, J̇ṗ)`` of a one-slot layout, and the slot values."""
    layout = ParameterLayout((), 0, shape_slots=ShapeSlots(**{kind: 1}))
    symbols = layout.symbols()
    relative, velocity = ca.SX.sym("r", dims), ca.SX.sym("v", dims)
    dmap = ShapeObstacleAvoidance().clearance_map(relative, velocity, symbols.shapes[0], SPHERE_RADIUS)
    function = ca.Function("map", [relative, velocity, symbols.vector], [dmap.phi, dmap.jacobian, dmap.jdot_qdot])
    placement = Placement((0.0, 0.0, 0.0), quaternion_from_rpy(RNG.uniform(-np.pi, np.pi, 3)))
    buffer = np.zeros(layout.size)
    views = layout.views(buffer).shape_views(kind)
    views.orientation[0] = placement.orientation
    views.dimensions[0] = DIMENSIONS[kind]
    return function, buffer, placement


@pytest.mark.parametrize("dims", [3, 2])
@pytest.mark.parametrize("kind", list(SHAPE_DIMENSIONS))
def test_leaf_map_value_jacobian_and_curvature(kind: str, dims: int) -> None:
    function, parameters, placement = _leaf_map(kind, dims)
    h = 1e-6
    checked = 0
    while checked < 20:
        p = RNG.uniform(-0.6, 0.6, dims)
        lifted = np.concatenate([p, np.zeros(3 - dims)])
        exact = float(placed_distance(GEOMETRY[kind], placement, lifted[None])[0]) - SPHERE_RADIUS
        if exact < 0.02:
            continue  # the barrier lives outside; inside, the smoothed depth saturates by design
        checked += 1
        v = RNG.normal(size=dims)
        x, jacobian, curvature = (np.array(value, dtype=float).ravel() for value in function(p, v, parameters))
        assert exact - 0.01 <= x[0] <= exact + 1e-9
        fd_jacobian = [(float(function(p + h * e, v, parameters)[0]) - float(function(p - h * e, v, parameters)[0]))
                       / (2 * h) for e in np.eye(dims)]
        np.testing.assert_allclose(jacobian.ravel(), fd_jacobian, atol=1e-6)
        forward = np.array(function(p + h * v, v, parameters)[1]).ravel() @ v
        backward = np.array(function(p - h * v, v, parameters)[1]).ravel() @ v
        assert curvature[0] == pytest.approx((forward - backward) / (2 * h), abs=1e-4, rel=1e-4)


@pytest.mark.parametrize("kind", list(SHAPE_DIMENSIONS))
def test_an_allowance_adds_to_the_clearance_and_leaves_its_derivatives(kind: str) -> None:
    function, parameters, _ = _leaf_map(kind, 3)
    allowed = parameters.copy()
    ParameterLayout((), 0, shape_slots=ShapeSlots(**{kind: 1})).views(allowed).shape_views(kind).allowance[0] = 0.012
    for _ in range(10):
        p, v = RNG.uniform(-0.6, 0.6, 3), RNG.normal(size=3)
        plain = [np.array(value, dtype=float).ravel() for value in function(p, v, parameters)]
        shifted = [np.array(value, dtype=float).ravel() for value in function(p, v, allowed)]
        assert shifted[0][0] == pytest.approx(plain[0][0] + 0.012, abs=1e-12)
        np.testing.assert_allclose(shifted[1], plain[1], atol=1e-12)
        np.testing.assert_allclose(shifted[2], plain[2], atol=1e-12)


def test_layout_keeps_sphere_offsets_and_views_match_symbols() -> None:
    plain = ParameterLayout((3, 2), 2, dynamic=True)
    slots = ShapeSlots(box=2, cylinder=1, capsule=1, plane=2)
    layout = ParameterLayout((3, 2), 2, dynamic=True, shape_slots=slots)
    per_slot = {kind: 9 + 4 + n + 1 for kind, n in SHAPE_DIMENSIONS.items()}   # origin, quaternion, sizes, allowance
    assert layout.size == plain.size + sum(per_slot[kind] * slots.count(kind) for kind in SHAPE_DIMENSIONS)
    buffer = RNG.normal(size=layout.size)
    views = layout.views(buffer)
    np.testing.assert_array_equal(views.obstacle_radius, plain.views(buffer[:plain.size].copy()).obstacle_radius)
    symbols = layout.symbols()
    outputs = []
    for slot in symbols.shapes:
        outputs += [slot.reference.position, slot.reference.velocity, slot.reference.acceleration,
                    slot.orientation, slot.dimensions, slot.allowance]
    values = [np.array(v).ravel() for v in ca.Function("f", [symbols.vector], outputs)(buffer)]
    expected = []
    for kind in SHAPE_DIMENSIONS:
        group = views.shape_views(kind)
        assert group.position.shape == (slots.count(kind), 3)
        for row in range(slots.count(kind)):
            expected += [group.position[row], group.velocity[row], group.acceleration[row], group.orientation[row],
                         group.dimensions[row], group.allowance[row:row + 1]]
    assert len(values) == len(expected)
    for value, view in zip(values, expected):
        np.testing.assert_array_equal(value, view)
    views.boxes.position[1] = [7.0, 8.0, 9.0]
    assert np.count_nonzero(buffer == 8.0) == 1


def test_static_layout_has_no_shape_velocities() -> None:
    views = ParameterLayout((3,), 0, shape_slots=ShapeSlots(plane=1)).views(np.zeros(3 + 1 + 3 + 4 + 1))
    assert not views.planes.velocity and views.planes.dimensions.shape == (1, 0)
    with pytest.raises(ParameterError, match=r"planes.velocity: .*dynamic=True"):
        views.planes.velocity[0] = [0.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="ShapeSlots.box"):
        ShapeSlots(box=-1)


@pytest.fixture(scope="module")
def panda():  # noqa: ANN201 - a Robot
    return load_robot("panda")


@pytest.mark.parametrize("dynamic", [False, True])
def test_a_box_slot_costs_at_most_three_sphere_slots(panda, dynamic: bool) -> None:  # noqa: ANN001
    goals = (GoalConfig(link="panda_hand"),)

    def instructions(**slots: object) -> int:
        return FabricPlanner(panda, PlannerConfig(goals=goals, dynamic=dynamic, **slots)).n_instructions

    base = instructions()
    sphere = instructions(obstacle_slots=1) - base
    for kind in SHAPE_DIMENSIONS:
        cost = instructions(shape_slots=ShapeSlots(**{kind: 1})) - base
        assert 0 < cost <= 3 * sphere, (kind, cost, sphere)
    # a further slot, once the robot's spheres are pulled anyway: a box still costs <= 3 spheres
    scene = instructions(obstacle_slots=5)
    further_sphere = instructions(obstacle_slots=6) - scene
    further_box = instructions(obstacle_slots=5, shape_slots=ShapeSlots(box=1)) - scene
    assert 0 < further_box <= 3 * further_sphere, (further_box, further_sphere)


Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])


def test_inactive_slots_change_nothing_and_an_active_box_pushes(panda) -> None:  # noqa: ANN001
    goals = (GoalConfig(link="panda_hand"),)
    plain = FabricPlanner(panda, PlannerConfig(goals=goals))
    slots = FabricPlanner(panda, PlannerConfig(goals=goals, shape_slots=ShapeSlots(box=1, cylinder=1, capsule=1,
                                                                                         plane=1)))
    for planner in (plain, slots):
        planner.parameters.goal_position[0][:] = [0.5, 0.0, 0.4]
    qdot = RNG.normal(scale=0.3, size=7)
    np.testing.assert_allclose(slots.compute(Q0, qdot), plain.compute(Q0, qdot), atol=1e-10)
    hand = np.array(panda.kinematics.position(Q0, "panda_hand")).ravel()
    boxes = slots.parameters.boxes
    boxes.position[0] = hand + [0.0, 0.0, -0.2]          # a box just below the hand
    boxes.orientation[0] = [1.0, 0.0, 0.0, 0.0]
    boxes.dimensions[0] = [0.3, 0.3, 0.2]
    down = np.linalg.pinv(_hand_jacobian(panda)) @ [0.0, 0.0, -0.3]  # the hand moves down onto the box
    free, avoiding = plain.compute(Q0, down), slots.compute(Q0, down)
    upward = (_hand_jacobian(panda) @ (avoiding - free))[2]
    assert upward > 0.5, "the box leaf decelerates the hand's descent"


def _hand_jacobian(panda) -> np.ndarray:  # noqa: ANN001
    q = ca.SX.sym("q", 7)
    return np.array(ca.Function("j", [q], [ca.jacobian(panda.kinematics.position(q, "panda_hand"), q)])(Q0))


def test_dynamic_box_moving_at_the_arm_pushes_it_at_rest() -> None:
    panda = panda_robot("hand-written")   # a hand without open fingers, which would reach into the box's range
    goals = (GoalConfig(link="panda_hand"),)
    planner = FabricPlanner(panda, PlannerConfig(goals=goals, dynamic=True, shape_slots=ShapeSlots(box=1)))
    hand = np.array(panda.kinematics.position(Q0, "panda_hand")).ravel()
    params = planner.parameters
    params.goal_position[0][:] = hand
    boxes = params.boxes
    boxes.position[0] = hand + [0.0, -0.25, 0.0]
    boxes.orientation[0] = [1.0, 0.0, 0.0, 0.0]
    boxes.dimensions[0] = [0.2, 0.2, 0.2]
    at_rest = planner.compute(Q0, np.zeros(7))
    boxes.velocity[0] = [0.0, 0.5, 0.0]  # coming at the hand
    pushed = planner.compute(Q0, np.zeros(7))
    assert np.linalg.norm(at_rest) < 1e-6
    assert (_hand_jacobian(panda) @ pushed)[1] > 0.1, "the hand accelerates away along the box's velocity"
