"""The ``fabric:`` block of a scenario: parameters of the fabric planners' leaves and root,
by name. Every key is optional; a key left out keeps the planner's default for the robot
(:meth:`dynfab.fabric.planner_config.PlannerConfig.for_robot`), so a file without the
block runs exactly as before. The ``mpc`` planner ignores the block.

```yaml
fabric:
  obstacle:                # every obstacle leaf: spheres, boxes, cylinders, capsules, planes
    gain: 5.0              # k of the barrier geometry h = −k ẋ²/x [-]
    energy_gain: 0.5       # λ of the barrier energy L_e = λ (1 − H(ẋ)) ẋ² (1/x − 1/r)₊² [m²]
    range: 0.2             # r: the leaf acts below this clearance [m] (0.5 on a differential-drive base)
  self_collision: {gain: 0.5, energy_gain: 0.1, range: 0.2}   # pairs of robot spheres [m]
  joint_limits: {gain: 0.1, energy_gain: 0.05, range: 0.3}    # distance to a limit [rad or m]
  goal:                    # position and joint goals: the attractor ψ, ∇ψ = k tanh(α‖x‖) x/‖x‖
    gain: 5.0              # k: slope of ψ far from the goal [m/s² per unit metric]
    sharpness: 10.0        # α: inverse radius of the quadratic zone [1/m]
    metric_far: 0.3        # m_far: metric weight far from the goal [-]
    metric_near: 2.0       # m_near: metric weight at the goal [-]
    metric_width: 0.75     # β: inverse radius of the heavy-metric zone [1/m]
  orientation: {gain: 5.0, sharpness: 10.0, metric_far: 0.3, metric_near: 2.0, metric_width: 1.5}
                           # pose and axis goals: the same attractor on the direction error [1/rad]
  speed_control:           # the root (dynfab/fabric/speed_control.py)
    execution_energy: 0.5  # target L_ex* of ½‖q̇‖² [(rad/s)²]
    energy_sharpness: 5.0  # a_η [1/(rad/s)²]
    damping: 0.5           # b [1/s]
    goal_damping: 6.0      # b_goal: extra damping near the goal [1/s]
    goal_damping_radius: 0.05      # r_b [m]
    goal_damping_sharpness: 10.0   # a_b [1/m]
    base_metric: 0.2       # c of the base energy ½ c ‖q̇‖² [-]
  steering: {lookahead: 0.5, weight: 1.0}   # differential-drive bases only: L [m], w [-]
```

The ranges below are those of every value (checked on load, one-line errors naming the
field); the defaults are the planner's, listed in the comments above.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Annotated, Any

from pydantic import Field

from dynfab.fabric.leaves.barrier import Barrier
from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.leaves.orientation import OrientationGoalConfig
from dynfab.fabric.planner_config import PlannerConfig
from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.model_types import Range, ScenarioModel

__all__ = ["AttractorSpec", "BarrierSpec", "FabricMapping", "FabricSpec", "SpeedControlSpec", "SteeringSpec",
           "fabric_block"]

#: Largest gain of a barrier or an attractor, and largest sharpness [1/m or 1/rad].
MAX_GAIN = 1e3
#: Largest metric weight, damping [1/s] and steering weight.
MAX_WEIGHT = 1e2
#: Smallest and largest barrier ``range`` [m or rad] (the barrier clamps clearances at 1 mm).
MIN_RANGE, MAX_RANGE = 1e-2, 10.0
#: Largest ``execution_energy`` [(rad/s)²], goal damping radius and steering look-ahead [m].
MAX_ENERGY = 1e2
MAX_DISTANCE = 10.0

NonNegative = Annotated[float, Range(0.0, MAX_GAIN)]
Positive = Annotated[float, Range(0.0, MAX_GAIN, open_lower=True)]
Weight = Annotated[float, Range(0.0, MAX_WEIGHT, open_lower=True)]


def _key(description: str) -> Any:
    """An optional key of the block (``None``: the planner's default)."""
    return Field(None, description=description)


@dataclass(frozen=True)
class BarrierSpec:
    """Barrier parameters a scenario sets (:class:`~dynfab.fabric.leaves.barrier.Barrier`);
    ``None`` keeps the planner's.

    Attributes:
        gain: ``k`` of the geometry ``h = −k ẋ²/x`` [-].
        energy_gain: ``λ`` of the energy ``L_e = λ (1 − H(ẋ)) ẋ² (1/x − 1/r)₊²`` [m²].
        range: ``r``, the clearance below which the leaf acts [m or rad].
    """

    gain: float | None = None
    energy_gain: float | None = None
    range: float | None = None

    def applied(self, barrier: Barrier) -> Barrier:
        """``barrier`` with the values that are set."""
        return replace(barrier, **_set({"geometry_gain": self.gain, "energy_gain": self.energy_gain,
                                        "horizon": self.range}))


@dataclass(frozen=True)
class AttractorSpec:
    """Goal-attractor parameters a scenario sets
    (:class:`~dynfab.fabric.leaves.goal.GoalAttractor`, same names); ``None`` keeps the
    planner's.

    Attributes:
        gain: ``k``, slope of the potential far from the goal [m/s² per unit metric].
        sharpness: ``α``, inverse radius of the quadratic zone [1/m or 1/rad].
        metric_far: ``m_far`` [-].
        metric_near: ``m_near`` [-].
        metric_width: ``β``, inverse radius of the heavy-metric zone [1/m or 1/rad].
    """

    gain: float | None = None
    sharpness: float | None = None
    metric_far: float | None = None
    metric_near: float | None = None
    metric_width: float | None = None

    def applied(self, attractor: GoalAttractor) -> GoalAttractor:
        """``attractor`` with the values that are set."""
        return replace(attractor, **_set(_values(self)))


@dataclass(frozen=True)
class SpeedControlSpec:
    """Root parameters a scenario sets (:class:`~dynfab.fabric.speed_control.SpeedControl`,
    same names and units); ``None`` keeps the planner's."""

    execution_energy: float | None = None
    energy_sharpness: float | None = None
    damping: float | None = None
    goal_damping: float | None = None
    goal_damping_radius: float | None = None
    goal_damping_sharpness: float | None = None
    base_metric: float | None = None


@dataclass(frozen=True)
class SteeringSpec:
    """Look-ahead steering of a differential-drive base a scenario sets
    (:class:`~dynfab.fabric.nonholonomic.Steering`: ``lookahead`` [m], ``weight`` [-])."""

    lookahead: float | None = None
    weight: float | None = None


@dataclass(frozen=True)
class FabricSpec:
    """The ``fabric:`` block: what a scenario changes in its fabric planner.

    Attributes:
        obstacle: the barrier of every obstacle leaf (spheres and shapes).
        self_collision: the barrier between pairs of robot spheres.
        joint_limits: the barrier on the distance to each joint limit.
        goal: the attractor of position and joint goals.
        orientation: the attractor of orientation goals (pose and axis goals).
        speed_control: the root.
        steering: the look-ahead of a differential-drive base (an error for other robots).
    """

    obstacle: BarrierSpec = BarrierSpec()
    self_collision: BarrierSpec = BarrierSpec()
    joint_limits: BarrierSpec = BarrierSpec()
    goal: AttractorSpec = AttractorSpec()
    orientation: AttractorSpec = AttractorSpec()
    speed_control: SpeedControlSpec = SpeedControlSpec()
    steering: SteeringSpec = SteeringSpec()

    def configured(self, config: PlannerConfig) -> PlannerConfig:
        """``config`` with the values of this block.

        Raises:
            ScenarioError: ``steering`` is set for a robot without a differential-drive base.
        """
        steering = config.steering
        if _set(_values(self.steering)):
            if steering is None:
                raise ScenarioError("fabric.steering", "applies to robots on a differential-drive base only")
            steering = replace(steering, **_set(_values(self.steering)))
        goals = tuple(
            replace(goal, attractor=(self.orientation if isinstance(goal, OrientationGoalConfig) else self.goal)
                    .applied(goal.attractor))
            for goal in config.goals)
        return replace(
            config, goals=goals, steering=steering,
            obstacle_avoidance=_with_barrier(config.obstacle_avoidance, self.obstacle),
            shape_avoidance=_with_barrier(config.shape_avoidance, self.obstacle),
            self_collision=_with_barrier(config.self_collision, self.self_collision),
            joint_limits=_with_barrier(config.joint_limits, self.joint_limits),
            speed_control=replace(config.speed_control, **_set(_values(self.speed_control))))


def fabric_block(config: PlannerConfig) -> dict[str, dict[str, float]]:
    """The ``fabric:`` block of every value ``config`` uses (the inverse of
    :meth:`FabricSpec.configured`): the obstacle barrier is that of the sphere leaf, the
    goal and orientation attractors those of the first goal of each kind; parts the
    config does not have are left out."""
    block: dict[str, dict[str, float]] = {}
    for key, leaf in (("obstacle", config.obstacle_avoidance), ("self_collision", config.self_collision),
                      ("joint_limits", config.joint_limits)):
        if leaf is not None:
            barrier = leaf.barrier
            block[key] = {"gain": barrier.geometry_gain, "energy_gain": barrier.energy_gain, "range": barrier.horizon}
    for key, kind in (("goal", False), ("orientation", True)):
        goal = next((g for g in config.goals if isinstance(g, OrientationGoalConfig) == kind), None)
        if goal is not None:
            block[key] = {name: getattr(goal.attractor, name) for name in _names(AttractorSpec)}
    block["speed_control"] = {name: getattr(config.speed_control, name) for name in _names(SpeedControlSpec)}
    if config.steering is not None:
        block["steering"] = {name: getattr(config.steering, name) for name in _names(SteeringSpec)}
    return block


def _with_barrier(leaf: Any, spec: BarrierSpec) -> Any:
    """An avoidance leaf (``None`` stays ``None``) with its barrier changed by ``spec``."""
    return None if leaf is None else replace(leaf, barrier=spec.applied(leaf.barrier))


def _values(spec: Any) -> dict[str, float | None]:
    return {name: getattr(spec, name) for name in _names(type(spec))}


def _names(spec_type: type) -> tuple[str, ...]:
    return tuple(f.name for f in fields(spec_type))


def _set(values: dict[str, float | None]) -> dict[str, float]:
    return {name: value for name, value in values.items() if value is not None}


class BarrierMapping(ScenarioModel):
    """``{gain, energy_gain, range}`` of a barrier leaf (module docstring)."""

    gain: NonNegative | None = _key("k of the barrier geometry h = -k xdot^2/x [-], >= 0")
    energy_gain: NonNegative | None = _key("lambda of the barrier energy [m^2], >= 0 (0 turns the leaf off)")
    range: Annotated[float, Range(MIN_RANGE, MAX_RANGE)] | None = _key(
        "clearance below which the leaf acts [m, or rad for revolute joint limits]")

    def spec(self) -> BarrierSpec:
        return BarrierSpec(self.gain, self.energy_gain, self.range)


class AttractorMapping(ScenarioModel):
    """``{gain, sharpness, metric_far, metric_near, metric_width}`` of a goal attractor."""

    gain: Positive | None = _key("k: slope of the goal potential far from the goal [m/s^2 per unit metric]")
    sharpness: Positive | None = _key("alpha: inverse radius of the potential's quadratic zone [1/m or 1/rad]")
    metric_far: Weight | None = _key("metric weight far from the goal [-]")
    metric_near: Weight | None = _key("metric weight at the goal [-]")
    metric_width: Annotated[float, Range(0.0, MAX_GAIN)] | None = _key(
        "beta: inverse radius of the heavy-metric zone [1/m or 1/rad]")

    def spec(self) -> AttractorSpec:
        return AttractorSpec(self.gain, self.sharpness, self.metric_far, self.metric_near, self.metric_width)


class SpeedControlMapping(ScenarioModel):
    """The root's parameters (module docstring)."""

    execution_energy: Annotated[float, Range(0.0, MAX_ENERGY, open_lower=True)] | None = _key(
        "target L_ex* of 0.5 |qdot|^2 [(rad/s)^2]: below it the goal accelerates the robot")
    energy_sharpness: Positive | None = _key("a_eta: sharpness of the switch at the target energy [1/(rad/s)^2]")
    damping: Weight | None = _key("b: constant damping [1/s], > 0")
    goal_damping: Annotated[float, Range(0.0, MAX_WEIGHT)] | None = _key("b_goal: extra damping near the goal [1/s]")
    goal_damping_radius: Annotated[float, Range(0.0, MAX_DISTANCE)] | None = _key(
        "r_b: goal distance within which the extra damping acts [m]")
    goal_damping_sharpness: Positive | None = _key("a_b: sharpness of the extra damping's switch [1/m]")
    base_metric: Weight | None = _key("c of the base energy 0.5 c |qdot|^2 [-], > 0")

    def spec(self) -> SpeedControlSpec:
        return SpeedControlSpec(**{name: getattr(self, name) for name in _names(SpeedControlSpec)})


class SteeringMapping(ScenarioModel):
    """``{lookahead, weight}`` of a differential-drive base's steering."""

    lookahead: Annotated[float, Range(0.0, MAX_DISTANCE, open_lower=True)] | None = _key(
        "L: distance of the steered point ahead of the axle [m]")
    weight: Annotated[float, Range(0.0, MAX_WEIGHT)] | None = _key("w: weight of the look-ahead term [-]")

    def spec(self) -> SteeringSpec:
        return SteeringSpec(self.lookahead, self.weight)


class FabricMapping(ScenarioModel):
    """``fabric:``: leaf and root parameters of the fabric planners by name; a key left out
    keeps the planner's default for the robot (README "Scenario files")."""

    obstacle: BarrierMapping | None = _key("barrier of every obstacle leaf (default gain 5, energy_gain 0.5, "
                                           "range 0.2 m; 0.5 m on a differential-drive base)")
    self_collision: BarrierMapping | None = _key("barrier between robot spheres (default 0.5, 0.1, 0.2 m)")
    joint_limits: BarrierMapping | None = _key("barrier on the distance to joint limits (default 0.1, 0.05, 0.3)")
    goal: AttractorMapping | None = _key("attractor of position and joint goals (default gain 5, sharpness 10, "
                                         "metric_far 0.3, metric_near 2, metric_width 0.75)")
    orientation: AttractorMapping | None = _key("attractor of pose and axis goals (default 5, 10, 0.3, 2, 1.5)")
    speed_control: SpeedControlMapping | None = _key(
        "the root (default execution_energy 0.5, energy_sharpness 5, damping 0.5, goal_damping 6, "
        "goal_damping_radius 0.05, goal_damping_sharpness 10, base_metric 0.2)")
    steering: SteeringMapping | None = _key("differential-drive bases only (default lookahead 0.5 m, weight 1)")

    def spec(self) -> FabricSpec:
        """The block's value."""
        parts = {name: getattr(self, name) for name in type(self).model_fields}
        return FabricSpec(**{name: part.spec() for name, part in parts.items() if part is not None})
