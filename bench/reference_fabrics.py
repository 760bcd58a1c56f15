"""Reference side of the dynfab benchmark: times the PyPI package `fabrics` 0.10.0.

This script runs INSIDE the separate virtualenv ``.venv-reference`` created by
``bench/setup_reference.sh`` (the reference pins numpy<2).  It must never import
dynfab, and dynfab never imports it: ``bench/reference.py`` runs it as a subprocess
and parses the JSON it prints.

    .venv-reference/bin/python bench/reference_fabrics.py \
        --spheres 5 --steps 1000 --urdf dynfab/robots/data/panda.urdf --json

Problem (Franka Panda, the same as dynfab's benchmark):
  * goal: position of ``panda_hand`` in ``panda_link0`` coordinates, weight 1,
    one primary ``staticSubGoal``;
  * N static sphere obstacles, radius 0.15, at seeded random positions away from
    the robot and the goal;
  * collision spheres (radius 0.08 each) centred on the frame origins of
    panda_link3, panda_link4, panda_link5, panda_link7 and panda_hand
    (panda_link1/2 have constant positions and would be skipped by the reference);
  * self-collision pairs: panda_hand vs panda_link2 and panda_hand vs panda_link3
    (radius_body_panda_link2 = 0.08 as well);
  * joint limits of the Panda (both bounds of all 7 joints).

API calls used (fabrics 0.10.0, forwardkinematics 1.2.x, mpscenes 0.4.x):
  GenericURDFFk(urdf_text, root_link="panda_link0", end_links=["panda_hand"])
  GoalComposition(name="goal", content_dict={...staticSubGoal...})
  ParameterizedFabricPlanner(dof, fk)
  planner.set_components(collision_links=..., self_collision_pairs=...,
                         goal=..., limits=..., number_obstacles=N)
  planner.concretize()
  planner.compute_action(q=, qdot=, x_goal_0=, weight_goal_0=, x_obst_i=,
                         radius_obst_i=, radius_body_<link>=)
  planner._funs.function()  -> the casadi.Function (n_instructions())

Note: set_components builds self-collision leaves (the configuration path,
``load_problem_configuration``, has ``set_self_collision_avoidance`` commented out
in 0.10.0 and silently drops them); we use set_components and report the number
of self-collision leaves actually built.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import math
import sys
import time
from pathlib import Path

import numpy as np

DEFAULT_URDF = Path(__file__).resolve().parent.parent / "dynfab" / "robots" / "data" / "panda.urdf"

ROOT_LINK = "panda_link0"
GOAL_LINK = "panda_hand"
# Collision spheres on the arm: frame origins of these links, radius 0.08 each.
COLLISION_LINKS = ["panda_link3", "panda_link4", "panda_link5", "panda_link7", "panda_hand"]
# Self-collision: key link vs. each listed link (reference convention: dict).
SELF_COLLISION_PAIRS = {"panda_hand": ["panda_link2", "panda_link3"]}
BODY_RADIUS = 0.08
OBSTACLE_RADIUS = 0.15
GOAL = [0.5, -0.4, 0.3]
Q0 = np.array([1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0])
LIMITS_LOW = [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]
LIMITS_HIGH = [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]
SEED = 0


def _parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spheres", type=int, default=1, help="number of static sphere obstacles")
    parser.add_argument("--steps", type=int, default=1000, help="number of timed compute_action calls")
    parser.add_argument("--urdf", type=Path, default=DEFAULT_URDF, help="Panda URDF file")
    parser.add_argument("--json", action="store_true", help="print one JSON object only")
    parser.add_argument("--seed", type=int, default=SEED, help="seed for obstacles and velocities")
    args = parser.parse_args(argv)
    if args.spheres < 0:
        parser.error("--spheres must be >= 0")
    if args.steps < 1:
        parser.error("--steps must be >= 1")
    return args


def _link_positions(fk, q: np.ndarray, links: list[str]) -> np.ndarray:
    return np.array([np.asarray(fk.numpy(q, link, position_only=True)).reshape(3) for link in links])


def _obstacle_positions(fk, n: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Seeded random sphere centres that neither touch the robot at q0 nor cover the goal."""
    # Points along the arm at q0: every link frame plus midpoints, and the base column.
    links = ["panda_link1", "panda_link2", "panda_link3", "panda_link4", "panda_link5",
             "panda_link6", "panda_link7", "panda_hand"]
    pts = _link_positions(fk, Q0, links)
    pts = np.vstack([pts, 0.5 * (pts[1:] + pts[:-1]), [[0.0, 0.0, 0.0], [0.0, 0.0, 0.15]]])
    goal = np.asarray(GOAL)
    clearance_robot = OBSTACLE_RADIUS + BODY_RADIUS + 0.10
    clearance_goal = OBSTACLE_RADIUS + BODY_RADIUS + 0.05
    out: list[np.ndarray] = []
    for _ in range(100000):
        if len(out) == n:
            break
        c = rng.uniform([-0.6, -0.8, 0.05], [0.8, 0.8, 1.0])
        if np.min(np.linalg.norm(pts - c, axis=1)) < clearance_robot:
            continue
        if np.linalg.norm(goal - c) < clearance_goal:
            continue
        out.append(c)
    if len(out) < n:
        raise RuntimeError(f"could not place {n} obstacles away from the robot")
    return out


