"""An experiment run in another setting: MuJoCo physics, a control interface, observation
delay and noise (the keys of ``scenario/simulation_schema.py``), and stall recovery
(``scenario/stall_recovery.py``, off in the paper's runs); or only some of its planners.

Every run's scenario file then carries the keys, so each run replays as it ran. The
series' summary is the same experiment's, with the setting named in its description.
"""

from __future__ import annotations

import dataclasses
from functools import partial

from dynfab.experiments.registry import Experiment, with_keys
from dynfab.scenario.simulation_schema import Simulation


def with_setting(experiment: Experiment, simulation: Simulation, recovery: bool = False) -> Experiment:
    """``experiment`` with ``simulation`` (and ``recovery: true``) written into every
    scenario it draws; unchanged for the paper's setting (kinematic, no recovery)."""
    if simulation == Simulation() and not recovery:
        return experiment
    keys = dataclasses.asdict(simulation) if simulation != Simulation() else {}
    if recovery:
        keys["recovery"] = True
    sampler = partial(with_keys, experiment.sampler, tuple(keys.items()))
    return dataclasses.replace(experiment, sampler=sampler,
                               description=f"{experiment.description} [{setting_name(simulation, recovery)}]")


def setting_name(simulation: Simulation, recovery: bool = False) -> str:
    """A short name of the setting, e.g. ``mujoco-torque``, ``kinematic-recovery`` or
    ``mujoco-torque-delay0.02-noise0.001``."""
    name = simulation.simulator
    if simulation.simulator != "kinematic":
        name += f"-{simulation.control}"
        if simulation.delay:
            name += f"-delay{simulation.delay:g}"
        if simulation.noise:
            name += f"-noise{simulation.noise:g}"
    return name + ("-recovery" if recovery else "")


def with_planners(experiment: Experiment, planners: tuple[str, ...]) -> Experiment:
    """``experiment`` comparing only ``planners`` (in its own order), e.g. the fabric of
    Experiment 1 without its MPC; unchanged for an empty tuple.

    Raises:
        ValueError: a name is not one of the experiment's planners (the message lists them).
    """
    unknown = [name for name in planners if name not in experiment.planners]
    if unknown:
        raise ValueError(f"{', '.join(unknown)} is not a planner of {experiment.name} "
                         f"(expected some of {', '.join(experiment.planners)})")
    if not planners:
        return experiment
    return dataclasses.replace(experiment, planners=tuple(p for p in experiment.planners if p in planners))
