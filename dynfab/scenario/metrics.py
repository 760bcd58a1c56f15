"""Run metrics of docs/design.md section 6 (as in the paper and localPlannerBench).

All functions are pure numpy. Positions are in metres, times in seconds. For planar
robots distances are measured in the xy-plane: only the first two coordinates count
(a box, cylinder, capsule or plane is cut at the height of its centre).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dynfab.geometry.distance import shape_distance
from dynfab.geometry.shapes import Shape, quaternion_matrix
from dynfab.sim.simulator import Record


@dataclass(frozen=True)
class Metrics:
    """Metrics of one run; ``to_dict`` gives the ``dynfab run --json`` object.

    Attributes:
        success: Goal reached and no collision.
        goal_reached: The goal link came within tolerance of the goal (or reference).
        collision: Clearance went below zero.
        time_to_goal: First time within tolerance [s]; None if never.
        clearance: min over time, robot spheres i and obstacles j of
            ||p_i - p_j|| - r_i - r_j [m] (a shape j: its exact signed distance from
            p_i, minus r_i); None without obstacles.
        path_length: sum_k ||x_{k+1} - x_k|| of the goal link [m].
        summed_error: Path goals: mean ||x - x_ref|| from the first time within
            tolerance [m]; None for other goals or if never within tolerance.
        solver_time_ms: Mean wall time of one controller call [ms].
        steps: Number of control steps.
        orientation_error: Final orientation error of the primary pose or axis goal (else
            of the first one) [rad]: the angle of ``R_dᵀ R`` for a pose, the angle between
            ``R a`` and ``d`` for an axis; None without such goals.
        sphere_clearance: The sphere figure of ``clearance`` [m], kept when ``clearance``
            comes from collision meshes (scenario/exact_metrics.py); None without obstacles.
        self_collision: Two checked links touched: on the collision meshes at every
            control sample (scenario/exact_metrics.py; URDF robots and the built-in
            ``panda`` / ``boxer-panda``), or, under MuJoCo, in a contact between two links
            (``link_contacts``); None for robots measured by spheres without such a contact.
        min_self_distance: Smallest distance between checked links [m] (collision
            meshes); None for robots measured by spheres.
        max_velocity_ratio: ``max_t,i |u_i(t)| / u_max,i`` over the run's velocity
            coordinates (``robot.limits``); ≤ 1 when the limits held.
        max_acceleration_ratio: ``max_t,i |u̇_i(t)| / a_max,i`` of the commands.
        contacts: Under MuJoCo, how many contacts began (robot with an obstacle or two
            robot links of a self-collision pair, at every 1 ms physics step); one with an
            obstacle is a collision, one between two links a self-collision. None for the
            kinematic simulator.
        link_contacts: Under MuJoCo, how many of ``contacts`` were between two robot links
            (on the collision meshes for a robot measured by meshes, built-in Panda included;
            else between the spheres of a self-collision pair). None for the kinematic
            simulator.
        guided: A global joint-space plan was followed (scenario/guided_controller.py);
            False for the fabric alone and the MPC. These outcome keys
            (scenario/outcome.py) are None only for a replayed recording.
        plans: Global plans made (guidance's first plan and replans, or stall-recovery
            paths followed); 0 for the MPC.
        plan_time_ms: Wall time of the first global plan [ms]; None without one.
        recovered: Replans of guidance (blocked reference, stalled progress) or
            stall-recovery paths of the fabric alone (attempts that found no path are
            not counted); 0 for the MPC.
        fallbacks: Safe actions taken: fabric outputs replaced by braking, plus one if
            guidance could not plan and the fabric alone took over; for the MPC, solves
            that failed (the last plan, or braking, was executed).
        goal_moved: A plan guidance followed in the run went to a target moved inside the
            goal's tolerance (a task goal's within half its position and angle tolerances, a
            joint goal's configuration within half its tolerance; :mod:`dynfab.motion.goal_region`),
            not the goal itself; False for controllers that do not move goals.
        failure: Why the run failed, None on success: a guidance reason
            (``goal_outside_limits``, ``no_ik_solution``, ``start_in_collision``,
            ``goal_in_collision``, ``no_path``) when guidance could not plan, else
            ``collision``, ``self_collision``, or ``stalled`` (the goal not reached:
            ``final_distance`` says how far).
        final_distance: Distance of the primary goal's coordinates from the goal at the
            end of the run [m] (joint goals: [rad]).
    """

    success: bool
    goal_reached: bool
    collision: bool
    time_to_goal: float | None
    clearance: float | None
    path_length: float
    summed_error: float | None
    solver_time_ms: float
    steps: int
    orientation_error: float | None = None
    sphere_clearance: float | None = None
    self_collision: bool | None = None
    min_self_distance: float | None = None
    max_velocity_ratio: float | None = None
    max_acceleration_ratio: float | None = None
    contacts: int | None = None
    link_contacts: int | None = None
    guided: bool | None = None
    plans: int | None = None
    plan_time_ms: float | None = None
    recovered: int | None = None
    fallbacks: int | None = None
    goal_moved: bool | None = None
    failure: str | None = None
    final_distance: float | None = None

    def to_dict(self) -> dict[str, bool | int | float | None]:
        """The metrics as a JSON-ready dict with the keys of docs/design.md section 5.5."""
        return asdict(self)


class NamedContact(Protocol):
    """A contact that began under MuJoCo (:class:`dynfab.sim.mujoco_sim.Contact`)."""

    @property
    def other(self) -> str:
        """What the robot link touched: ``obstacles[k]``, or another robot link."""
        ...


def with_contacts(metrics: Metrics, contacts: Sequence[NamedContact]) -> Metrics:
    """``metrics`` of a MuJoCo run: its ``contacts`` and ``link_contacts`` counts; a contact
    with an obstacle makes a collision, one between two robot links a self-collision."""
    links = sum(1 for contact in contacts if not contact.other.startswith("obstacles["))
    collision = metrics.collision or len(contacts) > links
    self_collision = True if links else metrics.self_collision
    return replace(metrics, contacts=len(contacts), link_contacts=links, collision=collision,
                   self_collision=self_collision, success=metrics.success and not collision and not links)


def compute_metrics(
    record: Record,
    goal_link_positions: ArrayLike,
    goal: ArrayLike,
    tolerance: float,
    sphere_centers: ArrayLike,
    sphere_radii: ArrayLike,
    obstacle_centers: ArrayLike,
    obstacle_radii: ArrayLike,
    *,
    planar: bool = False,
    path_goal: bool = False,
    orientation_errors: ArrayLike | None = None,
    angle_tolerance: float | None = None,
    shape_clearance: ArrayLike | None = None,
    end_required: bool = False,
) -> Metrics:
    """Compute the metrics of a run.

    Args:
        record: The simulated run; its states are at ``record.t`` (T = N + 1 samples).
        goal_link_positions: Goal-link positions at ``record.t``, shape (T, d).
        goal: Goal position, shape (d,), or the reference at ``record.t``, shape (T, d).
        tolerance: The goal is reached when ||x - goal|| < tolerance [m].
        sphere_centers: Robot collision-sphere centres, shape (T, k, 3).
        sphere_radii: Their radii, shape (k,).
        obstacle_centers: Obstacle centres, shape (T, m, 3) (planar robots: 2 or 3).
        obstacle_radii: Their radii, shape (m,); m = 0 means no obstacles.
        planar: Measure every distance in the xy-plane.
        path_goal: ``goal`` is a path reference: report ``summed_error``.
        orientation_errors: Orientation errors at ``record.t``, shape (T,) [rad], of the
            goal ``orientation_error`` reports; None without orientation goals.
        angle_tolerance: If given, the goal is reached only when also
            ``orientation_errors < angle_tolerance`` [rad] (a primary pose or axis goal).
        shape_clearance: Clearance to the other obstacle shapes at each sample, shape (T,)
            (:func:`shape_clearance_over_time`), counted with the spheres'.
        end_required: The goal counts as reached only if it is also within tolerance at
            the last sample (a path that ends at rest before the run does: following its
            start is not reaching its end).

    Returns:
        The metrics.

    Raises:
        ValueError: If the arrays do not match the record's T samples.
    """
    positions = _workspace(goal_link_positions, planar)
    target = _workspace(goal, planar)
    if positions.shape[0] != record.t.shape[0]:
        raise ValueError(
            f"goal_link_positions has {positions.shape[0]} samples, the record {record.t.shape[0]}"
        )
    errors = np.linalg.norm(positions - target, axis=-1)
    angles = None if orientation_errors is None else np.asarray(orientation_errors, dtype=float)
    if angles is not None and angles.shape != errors.shape:
        raise ValueError(f"orientation_errors has shape {angles.shape}, expected {errors.shape}")
    if angle_tolerance is not None and angles is None:
        raise ValueError("angle_tolerance needs orientation_errors")
    within = errors < tolerance
    if angle_tolerance is not None:
        within &= angles < angle_tolerance
    below = np.flatnonzero(within)
    first = int(below[0]) if below.size else None   # first time within tolerance
    reached = first if within[-1] or not end_required else None
    clearances = clearance_over_time(
        sphere_centers, sphere_radii, obstacle_centers, obstacle_radii, planar=planar
    )
    if shape_clearance is not None:
        clearances = np.minimum(clearances, np.asarray(shape_clearance, dtype=float))
    clearance = float(np.min(clearances)) if np.isfinite(clearances).any() else None
    collision = clearance is not None and clearance < 0.0
    return Metrics(
        success=reached is not None and not collision,
        goal_reached=reached is not None,
        collision=collision,
        time_to_goal=None if reached is None else float(record.t[reached]),
        clearance=clearance,
        path_length=path_length(positions),
        summed_error=_mean_from(errors, first) if path_goal else None,
        solver_time_ms=float(np.mean(record.solver_time)) * 1e3,
        steps=record.steps,
        orientation_error=None if angles is None else float(angles[-1]),
        sphere_clearance=clearance,
    )


def clearance_over_time(
    sphere_centers: ArrayLike,
    sphere_radii: ArrayLike,
    obstacle_centers: ArrayLike,
    obstacle_radii: ArrayLike,
    *,
    planar: bool = False,
) -> NDArray[np.float64]:
    """Clearance at each sample: min over i, j of ||p_i(t) - p_j(t)|| - r_i - r_j [m].

    Args:
        sphere_centers: Robot sphere centres, shape (T, k, 3).
        sphere_radii: Robot sphere radii, shape (k,).
        obstacle_centers: Obstacle centres, shape (T, m, 3) (planar robots: 2 or 3).
        obstacle_radii: Obstacle radii, shape (m,).
        planar: Use xy distances (spheres act as discs).

    Returns:
        Shape (T,); +inf at every sample if there are no spheres or no obstacles.
    """
    spheres = _workspace(sphere_centers, planar)
    obstacles = _workspace(obstacle_centers, planar)
    r_spheres = np.asarray(sphere_radii, dtype=float)
    r_obstacles = np.asarray(obstacle_radii, dtype=float)
    if (
        spheres.ndim != 3
        or obstacles.ndim != 3
        or spheres.shape[0] != obstacles.shape[0]
        or spheres.shape[2] != obstacles.shape[2]
    ):
        raise ValueError(
            f"expected centres of shape (T, k, d) and (T, m, d), got {spheres.shape} "
            f"and {obstacles.shape}"
        )
    if spheres.shape[1] == 0 or obstacles.shape[1] == 0:
        return np.full(spheres.shape[0], np.inf)
    gaps = np.linalg.norm(spheres[:, :, None, :] - obstacles[:, None, :, :], axis=-1)
    gaps -= r_spheres[None, :, None] + r_obstacles[None, None, :]
    return np.min(gaps, axis=(1, 2))


def shape_clearance_over_time(
    sphere_centers: ArrayLike,
    sphere_radii: ArrayLike,
    shapes: Sequence[Shape],
    orientations: Sequence[Sequence[float]],
    shape_centers: ArrayLike,
    *,
    planar: bool = False,
) -> NDArray[np.float64]:
    """Clearance at each sample: min over robot spheres i and shapes j of
    ``d_j(R_jᵀ (p_i(t) − c_j(t))) − r_i`` [m], with ``d_j`` the exact signed distance of
    :func:`dynfab.geometry.distance.shape_distance`.

    Args:
        sphere_centers: Robot sphere centres, shape (T, k, 3).
        sphere_radii: Robot sphere radii, shape (k,).
        shapes: The m shapes, each in its own frame.
        orientations: Their frames' unit quaternions (w, x, y, z).
        shape_centers: Their frames' origins, shape (T, m, 3) (a plane: its point).
        planar: Robot spheres act at the height of each shape's origin (their z is ignored).

    Returns:
        Shape (T,); +inf at every sample if there are no spheres or no shapes.
    """
    spheres = np.asarray(sphere_centers, dtype=float)
    centers = np.asarray(shape_centers, dtype=float)
    radii = np.asarray(sphere_radii, dtype=float)
    if spheres.ndim != 3 or centers.shape != (spheres.shape[0], len(shapes), 3):
        raise ValueError(f"expected sphere centres (T, k, 3) and shape centres (T, {len(shapes)}, 3), "
                         f"got {spheres.shape} and {centers.shape}")
    clearance = np.full(spheres.shape[0], np.inf)
    if spheres.shape[1] == 0:
        return clearance
    for j, (shape, orientation) in enumerate(zip(shapes, orientations)):
        offsets = spheres - centers[:, j, None, :]
        if planar:
            offsets[..., 2] = 0.0
        distances = shape_distance(shape, offsets @ quaternion_matrix(orientation)) - radii[None, :]
        clearance = np.minimum(clearance, distances.min(axis=1))
    return clearance


def path_length(positions: ArrayLike) -> float:
    """Length of a sampled path: sum_k ||x_{k+1} - x_k|| [m], positions of shape (T, d)."""
    points = np.asarray(positions, dtype=float)
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=-1)))


def summed_error(positions: ArrayLike, reference: ArrayLike, tolerance: float) -> float | None:
    """Path-following error: mean ||x(t) - x_ref(t)|| from the first time it is < tolerance.

    Args:
        positions: Goal-link positions x(t), shape (T, d).
        reference: Reference positions x_ref(t) at the same times, shape (T, d).
        tolerance: Distance at which the reference counts as caught up [m].

    Returns:
        The mean distance [m] over the samples from that time on; None if never reached.
    """
    errors = np.linalg.norm(
        np.asarray(positions, dtype=float) - np.asarray(reference, dtype=float), axis=-1
    )
    return _mean_from(errors, _first_within(errors, tolerance))


def _first_within(errors: NDArray[np.float64], tolerance: float) -> int | None:
    """Index of the first error below ``tolerance``; None if there is none."""
    below = np.flatnonzero(errors < tolerance)
    return int(below[0]) if below.size else None


def _mean_from(errors: NDArray[np.float64], start: int | None) -> float | None:
    """Mean of ``errors[start:]``; None if ``start`` is None."""
    return None if start is None else float(np.mean(errors[start:]))


def _workspace(points: ArrayLike, planar: bool) -> NDArray[np.float64]:
    """Points as a float array; for planar robots only their x and y coordinates."""
    array = np.asarray(points, dtype=float)
    return array[..., :2] if planar else array
