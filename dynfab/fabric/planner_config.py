"""What a fabric planner is made of: its goals (:class:`GoalConfig`, and
:class:`~dynfab.fabric.leaves.orientation.OrientationGoalConfig`) and its configuration
(:class:`PlannerConfig`: slots, leaves, speed control, limits, backend). The planner that
compiles them is :class:`dynfab.fabric.planner.FabricPlanner`."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from dynfab.fabric.backends import BACKENDS, default_backend
from dynfab.fabric.leaf import Leaf
from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.leaves.limits import JointLimitAvoidance
from dynfab.fabric.leaves.obstacle import SphereObstacleAvoidance
from dynfab.fabric.leaves.orientation import OrientationGoalConfig
from dynfab.fabric.leaves.self_collision import SelfCollisionAvoidance
from dynfab.fabric.leaves.shape_obstacle import ShapeObstacleAvoidance
from dynfab.fabric.nonholonomic import Steering
from dynfab.fabric.parameters import ShapeSlots
from dynfab.fabric.speed_control import SpeedControl
from dynfab.robots.limits import MotionLimits
from dynfab.robots.robot import Robot


_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True)
class GoalConfig:
    """One position or joint sub-goal; the first of these is the primary goal (its error
    drives the goal damping of speed control).

    Attributes:
        link: goal link for a position goal; ``None`` for a joint-space goal.
        offset: the goal point on ``link``, in the link frame [m] (e.g. a tool centre
            point); the origin of the link by default.
        axes: controlled axes of the link position, e.g. ``"xyz"`` or ``"xy"``; ``None``
            means ``"xy"`` for planar robots and ``"xyz"`` otherwise.
        parent_link: express the link position in this link's frame (``None``: root).
        joints: indices of the joints of a joint-space goal (``None``: all).
        weight: initial weight; changed at run time through the parameters.
        attractor: potential and metric of the forcing.
    """

    link: str | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axes: str | None = None
    parent_link: str | None = None
    joints: tuple[int, ...] | None = None
    weight: float = 1.0
    attractor: GoalAttractor = field(default_factory=GoalAttractor)


@dataclass(frozen=True)
class PlannerConfig:
    """What the planner is made of. ``None`` disables a component.

    Attributes:
        goals: sub-goals (at least one): position or joint goals (:class:`GoalConfig`)
            and orientation goals (:class:`OrientationGoalConfig`). The primary goal, whose
            error drives speed control and whose reference velocity a dynamic planner
            follows, is the first :class:`GoalConfig` (the first goal if there is none).
        obstacle_slots: number of sphere obstacle slots (fixed at build time).
        obstacle_avoidance: leaf of each robot sphere against each obstacle slot.
        shape_slots: number of box, cylinder, capsule and plane slots (fixed at build time).
        shape_avoidance: leaf of each robot sphere against each shape slot.
        joint_limits: joint-limit leaf.
        self_collision: leaf of each self-collision pair of the robot.
        speed_control: root parameters.
        collision_links: restrict obstacle avoidance to spheres on these links
            (``None``: every collision sphere of the robot).
        fallback_braking: ``k`` of the safe action ``q̈ = −k q̇`` returned if the fabric
            ever produced a non-finite value [1/s].
        dynamic: build dynamic fabrics: goals and obstacles take velocities and
            accelerations as runtime parameters (paper section IV). ``False`` builds the
            static fabric, which is the dynamic one with all of them zero.
        reference_damping: ``λ₀`` of the pseudo-inverse ``J⁺ = Jᵀ (J Jᵀ + λ² I)⁻¹`` that
            brings the primary goal's reference to joint space, damped only near
            singularities (:mod:`dynfab.fabric.joint_reference`) [m].
        steering: for a differential-drive base, the look-ahead term of the
            non-holonomic solve (:class:`dynfab.fabric.nonholonomic.Steering`); ``None`` for the
            paper's plain least squares.
        limits: velocity, acceleration (and jerk) limits of the velocity coordinates;
            ``None`` takes the robot's (``robot.limits``). The planner's ``config`` holds
            the limits in use.
        control_period: ``Δt`` over which a command is held [s]: the velocity and
            position bounds look one period ahead (:mod:`dynfab.fabric.command_bounds`).
        bound_command: make every command executable (:mod:`dynfab.fabric.command_bounds`);
            ``False`` returns the fabric's raw acceleration (for studying the theory).
        leaves: further leaves built through the leaf interface (:mod:`dynfab.fabric.leaf`),
            e.g. :class:`~dynfab.fabric.leaves.workspace.WorkspaceBounds`; their runtime
            parameters are ``planner.parameters.leaves[name]``.
        backend: ``"c"`` (the default, unless ``$DYNFAB_BACKEND`` says ``vm``) compiles the
            function to C and caches the library, falling back to the VM without a
            compiler; ``"vm"`` interprets it in CasADi's virtual machine
            (:mod:`dynfab.fabric.backends`).
    """

    goals: tuple[GoalConfig | OrientationGoalConfig, ...]
    obstacle_slots: int = 0
    obstacle_avoidance: SphereObstacleAvoidance | None = field(default_factory=SphereObstacleAvoidance)
    shape_slots: ShapeSlots = field(default_factory=ShapeSlots)
    shape_avoidance: ShapeObstacleAvoidance | None = field(default_factory=ShapeObstacleAvoidance)
    joint_limits: JointLimitAvoidance | None = field(default_factory=JointLimitAvoidance)
    self_collision: SelfCollisionAvoidance | None = field(default_factory=SelfCollisionAvoidance)
    speed_control: SpeedControl = field(default_factory=SpeedControl)
    collision_links: tuple[str, ...] | None = None
    fallback_braking: float = 5.0
    dynamic: bool = False
    reference_damping: float = 0.05
    steering: Steering | None = None
    limits: MotionLimits | None = None
    control_period: float = 0.01
    bound_command: bool = True
    leaves: tuple[Leaf, ...] = ()
    backend: str = field(default_factory=default_backend)

    @classmethod
    def for_robot(cls, robot: Robot, goals: tuple[GoalConfig | OrientationGoalConfig, ...], obstacle_slots: int = 0,
                  dynamic: bool = False, shape_slots: ShapeSlots = ShapeSlots()) -> PlannerConfig:
        """The defaults for ``robot``: those of the fields, except that a robot on a
        differential-drive base, which cannot sidestep, sees obstacles (spheres and shapes)
        from 0.5 m (instead of 0.2 m) and steers with a look-ahead point (:class:`Steering`
        ``L = 0.5 m``, ``w = 1``). Chosen on Experiment 4 seeds 0-49 (commit 0c5d6c6: 45/50
        reached, no collision), the seeds docs/results.md reports; today's code there: 45/50,
        no collision. Held out, seeds 1000-1049: 46/50 reached, no collision (4 deadlocks),
        by ``dynfab experiment exp4 --runs 50 --seed 1000 --planners static-fabric``
        (docs/results.md, "Tuned constants on held-out seeds")."""
        if robot.base is None:
            return cls(goals=goals, obstacle_slots=obstacle_slots, dynamic=dynamic, shape_slots=shape_slots)
        barrier = Barrier(geometry_gain=5.0, energy_gain=0.5, horizon=0.5)
        return cls(goals=goals, obstacle_slots=obstacle_slots, dynamic=dynamic, shape_slots=shape_slots,
                   obstacle_avoidance=SphereObstacleAvoidance(barrier), shape_avoidance=ShapeObstacleAvoidance(barrier),
                   steering=Steering(lookahead=0.5, weight=1.0))

    def __post_init__(self) -> None:
        if not self.goals:
            raise ValueError("PlannerConfig.goals: at least one goal is required")
        if self.obstacle_slots < 0:
            raise ValueError(f"PlannerConfig.obstacle_slots must be >= 0, got {self.obstacle_slots}")
        if not (np.isfinite(self.control_period) and self.control_period > 0):
            raise ValueError(f"PlannerConfig.control_period must be a positive finite number, "
                             f"got {self.control_period}")
        _check_leaves(self.leaves)
        if self.backend not in BACKENDS:
            raise ValueError(f"PlannerConfig.backend must be one of {', '.join(BACKENDS)}, got {self.backend!r}")


def _check_leaves(leaves: tuple[Leaf, ...]) -> None:
    """Each leaf follows :class:`~dynfab.fabric.leaf.Leaf`, with a unique identifier for a
    name and identifiers for parameter names (they name C fields in an export)."""
    names: set[str] = set()
    for i, leaf in enumerate(leaves):
        if not isinstance(leaf, Leaf):
            raise TypeError(f"PlannerConfig.leaves[{i}]: {type(leaf).__name__} is not a leaf "
                            "(it needs name, parameter_sizes() and geometry(context): dynfab.fabric.leaf)")
        if not isinstance(leaf.name, str) or not _IDENTIFIER.fullmatch(leaf.name):
            raise ValueError(f"PlannerConfig.leaves[{i}].name must be an identifier, got {leaf.name!r}")
        if leaf.name in names:
            raise ValueError(f"PlannerConfig.leaves: two leaves are named {leaf.name!r}")
        names.add(leaf.name)
        for key, size in leaf.parameter_sizes().items():
            if not _IDENTIFIER.fullmatch(key) or isinstance(size, bool) or not isinstance(size, int) or size < 1:
                raise ValueError(f"PlannerConfig.leaves[{i}] ({leaf.name}): parameter {key!r} needs an identifier "
                                 f"for a name and a size >= 1, got {size!r}")
