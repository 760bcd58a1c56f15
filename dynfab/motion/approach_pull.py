"""The pull toward a grasp's approach segment (:class:`~dynfab.motion.guided_fabric.GuidedFabric`):
once the robot follows the approach, the position written into the fabric's goal is the
reference shifted across the checked straight segment,

    q_goal = q_r(τ) + k_p e + k_i ∫e dt,   ‖k_i ∫e dt‖ ≤ p_max,

``e`` the robot's step across to the segment's line
(:func:`~dynfab.motion.approach_segment.across_segment`; nothing along it, where a lag does
no harm), ``k_p, k_i, p_max`` = ``approach_pull``, ``approach_pull_rate``,
``approach_pull_limit`` [-, 1/s, rad]. What pushes the robot sideways (the root's damping
near the object, the obstacle leaves) then does not hold it beside the segment, where the
reference's clock waits for it (:mod:`dynfab.motion.reference_clock`). Once the reference has
ended the integral is dropped (``ended`` of :meth:`ApproachPull.shift`): wound up
in the approach, it kept the robot past the segment's line at the goal for seconds (decaying
with ``(1 + k_p)/k_i``, 3 s), and a goal 0.29 mm from a wall on the meshes (as posed MBM
cage/0076) was touched 0.65 mm deep. What it gives up: the
fabric tracks a point up to ``k_p ‖e‖ + p_max`` beside the planned reference (on the
segment's far side from the robot), while the reference's velocity and acceleration stay
the planned ones.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.approach_segment import across_segment
from dynfab.motion.guidance_settings import GuidanceSettings

__all__ = ["ApproachPull"]


class ApproachPull:
    """The shift ``k_p e + k_i ∫e dt`` of one approach (module docstring); its integral
    starts at zero."""

    def __init__(self, settings: GuidanceSettings, dof: int) -> None:
        self._settings = settings
        self._summed = np.zeros(dof)   # k_i ∫e dt [rad]

    def reset(self) -> None:
        """Start the integral again (a new plan)."""
        self._summed = np.zeros_like(self._summed)

    def shift(self, segment: NDArray[np.float64], q: NDArray[np.float64], dt: float,
              ended: bool = False) -> NDArray[np.float64]:
        """The shift [rad] for the robot at ``q`` on the approach's configurations ``segment``
        (k, n), ``dt`` [s] after the last one; ``ended``: the reference has ended, the integral
        starts again from zero (module docstring)."""
        settings = self._settings
        across = across_segment(segment, q)
        summed = (0.0 if ended else self._summed) + settings.approach_pull_rate * dt * across
        length = float(np.linalg.norm(summed))
        if length > settings.approach_pull_limit:
            summed *= settings.approach_pull_limit / length
        self._summed = summed
        return settings.approach_pull * across + summed
