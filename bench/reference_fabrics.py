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

Options that change the problem (both used by ``bench/bench_planner.py``):
  --scene FILE  a JSON object {"goal": [x, y, z], "obstacles": [{"position": [...],
                "radius": r}, ...]}: the goal and static spheres of a scene (e.g. an
                experiment-1 scenario) instead of the seeded ones; --spheres is then the
                number of obstacles in it.
  --model FILE  a JSON object {"spheres": [[link, [cx, cy, cz], radius], ...],
                "pairs": [[i, j], ...], "locked": {joint: value}}: ANOTHER collision
                model, e.g. dynfab's built-in Panda (spheres with centre offsets in link
                frames). fabrics 0.10.0 puts a collision sphere only at the ORIGIN of a
                link frame (``set_components(collision_links=[link names])``, radius the
                runtime input ``radius_body_<link>``, self-collision pairs by link name),
                so each sphere becomes a link of its own: the URDF is rewritten with one
                fixed joint per sphere (origin = the sphere's centre in its link), the
                locked joints (the Panda's fingers) turned into fixed joints at their
                value, and every sphere link an end link of the kinematics (the
                reference's forward kinematics only follows joints on chains to its end
                links). The kinematics, goal and limits are unchanged.

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
from dataclasses import dataclass
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
    parser.add_argument("--scene", type=Path, help="JSON file: goal and obstacles (module docstring)")
    parser.add_argument("--model", type=Path, help="JSON file: another collision model (module docstring)")
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


@dataclass(frozen=True)
class CollisionModel:
    """What set_components gets: the URDF text, the kinematics' end links, the collision
    links (a sphere at each one's origin), the self-collision pairs (key link: links) and
    each link's ``radius_body_<link>``."""

    urdf_text: str
    end_links: tuple
    collision_links: tuple
    self_collision_pairs: dict
    radii: dict


def reference_model(urdf_text: str) -> CollisionModel:
    """The reference's own Panda model (module docstring)."""
    links = sorted(set(COLLISION_LINKS) | set(SELF_COLLISION_PAIRS)
                   | {l for v in SELF_COLLISION_PAIRS.values() for l in v})
    return CollisionModel(urdf_text, (GOAL_LINK,), tuple(COLLISION_LINKS), dict(SELF_COLLISION_PAIRS),
                          {link: BODY_RADIUS for link in links})


def _rpy_matrix(rpy) -> np.ndarray:
    r, p, y = rpy
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return rz @ ry @ rx


def sphere_link_model(urdf_text: str, model: dict) -> CollisionModel:
    """Another collision model given to the reference (``--model``): one fixed link per
    sphere at its centre, locked joints fixed at their value (module docstring)."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(urdf_text)
    locked = {name: float(value) for name, value in model.get("locked", {}).items()}
    for joint in root.findall("joint"):
        name = joint.get("name")
        mimic = joint.find("mimic")
        source = mimic.get("joint") if mimic is not None else name
        if source not in locked:
            continue
        if joint.get("type") != "prismatic":
            raise ValueError(f"--model: locking joint {name} of type {joint.get('type')} is not supported")
        value = locked[source] * float(mimic.get("multiplier", 1.0) if mimic is not None else 1.0)
        value += float(mimic.get("offset", 0.0)) if mimic is not None else 0.0
        origin = joint.find("origin")
        xyz = np.array([float(x) for x in origin.get("xyz", "0 0 0").split()])
        rpy = [float(x) for x in origin.get("rpy", "0 0 0").split()]
        axis = np.array([float(x) for x in joint.find("axis").get("xyz").split()])
        xyz = xyz + _rpy_matrix(rpy) @ (axis / np.linalg.norm(axis)) * value
        origin.set("xyz", " ".join(repr(float(x)) for x in xyz))
        joint.set("type", "fixed")
        for child in ("axis", "limit", "mimic", "dynamics"):
            for element in joint.findall(child):
                joint.remove(element)
    names, radii = [], {}
    for i, (link, center, radius) in enumerate(model["spheres"]):
        name = f"dynfab_sphere_{i}"
        ET.SubElement(root, "link", name=name)
        joint = ET.SubElement(root, "joint", name=f"{name}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=link)
        ET.SubElement(joint, "child", link=name)
        ET.SubElement(joint, "origin", xyz=" ".join(repr(float(x)) for x in center), rpy="0 0 0")
        names.append(name)
        radii[name] = float(radius)
    pairs: dict = {}
    for a, b in model["pairs"]:
        pairs.setdefault(names[a], []).append(names[b])
    return CollisionModel(ET.tostring(root, encoding="unicode"), (GOAL_LINK, *names), tuple(names), pairs, radii)


def build_planner(urdf_text: str, n_spheres: int, goal_position=GOAL, end_links=(GOAL_LINK,),
                  collision_links=COLLISION_LINKS, self_collision_pairs=SELF_COLLISION_PAIRS):
    """Returns (planner, fk, build_s, setup_s)."""
    from fabrics.planner.parameterized_planner import ParameterizedFabricPlanner
    from forwardkinematics.urdfFks.generic_urdf_fk import GenericURDFFk
    from mpscenes.goals.goal_composition import GoalComposition

    t0 = time.perf_counter()
    fk = GenericURDFFk(urdf_text, root_link=ROOT_LINK, end_links=list(end_links))
    dof = fk.n()
    goal = GoalComposition(name="goal", content_dict={
        "subgoal0": {
            "weight": 1.0,
            "is_primary_goal": True,
            "indices": [0, 1, 2],
            "parent_link": ROOT_LINK,
            "child_link": GOAL_LINK,
            "desired_position": [float(x) for x in goal_position],
            "epsilon": 0.05,
            "type": "staticSubGoal",
        },
    })
    planner = ParameterizedFabricPlanner(dof, fk)
    # planner.leaves is keyed by name, and 0.10.0 names a self-collision leaf after its first
    # link only (an f-string missing its f), so pairs sharing that link overwrite each other
    # there although every leaf is in the fabric: count the leaves as they are added.
    planner.leaf_counts = {}
    add_leaf = planner.add_leaf

    def counting_add_leaf(leaf, *args, **kwargs):
        kind = type(leaf).__name__
        planner.leaf_counts[kind] = planner.leaf_counts.get(kind, 0) + 1
        return add_leaf(leaf, *args, **kwargs)

    planner.add_leaf = counting_add_leaf
    t1 = time.perf_counter()
    planner.set_components(
        collision_links=list(collision_links),
        self_collision_pairs={k: list(v) for k, v in self_collision_pairs.items()},
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


def run(n_spheres: int, steps: int, urdf: Path, seed: int = SEED, scene: dict | None = None,
        model: dict | None = None) -> dict:
    """Build and time the reference; ``scene`` and ``model``: the --scene and --model objects."""
    t_import = time.perf_counter()
    import fabrics
    from fabrics.planner.parameterized_planner import ParameterizedFabricPlanner  # noqa: F401

    import casadi as ca

    import_s = time.perf_counter() - t_import
    try:  # casadi >= 3.8 warns once that fabrics relies on its legacy numpy interplay
        ca.GlobalOptions.setNumpyMode(-1)  # legacy behaviour, silently
    except AttributeError:
        pass
    urdf_text = Path(urdf).read_text()
    collision = reference_model(urdf_text) if model is None else sphere_link_model(urdf_text, model)
    goal = GOAL if scene is None else [float(x) for x in scene["goal"]]
    if scene is not None:
        n_spheres = len(scene["obstacles"])
    # The reference prints progress ("Setting exection energy", skipped links) to
    # stdout; keep stdout clean for the JSON.
    with contextlib.redirect_stdout(sys.stderr):
        planner, fk, build_s, setup_s = build_planner(collision.urdf_text, n_spheres, goal, collision.end_links,
                                                      collision.collision_links, collision.self_collision_pairs)

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
    if scene is None:
        obstacles = [(c, OBSTACLE_RADIUS) for c in _obstacle_positions(fk, n_spheres, rng)]
    else:
        obstacles = [(np.array(o["position"], dtype=float), float(o["radius"])) for o in scene["obstacles"]]

    fixed_kwargs: dict[str, object] = {
        "x_goal_0": np.array(goal),
        "weight_goal_0": 1.0,
    }
    for i, (c, radius) in enumerate(obstacles):
        fixed_kwargs[f"x_obst_{i}"] = c
        fixed_kwargs[f"radius_obst_{i}"] = radius
    for link, radius in collision.radii.items():
        fixed_kwargs[f"radius_body_{link}"] = radius
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

    self_collision_leaves = planner.leaf_counts.get("SelfCollisionLeaf", 0)
    obstacle_leaves = sum(count for kind, count in planner.leaf_counts.items() if "Obstacle" in kind)
    blocks = np.array_split(times, 5)
    centres = {link: [float(x) for x in np.asarray(fk.numpy(Q0, link, position_only=True)).reshape(3)]
               for link in collision.radii}
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
        "import_s": import_s,
        "n_inputs": len(input_names),
        "model_spheres": len(collision.radii),
        "model_collision_links": obstacle_leaves // n_spheres if n_spheres else None,
        "model_pairs": sum(len(v) for v in collision.self_collision_pairs.values()),
        "n_self_collision_leaves": self_collision_leaves,
        "n_obstacle_leaves": obstacle_leaves,
        "leaf_counts": planner.leaf_counts,
        "step_ms_blocks": [float(np.median(block) * 1e3) for block in blocks if block.size],
        "sphere_centres_q0": centres,
        "fabrics_version": getattr(fabrics, "__version__", None),
        "numpy_version": np.__version__,
    }


def main(argv: list[str] | None = None) -> int:
    args = _parse_args(argv)
    if not args.urdf.is_file():
        print(f"reference_fabrics.py: URDF not found: {args.urdf}", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.ERROR)  # the reference warns on tiny actions
    scene = None if args.scene is None else json.loads(args.scene.read_text())
    model = None if args.model is None else json.loads(args.model.read_text())
    result = run(args.spheres, args.steps, args.urdf, args.seed, scene, model)
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
