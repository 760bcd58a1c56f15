"""An experiment run under another simulation: MuJoCo physics, a control interface,
observation delay and noise (the scenario keys of ``scenario/simulation_schema.py``).

Every run's scenario file then carries the keys, so each run replays as it ran. The
series' summary is the same experiment's, with the setting named in its description.
"""

from __future__ import annotations

import dataclasses
from functools import partial
from typing import Any

from dynfab.experiments.registry import Experiment, Sampler
from dynfab.scenario.simulation_schema import Simulation


def under_simulation(experiment: Experiment, simulation: Simulation) -> Experiment:
    """``experiment`` with ``simulation`` written into every scenario it draws."""
    if simulation == Simulation():
        return experiment
    keys = dataclasses.asdict(simulation)
    sampler: Sampler = partial(_with_keys, experiment.sampler, tuple(keys.items()))
    return dataclasses.replace(experiment, sampler=sampler,
                               description=f"{experiment.description} [{setting_name(simulation)}]")


def setting_name(simulation: Simulation) -> str:
    """A short name of the setting, e.g. ``mujoco-torque`` or ``mujoco-torque-delay0.02-noise0.001``."""
    if simulation.simulator == "kinematic":
        return "kinematic"
    name = f"{simulation.simulator}-{simulation.control}"
    if simulation.delay:
        name += f"-delay{simulation.delay:g}"
    if simulation.noise:
        name += f"-noise{simulation.noise:g}"
    return name


def _with_keys(sampler: Sampler, keys: tuple[tuple[str, Any], ...], seed: int, planner: str) -> dict[str, Any]:
    return {**sampler(seed, planner), **dict(keys)}
