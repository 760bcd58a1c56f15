"""The C backend: outputs equal to the VM's, the cache by code and by inputs, verification
of cache entries, and the fallback without a compiler."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dynfab.fabric import c_backend
from dynfab.fabric.fingerprint import canonical, inputs_digest
from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig
from dynfab.robots import load_robot
from dynfab.robots.builtin import panda_robot
from dynfab.robots.robot import CollisionSphere

#: the Panda with its 13 hand-written spheres: what these tests check does not depend on the
#: collision model, and the built-in one (75 spheres) takes minutes to compile
PANDA = panda_robot("hand-written")
HAND_GOAL = (GoalConfig(link="panda_hand"),)
needs_compiler = pytest.mark.skipif(c_backend.find_compiler() is None, reason="no C compiler")


def _randomize(planner: FabricPlanner, rng: np.random.Generator) -> None:
    """Random goals and obstacles in every parameter (velocities too on a dynamic planner)."""
    buffer = planner._input[planner.robot.dof + len(planner.config.limits.names):]
    buffer[:] = rng.normal(0.0, 0.5, buffer.size)
    planner.parameters.obstacle_radius[:] = rng.uniform(0.05, 0.2, planner.parameters.obstacle_radius.size)
    planner.parameters.goal_weight[:] = 1.0


def _both(robot_name: str, config: PlannerConfig) -> tuple[FabricPlanner, FabricPlanner]:
    robot = PANDA if robot_name == "panda" else load_robot(robot_name)
    return (FabricPlanner(robot, config),
            FabricPlanner(robot, dataclasses.replace(config, backend="c")))


CASES = {
    "static": ("panda", PlannerConfig(goals=HAND_GOAL, obstacle_slots=2)),
    "dynamic": ("panda", PlannerConfig(goals=HAND_GOAL, obstacle_slots=2, dynamic=True)),
    "base": ("boxer", PlannerConfig.for_robot(load_robot("boxer"), (GoalConfig(link="base_link"),), obstacle_slots=2)),
    "jerk-limited": ("panda", PlannerConfig(goals=HAND_GOAL, obstacle_slots=1,
                                            limits=dataclasses.replace(PANDA.limits, jerk=np.full(7, 50.0)))),
}


@needs_compiler
@pytest.mark.parametrize("case", sorted(CASES))
def test_c_outputs_equal_vm_outputs(case: str) -> None:
    robot_name, config = CASES[case]
    vm, compiled = _both(robot_name, config)
    assert (vm.backend, compiled.backend) == ("vm", "c")
    assert compiled.n_instructions == vm.n_instructions
    rng = np.random.default_rng(7)
    n, nv = vm.robot.dof, len(vm.config.limits.names)
    for _ in range(50):
        q = vm.robot.default_q + rng.normal(0.0, 0.4, n)
        qdot = rng.normal(0.0, 0.5, nv)
        _randomize(vm, rng)
        compiled._input[n + nv:] = vm._input[n + nv:]  # same parameters (and previous command)
        expected, got = vm.compute(q, qdot), compiled.compute(q, qdot)
        assert np.isfinite(expected).all()
        np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-12)


@needs_compiler
def test_second_planner_loads_by_inputs_without_building(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path))
    config = PlannerConfig(goals=HAND_GOAL, backend="c")
    first = FabricPlanner(PANDA, config)
    assert "compiled in" in capsys.readouterr().err
    monkeypatch.setattr(FabricPlanner, "_build", lambda self: pytest.fail("built the expression on a cache hit"))
    second = FabricPlanner(PANDA, config)
    assert capsys.readouterr().err == ""
    assert second.backend == "c" and second.build_time_s < 0.3
    q, qdot = PANDA.default_q, np.full(7, 0.2)
    np.testing.assert_array_equal(second.compute(q, qdot), first.compute(q, qdot))


def _entry(folder: Path) -> tuple[Path, Path]:
    (library,) = folder.glob("planner-[0-9a-f]*.so")
    return library, library.with_suffix(".json")


def _build_in_new_process(cache: Path, obstacle_slots: int) -> None:
    """Build a C planner in another process, so that this one never maps the library
    the test then damages."""
    code = ("from dynfab.fabric.planner import FabricPlanner, GoalConfig, PlannerConfig; "
            "from dynfab.robots.builtin import panda_robot; "
            f"FabricPlanner(panda_robot('hand-written'), PlannerConfig(goals=(GoalConfig(link='panda_hand'),), "
            f"obstacle_slots={obstacle_slots}, backend='c'))")
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                   env={**os.environ, "DYNFAB_CACHE_DIR": str(cache)})


@needs_compiler
@pytest.mark.parametrize("damage", ["corrupt", "foreign", "metadata"])
def test_damaged_cache_entry_is_rebuilt_never_loaded(damage: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    _build_in_new_process(tmp_path, obstacle_slots=0)
    library, meta = _entry(tmp_path)
    if damage == "corrupt":
        data = bytearray(library.read_bytes())
        data[len(data) // 2] ^= 0xFF
        library.write_bytes(bytes(data))
    elif damage == "foreign":  # another planner's self-consistent entry, renamed to this key
        _build_in_new_process(tmp_path / "other", obstacle_slots=1)
        foreign, foreign_meta = _entry(tmp_path / "other")
        library.write_bytes(foreign.read_bytes())
        meta.write_text(foreign_meta.read_text().replace(foreign.stem[len("planner-"):],
                                                         library.stem[len("planner-"):]))
    else:
        meta.write_text("{not json")
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path))
    config = PlannerConfig(goals=HAND_GOAL, backend="c")
    rebuilt = FabricPlanner(PANDA, config)
    assert "compiled in" in capsys.readouterr().err
    q, qdot = PANDA.default_q, np.full(7, 0.2)
    expected = FabricPlanner(PANDA, dataclasses.replace(config, backend="vm")).compute(q, qdot)
    np.testing.assert_allclose(rebuilt.compute(q, qdot), expected, rtol=0.0, atol=1e-12)


def test_without_compiler_falls_back_to_the_vm_with_one_warning(monkeypatch: pytest.MonkeyPatch,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("CC", "no-such-compiler-dynfab")
    c_backend.find_compiler.cache_clear()
    try:
        planner = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, backend="c"))
    finally:
        c_backend.find_compiler.cache_clear()
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "warning" in lines[0] and "VM" in lines[0]
    assert planner.backend == "vm"
    assert np.isfinite(planner.compute(PANDA.default_q, np.zeros(7))).all()


def test_unknown_backend_is_one_line_error() -> None:
    with pytest.raises(ValueError, match="PlannerConfig.backend must be one of vm, c, got 'gpu'"):
        PlannerConfig(goals=HAND_GOAL, backend="gpu")


def test_inputs_digest_follows_robot_and_config() -> None:
    config = PlannerConfig(goals=HAND_GOAL, obstacle_slots=2)
    same = PlannerConfig(goals=(GoalConfig(link="panda_hand"),), obstacle_slots=2)
    assert canonical(config) == canonical(same)
    assert inputs_digest(PANDA, config) == inputs_digest(panda_robot("hand-written"), same)
    assert inputs_digest(PANDA, config) != inputs_digest(load_robot("panda"), same)
    assert inputs_digest(PANDA, config) != inputs_digest(PANDA, dataclasses.replace(config, obstacle_slots=3))
    spheres = list(PANDA.collision_spheres)
    spheres[0] = CollisionSphere(spheres[0].link, spheres[0].center, spheres[0].radius + 1e-9)
    bigger = dataclasses.replace(PANDA, collision_spheres=tuple(spheres))
    assert inputs_digest(bigger, config) != inputs_digest(PANDA, config)


@needs_compiler
def test_planner_with_a_python_callable_compiles_and_is_found_by_its_code(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    from dynfab.fabric.fingerprint import UnknownValueError
    from dynfab.fabric.leaves.barrier import Barrier
    from dynfab.fabric.leaves.obstacle import SphereObstacleAvoidance

    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path))
    custom = SphereObstacleAvoidance(Barrier(geometry=lambda x, xd: -2 / x * xd**2))
    config = PlannerConfig(goals=HAND_GOAL, obstacle_slots=1, obstacle_avoidance=custom, backend="c")
    with pytest.raises(UnknownValueError):
        canonical(config)
    first = FabricPlanner(PANDA, config)
    assert "compiled in" in capsys.readouterr().err
    second = FabricPlanner(PANDA, config)  # built symbolically, library found by the code's hash
    assert capsys.readouterr().err == "" and second.backend == "c"
    assert not list(tmp_path.glob("planner-inputs-*.json"))
    q, qdot = PANDA.default_q, np.full(7, 0.2)
    np.testing.assert_array_equal(second.compute(q, qdot), first.compute(q, qdot))


@needs_compiler
def test_run_with_backend_c_gives_the_vm_metrics(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from test_cli import write_scenario

    from dynfab.cli import main

    point = {"robot": "point", "planner": "static-fabric", "dt": 0.01, "duration": 8.0,
             "initial_state": {"q": [0.0, 0.0]}, "goal": [{"type": "position", "position": [2.0, 0.5]}],
             "obstacles": [{"type": "sphere", "position": [1.0, 0.3], "radius": 0.3}]}
    path = write_scenario(tmp_path, point)
    assert main(["run", str(path), "--json"]) == 0
    vm = json.loads(capsys.readouterr().out)
    assert main(["run", str(path), "--json", "--backend", "c"]) == 0
    compiled = json.loads(capsys.readouterr().out)
    assert compiled.pop("solver_time_ms") > 0 and vm.pop("solver_time_ms") > 0
    assert compiled == vm and compiled["success"]
    assert main(["run", str(write_scenario(tmp_path, {**point, "backend": "c"}, "c.yaml")), "--json"]) == 0
    from_key = json.loads(capsys.readouterr().out)
    from_key.pop("solver_time_ms")
    assert from_key == vm


def test_failing_compiler_falls_back_to_the_vm_with_one_warning(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    broken = tmp_path / "broken-cc"
    broken.write_text('#!/bin/sh\nif [ "$1" = --version ]; then echo "broken-cc 1.0"; exit 0; fi\n'
                      'echo "broken-cc: internal error" >&2\nexit 1\n')
    broken.chmod(0o755)
    monkeypatch.setenv("CC", str(broken))
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path / "cache"))
    c_backend.find_compiler.cache_clear()
    try:
        planner = FabricPlanner(PANDA, PlannerConfig(goals=HAND_GOAL, backend="c"))
    finally:
        c_backend.find_compiler.cache_clear()
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "broken-cc: internal error" in warnings[0] and "VM" in warnings[0]
    assert planner.backend == "vm" and not list((tmp_path / "cache").glob("planner-*.so"))
