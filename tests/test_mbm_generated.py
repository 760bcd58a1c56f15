"""New MBM problems of the seven primitive types drawn from a seed (``--source generated``):
reproducible, free on Franka's meshes at start and goal, at their queries, scenes within
their variation, every variant working on them, bad input refused by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dynfab.benchmarks.mbm.benchmark import BenchmarkSettings, _cases
from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.generated_problems import generate_problem, generated_problems, sample_scene
from dynfab.benchmarks.mbm.moveit import SceneObject
from dynfab.benchmarks.mbm.primitive_configs import primitive_config
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, Problem
from dynfab.benchmarks.mbm.query_ik import READY, TIP_LINK
from dynfab.benchmarks.mbm.variants import VARIANTS, prepare_case
from dynfab.cli import main
from dynfab.geometry.shapes import quaternion_matrix


def _pose(item: SceneObject) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = quaternion_matrix(item.orientation)
    pose[:3, 3] = item.position
    return pose


def _query_error(problem: Problem, q: tuple[float, ...], obj: str, start: bool) -> tuple[np.ndarray, float]:
    """Tip position error per axis [m] (world axes) and rotation angle [rad] of ``q`` from
    the query target of ``obj``."""
    config = primitive_config(problem.type)
    query = next(x for x in (config.start_queries if start else config.goal_queries) if x.obj == obj)
    item = next(o for o in problem.objects if o.id == obj)
    target = _pose(item) @ query.offset @ np.linalg.inv(config.ee_offset)
    tip = np.array(franka().robot.kinematics.transform(np.array(q), TIP_LINK), dtype=float)
    turn = target[:3, :3].T @ tip[:3, :3]
    return np.abs(tip[:3, 3] - target[:3, 3]), float(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1.0, 1.0)))


def test_a_seed_gives_the_same_problem_twice_and_another_seed_another() -> None:
    robot = franka()
    problem = generate_problem("box", 2, 5, robot)
    assert generate_problem("box", 2, 5, robot) == problem
    other = generate_problem("box", 2, 6, robot)
    assert other.goal != problem.goal and other.objects != problem.objects
    assert problem.name == "box/0002" and problem.start == READY  # as every archive box problem starts


@pytest.mark.parametrize(("name", "obj"), [("cage", "Cube1"), ("table_under_pick", "Can1")])
def test_start_and_goal_are_free_on_the_meshes_and_at_their_queries(name: str, obj: str) -> None:
    robot = franka()
    problem = generate_problem(name, 1, 11, robot)
    assert prepare_case(problem, "as-posed", robot).invalid is None  # in limits, no contact at start or goal
    config = primitive_config(name)
    query = next(q for q in config.goal_queries if q.obj == obj)
    position, angle = _query_error(problem, problem.goal, obj, start=False)
    assert np.all(position <= np.asarray(query.position_tolerance) / 2 + 1e-4)
    assert angle <= float(np.linalg.norm(query.orientation_tolerance)) + 1e-4
    if config.start_queries:  # table_under_pick: the hand starts under the table
        assert problem.start != READY
        position, angle = _query_error(problem, problem.start, "table_top", start=True)
        assert np.all(position <= 1e-4) and angle <= 0.006
    else:
        assert problem.start == READY


@pytest.mark.parametrize("name", PROBLEM_TYPES)
def test_a_drawn_scene_has_the_config_objects_within_the_variation_bounds(name: str) -> None:
    config = primitive_config(name)
    assert config.world is not None
    varied = {obj: v for v in config.object_variations for obj in v.names}
    anchor = next(k for k, o in enumerate(config.scene) if o.id not in varied)
    rng = np.random.default_rng(0)
    worlds, locals_ = [], {obj: [] for obj in varied}
    for _ in range(200):
        scene = sample_scene(config, rng)
        assert [(o.id, o.kind, o.dimensions) for o in scene] == [(o.id, o.kind, o.dimensions) for o in config.scene]
        world = _pose(scene[anchor]) @ np.linalg.inv(config.base_offset @ _pose(config.scene[anchor]))
        worlds.append(world)
        for nominal, drawn in zip(config.scene, scene):
            local = np.linalg.inv(world @ config.base_offset @ _pose(nominal)) @ _pose(drawn)
            if nominal.id in varied:
                locals_[nominal.id].append(local)
            else:
                assert np.allclose(local, np.eye(4), atol=1e-9)  # moved with the whole scene only
    for poses, variation in [(worlds, config.world)] + [(locals_[obj], v) for obj, v in varied.items()]:
        translations = np.array([p[:3, 3] for p in poses])
        yaws = np.array([np.arctan2(p[1, 0], p[0, 0]) for p in poses])
        bounds = np.asarray(variation.position)
        assert np.all(np.abs(translations) <= bounds + 1e-9)
        assert np.all(np.abs(yaws) <= variation.orientation[2] + 1e-9)
        assert np.allclose([p[2, :3] for p in poses], [0.0, 0.0, 1.0], atol=1e-9)  # yaw only (roll, pitch 0)
        assert np.all(np.abs(translations).max(0) >= 0.8 * bounds)  # the bounds are used, not only the centre
        if variation.orientation[2] > 0:
            assert np.abs(yaws).max() >= 0.8 * variation.orientation[2]


def test_every_variant_runs_on_a_generated_problem_and_removes_the_query_object() -> None:
    robot = franka()
    cases = {variant: _cases(BenchmarkSettings(variant, ("bookshelf_small",), 1, seed=4, source="generated"))[0]
             for variant in VARIANTS}
    problem = generate_problem("bookshelf_small", 1, 4, robot)
    assert all(case.problem == problem for case in cases.values())
    assert cases["as-posed"].removed is None and cases["as-posed"].invalid is None
    can = min((o for o in problem.objects if o.id.startswith("Can")),
              key=lambda o: float(np.linalg.norm(np.asarray(o.position) - robot.tcp(problem.goal))))
    for variant in ("object-removed", "moving-sphere", "points"):
        assert cases[variant].removed == can.id and cases[variant].invalid is None, variant


@pytest.mark.parametrize(("arguments", "message"), [
    (["--seed", "-1"], "argument --seed: expected a non-negative integer, got -1"),
    (["--source", "generated", "--archive", "other.tar.bz2"], "--archive reads an archive's problems"),
    (["--source", "made-up"], "argument --source: invalid choice: 'made-up'"),
    (["--types", "shelf"], "unknown problem type 'shelf'"),
])
def test_the_command_refuses_bad_options_by_name(arguments: list[str], message: str, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    try:
        code = main(["benchmark", "mbm", *arguments, "--out", str(tmp_path)])
    except SystemExit as error:  # argparse's usage errors
        code = error.code
    assert code == 2
    assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing was run


@pytest.mark.parametrize(("call", "message"), [
    (lambda robot: generate_problem("shelf", 1, 0, robot), "unknown problem type 'shelf'"),
    (lambda robot: generate_problem("box", 1, -1, robot), "seed: expected a non-negative integer, got -1"),
    (lambda robot: generate_problem("box", 0, 0, robot), "number: expected an integer of at least 1, got 0"),
])
def test_the_generator_refuses_a_bad_type_seed_or_number_by_name(call, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=message):
        call(franka())



def test_problems_drawn_over_two_processes_are_those_drawn_in_one() -> None:
    robot = franka()
    serial = generated_problems(("cage", "box"), 1, 2, 9, robot)
    assert [p.name for p in serial] == ["cage/0003", "box/0003"]
    assert generated_problems(("cage", "box"), 1, 2, 9, robot, jobs=2) == serial
