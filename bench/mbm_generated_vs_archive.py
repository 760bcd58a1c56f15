"""Issue 19: do the generated MotionBenchMaker problems (``--source generated``) look like the
archive's of the same type? A markdown table on stdout, one row per type and source:

    .venv/bin/python bench/mbm_generated_vs_archive.py --per-type 20 --seed 0

Per type, over the archive's problems (all 92 of the bundled archive) and ``--per-type``
generated ones:

- ``objects``: primitives per scene; ``start=ready``: the share starting at MBM's ready state;
- ``yaw``: the range of the scene's yaw [rad] (of the first object of the scene file that
  no variation entry but ``World`` moves);
- ``object z``: the range of the grasped object's height [m];
- ``goal hand``: mean and range of the hand (``panda_hand_tcp``) at the goal [m];
- ``hand in object``: the goal hand in the grasped object's frame, mean (and its spread,
  the largest standard deviation of the three axes) [m];
- ``gap``: the median mesh distance of the robot to the grasped object at the goal [mm];
- ``goal - start``: the median joint distance from start to goal (Euclidean, 7 joints) [rad];
- ``valid``: the share valid as posed on Franka's meshes (start and goal free, in limits).

The grasped object is the graspable one nearest the hand at the goal
(:func:`~dynfab.benchmarks.mbm.variants.grasped_object`). Nothing here was tuned.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

import numpy as np

from dynfab.benchmarks.mbm.franka import TCP_LINK, Franka, franka
from dynfab.benchmarks.mbm.generated_problems import generated_problems
from dynfab.benchmarks.mbm.primitive_configs import primitive_config
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, Problem, load_problems
from dynfab.benchmarks.mbm.query_ik import READY
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.benchmarks.mbm.variants import grasped_object, prepare_case
from dynfab.geometry.shapes import quaternion_matrix
from dynfab.robots.mesh_sweep import PlacedShape, clearance_per_sample
from dynfab.scenario.schema import scenario_from_dict


def row(problems: Sequence[Problem], robot: Franka) -> list[str]:
    """The table's cells of one type and source (module doc)."""
    hands, local, gaps, heights, yaws, spans = [], [], [], [], [], []
    for problem in problems:
        index = grasped_object(problem, robot)
        obj = problem.objects[index]
        goal = np.array(robot.clipped(problem.goal))
        hand = np.array(robot.robot.kinematics.transform(goal, TCP_LINK), dtype=float)[:3, 3]
        rotation = quaternion_matrix(obj.orientation)
        hands.append(hand)
        local.append(rotation.T @ (hand - np.asarray(obj.position)))
        heights.append(obj.position[2])
        spans.append(float(np.linalg.norm(goal - np.array(robot.clipped(problem.start)))))
        anchor = quaternion_matrix(next(o for o in problem.objects if o.id == _anchor(problem.type)).orientation)
        yaws.append(float(np.arctan2(anchor[1, 0], anchor[0, 0])))
        case = prepare_case(problem, "as-posed", robot)
        shapes = _shapes_of(case.mapping, index)
        gaps.append(float(clearance_per_sample(robot.meshes, goal[None], shapes)[0]) * 1000)
    valid = sum(prepare_case(p, "as-posed", robot).invalid is None for p in problems)
    hands_array, local_array = np.array(hands), np.array(local)
    ready = sum(np.allclose(p.start, READY, atol=1e-3) for p in problems)
    return [f"{len(problems[0].objects)}", f"{ready / len(problems):.0%}", f"{min(yaws):+.2f}..{max(yaws):+.2f}",
            f"{min(heights):.2f}..{max(heights):.2f}", _vector(hands_array.mean(0)),
            f"{_vector(hands_array.min(0))}..{_vector(hands_array.max(0))}",
            f"{_vector(local_array.mean(0))} ±{local_array.std(0).max():.3f}", f"{np.median(gaps):.1f}",
            f"{np.median(spans):.2f}",
            f"{valid}/{len(problems)}"]


def _shapes_of(mapping: dict[str, Any], index: int) -> list[PlacedShape]:
    """The placed shape of obstacle ``index`` of a scenario mapping."""
    return [static_shapes(scenario_from_dict(mapping))[index]]


def _anchor(name: str) -> str:
    """The id of the first object of type ``name``'s scene file that only ``World`` moves."""
    config = primitive_config(name)
    varied = {obj for v in config.object_variations for obj in v.names}
    return next(o.id for o in config.scene if o.id not in varied)


def _vector(values: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:+.2f}" for v in values) + ")"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-type", type=int, default=20, help="generated problems per type (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="generation seed (default 0)")
    parser.add_argument("--types", default=",".join(PROBLEM_TYPES), help="comma-separated types (default all)")
    args = parser.parse_args()
    robot = franka()
    types = tuple(args.types.split(","))
    archive = load_problems(types)
    print("| type | source | objects | start=ready | yaw [rad] | object z [m] | goal hand mean [m] | goal hand range [m] "
          "| hand in object [m] | gap [mm] | goal - start [rad] | valid |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in types:
        generated = generated_problems((name,), args.per_type, 0, args.seed, robot)
        for source, problems in (("archive", [p for p in archive if p.type == name]), ("generated", generated)):
            print(f"| {name} | {source} | " + " | ".join(row(problems, robot)) + " |", flush=True)


if __name__ == "__main__":
    main()
