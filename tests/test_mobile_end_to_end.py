"""Mobile robots end to end: the differential-drive Boxer (``boxer``) and the Panda on a
Boxer (``boxer-panda``) in closed loop, through ``run_scenario`` and the CLI.

Every run is a real simulation of the fabric planner with the runner's differential-drive
model (arcs, ``runner.BASE_SUBSTEPS`` sub-steps per control period). The success levels
asserted on seeds 0..9 are the measured levels of the current planner (static fabrics,
non-holonomic least-squares root with look-ahead steering), on this machine:

- Experiment 4 (``exp4.scenario``, Boxer among 5 discs): 45/50 seeds 0..49 succeed
  (90 %), no collision; seeds 0..9: 10/10. The failures are deadlocks against a disc
  (see ``test_experiment4_boxer_reaches_its_goal_without_collision``).
- Experiment 5 (``exp5.scenario``, mobile manipulator among 8 spheres): 49/50 seeds 0..49
  (98 %), no collision; seeds 0..9: 10/10.

The tests ask for at least 8/10 and 9/10 so that a single extra deadlock does not fail
them, and for no collision at all. (The plain least-squares root of the paper, with the
0.2 m obstacle range, measured 41/50 on Experiment 4 with 42/50 goals reached and two
creeping collisions of at most 1 cm, seeds 15 and 42, and 48/50 on Experiment 5.)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest
import yaml

from dynfab.scenario import runner
from dynfab.cli import main
from dynfab.scenario.controllers import FabricController, make_controller
from dynfab.experiments import exp4, exp5
from dynfab.mpc import MpcController
from dynfab.scenario.references import scenario_references
from dynfab.robots import load_robot
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import scenario_from_dict, validate_for_robot

SEEDS = range(10)
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
ARM_Q0 = [1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0]


def run(data: dict[str, Any]) -> RunResult:
    """Run a scenario mapping as the paper would (no stall recovery); the runner must have
    built a fabric controller."""
    result = run_scenario(scenario_from_dict({**data, "recovery": False}))
    assert isinstance(result.controller, FabricController)
    return result


def lateral_and_forward(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per recorded step, the base's displacement across and along the mean heading
    ``mid = (θ_k + θ_{k+1}) / 2``: ``−dx sin(mid) + dy cos(mid)`` and
    ``dx cos(mid) + dy sin(mid)`` [m]."""
    dx, dy = np.diff(q[:, 0]), np.diff(q[:, 1])
    mid = 0.5 * (q[1:, 2] + q[:-1, 2])
    return -dx * np.sin(mid) + dy * np.cos(mid), dx * np.cos(mid) + dy * np.sin(mid)


# -- (a), (b): the paper's Experiments 4 and 5 on seeded scenarios -----------------------


def test_experiment4_boxer_reaches_its_goal_without_collision() -> None:
    """Seeds 0..9 of Experiment 4: no collision on any, at least 8 reach the goal.

    Measured: 10/10 here, 45/50 on seeds 0..49 (no collision). The failures are deadlocks.
    Seed 15: the base stops for good at (-0.68, 1.46) heading -165 deg, 2.15 m short of
    the goal, with its front-right body disc 6 mm from the disc at (-1.69, 1.21) (radius
    0.46 m), which lies dead ahead (1 deg) with the goal 11.5 deg to the left behind it.
    Forward is blocked by the barrier; turning left on the spot swings that front disc
    (0.4 m ahead of the axle) forward-left, into the obstacle; turning right or backing up
    climbs the goal potential. The least-squares root has no sideways acceleration to
    offer, so v and omega settle at zero (a holonomic base would slide along the disc).
    Seeds 21, 34 and 44 are the same picture (disc within 1.5 deg of the heading, goal 8-16
    deg off it); seed 43 is pinned with a disc on its right flank.
    """
    reached = []
    for seed in SEEDS:
        result = run(exp4.scenario(seed))
        metrics = result.metrics
        assert not metrics.collision, f"exp4 seed {seed}: collision, {metrics}"
        assert metrics.clearance is not None and metrics.clearance > 0.0
        assert np.isfinite(result.record.qddot).all()
        assert result.controller.planner.fallback_count == 0, f"exp4 seed {seed}: non-finite fabric output"
        assert result.record.qdot.shape[1] == 2
        if metrics.success:
            goal = np.array(result.scenario.goals[0].position)
            assert np.linalg.norm(result.goal_positions[-1] - goal) < result.scenario.goals[0].tolerance
        reached.append(metrics.success)
    assert sum(reached) >= 8, f"exp4: {sum(reached)}/10 succeeded (failed seeds {[s for s in SEEDS if not reached[s]]})"


