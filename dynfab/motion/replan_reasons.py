"""Why a guided fabric asks for a replan: :class:`ReplanWatch` keeps the timers and
:func:`counted` the tally (:class:`~dynfab.motion.guided_fabric.GuidedFabric` keeps the plan,
its clock and the robot, and asks the watch every tick no plan is pending). A replan is asked
for when

- the run stalls: while the reference runs, the robot has stayed more than ``lag_slow``
  behind it for ``stall_lag_time`` seconds (outside an approach: ``held``), or the clock
  ``τ`` has not advanced by ``stall_rate · stall_window`` within ``stall_window`` seconds
  (the robot is held back: ``held``); on an approach the robot follows, the joint-space
  distance to the goal configuration has not come ``stall_floor`` below its best for
  ``stall_window`` seconds (the clock waits for a robot the obstacle leaves slow down; it
  still closes in: ``stalled``); once the reference has ended, that distance has not come
  ``max(stall_floor, stall_progress · d₀)`` below its best for ``stall_window`` seconds
  (``d₀``: its distance when the goal was set, so the test scales with the motion asked
  for: ``stalled``). A detour that leads away from the goal is progress as long as it is
  followed;
- the robot is held short of the approach (``short``): the reference waits at the
  approach's start and the robot has stayed more than ``approach_lag_stop`` from it for
  ``approach_hold_time`` seconds;
- what moves asks for it (checked every ``check_period``, and not within
  ``blocked_interval`` of a blocked or refuge replan): the reference within
  ``check_horizon`` ahead meets what a moving obstacle sweeps within ``sweep_horizon``
  (``blocked``), or the robot makes way for what sweeps the goal (``refuge``, ``return``:
  :func:`~dynfab.motion.making_way.moving_reason`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GuidanceSettings, JointGuidance, Plan
from dynfab.motion.guidance_status import GuidanceStatus
from dynfab.motion.making_way import moving_reason
from dynfab.motion.reference_clock import in_approach, run_progress

__all__ = ["ReplanWatch", "counted"]

#: the :class:`GuidanceStatus` count each replan reason adds to (``return`` adds to none)
_COUNTS = {"held": "replans_stalled", "short": "replans_stalled", "stalled": "replans_stalled",
           "refuge": "refuges", "blocked": "replans_blocked"}


def counted(status: GuidanceStatus, reason: str | None) -> GuidanceStatus:
    """``status`` with the count of ``reason`` (:data:`_COUNTS`) one higher."""
    count = _COUNTS.get(reason) if reason is not None else None
    return status if count is None else replace(status, **{count: getattr(status, count) + 1})


class ReplanWatch:
    """The timers behind a guided fabric's replan reasons (module docstring)."""

    def __init__(self, settings: GuidanceSettings) -> None:
        self._settings = settings
        self._lagging_since: float | None = None   # since when the robot lags on the way [s]
        self._short_since: float | None = None     # since when it is held short of the approach [s]
        self._stage: str | None = None             # run_progress's stage at the best progress
        self._best = np.inf                        # the best progress in that stage
        self._best_time = 0.0                      # when it was reached [s]
        self._next_check = 0.0                     # when what moves is checked next [s]
        self._ended_needed = settings.stall_floor  # progress needed after the reference ended [rad]

    def scale_to(self, distance: float) -> None:
        """Scale the progress needed once the reference has ended to a goal ``distance``
        [rad] from where the robot was when it was set: ``max(stall_floor, stall_progress · d₀)``."""
        self._ended_needed = max(self._settings.stall_floor, self._settings.stall_progress * distance)

    def restart(self, t: float, pause: bool) -> None:
        """Start watching a new plan (or the old one after a failed replan) at time ``t`` [s];
        ``pause``: check what moves no sooner than ``blocked_interval`` from now."""
        self._stage, self._best, self._best_time = None, np.inf, t
        self._next_check = t + (self._settings.blocked_interval if pause else 0.0)
        self._lagging_since = self._short_since = None

    def reason(self, t: float, q: NDArray[np.float64], lag: float, plan: Plan, tau: float, approaching: bool,
               guidance: JointGuidance, home: NDArray[np.float64] | None,
               moving: Sequence[PlacedObstacle]) -> str | None:
        """Why to replan at time ``t`` [s] the robot at ``q`` [rad], ``lag`` = ``‖q − q_r‖``
        [rad] behind the reference of ``plan`` at its clock ``tau`` [s] (``approaching``:
        the robot follows its approach; ``home``: the goal configuration while at a refuge):
        ``held`` if progress stalled on the way (the reference running, not in an approach),
        ``short`` if the robot is held short of the approach's start, ``stalled`` if it
        stalled elsewhere, else what ``moving`` asks for (``return``, ``refuge``,
        ``blocked``: :func:`~dynfab.motion.making_way.moving_reason`) or None."""
        settings = self._settings
        running = tau < plan.trajectory.duration
        approach = in_approach(plan, tau)
        if running and not approach and lag > settings.lag_slow:
            self._lagging_since = t if self._lagging_since is None else self._lagging_since
        else:
            self._lagging_since = None
        if self._lagging_since is not None and t - self._lagging_since > settings.stall_lag_time:
            return "held"
        if running and approach and not approaching and lag > settings.approach_lag_stop:
            self._short_since = t if self._short_since is None else self._short_since
        else:
            self._short_since = None
        if self._short_since is not None and t - self._short_since > settings.approach_hold_time:
            return "short"
        stage, progress, needed = run_progress(settings, plan, tau, approaching, q, self._ended_needed)
        if progress < self._best - needed or stage != self._stage:
            self._stage, self._best, self._best_time = stage, progress, t
        at_goal = stage == "ended" and progress <= settings.stall_floor
        if not at_goal and t - self._best_time > settings.stall_window:
            return "held" if running and not approach else "stalled"
        if moving and t >= self._next_check:
            self._next_check = t + settings.check_period
            return moving_reason(guidance, plan, tau, q, home, moving)
        return None