def build_planner(urdf_text: str, n_spheres: int):
    """Returns (planner, fk, goal, build_s, setup_s)."""
    from fabrics.planner.parameterized_planner import ParameterizedFabricPlanner
    from forwardkinematics.urdfFks.generic_urdf_fk import GenericURDFFk
    from mpscenes.goals.goal_composition import GoalComposition

    t0 = time.perf_counter()
    fk = GenericURDFFk(urdf_text, root_link=ROOT_LINK, end_links=[GOAL_LINK])
    dof = fk.n()
    goal = GoalComposition(name="goal", content_dict={
        "subgoal0": {
            "weight": 1.0,
            "is_primary_goal": True,
            "indices": [0, 1, 2],
            "parent_link": ROOT_LINK,
            "child_link": GOAL_LINK,
            "desired_position": list(GOAL),
            "epsilon": 0.05,
            "type": "staticSubGoal",
        },
    })
    planner = ParameterizedFabricPlanner(dof, fk)
    t1 = time.perf_counter()
    planner.set_components(
        collision_links=list(COLLISION_LINKS),
        self_collision_pairs={k: list(v) for k, v in SELF_COLLISION_PAIRS.items()},
        goal=goal,
        limits=[[lo, hi] for lo, hi in zip(LIMITS_LOW, LIMITS_HIGH)],
        number_obstacles=n_spheres,
    )
    planner.concretize()
    t2 = time.perf_counter()
    return planner, fk, t2 - t1, t1 - t0


def _casadi_function(planner):
    funs = getattr(planner, "_funs", None)
    if funs is None:
        return None
    if hasattr(funs, "function"):
        return funs.function()
    return getattr(funs, "_function", None)


def run(n_spheres: int, steps: int, urdf: Path, seed: int = SEED) -> dict:
    import fabrics

    import casadi as ca

    try:  # casadi >= 3.8 warns once that fabrics relies on its legacy numpy interplay
        ca.GlobalOptions.setNumpyMode(-1)  # legacy behaviour, silently
    except AttributeError:
        pass
    urdf_text = Path(urdf).read_text()
    # The reference prints progress ("Setting exection energy", skipped links) to
    # stdout; keep stdout clean for the JSON.
    with contextlib.redirect_stdout(sys.stderr):
        planner, fk, build_s, setup_s = build_planner(urdf_text, n_spheres)

    function = _casadi_function(planner)
    n_instructions = None
    input_names: list[str] = []
    if function is not None:
        try:
            n_instructions = int(function.n_instructions())
        except Exception:  # pragma: no cover - depends on casadi build
            n_instructions = None
        input_names = list(function.name_in())

    rng = np.random.default_rng(seed)
    obstacles = _obstacle_positions(fk, n_spheres, rng)

    body_links = sorted(set(COLLISION_LINKS)
                        | set(SELF_COLLISION_PAIRS)
                        | {l for v in SELF_COLLISION_PAIRS.values() for l in v})
    fixed_kwargs: dict[str, object] = {
        "x_goal_0": np.array(GOAL),
        "weight_goal_0": 1.0,
    }
    for i, c in enumerate(obstacles):
        fixed_kwargs[f"x_obst_{i}"] = c
        fixed_kwargs[f"radius_obst_{i}"] = OBSTACLE_RADIUS
    for link in body_links:
        fixed_kwargs[f"radius_body_{link}"] = BODY_RADIUS
    # Pass only what the function takes (a link skipped as sparse has no radius input).
    if input_names:
        fixed_kwargs = {k: v for k, v in fixed_kwargs.items() if k in input_names}
        missing = [n for n in input_names if n not in fixed_kwargs and n not in ("q", "qdot")]
        if missing:
            raise RuntimeError(f"reference function needs inputs we do not supply: {missing}")

    # Realistic states: q0 plus a little noise, small random velocities.
    qs = Q0 + rng.normal(0.0, 0.01, size=(steps, Q0.size))
    qdots = rng.normal(0.0, 0.1, size=(steps, Q0.size))

    for k in range(min(20, steps)):  # warm-up, untimed
        planner.compute_action(q=qs[k], qdot=qdots[k], **fixed_kwargs)

    times = np.empty(steps)
    n_bad = 0
    perf = time.perf_counter
    for k in range(steps):
        t0 = perf()
        action = planner.compute_action(q=qs[k], qdot=qdots[k], **fixed_kwargs)
        times[k] = perf() - t0
        if not np.all(np.isfinite(action)):
            n_bad += 1

    self_collision_leaves = [name for name in planner.leaves if name.startswith("self_collision")]
    obstacle_leaves = [name for name in planner.leaves if name.startswith("obst_")]
    return {
        "build_s": build_s,
        "step_ms_median": float(np.median(times) * 1e3),
        "step_ms_mean": float(np.mean(times) * 1e3),
        "n_instructions": n_instructions,
        "spheres": n_spheres,
        "nan_fraction": n_bad / steps,
        # extra information
        "steps": steps,
        "setup_s": setup_s,
        "n_inputs": len(input_names),
        "n_self_collision_leaves": len(self_collision_leaves),
        "n_obstacle_leaves": len(obstacle_leaves),
        "fabrics_version": getattr(fabrics, "__version__", None),
        "numpy_version": np.__version__,
    }


def main(argv: list[str] | None = None) -> int:
    args = _parse_args(argv)
    if not args.urdf.is_file():
        print(f"reference_fabrics.py: URDF not found: {args.urdf}", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.ERROR)  # the reference warns on tiny actions
    result = run(args.spheres, args.steps, args.urdf, args.seed)
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            if isinstance(value, float) and math.isfinite(value):
                print(f"{key:>24}: {value:.6g}")
            else:
                print(f"{key:>24}: {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
