"""Every scenario file under ``examples/`` loads, runs and succeeds."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import UrdfRobotSpec, load_scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FILES = sorted(EXAMPLES.glob("**/*.yaml"))


def test_examples_are_present() -> None:
    names = {path.relative_to(EXAMPLES).as_posix() for path in FILES}
    assert {"panda_reach.yaml", "panda_spheres.yaml", "panda_joint_goal.yaml", "panda_multi_goal.yaml",
            "point_spheres.yaml", "custom_urdf/arm_spheres.yaml", "panda_table_box.yaml",
            "panda_moving_box.yaml", "panda_pose_down.yaml", "panda_path_tool_down.yaml",
            "ur5_table_pose.yaml"} <= names


@pytest.mark.parametrize("path", FILES, ids=lambda path: path.relative_to(EXAMPLES).as_posix())
def test_example_runs_and_succeeds(path: Path) -> None:
    assert path.read_text(encoding="utf-8").startswith("#"), "an example starts with a comment saying what it shows"
    result = run_scenario(load_scenario(path))
    assert result.metrics.success, f"{path.name}: {result.metrics}"


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
