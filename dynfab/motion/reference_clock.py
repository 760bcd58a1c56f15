"""The clock ``τ`` of a guided fabric's reference (:class:`~dynfab.motion.guided_fabric.GuidedFabric`):
how fast it runs while the robot follows, and the progress a run is judged on
(:func:`run_progress`).

It slows while the robot lags behind the reference (a moving obstacle in the way):

    ρ = clip((e_stop − e) / (e_stop − e_slow), 0, 1),   e = ‖q − q_r(τ)‖,
    τ ← τ + ρ Δt,   q̇_r ← ρ q̇_r(τ),   q̈_r ← ρ² q̈_r(τ),

with ``e_slow, e_stop`` = ``lag_slow, lag_stop`` on the way; ``close_lag_slow,
close_lag_stop`` in the last ``close_time`` of the way before a grasp's approach and on the
whole way of a plan made after the robot was held short of one (a robot lagging there cuts
the corner into the approach and is held by what it passes); and ``approach_lag_slow,
approach_lag_stop`` in the approach, where ``ρ`` is also at most ``clip((o_stop − o) /
(o_stop − o_slow), 0, 1)``, ``o`` the robot's distance from the approach's straight segment
[rad] (``approach_offset_slow``, ``approach_offset_stop``): the segment is what the planner
checked; along it a lag does no harm, beside it the hand nears what it is to grasp. So
that the clock seldom has to wait there, the guided fabric pulls the robot back toward the
segment once it follows the approach (``approach_pull``: its goal's position is ``q_r(τ)``
shifted across the segment by ``k_p e + k_i ∫e dt``; :class:`~dynfab.motion.guided_fabric.GuidedFabric`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.guidance import Plan
from dynfab.motion.guidance_settings import GuidanceSettings

__all__ = ["approach_rate", "in_approach", "run_progress", "way_rate"]


def way_rate(settings: GuidanceSettings, lag: float, close: bool) -> float:
    """``ρ`` [-] on the way for a lag ``e`` [rad]; ``close``: near or after an approach
    the robot was held short of (module docstring)."""
    if close:
        return _ramp(lag, settings.close_lag_slow, settings.close_lag_stop)
    return _ramp(lag, settings.lag_slow, settings.lag_stop)


def approach_rate(settings: GuidanceSettings, lag: float, offset: float) -> float:
    """``ρ`` [-] in the approach for a lag ``e`` and an offset ``o`` from its segment [rad]
    (module docstring)."""
    return min(_ramp(lag, settings.approach_lag_slow, settings.approach_lag_stop),
               _ramp(offset, settings.approach_offset_slow, settings.approach_offset_stop))


def in_approach(plan: Plan, tau: float) -> bool:
    """Whether the clock ``tau`` [s] of ``plan``'s reference is in the plan's approach."""
    return plan.approach > 0.0 and tau >= plan.approach_start


def run_progress(settings: GuidanceSettings, plan: Plan, tau: float, approaching: bool, q: NDArray[np.float64],
                 ended_needed: float) -> tuple[str, float, float]:
    """The stage a run following ``plan`` is in at its clock ``tau`` [s], its measure of
    progress (smaller is better) and the least decrease of it expected within
    ``stall_window``: on the way (``way``), the reference's clock ``−τ`` [s] must advance;
    on the approach once the robot follows it (``approaching``: ``approach``), however slowly
    the clock runs there, and after the reference ended (``ended``), the joint-space distance
    of ``q`` to the goal configuration [rad] must shrink, by ``stall_floor`` on the approach,
    by ``ended_needed`` [rad] after it."""
    distance = float(np.linalg.norm(q - plan.goal))
    if tau >= plan.trajectory.duration:
        return "ended", distance, ended_needed
    if approaching:
        return "approach", distance, settings.stall_floor
    return "way", -tau, settings.stall_rate * settings.stall_window


def _ramp(error: float, slow: float, stop: float) -> float:
    """1 up to ``slow``, 0 from ``stop`` on, linear between."""
    return float(np.clip((stop - error) / (stop - slow), 0.0, 1.0))
