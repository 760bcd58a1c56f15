"""Making way for what moves through the goal: a refuge out of its way until it has passed.

A replan leaves out a moving sphere that touches the goal configuration: it is passing
the goal, and a plan around it would end in a needless escape (:mod:`dynfab.motion.plan_requests`).
At the goal such a sphere is the fabric's alone to avoid, and where the goal is among
static obstacles its leaves can only push the arm into them: on moving-sphere MBM
bookshelf_thin/0087 (``--seed 1``, problems 81-96) a sphere of 5.6 cm at 0.42 m/s swept
the forearm of an arm holding a grasp inside a shelf, and the sphere's leaf swung the hand
through a 4 cm shelf wall (53.7 mm deep on the meshes) at 3 rad/s. No weighting of the two
leaves kept it clear (tried: the shapes' energy 0 to 0.5, their range 10 cm, the sphere's
braking 1 m/s² or none, its gain 1, its margin 1.5 cm), and a refuge sought only once the
robot held the goal was 1 rad away and too late.

So a guided fabric does not wait at its goal for the sphere: while the capsule a moving
sphere sweeps over ``sweep_horizon`` (:func:`~dynfab.motion.swept_obstacles.swept_obstacle`)
comes within the planner's margin of the goal configuration (:func:`sweeps`), it asks for
a *refuge* (:func:`moving_reason`): the robot's own configuration if no such capsule comes
within the margin of it, else, among configurations sampled about it at growing
joint-space radii :data:`REFUGE_RADII`, the nearest that keeps the margin from every such
capsule and from the static obstacles (no less than the robot keeps now: a grasp is
closer than the margin) and whose straight way keeps them from the static obstacles and
the spheres where they are; the way is timed at the robot's full limits
(:func:`refuge_plan`). At the refuge it seeks another if a capsule comes at the robot,
and it replans to the goal once none comes within the margin of the goal configuration.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GuidanceError, JointGuidance, Plan
from dynfab.motion.joint_trajectory import TimingError, time_path
from dynfab.motion.swept_obstacles import swept_clear_of, swept_obstacle

__all__ = ["REFUGE_RADII", "REFUGE_SAMPLES", "moving_reason", "refuge", "refuge_plan", "swept_capsules", "sweeps"]

#: joint-space distances [rad] from the robot at which refuges are sampled, nearest first
REFUGE_RADII = (0.15, 0.3, 0.6, 1.0)
#: configurations sampled at each radius [-]
REFUGE_SAMPLES = 64


def swept_capsules(guidance: JointGuidance, moving: Sequence[PlacedObstacle]) -> tuple[PlacedObstacle, ...]:
    """What each of the ``moving`` spheres sweeps over ``sweep_horizon``
    (:func:`~dynfab.motion.swept_obstacles.swept_obstacle`; a sphere at rest: itself)."""
    return tuple(swept_obstacle(o, guidance.settings.sweep_horizon) for o in moving)


def sweeps(guidance: JointGuidance, q: NDArray[np.float64], moving: Sequence[PlacedObstacle],
           capsules: Sequence[PlacedObstacle] | None = None) -> tuple[PlacedObstacle, ...]:
    """The capsules the ``moving`` spheres sweep over ``sweep_horizon`` that come within the
    planner's margin of the robot at ``q`` [rad] (a sphere at rest sweeps none: one resting
    on the goal is not passing it, and the fabric avoids it there); ``capsules``: their
    :func:`swept_capsules` if already built."""
    capsules = swept_capsules(guidance, moving) if capsules is None else capsules
    return tuple(c for c, o in zip(capsules, moving)
                 if c is not o and guidance.obstacle_clearance(q, c) < guidance.settings.path.margin)


def moving_reason(guidance: JointGuidance, plan: Plan, tau: float, q: NDArray[np.float64],
                  home: NDArray[np.float64] | None, moving: Sequence[PlacedObstacle]) -> str | None:
    """Why the ``moving`` obstacles ask a guided fabric following ``plan`` (its clock at
    ``tau`` [s], the robot at ``q`` [rad]) for a new plan: ``return`` to ``home`` (the goal
    configuration, while at a refuge) once nothing sweeps it; ``refuge`` while something
    sweeps the goal configuration (at a refuge: the robot); ``blocked`` if the reference
    within ``check_horizon`` meets what they sweep (each capsule shortened until it clears
    the robot, :func:`~dynfab.motion.swept_obstacles.swept_clear_of`); else None."""
    capsules = swept_capsules(guidance, moving)
    if home is not None and not sweeps(guidance, home, moving, capsules):
        return "return"
    if sweeps(guidance, plan.goal if home is None else q, moving, capsules):
        return "refuge"
    settings = guidance.settings
    swept = [swept_clear_of(o, settings.sweep_horizon, (q,), guidance.obstacle_clearance, settings.path.margin)
             for o in moving]
    return "blocked" if guidance.blocked_ahead(plan, tau, swept) else None


def refuge(guidance: JointGuidance, q: NDArray[np.float64], static: Sequence[PlacedObstacle],
           moving: Sequence[PlacedObstacle], seed: int) -> NDArray[np.float64] | None:
    """``q`` [rad] if it keeps the planner's margin from the capsules the ``moving`` spheres
    sweep over ``sweep_horizon``, else the configuration nearest it among
    :data:`REFUGE_SAMPLES` at each radius of :data:`REFUGE_RADII` (uniform directions,
    within guidance's joint bounds; ``seed``) that keeps the planner's margin from those
    capsules, from ``static`` no less than ``q`` does up to the margin, and the
    self-collision margin, and whose straight way from ``q`` keeps them from ``static`` and
    the ``moving`` spheres where they are; None if none does."""
    settings = guidance.settings.path
    capsules = swept_capsules(guidance, moving)
    lower, upper = guidance.bounds
    rng = np.random.default_rng(seed)
    checker = guidance.checker
    checker.set_obstacles(capsules)
    if checker.free(q, settings.margin, -np.inf):
        return q
    checker.set_obstacles(tuple(static))
    near = min(settings.margin, checker.clearances(q)[0])   # a grasp: closer to the static ones than the margin
    for radius in REFUGE_RADII:
        directions = rng.normal(size=(REFUGE_SAMPLES, len(q)))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        candidates = np.clip(q + radius * directions, lower, upper)
        checker.set_obstacles(capsules)
        clear = [c for c in candidates if checker.free(c, settings.margin, settings.self_margin)]
        checker.set_obstacles(tuple(static))
        clear = sorted((c for c in clear if checker.free(c, near, settings.self_margin)),
                       key=lambda c: float(np.linalg.norm(c - q)))
        for candidate in clear:
            if checker.motion_free(q, candidate, settings.resolution, near, settings.self_margin)[0]:
                return candidate
    return None


def refuge_plan(guidance: JointGuidance, q: NDArray[np.float64], static: Sequence[PlacedObstacle],
                moving: Sequence[PlacedObstacle], seed: int) -> Plan:
    """The straight motion from ``q`` [rad] to its :func:`refuge` from what the ``moving``
    spheres sweep, timed at the robot's full velocity and acceleration limits (an evasion,
    not a cruise: the sphere is at most ``sweep_horizon`` away) (module docstring).

    Raises:
        GuidanceError: ``no_refuge`` if no sampled configuration is clear, ``timing`` if
            the motion cannot be timed.
    """
    began = time.perf_counter()
    start = np.asarray(q, dtype=float)
    target = refuge(guidance, start, static, moving, seed)
    if target is None:
        raise GuidanceError("no_refuge", f"no configuration within {REFUGE_RADII[-1]} rad of the robot keeps "
                                         f"{guidance.settings.path.margin} m from what the moving obstacles sweep")
    limits = guidance.robot.limits
    try:
        trajectory = time_path(np.vstack([start, target]), limits.velocity, limits.acceleration,
                               guidance.settings.timing)
    except TimingError as failure:
        raise GuidanceError("timing", str(failure)) from None
    return Plan(trajectory, target, time.perf_counter() - began, 0, 0.0, trajectory.duration)
