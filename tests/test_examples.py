"""Every scenario file under ``examples/`` loads, runs and succeeds as its opening comment
says: an example whose comment names the fabric that does the work (static or dynamic
fabrics) runs it alone (``guidance: false`` where guidance would apply, ``recovery: false``
where stall recovery would), and its run's JSON shows that nothing else helped."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from dynfab.scenario.guided_controller import guidance_refusal
from dynfab.scenario.runner import robot_for, run_scenario
from dynfab.scenario.schema import Scenario, UrdfRobotSpec, load_scenario, validate_for_robot

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FILES = sorted(EXAMPLES.glob("**/*.yaml"))
#: the figures the examples' comments give, to 5 mm [m]
CLAIMED = {
    "panda_table_box.yaml": {"clearance": 0.04, "sphere_clearance": 0.02},
    "panda_moving_obstacles.yaml": {"clearance": 0.106},
    "panda_moving_obstacles_static.yaml": {"clearance": 0.051},
    "boxer_panda_moving_obstacle.yaml": {"clearance": 0.25, "sphere_clearance": 0.22},
}
#: an opening comment that says which fabric does the work
NAMES_A_FABRIC = re.compile(r"\b(static|dynamic)[ -]fabrics?\b", re.IGNORECASE)


def _comment(path: Path) -> str:
    """The example's opening comment."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return "\n".join(line for line in lines[:next(i for i, line in enumerate(lines) if not line.startswith("#"))])


def _helpers(scenario: Scenario) -> tuple[bool, bool]:
    """Whether global guidance and stall recovery would act on ``scenario`` (recovery:
    a static position goal, scenario/recovering_controller.py)."""
    robot = robot_for(scenario)
    guided = guidance_refusal(validate_for_robot(scenario, robot), robot) is None
    return guided, scenario.recovery and scenario.goals[0].type == "position"


def test_examples_are_present() -> None:
    names = {path.relative_to(EXAMPLES).as_posix() for path in FILES}
    assert {"panda_reach.yaml", "panda_spheres.yaml", "panda_joint_goal.yaml", "panda_multi_goal.yaml",
            "point_spheres.yaml", "custom_urdf/arm_spheres.yaml", "panda_table_box.yaml",
            "panda_moving_box.yaml", "panda_pose_down.yaml", "panda_path_tool_down.yaml",
            "ur5_table_pose.yaml"} <= names


@pytest.mark.parametrize("path", FILES, ids=lambda path: path.relative_to(EXAMPLES).as_posix())
def test_example_runs_and_succeeds_as_its_comment_says(path: Path) -> None:
    comment = _comment(path)
    assert comment, "an example starts with a comment saying what it shows"
    scenario = load_scenario(path)
    guidance, recovery = _helpers(scenario)
    if NAMES_A_FABRIC.search(comment):
        assert not guidance and not recovery, f"{path.name} says a fabric does the work: run it alone"
    metrics = run_scenario(scenario).metrics
    assert metrics.success, f"{path.name}: {metrics}"
    assert metrics.fallbacks == 0, metrics   # no braked output, no fabric taking over from guidance
    assert metrics.guided is guidance and (metrics.plans >= 1) is guidance, metrics
    if not guidance:
        assert metrics.recovered == 0, metrics   # what succeeded is the fabric
    for key, value in CLAIMED.get(path.name, {}).items():
        assert getattr(metrics, key) == pytest.approx(value, abs=0.005), (key, metrics)


def test_the_mobile_manipulator_example_gives_way_as_its_comment_says() -> None:
    """``boxer_panda_moving_obstacle.yaml``: the hand stays within 0.1 m of its goal once
    there (its clearances: CLAIMED), the base moves about 0.6 m forward and left from where
    it was then; the static fabric collides."""
    scenario = load_scenario(EXAMPLES / "boxer_panda_moving_obstacle.yaml")
    result = run_scenario(scenario)
    metrics = result.metrics
    reached = result.record.t >= metrics.time_to_goal
    assert np.linalg.norm(result.goal_positions - result.goal_reference, axis=1)[reached].max() < 0.1
    moved = result.record.q[-1, :2] - result.record.q[np.argmax(reached), :2]   # once at the goal, out of the way
    assert moved[0] > 0.0 and moved[1] > 0.0 and np.linalg.norm(moved) == pytest.approx(0.6, abs=0.1)
    static = run_scenario(dataclasses.replace(scenario, planner="static-fabric")).metrics
    assert static.collision and not static.success


def test_custom_urdf_example_uses_its_own_robot() -> None:
    scenario = load_scenario(EXAMPLES / "custom_urdf" / "arm_spheres.yaml")
    assert isinstance(scenario.robot, UrdfRobotSpec)
    assert scenario.robot.urdf == EXAMPLES / "custom_urdf" / "arm.urdf"
    result = run_scenario(scenario)
    assert result.robot.kinematics.dof == 3
    assert result.metrics.clearance is not None and result.metrics.clearance > 0.0


def test_multi_goal_example_reaches_its_secondary_goal() -> None:
    scenario = load_scenario(EXAMPLES / "panda_multi_goal.yaml")
    secondary = scenario.goals[1]
    result = run_scenario(scenario)
    kinematics = result.robot.kinematics
    q = ca.SX.sym("q", kinematics.dof)
    link7 = ca.Function("link7", [q], [kinematics.position(q, secondary.link)])
    final_xy = np.array(link7(result.record.q[-1])).ravel()[:2]
    assert np.linalg.norm(final_xy - np.array(secondary.position)) < secondary.tolerance


def test_the_api_example_with_a_shipped_urdf_reaches_its_pose() -> None:
    import re
    import subprocess
    import sys

    completed = subprocess.run([sys.executable, str(EXAMPLES / "ur5_api.py")], capture_output=True, text=True,
                               timeout=600, check=True)
    match = re.search(r"error ([0-9.]+) m; tool z tilted ([0-9.]+) deg", completed.stdout)
    assert match, completed.stdout + completed.stderr
    assert float(match.group(1)) < 0.01 and float(match.group(2)) < 2.0


def test_the_documented_scenario_reference_is_a_valid_scenario() -> None:
    """The annotated file of docs/guides/scenario-files.md ("Annotated reference") parses and
    validates (its MuJoCo-only keys with ``simulator: mujoco``)."""
    import yaml

    from dynfab.scenario.schema import scenario_from_dict

    page = Path(__file__).resolve().parents[1] / "docs" / "guides" / "scenario-files.md"
    text = page.read_text(encoding="utf-8")
    start = text.index("```yaml", text.index("## Annotated reference")) + len("```yaml")
    document = yaml.safe_load(text[start:text.index("```", start)])
    scenario = scenario_from_dict({**document, "simulator": "mujoco"})
    assert scenario.obstacles and scenario.limits.headroom == 0.05
