"""``dynfab export``: the C files compile with -Wall -Werror (under AddressSanitizer and UBSan for the
point robot, whose planner is small enough), and the exported planner computes what the Python
planner computes, field by named field."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dynfab.cli import main
from dynfab.fabric.c_backend import find_compiler
from dynfab.scenario.controllers import make_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import load_scenario, validate_for_robot

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
STRICT = "-O1 -g -Wall -Wextra -Wno-unused-parameter -Werror -fsanitize=address,undefined -fno-omit-frame-pointer"
pytestmark = pytest.mark.skipif(find_compiler() is None or shutil.which("make") is None,
                                reason="needs a C compiler and make")

#: reads cases from stdin, sets q, qdot, goal0_position and obstacle_position[0] BY NAME
#: on top of the defaults, prints status and command
CHECK_C = r"""
#include <stdio.h>
#include "NAME.h"
int main(void) {
    NAME_input input;
    double qddot[UPPER_NV];
    int i, status;
    NAME_defaults(&input);
    for (;;) {
        for (i = 0; i < UPPER_NQ; ++i) if (scanf("%lf", &input.q[i]) != 1) return 0;
        for (i = 0; i < UPPER_NV; ++i) if (scanf("%lf", &input.qdot[i]) != 1) return 1;
        for (i = 0; i < 3; ++i) if (scanf("%lf", &input.goal0_position[i]) != 1) return 1;
        for (i = 0; i < 3; ++i) if (scanf("%lf", &input.obstacle_position[0][i]) != 1) return 1;
        status = NAME_compute(&input, qddot);
        printf("%d", status);
        for (i = 0; i < UPPER_NV; ++i) printf(" %.17g", qddot[i]);
        printf("\n");
    }
}
"""


def _python_planner(path: Path):
    scenario = dataclasses.replace(load_scenario(path), backend="vm")
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    return scenario, make_controller(scenario, robot, scenario_references(scenario, robot)).planner


def _export(tmp_path: Path, scenario: str, capsys: pytest.CaptureFixture[str]) -> Path:
    out = tmp_path / "exported"
    assert main(["export", str(EXAMPLES / scenario), "--out", str(out), "--name", "planner"]) == 0
    assert "make -C" in capsys.readouterr().err
    assert {p.name for p in out.iterdir()} == {"planner.c", "planner.h", "example.c", "Makefile"}
    return out


#: -Werror without the sanitizers, at -O0: the Panda's planner is ~2 MB of C, which the
#: sanitizers take minutes to compile; the generated code is the same for every robot, and
#: the point robot's export runs under them (``STRICT``)
WARNINGS = "-O0 -Wall -Wextra -Wno-unused-parameter -Werror"


@pytest.mark.parametrize(("scenario", "flags"), [("point_spheres.yaml", STRICT),
                                                 ("panda_moving_obstacles.yaml", WARNINGS)])
def test_example_builds_strictly_runs_and_matches_python(scenario: str, flags: str, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = _export(tmp_path, scenario, capsys)
    assert len((out / "example.c").read_text().splitlines()) <= 32
    subprocess.run(["make", "-C", str(out), f"CFLAGS={flags}"], check=True, capture_output=True)
    run = subprocess.run([str(out / "example")], check=True, capture_output=True, text=True)
    lines = dict(line.split(" ", 1) for line in run.stdout.splitlines())
    assert lines["status"] == "0" and float(lines["step_us"]) > 0
    exported = np.array(lines["qddot"].split(), dtype=float)
    loaded, planner = _python_planner(EXAMPLES / scenario)
    qdot = np.array(loaded.initial_state.qdot)
    qdot[0] += 0.1
    np.testing.assert_allclose(exported, planner.compute(np.array(loaded.initial_state.q), qdot), rtol=0, atol=1e-12)


def test_the_makefiles_default_flags_give_the_same_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = _export(tmp_path, "point_spheres.yaml", capsys)
    outputs = []
    for flags in ([f"CFLAGS={STRICT}"], []):  # [] builds with the Makefile's own flags
        subprocess.run(["make", "-B", "-C", str(out), *flags], check=True, capture_output=True)
        run = subprocess.run([str(out / "example")], check=True, capture_output=True, text=True)
        outputs.append(np.array(dict(line.split(" ", 1) for line in run.stdout.splitlines())["qddot"].split(),
                                dtype=float))
    np.testing.assert_allclose(outputs[1], outputs[0], rtol=0, atol=1e-12)


def test_named_fields_match_python_on_random_states(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = _export(tmp_path, "panda_spheres.yaml", capsys)
    (out / "check.c").write_text(CHECK_C.replace("UPPER", "PLANNER").replace("NAME", "planner"))
    subprocess.run(["cc", *WARNINGS.split(), "-o", str(out / "check"), str(out / "check.c"), str(out / "planner.c"),
                    "-lm"], check=True, capture_output=True)
    _, planner = _python_planner(EXAMPLES / "panda_spheres.yaml")
    rng = np.random.default_rng(3)
    cases = [(planner.robot.default_q + rng.normal(0, 0.5, 7), rng.normal(0, 1.0, 7),
              rng.uniform(-0.6, 0.6, 3), rng.uniform(-0.6, 0.6, 3)) for _ in range(40)]
    cases.append((cases[0][0], np.full(7, np.nan), cases[0][2], cases[0][3]))  # refused: status -1
    text = "\n".join(" ".join(repr(float(x)) for part in case for x in part) for case in cases)
    run = subprocess.run([str(out / "check")], input=text, check=True, capture_output=True, text=True)
    rows = [line.split() for line in run.stdout.splitlines()]
    assert len(rows) == len(cases) and rows[-1][0] == "-1"
    for (q, qdot, goal, obstacle), row in zip(cases[:-1], rows[:-1]):
        planner.parameters.goal_position[0][:] = goal
        planner.parameters.obstacle_position[0] = obstacle
        assert row[0] == "0"
        np.testing.assert_allclose(np.array(row[1:], dtype=float), planner.compute(q, qdot), rtol=0, atol=1e-12)


def test_export_of_an_mpc_scenario_is_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = tmp_path / "mpc.yaml"
    scenario.write_text((EXAMPLES / "panda_spheres.yaml").read_text().replace("static-fabric", "mpc"))
    assert main(["export", str(scenario), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["dynfab: error: planner: export needs a fabric planner, got 'mpc'"]
