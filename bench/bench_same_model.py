"""Issue 21: our planner against the reference (PyPI ``fabrics`` 0.10.0) on the SAME robot
model, on an experiment-1 scene; used by ``bench/bench_planner.py`` (``./run bench``).

Our planner is the one ``dynfab run`` builds for the scene (it is built here by the same
code path: :func:`dynfab.scenario.guided_controller.make_scenario_controller`):

- ``default``: the scene as ``dynfab/experiments/exp1.py`` writes it, default settings:
  global guidance on, so the fabric is the *guided* one (dynamic fabric, goal: the
  joint-space reference that OMPL's plan feeds it, one slot per sphere of the scene,
  bounded command, C backend). The per-step figure is the fabric step
  (``FabricPlanner.compute``); the OMPL plan made at the first tick is not in it;
- ``paper``: ``guidance: false, recovery: false`` (the paper's setup, the planner the
  reference builds, and what ``dynfab experiment exp1`` runs, on the VM there unless
  ``$DYNFAB_BACKEND`` says c): static fabric, the hand's position goal.

Two robot models, each given to both sides:

- ``reference``: the reference's Panda (``bench/reference_fabrics.py``): spheres of
  0.08 m at the origins of panda_link3, 4, 5, 7 and panda_hand, self-collision pairs
  panda_hand-panda_link2 and panda_hand-panda_link3. Ours: the built-in Panda's
  kinematics with exactly these spheres (a sphere at panda_link2's origin for the pair;
  that point does not move, so neither side gives it obstacle leaves);
- ``builtin``: our built-in Panda (75 spheres with centre offsets in link frames, 268
  pairs, hand open). The reference takes it through a rewritten URDF, one fixed link per
  sphere (``reference_fabrics.py --model``).
"""

from __future__ import annotations

import dataclasses
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BENCH_DIR = Path(__file__).resolve().parent
PANDA_URDF = BENCH_DIR.parent / "dynfab" / "robots" / "data" / "panda.urdf"
#: the experiment-1 seed measured: 5 spheres (the most an experiment-1 scene has)
EXP1_SEED = 2
#: the reference's model (bench/reference_fabrics.py): links at whose origin a sphere sits
REFERENCE_COLLISION_LINKS = ("panda_link3", "panda_link4", "panda_link5", "panda_link7", "panda_hand")
REFERENCE_PAIRS = (("panda_hand", "panda_link2"), ("panda_hand", "panda_link3"))
REFERENCE_BODY_RADIUS = 0.08
BLOCKS = 5


def reference_model_robot(robot):
    """``robot`` (the built-in Panda) with the reference's collision model instead of its own."""
    from dynfab.robots import CollisionSphere

    links = list(REFERENCE_COLLISION_LINKS) + ["panda_link2"]
    spheres = tuple(CollisionSphere(link, (0.0, 0.0, 0.0), REFERENCE_BODY_RADIUS) for link in links)
    pairs = tuple((links.index(a), links.index(b)) for a, b in REFERENCE_PAIRS)
    return dataclasses.replace(robot, collision_spheres=spheres, self_collision_pairs=pairs)


def builtin_model() -> dict:
    """The built-in Panda's collision model as ``reference_fabrics.py --model`` takes it."""
    from dynfab.robots.builtin import panda_robot
    from dynfab.robots.franka import FINGER_JOINT, OPEN

    robot = panda_robot("fitted")
    return {"spheres": [[s.link, list(s.center), s.radius] for s in robot.collision_spheres],
            "pairs": [list(pair) for pair in robot.self_collision_pairs], "locked": {FINGER_JOINT: OPEN}}


def exp1_scene(seed: int = EXP1_SEED) -> dict:
    """The goal and spheres of experiment-1 scene ``seed`` (``reference_fabrics.py --scene``)."""
    from dynfab.experiments import exp1

    scenario = exp1.scenario(seed)
    return {"goal": scenario["goal"][0]["position"],
            "obstacles": [{"position": o["position"], "radius": o["radius"]} for o in scenario["obstacles"]]}


