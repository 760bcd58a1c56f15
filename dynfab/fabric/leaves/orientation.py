"""Orientation goals: forcing on the world directions of link axes.

Task map. For a link with rotation ``R(q)`` (link frame to world) and unit axes
``a_1 … a_k`` fixed in the link frame, the task is the stack of their world directions

    y = φ(q) = [R(q) a_1; …; R(q) a_k]  ∈ ℝ^{3k}  [-, unit vectors],

with ``J = ∂φ/∂q`` and ``J̇ q̇`` by automatic differentiation (a revolute joint with world
axis ``ω_j`` moves each direction as ``∂(R a)/∂q_j = ω_j × R a``). The target is the stack
``x̃ = [d_1; …; d_k]`` of unit world directions and the error is ``x = y − x̃``.

- An *axis goal* is ``k = 1``: keep the link axis ``a`` along ``d`` (e.g. the tool's z
  pointing down). ``‖x‖ = ‖R a − d‖ = 2 sin(θ/2)``, θ the angle between ``R a`` and ``d``.
  Rotations about ``d`` are free.
- A *full orientation goal* is ``k = 3`` with ``a_i = e_i`` and ``d_i`` the columns of the
  target rotation ``R_d``: ``‖x‖ = ‖R − R_d‖_F = 2√2 sin(θ/2)``, θ the angle of ``R_dᵀ R``.
  This chordal error is isotropic (independent of the rotation axis), unlike two axes,
  whose chord depends on the axis of the error rotation.

Forcing. The error feeds :class:`~dynfab.fabric.leaves.goal.GoalAttractor` unchanged:
potential ``ψ(x)`` with ``∇ψ = k tanh(α‖x‖) x/‖x‖`` and metric
``M_ψ = ((m_near − m_far) exp(−(β‖x‖)²) + m_far) I`` on the error space. ``x`` is
dimensionless (a chord of the unit sphere, ≈ the angle in rad near the goal), so ``k`` is
in [1/s²] per unit metric and ``α``, ``β`` in [1/rad]. Pulled back, ``Jᵀ M_ψ J`` is
positive semi-definite (``J`` only spans the directions the joints can turn), and the
force ``Jᵀ M_ψ ∇ψ`` is the gradient of ``ψ(φ(q))`` scaled by the metric: it points
downhill in ``ψ`` for every configuration.

Behaviour at 180°. At ``R a = −d`` the error ``x = −2d`` is parallel to ``R a``, while every
column of ``J`` is perpendicular to ``R a`` (unit directions only turn), so ``Jᵀ M_ψ ∇ψ = 0``:
the half turn is an equilibrium, but the maximum of ``ψ`` on the sphere of directions,
hence unstable: any perturbation (another leaf, the motion of the robot, numerical noise)
leaves it and the goal then pulls the axis round. (For the full orientation goal the
half turns about any axis form the same unstable equilibrium set.)

Moving targets (a direction turning with angular velocity ``ω``: ``ḋ = ω × d``,
``d̈ = ω̇ × d + ω × (ω × d)``) use the dynamic pullback of the goal attractor unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from dynfab.fabric.leaves.goal import GoalAttractor
from dynfab.fabric.maps import DifferentialMap

Vector3 = tuple[float, float, float]

#: Link axes of a full orientation goal: the columns of the link rotation.
FRAME_AXES: tuple[Vector3, ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _orientation_attractor() -> GoalAttractor:
    """The default attractor of orientation goals: ``k = 5``, quadratic inside
    ``1/α ≈ 0.1`` rad, heavy metric (``m_near = 2``) inside ``1/β ≈ 0.7`` rad."""
    return GoalAttractor(gain=5.0, sharpness=10.0, metric_far=0.3, metric_near=2.0, metric_width=1.5)


@dataclass(frozen=True)
class OrientationGoalConfig:
    """An orientation sub-goal of a planner: the link axes ``a_i`` should point along target
    world directions ``d_i``, runtime parameters of dimension ``3 k`` (the stacked ``d_i``;
    in a dynamic planner also ``ḋ_i`` [1/s] and ``d̈_i`` [1/s²]).

    Attributes:
        link: the link whose axes are steered.
        link_axes: the axes ``a_i`` in the link frame (normalised here); one axis for an
            axis goal, :data:`FRAME_AXES` for a full orientation.
        weight: initial weight; changed at run time through the parameters.
        attractor: potential and metric of the forcing on the direction error.
    """

    link: str
    link_axes: tuple[Vector3, ...] = FRAME_AXES
    weight: float = 1.0
    attractor: GoalAttractor = field(default_factory=_orientation_attractor)

    def __post_init__(self) -> None:
        if not self.link_axes:
            raise ValueError("OrientationGoalConfig.link_axes: at least one axis is required")
        axes = []
        for axis in self.link_axes:
            a = np.asarray(axis, dtype=float).reshape(-1)
            norm = float(np.linalg.norm(a)) if a.size == 3 and np.isfinite(a).all() else 0.0
            if norm < 1e-9:
                raise ValueError(f"OrientationGoalConfig.link_axes: expected non-zero 3-vectors, got {list(axis)}")
            axes.append(tuple(float(c) for c in a / norm))
        object.__setattr__(self, "link_axes", tuple(axes))

    @property
    def dimension(self) -> int:
        """``3 k``: the size of the task and of the target parameter."""
        return 3 * len(self.link_axes)

    def target(self, rotation: np.ndarray) -> np.ndarray:
        """The target ``[R_d a_1; …; R_d a_k]`` that puts the link at rotation ``R_d`` (3, 3)."""
        return np.concatenate([np.asarray(rotation, dtype=float) @ np.asarray(a) for a in self.link_axes])


def direction_map(rotation: ca.SX, link_axes: Sequence[Vector3], q: ca.SX, qdot: ca.SX) -> DifferentialMap:
    """``y = [R(q) a_1; …; R(q) a_k]``: world directions of link axes, ``J``, ``J̇ q̇``.

    Args:
        rotation: ``R(q)`` (3, 3), link frame to world, an expression in ``q``.
        link_axes: unit axes ``a_i`` in the link frame.
        q: joint position symbols.
        qdot: joint velocity symbols.
    """
    directions = [ca.mtimes(rotation, ca.DM(list(axis))) for axis in link_axes]
    return DifferentialMap.from_expression(ca.vertcat(*directions), q, qdot)
