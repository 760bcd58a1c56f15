"""The scenario keys that choose the simulator and, under MuJoCo, the robot's control.

```yaml
simulator: kinematic   # kinematic (default) | mujoco
control: torque        # mujoco only: torque (default) | velocity | position
delay: 0.0             # mujoco only: age of the state the planner sees [s], >= 0
noise: 0.0             # mujoco only: std of Gaussian noise on what the planner sees,
                       #   [rad or m] on q, [rad/s or m/s] on the velocities, >= 0
```
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dynfab.scenario import fields
from dynfab.scenario.fields import ScenarioError

__all__ = ["CONTROLS", "SIMULATION_KEYS", "SIMULATORS", "Simulation", "parse_simulation"]

SIMULATORS: tuple[str, ...] = ("kinematic", "mujoco")
CONTROLS: tuple[str, ...] = ("torque", "velocity", "position")
#: The top-level keys read here.
SIMULATION_KEYS: tuple[str, ...] = ("simulator", "control", "delay", "noise")


@dataclass(frozen=True)
class Simulation:
    """How a scenario is simulated.

    Attributes:
        simulator: ``kinematic`` (the robot follows the commanded acceleration exactly)
            or ``mujoco`` (physics, joint controllers at 1 kHz).
        control: Under MuJoCo, the joints' control interface: ``torque``, ``velocity``
            or ``position``.
        delay: Under MuJoCo, the age of the state the planner sees [s].
        noise: Under MuJoCo, the standard deviation of the Gaussian noise on the state the
            planner sees [rad or m on q, rad/s or m/s on the velocities].
    """

    simulator: str = "kinematic"
    control: str = "torque"
    delay: float = 0.0
    noise: float = 0.0

    def __post_init__(self) -> None:
        fields.choice(self.simulator, "simulator", SIMULATORS)
        fields.choice(self.control, "control", CONTROLS)
        for key in ("delay", "noise"):
            if fields.number(getattr(self, key), key) < 0.0:
                raise ScenarioError(key, f"must be >= 0, got {getattr(self, key):g}")


def parse_simulation(root: Mapping[str, Any]) -> Simulation:
    """The simulation keys of a scenario's top level (defaults for those it omits).

    Raises:
        ScenarioError: An unknown simulator or control, a negative or non-finite delay or
            noise, or ``control``, ``delay`` or ``noise`` without ``simulator: mujoco``.
    """
    simulation = Simulation(
        simulator=root.get("simulator", "kinematic"), control=root.get("control", "torque"),
        delay=root.get("delay", 0.0), noise=root.get("noise", 0.0))
    if simulation.simulator != "mujoco":
        for key in ("control", "delay", "noise"):
            if key in root:
                raise ScenarioError(key, "applies to simulator: mujoco only (the kinematic simulator follows "
                                    "the planner exactly)")
    return simulation