def measure_exp1(model: str, setting: str, backend: str | None, steps: int, seed: int = EXP1_SEED) -> dict:
    """Build the controller ``dynfab run`` builds for experiment-1 scene ``seed`` (``setting``
    ``"default"`` or ``"paper"``, robot model ``"builtin"`` or ``"reference"``, ``backend``
    ``None`` for the default) and time its fabric's ``compute`` over ``steps`` states near
    the start, in :data:`BLOCKS` blocks."""
    start = time.perf_counter()
    from dynfab.experiments import exp1
    from dynfab.scenario.references import scenario_references
    from dynfab.scenario.guided_controller import make_scenario_controller
    from dynfab.scenario.runner import robot_for
    from dynfab.scenario.schema import scenario_from_dict, validate_for_robot

    imported = time.perf_counter()
    data = exp1.scenario(seed)
    if setting == "paper":
        data.update(guidance=False, recovery=False)
    if backend is not None:
        data["backend"] = backend
    scenario = scenario_from_dict(data)
    robot = robot_for(scenario)
    if model == "reference":
        robot = reference_model_robot(robot)
    scenario = validate_for_robot(scenario, robot)
    references = scenario_references(scenario, robot)
    built = time.perf_counter()
    controller = make_scenario_controller(scenario, robot, references)
    controller_s = time.perf_counter() - built
    planner = controller.planner
    q0 = np.asarray(scenario.initial_state.q, dtype=float)
    rng = np.random.default_rng(1)
    states = [(q0 + rng.normal(0, 0.01, q0.size), rng.normal(0, 0.1, q0.size)) for _ in range(steps)]
    first = time.perf_counter()
    planner.compute(*states[0])
    first_action_s = time.perf_counter() - first
    for q, qdot in states[:50]:
        planner.compute(q, qdot)
    times = np.empty(steps)
    for k, (q, qdot) in enumerate(states):
        t0 = time.perf_counter()
        planner.compute(q, qdot)
        times[k] = time.perf_counter() - t0
    config = planner.config
    spheres = planner.robot.collision_spheres
    centres = planner.robot.sphere_centers(q0)
    return {"model": model, "setting": setting, "backend": planner.backend, "import_s": imported - start,
            "build_s": planner.build_time_s, "controller_s": controller_s, "first_action_s": first_action_s,
            "step_us_median": 1e6 * float(np.median(times)),
            "step_us_blocks": [1e6 * float(np.median(b)) for b in np.array_split(times, BLOCKS)],
            "n_instructions": planner.n_instructions, "dynamic": config.dynamic,
            "goal": "joint" if config.goals[0].link is None else f"position of {config.goals[0].link}",
            "obstacle_slots": config.obstacle_slots, "robot_spheres": len(spheres),
            "robot_pairs": len(planner.robot.self_collision_pairs),
            "sphere_centres_q0": {s.link if model == "reference" else str(i): [float(x) for x in c]
                                  for i, (s, c) in enumerate(zip(spheres, centres))}}


def _fresh(model: str, setting: str, backend: str | None, steps: int, cache: str) -> dict:
    code = (f"import json, sys; sys.path.insert(0, {str(BENCH_DIR)!r}); import bench_same_model as b; "
            f"print(json.dumps(b.measure_exp1({model!r}, {setting!r}, {backend!r}, {steps!r})))")
    env = {**os.environ, "DYNFAB_CACHE_DIR": cache}
    env.pop("DYNFAB_BACKEND", None)  # the default backend is what a user gets
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _centre_error(ours: dict, reference: dict, model: str) -> float:
    """Largest distance between the sphere centres at q0 of the two sides [m]."""
    errors = []
    for key, centre in ours["sphere_centres_q0"].items():
        name = key if model == "reference" else f"dynfab_sphere_{key}"
        if name in reference["sphere_centres_q0"]:
            errors.append(float(np.linalg.norm(np.subtract(centre, reference["sphere_centres_q0"][name]))))
    return max(errors) if errors else float("nan")


