"""Making way for what moves through the goal: a refuge beside it until it has passed.

A replan leaves out a moving sphere that touches the goal configuration: it is passing
the goal, and a plan around it would end in a needless escape (:mod:`dynfab.motion.plan_requests`).
Once the robot holds its goal, such a sphere is the fabric's alone to avoid, and where
the goal is among static obstacles its leaves can only push the arm into them: on
moving-sphere MBM bookshelf_thin/0087 (``--seed 1``, problems 81-96) a sphere of 5.6 cm
at 0.42 m/s swept the forearm of an arm holding a grasp inside a shelf, and the sphere's
leaf swung the hand through a 4 cm shelf wall (53.7 mm deep on the meshes) at 3 rad/s.
No weighting of the two leaves kept it clear (tried: the shapes' energy 0 to 0.5, their
range 10 cm, the sphere's braking 1 m/s² or none, its gain 1, its margin 1.5 cm).

A guided fabric holding its goal therefore asks for a *refuge* when the capsule a moving
sphere sweeps over ``sweep_horizon`` (:func:`~dynfab.motion.swept_obstacles.swept_obstacle`)
comes within the planner's margin of the robot: among configurations sampled about the
robot's at growing joint-space radii :data:`REFUGE_RADII`, the nearest that keeps the
margin from the static obstacles and from every such capsule and whose straight way
keeps it from the static obstacles and the spheres where they are, reached at the robot's
full limits (:func:`refuge_plan`). It returns to
its goal once no capsule comes within the margin of the goal configuration
(:func:`sweeps`), by a replan.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from dynfab.motion.configuration_checker import PlacedObstacle
from dynfab.motion.guidance import GuidanceError, JointGuidance, Plan
from dynfab.motion.joint_trajectory import TimingError, time_path
from dynfab.motion.swept_obstacles import swept_obstacle

__all__ = ["REFUGE_RADII", "REFUGE_SAMPLES", "refuge", "refuge_plan", "sweeps"]

#: joint-space distances [rad] from the robot at which refuges are sampled, nearest first
REFUGE_RADII = (0.15, 0.3, 0.6, 1.0)
#: configurations sampled at each radius [-]
REFUGE_SAMPLES = 64


def sweeps(guidance: JointGuidance, q: NDArray[np.float64],
           moving: Sequence[PlacedObstacle]) -> tuple[PlacedObstacle, ...]:
    """The capsules the ``moving`` spheres sweep over ``sweep_horizon`` that come within the
    planner's margin of the robot at ``q`` [rad]."""
    settings = guidance.settings
    capsules = (swept_obstacle(o, settings.sweep_horizon) for o in moving)
    return tuple(c for c in capsules if guidance.obstacle_clearance(q, c) < settings.path.margin)


def refuge(guidance: JointGuidance, q: NDArray[np.float64], static: Sequence[PlacedObstacle],
           capsules: Sequence[PlacedObstacle], moving: Sequence[PlacedObstacle], seed: int) -> NDArray[np.float64] | None:
    """The configuration nearest ``q`` [rad] among :data:`REFUGE_SAMPLES` at each radius of
    :data:`REFUGE_RADII` (uniform directions, within the joint limits; ``seed``) that keeps
    the planner's margin and self-collision margin from ``static`` and ``capsules``, and
    whose straight way from ``q`` keeps them from ``static`` and the ``moving`` spheres
    where they are; None if none does."""
    settings = guidance.settings.path
    kinematics = guidance.robot.kinematics
    lower = np.where(np.isfinite(kinematics.lower), kinematics.lower, -np.pi)
    upper = np.where(np.isfinite(kinematics.upper), kinematics.upper, np.pi)
    rng = np.random.default_rng(seed)
    checker = guidance.checker
    checker.set_obstacles(tuple(capsules))
    if checker.free(q, settings.margin, -np.inf):
        return q
    checker.set_obstacles(tuple(static))
    near = min(settings.margin, checker.clearances(q)[0])   # a grasp: closer to the static ones than the margin
    for radius in REFUGE_RADII:
        directions = rng.normal(size=(REFUGE_SAMPLES, len(q)))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        candidates = np.clip(q + radius * directions, lower, upper)
        checker.set_obstacles(tuple(capsules))
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
    target = refuge(guidance, start, static, sweeps(guidance, start, moving), moving, seed)
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
