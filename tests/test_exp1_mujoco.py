"""Experiment 1 under MuJoCo physics, end to end: the static fabric alone (the paper's
setting: no guidance, no recovery) reaches its goals with no link touching another on
Franka's collision meshes, and MuJoCo itself collides the built-in Panda by those meshes.

Slow-ish (about 25 s of CPU, 1.5 min on a loaded 2-core machine): four exp1 seeds, each
20 s simulated at 1 kHz. The 20-run figure is in docs/results.md (exp1, under MuJoCo)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from dynfab.experiments.registry import EXPERIMENTS, SF
from dynfab.experiments.settings import with_setting
from dynfab.robots.builtin import load_robot
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.mesh_sweep import sweep_meshes
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import scenario_from_dict
from dynfab.scenario.simulation_schema import Simulation
from dynfab.sim.mujoco_model import build_scene

#: Seeds of exp1 run here: 12 has the closest link approach of seeds 0-19 on the meshes
#: (17.8 mm), 10 the closest obstacle approach (6.3 cm), 0 and 7 reach their goals last.
SEEDS = (0, 7, 10, 12)

#: The hand folded down onto the forearm (joint 6 at its lower limit): a finger, the hand and
#: the flange touch ``panda_link5`` on the meshes. The fabric's sphere pairs have no
#: finger-forearm pair (its hand-forearm pairs cover it), so MuJoCo on the spheres had none.
FOLDED = (-1.28, 1.41, 1.05, -0.51, -0.56, -0.01, 1.66)


@pytest.mark.parametrize("seed", SEEDS)
def test_exp1_under_mujoco_reaches_the_goal_with_no_link_contact_on_the_meshes(seed: int) -> None:
    experiment = with_setting(EXPERIMENTS["exp1"], Simulation("mujoco"))
    data = experiment.sampler(seed, SF)
    assert data["guidance"] is False and data["recovery"] is False   # the paper's setting
    result = run_scenario(scenario_from_dict(data))
    metrics = result.metrics
    assert metrics.success and metrics.goal_reached and metrics.failure is None, metrics
    assert metrics.self_collision is False and metrics.min_self_distance > 0.005, metrics   # on the meshes
    assert metrics.collision is False and metrics.clearance > 0.0, metrics
    assert metrics.contacts == 0 and metrics.link_contacts == 0 and result.contacts == (), result.contacts
    assert result.mesh_sweep is not None and result.mesh_sweep.self_contacts == ()


def _touching(scene_model: mujoco.MjModel, q: np.ndarray) -> set[frozenset[str]]:
    """The pairs of robot bodies MuJoCo finds in contact at ``q``."""
    data = mujoco.MjData(scene_model)
    data.qpos[:7] = q
    mujoco.mj_forward(scene_model, data)
    bodies = scene_model.geom_bodyid
    return {frozenset((scene_model.body(int(bodies[a])).name, scene_model.body(int(bodies[b])).name))
            for a, b in data.contact.geom[:data.ncon].tolist()}


def test_mujoco_collides_the_builtin_panda_by_franka_meshes() -> None:
    robot = load_robot("panda")
    model = mesh_model_for(robot)
    assert model is not None, "example-robot-data (test extra) gives the Panda's meshes"
    pairs = [(model.links[i], model.links[j]) for i, j in model.pairs]
    scene = build_scene(robot, (), pairs, builtin_collision_meshes(robot))
    types = {int(t) for t in scene.model.geom_type}
    assert types == {int(mujoco.mjtGeom.mjGEOM_MESH)}
    q = np.array(FOLDED)
    on_meshes = {frozenset((c.first, c.second)) for c in sweep_meshes(model, q[None, :], []).self_contacts}
    assert frozenset(("panda_link5", "panda_leftfinger")) in on_meshes
    assert frozenset(("panda_link5", "panda_leftfinger")) in _touching(scene.model, q)
    assert _touching(scene.model, np.array(robot.default_q)) == set()
    spheres = build_scene(robot)   # without meshes: the spheres and the fabric's sphere pairs
    assert frozenset(("panda_link5", "panda_leftfinger")) not in _touching(spheres.model, q)