def same_model_measurements(steps: int, rounds: int = 3, reference_steps: int = 1000) -> dict:
    """Every variant of both models, ``rounds`` fresh processes each, alternating ours and the
    reference's; our first C build of each model starts from an empty cache (cold)."""
    from reference import run_reference

    scene = exp1_scene()
    results: dict = {"cpus": os.cpu_count(), "load_before": os.getloadavg(), "seed": EXP1_SEED, "scene": scene,
                     "models": {}}
    variants = (("default", None), ("default", "vm"), ("paper", None), ("paper", "vm"))
    with tempfile.TemporaryDirectory(prefix="dynfab-bench-same-") as work:
        for model in ("reference", "builtin"):
            cache = str(Path(work) / model)
            runs: dict = {f"{s}/{b or 'c'}": [] for s, b in variants}
            cold = {}
            reference = []
            model_json = None if model == "reference" else builtin_model()
            # the built-in model costs the reference ~30 s to build and ~16 ms a step: one process
            ref_rounds, ref_steps = (rounds, reference_steps) if model == "reference" else (1, max(100, steps // 8))
            for r in range(rounds):
                if r < ref_rounds:
                    result = run_reference(len(scene["obstacles"]), ref_steps, PANDA_URDF, scene=scene,
                                           model=model_json)
                    if result is None:
                        return {**results, "missing": True}
                    reference.append(result)
                for setting, backend in variants:
                    key = f"{setting}/{backend or 'c'}"
                    if backend == "vm" and r > 0 and model == "builtin":
                        continue  # one VM round of the big model: its builds are slow and it is not the default
                    if backend is None and r == 0:
                        cold[key] = _fresh(model, setting, backend, steps, cache)  # compiles: cold cache
                        continue
                    runs[key].append(_fresh(model, setting, backend, steps, cache))
            for key, result in cold.items():
                runs[key].append(_fresh(model, key.split("/")[0], None, steps, cache))  # a warm round for it too
            results["models"][model] = {"reference": reference, "ours": runs, "cold": cold,
                                        "centre_error_m": _centre_error(runs["default/c"][0], reference[0], model)}
    results["load_after"] = os.getloadavg()
    return results


def summary(results: dict) -> list[str]:
    """The printed report of :func:`same_model_measurements`."""
    if results.get("missing"):
        return []
    lines = [f"issue 21: ours vs the reference (fabrics 0.10.0) on the SAME robot model, experiment-1 scene "
             f"(seed {results['seed']}: {len(results['scene']['obstacles'])} spheres); {results['cpus']} CPUs, "
             f"load average {results['load_before'][0]:.2f} before, {results['load_after'][0]:.2f} after; "
             "medians of per-process medians (fresh processes, alternating), [min-max of 5-block medians]"]
    names = {"reference": "the reference's model: 5 spheres of 0.08 m at the origins of panda_link3/4/5/7/hand, "
                          "pairs hand-link2, hand-link3",
             "builtin": "the built-in model: 75 spheres (centres offset in link frames), 268 pairs, hand open"}
    settings = {"default": "`dynfab run` default (guided: dynamic fabric, joint-space reference goal)",
                "paper": "`guidance: false`, the paper's setup (static fabric, position goal)"}
    for model, data in results["models"].items():
        ref = data["reference"]
        ref_ms = statistics.median(r["step_ms_median"] for r in ref)
        blocks = [b for r in ref for b in r["step_ms_blocks"]]
        first = ref[0]
        lines.append(f"  {names[model]}:")
        lines.append(f"    reference (static fabric, position goal; {first['model_collision_links']} spheres "
                     f"against obstacles, {first['n_self_collision_leaves']} self-collision leaves, "
                     f"{first['n_inputs']} inputs, {first['n_instructions']} SX instructions): step "
                     f"{1e3 * ref_ms:8.1f} us [{1e3 * min(blocks):.1f}-{1e3 * max(blocks):.1f}] over {len(ref)} "
                     f"process(es); build {first['setup_s'] + first['build_s']:.2f} s after importing in "
                     f"{first['import_s']:.2f} s")
        for key, measured in data["ours"].items():
            if not measured:
                continue
            setting, backend = key.split("/")
            us = statistics.median(m["step_us_median"] for m in measured)
            blocks = [b for m in measured for b in m["step_us_blocks"]]
            m0 = measured[0]
            build = f"build {m0['build_s']:.2f} s"
            if key in data["cold"]:
                build = (f"build {data['cold'][key]['build_s']:.2f} s with a cold cache (compile), "
                         f"{statistics.median(m['build_s'] for m in measured):.3f} s warm")
            lines.append(f"    ours {backend.upper():<2} {settings[setting]}: step {us:8.2f} us "
                         f"[{min(blocks):.2f}-{max(blocks):.2f}] over {len(measured)}; {m0['n_instructions']} SX "
                         f"instructions; {build}; reference / ours = {1e3 * ref_ms / us:6.1f}x")
        lines.append(f"    (same model checked: sphere centres at q0 agree within {data['centre_error_m']:.1e} m)")
    lines.append("  ours: the fabric step (FabricPlanner.compute) of the planner `dynfab run` builds for the scene; "
                 "with guidance a run also plans with OMPL at its first tick (not in the step). `dynfab experiment "
                 "exp1` runs the `guidance: false` planner on the VM.")
    return lines
