"""The built-in Panda's hand and fingers: the opening a scenario sets, Franka's frames,
mesh metrics on Franka's meshes, and a start state the meshes find free."""

from __future__ import annotations

import numpy as np
import pytest

from dynfab.geometry.shapes import Placement, Sphere
from dynfab.robots import load_robot
from dynfab.robots.franka import DYNFAB_LINKS, franka_kinematics
from dynfab.robots.mesh_sweep import PlacedShape, sweep_meshes
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.schema import BuiltinRobotSpec, ScenarioError, scenario_from_dict
from dynfab.scenario.start_state import check_start_collisions

Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])


@pytest.mark.parametrize("fingers", [0.0, 0.013, 0.04])
def test_frames_are_frankas_at_every_opening(fingers: float) -> None:
    panda, franka = load_robot("panda", fingers=fingers), franka_kinematics(fingers)
    pairs = [(dynfab, franka_link) for franka_link, dynfab in DYNFAB_LINKS.items()] + [("panda_hand", "panda_hand_tcp")]
    for q in [Q0, *np.random.default_rng(3).uniform(panda.kinematics.lower, panda.kinematics.upper, (5, 7))]:
        for ours, theirs in pairs:
            np.testing.assert_allclose(np.array(panda.kinematics.transform(q, ours)),
                                       np.array(franka.transform(q, theirs)), atol=1e-12)
    assert panda.dof == 7 and panda.goal_link == "panda_hand"


def test_finger_spheres_move_with_the_opening_and_the_rest_stays() -> None:
    open_hand, closed = load_robot("panda"), load_robot("panda", fingers=0.0)
    moved = np.linalg.norm(open_hand.sphere_centers(Q0) - closed.sphere_centers(Q0), axis=1)
    fingers = np.array([s.link in ("panda_leftfinger", "panda_rightfinger") for s in open_hand.collision_spheres])
    np.testing.assert_allclose(moved[fingers], 0.04, atol=1e-12)
    np.testing.assert_allclose(moved[~fingers], 0.0, atol=1e-12)
    assert load_robot("boxer-panda", fingers=0.0).dof == 10


def test_fingers_outside_frankas_limits_or_without_a_hand_are_refused() -> None:
    with pytest.raises(ValueError, match="fingers.*0 ... 0.04"):
        load_robot("panda", fingers=0.05)
    with pytest.raises(ValueError, match="fingers: the point has no fingers"):
        load_robot("point", fingers=0.01)


def _scenario(robot: object) -> dict:
    return {"robot": robot, "planner": "static-fabric", "dt": 0.01, "duration": 1.0,
            "initial_state": {"q": Q0.tolist()},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.5, -0.4, 0.3]}]}


def test_scenario_sets_the_opening_and_names_robot_fingers_when_wrong() -> None:
    assert scenario_from_dict(_scenario({"name": "panda", "fingers": 0.02})).robot == BuiltinRobotSpec("panda", 0.02)
    assert scenario_from_dict(_scenario("panda")).robot == "panda"
    for robot, message in (({"name": "panda", "fingers": 0.041}, "robot.fingers: must be at most 0.04 m"),
                           ({"name": "panda", "fingers": -0.01}, "robot.fingers: must be >= 0 m"),
                           ({"name": "boxer", "fingers": 0.01}, "robot.fingers: the boxer has no fingers")):
        with pytest.raises(ScenarioError) as error:
            scenario_from_dict(_scenario(robot))
        assert str(error.value).startswith(message) and "\n" not in str(error.value), str(error.value)


def test_builtin_arms_are_measured_on_frankas_meshes() -> None:
    panda = mesh_model_for(load_robot("panda", fingers=0.01))
    assert panda is not None and set(panda.links) == set(DYNFAB_LINKS.values())
    assert panda.kinematics.locked == {"panda_finger_joint1": 0.01}
    mobile = mesh_model_for(load_robot("boxer-panda"))
    assert mobile is not None and "chassis_link" in mobile.links
    assert mesh_model_for(load_robot("boxer")) is None  # planar: sphere metrics


def test_a_start_the_meshes_find_free_is_not_refused_by_the_spheres() -> None:
    """A ball just beside a fingertip: the finger spheres (up to 1 cm out of the meshes)
    overlap it, Franka's meshes are clear of it."""
    robot = load_robot("panda")
    model = mesh_model_for(robot)
    assert model is not None
    tip = np.array(robot.kinematics.position(Q0, "panda_leftfinger", offset=(0.0, 0.0, 0.045))).ravel()
    side = np.array(robot.kinematics.rotation(Q0, "panda_leftfinger"))[:, 1]  # away from the other finger
    for gap in np.arange(0.002, 0.02, 0.001):
        ball = PlacedShape("obstacles[0]", Sphere(0.01), (Placement(tuple(tip + (0.0152 / 2 + gap + 0.01) * side)),))
        if sweep_meshes(model, Q0[None, :], [ball]).clearance > 0.0:
            break
    with pytest.raises(ScenarioError, match="collision sphere"):
        check_start_collisions(Q0, robot, None, [ball])
    check_start_collisions(Q0, robot, model, [ball])