def test_experiment5_mobile_manipulator_reaches_its_goal_without_collision() -> None:
    """Seeds 0..9 of Experiment 5: no collision, at least 9 succeed (measured 10/10; 49/50
    on seeds 0..49)."""
    reached = []
    for seed in SEEDS:
        result = run(exp5.scenario(seed))
        metrics = result.metrics
        assert not metrics.collision, f"exp5 seed {seed}: collision, {metrics}"
        assert metrics.clearance is not None and metrics.clearance > 0.0
        assert np.isfinite(result.record.qddot).all()
        assert result.controller.planner.fallback_count == 0, f"exp5 seed {seed}: non-finite fabric output"
        assert result.record.qdot.shape[1] == 9
        reached.append(metrics.success)
    assert sum(reached) >= 9, f"exp5: {sum(reached)}/10 succeeded (failed seeds {[s for s in SEEDS if not reached[s]]})"


# -- (c): the base rolls, it never slides sideways ---------------------------------------


def test_base_never_slides_sideways_along_a_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """With one integration sub-step per control period every recorded step is one arc
    of the differential-drive model: its chord lies along the mean heading, so the
    displacement across it is zero (to rounding), while the base drives and turns."""
    monkeypatch.setattr(runner, "BASE_SUBSTEPS", 1)
    result = run(exp4.scenario(1))
    q, qdot = result.record.q, result.record.qdot
    assert qdot.shape == (q.shape[0], 2), "a Boxer run records (v, omega)"
    lateral, forward = lateral_and_forward(q)
    assert np.abs(lateral).max() <= 1e-12
    # not vacuous: the base covered metres, turned, and drove forward and (or) backward
    assert np.abs(forward).sum() > 2.0
    assert np.abs(np.diff(q[:, 2])).sum() > 0.5
    # the forward displacement is the one of the mid-step speed (v + v̇ dt/2) dt
    dt = result.scenario.dt
    expected = (qdot[:-1, 0] + 0.5 * result.record.qddot[:, 0] * dt) * dt
    assert np.abs(forward - expected).max() < 1e-6


def test_base_rolls_along_arcs_with_the_default_substeps() -> None:
    """With the runner's ``BASE_SUBSTEPS`` arcs per control period the turn rate changes
    between sub-steps (ω̇ is held), so a whole step's chord leaves the mean heading by
    exactly what rolling on a curve of changing curvature gives,
    ``(v̇ ω − v ω̇)(dt³ − dt h²)/12`` for sub-steps of length ``h`` (zero for ``h = dt``),
    and by nothing else: no slip."""
    data = exp4.scenario(1)
    result = run(data)
    record = result.record
    dt = data["dt"]
    h = dt / runner.BASE_SUBSTEPS
    v, omega = record.qdot[:-1, 0], record.qdot[:-1, 1]
    v_dot, omega_dot = record.qddot[:, 0], record.qddot[:, 1]
    rolling = (v_dot * omega - v * omega_dot) * (dt**3 - dt * h * h) / 12
    lateral, _ = lateral_and_forward(record.q)
    assert np.abs(rolling).max() > 1e-8, "the run should turn with a changing rate"
    assert np.abs(lateral - rolling).max() <= 1e-10


# -- (d): the mobile manipulator's planner at arbitrary states ---------------------------


@pytest.fixture(scope="module")
def boxer_panda_controller() -> FabricController:
    """The controller the runner builds for a boxer-panda scenario with 4 obstacle slots."""
    data = {
        "robot": "boxer-panda",
        "planner": "static-fabric",
        "dt": 0.01,
        "duration": 1.0,
        "initial_state": {"q": [0.0, 0.0, 0.0, *ARM_Q0]},
        "goal": [{"type": "position", "link": "panda_hand", "position": [2.0, 0.5, 0.7], "tolerance": 0.05}],
        "obstacles": [{"type": "sphere", "position": [3.0, 3.0, 0.5], "radius": 0.3} for _ in range(4)],
    }
    robot = load_robot("boxer-panda")
    scenario = validate_for_robot(scenario_from_dict(data), robot)
    controller = make_controller(scenario, robot, scenario_references(scenario, robot))
    assert isinstance(controller, FabricController)
    return controller


