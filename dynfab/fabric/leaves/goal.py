"""Goal attraction: a forcing potential on the error ``x = y − x̃(t)`` of a task ``y = S φ(q)``.

Default potential (Ratliff et al. 2020, "speed-controlled" attractor): the smoothed norm

    ψ(x) = k (‖x‖ + log(1 + exp(−2α‖x‖)) / α),  ∇ψ = k tanh(α‖x‖) x/‖x‖,

whose gradient has magnitude ``k`` away from the goal and fades linearly inside a radius
``≈ 1/α``. Default metric: ``M_ψ(x) = ((m_near − m_far) exp(−(β‖x‖)²) + m_far) I``, heavier
near the goal so the goal wins over other leaves there. The forcing spec is
``(M_ψ, w M_ψ ∇ψ)`` in the error coordinates; a goal of weight ``w = 0`` is inactive.

For a moving goal (path following, paper Lemma "Dynamic Lagrangian fabrics") the forcing
spec is brought to the task coordinates by the dynamic pullback, ``(M_ψ, w M_ψ ∇ψ − M_ψ ẍ̃)``;
since ``ψ`` depends on ``y − x̃`` only, ``∂ψ/∂y = −∂ψ/∂x̃`` as the lemma requires. A
static goal has ``ẋ̃ = ẍ̃ = 0``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.maps import DifferentialMap, Reference
from dynfab.fabric.spec import Spec

#: ``ψ(x)``: a scalar potential of the goal error.
PotentialFunction = Callable[[ca.SX], ca.SX]
#: ``M_ψ(x)``: a symmetric positive definite metric of the goal error.
MetricFunction = Callable[[ca.SX], ca.SX]

_SMOOTHING = 1e-6


def _smooth_norm(x: ca.SX) -> ca.SX:
    return ca.sqrt(ca.dot(x, x) + _SMOOTHING**2)


@dataclass(frozen=True)
class GoalAttractor:
    """Forcing of a goal.

    Attributes:
        gain: ``k``, slope of the potential far from the goal [m/s² per unit metric].
        sharpness: ``α``, inverse radius of the quadratic zone [1/m].
        metric_far: ``m_far``, metric weight far from the goal [-].
        metric_near: ``m_near``, metric weight at the goal [-].
        metric_width: ``β``, inverse radius of the heavy-metric zone [1/m].
        potential: optional replacement ``ψ(x)``.
        metric: optional replacement ``M_ψ(x)``.
    """

    gain: float = 5.0
    sharpness: float = 10.0
    metric_far: float = 0.3
    metric_near: float = 2.0
    metric_width: float = 0.75
    potential: PotentialFunction | None = None
    metric: MetricFunction | None = None

    def potential_of(self, x: ca.SX) -> ca.SX:
        """``ψ(x)``."""
        if self.potential is not None:
            return self.potential(x)
        r = _smooth_norm(x)
        return self.gain * (r + ca.log(1 + ca.exp(-2 * self.sharpness * r)) / self.sharpness)

    def metric_of(self, x: ca.SX) -> ca.SX:
        """``M_ψ(x)``."""
        if self.metric is not None:
            return self.metric(x)
        r = _smooth_norm(x)
        scale = (self.metric_near - self.metric_far) * ca.exp(-((self.metric_width * r) ** 2)) + self.metric_far
        return scale * ca.SX.eye(x.shape[0])

    def forcing(self, task: DifferentialMap, goal: Reference, weight: ca.SX) -> Spec:
        """The forcing spec pulled to joint space.

        Args:
            task: the goal task map ``y = S φ(q)``.
            goal: the goal reference ``x̃``, ``ẋ̃``, ``ẍ̃`` in task coordinates.
            weight: the goal's weight parameter ``w``.
        """
        dimension = task.phi.shape[0]
        x, xdot = ca.SX.sym("x", dimension), ca.SX.sym("xdot", dimension)
        metric = self.metric_of(x)
        active = weight > 0
        in_error_frame = Spec(metric * active, weight * ca.mtimes(metric, ca.gradient(self.potential_of(x), x)), x, xdot)
        y, ydot = ca.SX.sym("y", dimension), ca.SX.sym("ydot", dimension)
        return in_error_frame.dynamic_pull(y, ydot, goal).pull(task)
