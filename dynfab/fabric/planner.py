"""The fabric planner: leaves composed into the root and compiled into one function.

``FabricPlanner(robot, config)`` builds, in CasADi SX, the joint-space fabric

- one point map per robot collision sphere (forward kinematics, ``J``, ``J̇ q̇``);
- obstacle leaves (sphere slots and shape slots: boxes, cylinders, capsules, planes)
  summed in each sphere's point space, then pulled once per sphere;
- self-collision leaves on sphere pairs, joint-limit leaves on joints, a base energy;
- goal forcing on the goal links (a point on the link, or the directions of link axes:
  :mod:`dynfab.fabric.leaves.orientation`) or joints;
- the root of :mod:`dynfab.fabric.speed_control` (static, or dynamic with goal and obstacle
  velocities and accelerations);
- for a differential-drive base, the least-squares solve of :mod:`dynfab.fabric.nonholonomic`;

and compiles ONE function ``z = [q, q̇, p] ↦ q̈`` (``[q, q̇_u, p] ↦ q̈_u`` on a base). The
runtime parameters ``p`` (goals, weights, obstacle slots) are written through
:attr:`FabricPlanner.parameters`; calling
:meth:`FabricPlanner.compute` then costs one buffer evaluation, with no per-argument
conversion.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import replace

import casadi as ca
import numpy as np

from dynfab.fabric.backends import planner_function
from dynfab.fabric.batch import BatchEvaluator
from dynfab.fabric.command_bounds import CommandBounds
from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.leaf import Leaf, LeafContext
from dynfab.fabric.leaves.orientation import OrientationGoalConfig, direction_map
from dynfab.fabric.joint_reference import joint_reference
from dynfab.fabric.maps import DifferentialMap, Reference, linear_map, selected
from dynfab.fabric.nonholonomic import least_squares_acceleration, velocity_map, velocity_map_derivative
from dynfab.fabric.point_maps import link_point_maps
from dynfab.fabric.parameters import ParameterLayout, ParameterSymbols, RuntimeParameters
from dynfab.robots.robot import Robot
from dynfab.fabric.spec import Spec
from dynfab.fabric.speed_control import EnvironmentMotion
from dynfab.fabric.planner_config import GoalConfig, PlannerConfig
from dynfab.sim.models import motion_model_for

__all__ = ["FabricPlanner", "GoalConfig", "PlannerConfig"]

_AXES = "xyz"


class FabricPlanner:
    """An optimization fabric for one robot: static or dynamic, holonomic or on a
    differential-drive base (see module docstring).

    Attributes:
        robot: the robot.
        config: the configuration it was built with.
        parameters: writable views of the runtime parameters.
        function: the CasADi function ``z ↦ q̈`` (SX, or the loaded C library).
        backend: the backend in use, ``"vm"`` or ``"c"`` (``"vm"`` if no compiler was found).
        build_time_s: wall time of building and compiling [s].
        fallback_count: how many calls returned the fallback action.
    """

    def __init__(self, robot: Robot, config: PlannerConfig) -> None:
        start = time.perf_counter()
        self.robot = robot
        if config.limits is None:
            config = replace(config, limits=robot.limits)
        elif config.limits.names != robot.limits.names:
            raise ValueError(f"PlannerConfig.limits must name {', '.join(robot.limits.names)}")
        self.config = config
        self._n = robot.kinematics.dof
        self._nv = self._n - 1 if robot.base is not None else self._n
        goal_dimensions = tuple(self._goal_dimension(goal) for goal in config.goals)
        leaf_parameters = tuple((leaf.name, tuple(leaf.parameter_sizes().items())) for leaf in config.leaves)
        self._layout = ParameterLayout(goal_dimensions, config.obstacle_slots, config.dynamic, config.shape_slots,
                                       leaf_parameters)
        self._remembers_command = config.bound_command and config.limits.jerk is not None
        built = planner_function(config.backend, self._build, (robot, config))
        self.function, self.backend, self._n_instructions = built.function, built.backend, built.n_instructions
        state_size = self._n + self._nv
        self._input = np.zeros(state_size + self._layout.size + (self._nv if self._remembers_command else 0))
        self._output = np.zeros(self._nv)
        self._buffer, self._evaluate = self.function.buffer()
        self._buffer.set_arg(0, memoryview(self._input))
        self._buffer.set_res(0, memoryview(self._output))
        self.parameters: RuntimeParameters = self._layout.views(
            self._input[state_size:state_size + self._layout.size])
        self._previous_command = self._input[state_size + self._layout.size:]
        for i, goal in enumerate(config.goals):
            self.parameters.goal_weight[i] = goal.weight
        self._batch = BatchEvaluator(self.function, self._n, self._nv, self._layout.size)
        self.fallback_count = 0
        self._motion = motion_model_for(robot.base is not None)
        self.build_time_s = time.perf_counter() - start

    @property
    def n_instructions(self) -> int:
        """SX instructions evaluated per call."""
        return self._n_instructions

    def compute(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The commanded acceleration for the state, with the current parameters. Always
        finite.

        Args:
            q: configuration (n,); for a differential-drive base ``(x, y, θ, arm...)``.
            qdot: velocity coordinates: ``q̇`` (n,), or for a differential-drive base the
                actuated velocities ``(v, ω, arm rates...)`` (n − 1,).

        Returns:
            ``q̈`` (n,), or ``(v̇, ω̇, arm accelerations...)`` (n − 1,) for a base.

        Raises:
            ValueError: if ``q`` or ``q̇`` has the wrong shape, or the state or a
                parameter is not finite.
        """
        n, nv = self._n, self._nv
        q = np.asarray(q, dtype=float)
        qdot = np.asarray(qdot, dtype=float)
        if q.shape != (n,):
            raise ValueError(f"q must have shape ({n},), got {q.shape}")
        if qdot.shape != (nv,):
            raise ValueError(f"qdot must have shape ({nv},), got {qdot.shape}")
        self._input[:n] = q
        self._input[n:n + nv] = qdot
        if not _all_finite(self._input):
            raise ValueError(self._describe_non_finite_input())
        self._evaluate()
        if _all_finite(self._output):
            command = self._output.copy()
        else:
            self.fallback_count += 1
            command = self._fallback(qdot)
        if self._remembers_command:
            self._previous_command[:] = command
        return command

    def step(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The state one control period later, for a loop without a simulator.

        Holds ``q̈ = compute(q, q̇)`` for ``Δt = config.control_period`` and integrates it
        exactly: ``q' = q + q̇ Δt + ½ q̈ Δt²``, ``q̇' = q̇ + q̈ Δt`` (on a differential-drive
        base, the unicycle arc of :class:`dynfab.sim.models.DifferentialDrive`). With
        ``bound_command`` (the default) ``q'`` and ``q̇'`` are within the joint, velocity and
        acceleration limits, because the command is bounded over exactly this period.

        Args:
            q: configuration (n,).
            qdot: velocity coordinates (n,), or (n − 1,) on a base.

        Returns:
            ``(q', q̇')``, new arrays.

        Raises:
            ValueError: as :meth:`compute`.
        """
        command = self.compute(q, qdot)
        return self._motion.step(np.asarray(q, dtype=float), np.asarray(qdot, dtype=float), command,
                                 self.config.control_period)

    def compute_batch(self, Q: np.ndarray, Qdot: np.ndarray, P: np.ndarray | None = None,
                      previous: np.ndarray | None = None, threads: int | None = None) -> np.ndarray:
        """The commands of many environments in one call: row ``i`` is :meth:`compute` of
        ``(Q[i], Qdot[i])`` with parameters ``P[i]``, always finite (the fallback per row).
        Does not change the planner's state (not even the previous command).

        Args:
            Q: configurations (N, n).
            Qdot: velocity coordinates (N, nv).
            P: packed parameters (N, p) in the order of the planner's parameter buffer;
                ``None``: the current :attr:`parameters` in every row.
            previous: previous commands (N, nv) of a jerk-limited planner; ``None``: the
                planner's current one in every row.
            threads: threads to spread the rows on (default: the CPUs).

        Returns:
            Commands (N, nv).

        Raises:
            ValueError: for a wrong shape or a non-finite input (naming the row).
        """
        z = self._batch.pack(self._input, Q, Qdot, P, previous)
        commands = self._batch(z, threads if threads is not None else os.cpu_count() or 1)
        failed = ~np.isfinite(commands).all(axis=1)
        if failed.any():
            self.fallback_count += int(failed.sum())
            commands[failed] = self._fallback(z[failed, self._n:self._n + self._nv])
        return commands

    def _fallback(self, qdot: np.ndarray) -> np.ndarray:
        """The safe action ``q̈ = −k q̇``, within the acceleration limits when the command
        is bounded."""
        command = -self.config.fallback_braking * qdot
        if not self.config.bound_command:
            return command
        peak = self.config.limits.acceleration
        return np.clip(command, -peak, peak)

    def _describe_non_finite_input(self) -> str:
        n, nv = self._n, self._nv
        if not np.isfinite(self._input[:n]).all():
            return "q contains NaN or infinity"
        if not np.isfinite(self._input[n:n + nv]).all():
            return "qdot contains NaN or infinity"
        return "a planner parameter (goal or obstacle) contains NaN or infinity"

    # -- construction -------------------------------------------------------------------

    def _goal_dimension(self, goal: GoalConfig | OrientationGoalConfig) -> int:
        if isinstance(goal, OrientationGoalConfig):
            return goal.dimension
        return len(self._goal_axes(goal)) if goal.link else len(self._goal_joints(goal))

    def _goal_axes(self, goal: GoalConfig) -> list[int]:
        axes = goal.axes if goal.axes is not None else ("xy" if self.robot.planar else "xyz")
        if not axes or any(a not in _AXES for a in axes) or len(set(axes)) != len(axes):
            raise ValueError(f"GoalConfig.axes must be distinct letters of 'xyz', got {axes!r}")
        return [_AXES.index(a) for a in axes]

    def _goal_joints(self, goal: GoalConfig) -> list[int]:
        joints = list(goal.joints) if goal.joints is not None else list(range(self._n))
        if any(not 0 <= j < self._n for j in joints):
            raise ValueError(f"GoalConfig.joints must index the {self._n} joints, got {joints}")
        return joints

    def _build(self) -> ca.Function:
        n = self._n
        q = ca.SX.sym("q", n)
        qdot = ca.SX.sym("qdot", n)
        params = self._layout.symbols()
        geometry = self.config.speed_control.base(q, qdot)
        sphere_maps = self._sphere_maps(q, qdot)
        obstacle_momentum = ca.SX(n, 1)
        for term, momentum in self._obstacle_terms(sphere_maps, params):
            geometry = geometry + term
            obstacle_momentum = obstacle_momentum + momentum
        for term in self._self_collision_terms(sphere_maps):
            geometry = geometry + term
        if self.config.joint_limits is not None:
            kin = self.robot.kinematics
            geometry = geometry + self.config.joint_limits.on_joints(q, qdot, kin.lower, kin.upper)
        for leaf in self.config.leaves:
            geometry = geometry + self._leaf_geometry(leaf, q, qdot, params)
        forcing, goal_distance, joint = self._forcing(q, qdot, params)
        motion = EnvironmentMotion(*joint, obstacle_momentum) if joint is not None else None
        qddot = self.config.speed_control.acceleration(geometry, forcing, goal_distance, motion)
        if self.robot.base is None:
            velocity = qdot
        else:  # paper section V: least squares in the actuated accelerations
            velocity = ca.SX.sym("u", self._nv)
            jacobian = velocity_map(q)
            jdot_u = velocity_map_derivative(q, velocity)
            qddot = least_squares_acceleration(geometry.M + forcing.M, qddot, jacobian, jdot_u,
                                               self.config.steering, q)
            qddot = ca.substitute(qddot, qdot, ca.mtimes(jacobian, velocity))
        previous = ca.SX.sym("previous", self._nv if self._remembers_command else 0)
        if self.config.bound_command:
            qddot = self._bounds().bounded(self._bounded_positions(q), velocity, qddot,
                                           previous if self._remembers_command else None)
        inner = ca.Function("fabric_parts", [q, velocity, params.vector, previous], [qddot])
        state, size = n + self._nv, self._layout.size
        z = ca.SX.sym("z", state + size + previous.shape[0])
        qddot = inner(z[:n], z[n:state], z[state:state + size], z[state + size:])
        return ca.Function("fabric", [z], [qddot], {"cse": True})

    def _leaf_geometry(self, leaf: Leaf, q: ca.SX, qdot: ca.SX, params: ParameterSymbols) -> WeightedGeometry:
        """A leaf of ``config.leaves`` in joint space, its shapes checked."""
        term = leaf.geometry(LeafContext(self.robot, q, qdot, params.leaves[leaf.name]))
        n = self._n
        if term.M.shape != (n, n) or term.f_geometry.shape != (n, 1) or term.f_energy.shape != (n, 1):
            raise ValueError(f"leaf {leaf.name!r}: geometry(context) must be in joint space (M {n}x{n}, "
                             f"forces {n}x1), got M {term.M.shape[0]}x{term.M.shape[1]}")
        return term

    def _bounds(self) -> CommandBounds:
        """The command bounds of the velocity coordinates (position limits of the joints
        they move; none for a base's ``v``, ``ω``)."""
        kin = self.robot.kinematics
        index = self.robot.position_index
        lower = np.array([-np.inf if j is None else kin.lower[j] for j in index])
        upper = np.array([np.inf if j is None else kin.upper[j] for j in index])
        return CommandBounds(self.config.limits, lower, upper, self.config.control_period)

    def _bounded_positions(self, q: ca.SX) -> ca.SX:
        """The configuration variable of each velocity coordinate (0 for a base's ``v``, ``ω``)."""
        return ca.vertcat(*[ca.SX(0) if j is None else q[j] for j in self.robot.position_index])

    def _sphere_maps(self, q: ca.SX, qdot: ca.SX) -> list[DifferentialMap]:
        return link_point_maps(self.robot.kinematics, q, qdot,
                               [(sphere.link, sphere.center) for sphere in self.robot.collision_spheres],
                               dims=2 if self.robot.planar else 3)

    def _obstacle_terms(self, sphere_maps: list[DifferentialMap],
                        params: ParameterSymbols) -> list[tuple[WeightedGeometry, ca.SX]]:
        """Per robot sphere: the obstacle leaves of all sphere and shape slots summed in the
        sphere's point space and pulled once to joint space, with their momentum
        ``J_pᵀ Σ_o M_o ċ_o`` (structurally zero for a static planner)."""
        avoidance = self.config.obstacle_avoidance
        spheres = () if avoidance is None else tuple(zip(params.obstacles, params.obstacle_radius))
        shape_avoidance = self.config.shape_avoidance
        shapes = () if shape_avoidance is None else params.shapes
        if not spheres and not shapes:
            return []
        links = self.config.collision_links
        if links is not None:
            unknown = sorted(set(links) - set(self.robot.kinematics.link_names))
            if unknown:
                raise ValueError(f"PlannerConfig.collision_links: unknown links {unknown}")
        dims = 2 if self.robot.planar else 3
        terms = []
        for sphere, point_map in zip(self.robot.collision_spheres, sphere_maps):
            if links is not None and sphere.link not in links:
                continue
            if point_map.jacobian.nnz() == 0:
                continue  # a sphere no joint moves (e.g. on the base) cannot avoid anything
            p = ca.SX.sym("p", dims)
            pdot = ca.SX.sym("pdot", dims)
            in_point_space = None
            momentum = ca.SX(dims, 1)
            for obstacle, radius in spheres:
                planar_obstacle = _first_axes(obstacle, dims)
                leaf = avoidance.on_point(p, pdot, planar_obstacle, radius, sphere.radius)
                in_point_space = leaf if in_point_space is None else in_point_space + leaf
                momentum = momentum + ca.mtimes(leaf.M, planar_obstacle.velocity)
            for shape in shapes:
                leaf = shape_avoidance.on_point(p, pdot, shape, sphere.radius)
                in_point_space = leaf if in_point_space is None else in_point_space + leaf
                momentum = momentum + ca.mtimes(leaf.M, shape.reference.velocity[:dims])
            (momentum,) = point_map.substitute([momentum], p, pdot)
            terms.append((in_point_space.pull(point_map), ca.mtimes(point_map.jacobian.T, momentum)))
        return terms

    def _self_collision_terms(self, sphere_maps: list[DifferentialMap]) -> list[WeightedGeometry]:
        avoidance = self.config.self_collision
        if avoidance is None:
            return []
        spheres = self.robot.collision_spheres
        return [avoidance.on_pair(sphere_maps[a], sphere_maps[b], spheres[a].radius, spheres[b].radius)
                for a, b in self.robot.self_collision_pairs]

    def _forcing(self, q: ca.SX, qdot: ca.SX,
                 params: ParameterSymbols) -> tuple[Spec, ca.SX, tuple[ca.SX, ca.SX] | None]:
        """Summed goal forcing, the primary goal's error norm, and (dynamic planners) the
        primary goal reference's velocity and acceleration in joint space
        (:mod:`dynfab.fabric.joint_reference`)."""
        goals = self.config.goals
        primary_index = next((i for i, goal in enumerate(goals) if isinstance(goal, GoalConfig)), 0)
        total: Spec | None = None
        for i, goal in enumerate(goals):
            reference = params.goals[i]
            task = self._goal_task(goal, q, qdot)
            spec = goal.attractor.forcing(task, reference, params.goal_weight[i])
            total = spec if total is None else total + spec
            if i == primary_index:
                distance = ca.norm_2(task.phi - reference.position)
                joint = (joint_reference(task, reference, self.config.reference_damping)
                         if self.config.dynamic else None)
        return total, distance, joint

    def _goal_task(self, goal: GoalConfig | OrientationGoalConfig, q: ca.SX, qdot: ca.SX) -> DifferentialMap:
        """The task map of a goal: directions of link axes, a point on a link (on the
        goal's axes), or selected joints."""
        kin = self.robot.kinematics
        if isinstance(goal, OrientationGoalConfig):
            return direction_map(kin.rotation(q, goal.link), goal.link_axes, q, qdot)
        if goal.link is not None:
            position = kin.position(q, goal.link, parent=goal.parent_link, offset=goal.offset)
            axes = self._goal_axes(goal)
            return selected(DifferentialMap.from_expression(position, q, qdot), axes, ca.SX(len(axes), 1))
        joints = self._goal_joints(goal)
        selector = np.zeros((len(joints), self._n))
        selector[range(len(joints)), joints] = 1.0
        return linear_map(selector, ca.SX(len(joints), 1), q, qdot)

def _first_axes(reference: Reference, dims: int) -> Reference:
    """The first ``dims`` coordinates of a 3-D reference (planar robots use x, y)."""
    return Reference(reference.position[:dims], reference.velocity[:dims], reference.acceleration[:dims])


def _all_finite(x: np.ndarray) -> bool:
    """Whether every entry of ``x`` is finite. ``x·x`` is finite exactly when every entry is,
    unless it overflows (entries beyond ~1e154: numpy warns, and the entry-wise test decides); the
    dot product costs a quarter of ``np.isfinite(x).all()`` (0.3 vs 1.0 µs for 60 entries),
    which is a sixth of a compiled planner step."""
    return math.isfinite(x.dot(x)) or bool(np.isfinite(x).all())