def test_boxer_panda_planner_is_finite_at_random_states(boxer_panda_controller: FabricController) -> None:
    planner = boxer_panda_controller.planner
    robot = planner.robot
    kin = robot.kinematics
    lower = np.where(np.isfinite(kin.lower), kin.lower, -np.pi)
    upper = np.where(np.isfinite(kin.upper), kin.upper, np.pi)
    rng = np.random.default_rng(7)
    for trial in range(200):
        q = rng.uniform(lower, upper)
        q[:2] = rng.uniform(-3.0, 3.0, 2)
        velocity = np.zeros(9) if trial % 4 == 0 else rng.normal(0.0, 1.0, 9)
        centres = np.asarray(robot.sphere_centers(q))
        if trial % 2 == 0:  # obstacles overlapping the base's body spheres, one exactly centred
            chosen = rng.choice(6, size=4, replace=False)
            positions = centres[chosen] + rng.normal(0.0, 0.1, (4, 3))
            positions[0] = centres[chosen[0]]
        else:  # anywhere near the robot
            positions = q[None, :3] * [1, 1, 0] + rng.uniform([-1.5, -1.5, 0.0], [1.5, 1.5, 1.3], (4, 3))
        planner.parameters.obstacle_position[:] = positions
        planner.parameters.obstacle_radius[:] = rng.uniform(0.1, 0.5, 4)
        planner.parameters.goal_position[0][:] = q[:3] * [1, 1, 0] + rng.uniform([-3, -3, 0.2], [3, 3, 1.2])
        acceleration = planner.compute(q, velocity)
        assert acceleration.shape == (9,), f"trial {trial}: expected (v̇, ω̇, 7 arm accelerations)"
        assert np.isfinite(acceleration).all(), f"trial {trial}: q={q}, qdot={velocity}"
    assert planner.fallback_count == 0, "the fabric itself produced a non-finite value"


def test_boxer_panda_planner_rejects_configuration_sized_velocity(
        boxer_panda_controller: FabricController) -> None:
    planner = boxer_panda_controller.planner
    q = np.array([0.0, 0.0, 0.0, *ARM_Q0])
    with pytest.raises(ValueError, match="qdot"):
        planner.compute(q, np.zeros(10))
    with pytest.raises(ValueError, match="qdot"):
        planner.compute(q, np.zeros(8))
    with pytest.raises(ValueError, match=r"\bq\b"):
        planner.compute(q[:9], np.zeros(9))
    with pytest.raises(ValueError, match="qdot"):
        planner.compute(q, np.full(9, np.nan))


# -- (e): dynamic fabrics follow a path with the base ------------------------------------


def boxer_circle(planner: str) -> dict[str, Any]:
    """base_link on a circle of radius 1.5 m at 0.45 m/s, starting on it at rest and
    heading along it (base_link is 0.1503 m ahead of the axle), a disc just outside."""
    return {
        "robot": "boxer",
        "planner": planner,
        "dt": 0.01,
        "duration": 12.0,
        "initial_state": {"q": [1.5, -0.1503, np.pi / 2]},
        "goal": [{"type": "path", "link": "base_link", "tolerance": 0.1,
                  "trajectory": {"type": "circle", "center": [0.0, 0.0], "radius": 1.5, "angular_velocity": 0.3}}],
        "obstacles": [{"type": "sphere", "position": [0.0, 2.4], "radius": 0.3}],
    }


def test_dynamic_fabric_boxer_follows_a_circle() -> None:
    """Measured: summed error DF 0.0079 m, SF 0.0425 m (ratio 0.19); the DF error is
    largest (0.019 m) where the disc's barrier pushes the base inward. Bounds: DF below
    0.02 m (2.5x margin, 5x below the 0.1 m tolerance) and below half the SF error."""
    dynamic = run(boxer_circle("dynamic-fabric"))
    static = run(boxer_circle("static-fabric"))
    metrics = dynamic.metrics
    assert metrics.success and not metrics.collision, str(metrics)
    assert metrics.time_to_goal is not None and metrics.time_to_goal < 1.0
    assert metrics.summed_error is not None and metrics.summed_error < 0.02, str(metrics)
    assert static.metrics.summed_error is not None
    assert metrics.summed_error < 0.5 * static.metrics.summed_error, (metrics, static.metrics)
    error = np.linalg.norm(dynamic.goal_positions - dynamic.goal_reference, axis=1)
    assert error[dynamic.record.t > 2.0].max() < 0.05
    # the reference moves at 0.45 m/s: the base drives at that speed, forward
    v = dynamic.record.qdot[dynamic.record.t > 4.0, 0]
    assert np.all(np.abs(v - 0.45) < 0.05), (v.min(), v.max())
    assert dynamic.controller.planner.fallback_count == 0


