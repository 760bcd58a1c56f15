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

from dataclasses import dataclass

from dynfab.scenario.model_errors import checked
from dynfab.scenario.model_types import Choice, Range
from dynfab.scenario.ranges import MAX_DELAY, MAX_NOISE

__all__ = ["CONTROLS", "SIMULATORS", "Simulation"]

SIMULATORS: tuple[str, ...] = ("kinematic", "mujoco")
CONTROLS: tuple[str, ...] = ("torque", "velocity", "position")
#: The values of each key, as in the scenario file.
SIMULATOR = Choice(SIMULATORS)
CONTROL = Choice(CONTROLS)
DELAY = Range(0.0, MAX_DELAY)
NOISE = Range(0.0, MAX_NOISE)


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

    Raises:
        ScenarioError: An unknown simulator or control, or a delay or noise outside its
            range (:mod:`dynfab.scenario.ranges`).
    """

    simulator: str = "kinematic"
    control: str = "torque"
    delay: float = 0.0
    noise: float = 0.0

    def __post_init__(self) -> None:
        for key, check in (("simulator", SIMULATOR), ("control", CONTROL), ("delay", DELAY), ("noise", NOISE)):
            checked(check.check, getattr(self, key), key)