def test_dynamic_fabric_boxer_follows_a_spline() -> None:
    """A spline from rest to rest through 4 waypoints in 10 s. Measured summed error
    0.0065 m (SF 0.0368 m); bound 0.02 m."""
    data = {
        "robot": "boxer",
        "planner": "dynamic-fabric",
        "dt": 0.01,
        "duration": 12.0,
        "initial_state": {"q": [0.0, 0.0, 0.0]},
        "goal": [{"type": "path", "link": "base_link", "tolerance": 0.1,
                  "trajectory": {"type": "spline", "waypoints": [[0.1503, 0.0], [1.5, 0.6], [2.5, -0.4], [3.5, 0.5]],
                                 "duration": 10.0}}],
    }
    result = run(data)
    metrics = result.metrics
    assert metrics.success, str(metrics)
    assert metrics.summed_error is not None and metrics.summed_error < 0.02, str(metrics)
    assert np.linalg.norm(result.goal_positions[-1] - [3.5, 0.5]) < 0.01


# -- regression: dynamic fabrics on the mobile manipulator with a crossing sphere ---------


@pytest.mark.parametrize(("start", "speed"), [((2.2, -3.0, 0.4), 0.5), ((1.2, -1.5, 0.4), 0.8)])
def test_dynamic_fabric_mobile_manipulator_gives_way_to_a_crossing_sphere(
        start: tuple[float, float, float], speed: float) -> None:
    """A sphere crosses the robot's way while it reaches (or rests at) its hand goal. An
    earlier planner (without look-ahead steering, 0.2 m obstacle range) let the velocities
    of these two runs grow without bound (|u| ~ 1e186, finite, so no fallback) once the
    sphere came within the barrier's range of the idle base from the side; both now stay
    below 5 (measured max |u| 2.6 and 2.5)."""
    data = {
        "robot": "boxer-panda",
        "planner": "dynamic-fabric",
        "dt": 0.01,
        "duration": 8.0,
        "initial_state": {"q": [0.0, 0.0, 0.0, *ARM_Q0]},
        "goal": [{"type": "position", "link": "panda_hand", "position": [3.0, 0.5, 0.7], "tolerance": 0.05}],
        "obstacles": [{"type": "sphere", "radius": 0.3,
                       "trajectory": {"type": "linear", "start": list(start), "velocity": [0.0, speed, 0.0]}}],
    }
    result = run(data)
    assert not result.metrics.collision, str(result.metrics)
    assert result.metrics.success, str(result.metrics)
    assert np.abs(result.record.qdot).max() < 10.0
    assert np.abs(result.record.q[:, :2]).max() < 5.0, "the base stays in the room"


# -- (f): the MPC baseline on the non-holonomic base -------------------------------------


def test_mpc_drives_the_boxer_past_a_disc_to_its_goal() -> None:
    """``planner: mpc`` on the Boxer (unicycle model over (x, y, θ) with inputs (v̇, ω̇),
    ``dynfab.mpc.model``): the goal lies 3.5 m ahead behind a disc of radius 0.4 m that
    covers the straight line. Measured with Clearpath-derived acceleration limits (5 m/s²,
    5 rad/s²): reached at 4.78 s after swerving right (the axle passes the disc at
    y = −1.07 m, 0.77 m from its centre; with 10 m/s² it swerved left, 0.77 m too),
    clearance −0.81 mm: the constraints hold at the 10 Hz stage times (+0.52 mm) and the
    footprint grazes the disc between them, as the benchmark's discrete-time formulation
    allows; the bound is −1 mm."""
    disc = {"type": "sphere", "position": [1.8, -0.3], "radius": 0.4}
    data = {"robot": "boxer", "planner": "mpc", "dt": 0.01, "duration": 6.0, "initial_state": {"q": [0.0, 0.0, 0.0]},
            "goal": [{"type": "position", "link": "base_link", "position": [3.5, 0.3], "tolerance": 0.1}],
            "obstacles": [disc]}
    result = run_scenario(scenario_from_dict(data))
    assert isinstance(result.controller, MpcController)
    metrics = result.metrics
    assert metrics.goal_reached and metrics.time_to_goal is not None and metrics.time_to_goal < 5.5, str(metrics)
    assert np.linalg.norm(result.goal_positions[-1] - [3.5, 0.3]) < 0.1
    assert metrics.clearance is not None and metrics.clearance >= -1e-3, str(metrics)
    assert result.clearance[::10].min() >= -1e-4, "the constraints hold at the stage times"
    q, u = result.record.q, result.record.qdot
    assert u.shape == (q.shape[0], 2), "the MPC commands (v̇, ω̇) and sees (v, ω)"
    passing = np.argmin(np.abs(q[:, 0] - 1.8))
    assert abs(q[passing, 1] + 0.3) > 0.6 and np.abs(q[:, 2]).max() > 0.2, "the base swerved around the disc"
    assert result.controller.failures == 0
    assert np.abs(u[:, 0]).max() <= 1.9 + 1e-6 and np.abs(u[:, 1]).max() <= 2.0 + 1e-6


@pytest.mark.parametrize(("example", "robot"), [("boxer_spheres.yaml", "boxer"), ("boxer_panda_room.yaml", "boxer-panda")])
def test_cli_planner_mpc_override_on_a_mobile_robot_reaches_the_goal(
        example: str, robot: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``dynfab run EXAMPLE --planner mpc`` on both mobile robots prints one JSON object.
    Measured: boxer_spheres goal at 4.37 s, clearance −5.2 mm, solve 12 ms;
    boxer_panda_room goal at 3.38 s, clearance −3.0 mm, solve 79 ms. The negative
    clearances are grazes between the 10 Hz stage times (up to (s h)² / (8 R) for a
    sphere moving at s = 2.1 m/s past R = 0.49 m, 11 mm), so ``success`` is false by
    the metric's ``clearance < 0`` and only the goal and the graze bound are asserted. The
    runs last 4.5 s (the files say 10 s and 15 s): the goal is reached before, and an MPC step
    of the mobile manipulator costs 0.1-1 s of test time."""
    scenario = yaml.safe_load((EXAMPLES / example).read_text(encoding="utf-8"))
    assert scenario["robot"] == robot
    shortened = tmp_path / example
    shortened.write_text(yaml.safe_dump({**scenario, "duration": 4.5}), encoding="utf-8")
    code = main(["run", str(shortened), "--planner", "mpc", "--json"])
    out, _ = capsys.readouterr()
    metrics = json.loads(out)
    assert code == (0 if metrics["success"] else 1)
    assert metrics["goal_reached"], metrics
    assert metrics["clearance"] > -0.011, metrics
    assert metrics["solver_time_ms"] > 0.0   # boxer-panda: 81 robot spheres since the Panda's hand


# -- the base-goal example reaches both of its sub-goals ---------------------------------


def test_base_goal_example_reaches_base_and_hand_goals() -> None:
    """``examples/boxer_panda_base_goal.yaml``: the primary goal is base_link on x, y, the
    secondary (weight 0.5) the hand in 3-D; both end within 1 mm, as the example says."""
    data = yaml.safe_load((EXAMPLES / "boxer_panda_base_goal.yaml").read_text(encoding="utf-8"))
    result = run(data)
    assert result.metrics.success, str(result.metrics)
    base_goal, hand_goal = result.scenario.goals
    assert (base_goal.link, base_goal.axes) == ("base_link", "xy")
    assert result.goal_positions.shape[1] == 2
    assert np.linalg.norm(result.goal_positions[-1] - base_goal.position) < 1e-3
    kinematics = result.robot.kinematics
    q = ca.SX.sym("q", kinematics.dof)
    hand_position = ca.Function("hand", [q], [kinematics.position(q, "panda_hand")])
    final = np.array(hand_position(result.record.q[-1])).ravel()
    assert np.linalg.norm(final - np.array(hand_goal.position)) < 1e-3
