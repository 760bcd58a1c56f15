"""Root of the fabric: energization, forcing, damping and speed control.

Given, in joint space, the summed weighted geometry ``(M, f_g)`` with its energy force
``f_e`` (leaves plus a base energy ``½ c ‖q̇‖²``) and the summed forcing spec
``(M_ψ, f_ψ)``, the commanded acceleration is (Ratliff et al. 2020, sec. "speed control")

    ẍ_g = −M⁻¹ f_g                          geometry alone
    ẍ_f = −(M + M_ψ)⁻¹ (f_g + f_ψ)          forced geometry
    α_le = q̇ᵀ(f_g − f_e) / (q̇ᵀ M q̇)        energizes the geometry with its own energy
    α_0, α_ψ = −q̇ᵀ ẍ_g / ‖q̇‖², −q̇ᵀ ẍ_f / ‖q̇‖²   keep L_ex = ½ ‖q̇‖² constant
    η = ½ (tanh(−a_η (L_ex − L_ex*)) + 1)     1 below the target energy L_ex*, 0 above
    α_ex = η α_0 + (1 − η) α_ψ
    β = b + b_goal · ½ (tanh(−a_b (‖x_goal‖ − r_b)) + 1) + max(0, α_ex − α_le)
    q̈ = ẍ_f + (α_ex − β) q̇.

Below ``L_ex*`` the forcing accelerates the robot; above it, the forcing only steers. The
``max(0, α_ex − α_le)`` term keeps the total scaling at most ``α_le − b``, so the energy
of the fabric plus the potential decreases and the system converges to the potential's
minimum (the theory's damping condition ``β > 0``), with extra damping ``b_goal`` near
the goal. Units: accelerations in joint units/s², α and β in 1/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry, energization_coefficient
from dynfab.fabric.linalg import cholesky_solve
from dynfab.fabric.spec import Spec


@dataclass(frozen=True)
class SpeedControl:
    """Parameters of the root.

    Attributes:
        base_metric: ``c`` of the base energy ``½ c ‖q̇‖²`` that keeps ``M`` positive
            definite [-].
        execution_energy: target ``L_ex*`` of ``½ ‖q̇‖²`` [(rad/s)²].
        energy_sharpness: ``a_η`` [1/(rad/s)²].
        damping: constant damping ``b`` [1/s].
        goal_damping: extra damping ``b_goal`` near the goal [1/s].
        goal_damping_radius: ``r_b`` [m].
        goal_damping_sharpness: ``a_b`` [1/m].
        regularization: ε in the denominators of the α's [(rad/s)²].
    """

    base_metric: float = 0.2
    execution_energy: float = 0.5
    energy_sharpness: float = 5.0
    damping: float = 0.5
    goal_damping: float = 6.0
    goal_damping_radius: float = 0.05
    goal_damping_sharpness: float = 10.0
    regularization: float = 1e-6

    def __post_init__(self) -> None:
        if self.base_metric <= 0:
            raise ValueError(f"SpeedControl.base_metric must be > 0, got {self.base_metric}")
        if self.damping <= 0:
            raise ValueError(f"SpeedControl.damping must be > 0, got {self.damping}")

    def base(self, q: ca.SX, qdot: ca.SX) -> WeightedGeometry:
        """The base energy's spec ``(c I, 0)`` (a Lagrangian geometry: ``f_g = f_e = 0``)."""
        n = q.shape[0]
        return WeightedGeometry(self.base_metric * ca.SX.eye(n), ca.SX(n, 1), ca.SX(n, 1), q, qdot)

    def acceleration(self, geometry: WeightedGeometry, forcing: Spec, goal_distance: ca.SX,
                     motion: EnvironmentMotion | None = None) -> ca.SX:
        """``q̈`` of the damped, speed-controlled, forced fabric (module docstring).

        Args:
            geometry: summed weighted geometry in joint space (base included).
            forcing: summed forcing spec in joint space.
            goal_distance: ``‖x_goal‖`` of the primary goal [m].
            motion: how the goal reference and the obstacles move (dynamic fabrics);
                ``None``: a static world.

        With ``motion``, the base energy is pulled dynamically with the goal reference,
        ``½ c ‖q̇ − q̇̃‖²``, whose spec is ``(c I, −c q̈̃)``: the base then asks for the
        reference's own acceleration instead of rest, so that on the reference the whole
        fabric asks for exactly ``q̈̃`` and follows it without bias
        (:mod:`dynfab.fabric.joint_reference`). Energization and speed control act on the
        velocity relative to the goal reference, ``q̇ − q̇̃`` (paper Lemma "Dynamically
        energized fabrics": damping ``B ẋ_r``), and damping pulls ``q̇`` toward the
        metric-weighted velocity of the environment,

            v_env = (M + M_ψ)⁻¹ (c q̇̃ + M_ψ q̇̃ + Σ J_pᵀ M_o ċ_o),

        which is the goal reference's velocity where the goal's metric dominates (so a
        moving goal is followed without lag), a moving obstacle's velocity where that
        obstacle's metric dominates (so a robot pushed by an obstacle is not damped into
        it), and rest where the base metric dominates. In a static world ``v_env = 0``.
        """
        if motion is not None:
            base_inertia = -self.base_metric * motion.reference_acceleration
            geometry = WeightedGeometry(geometry.M, geometry.f_geometry + base_inertia,
                                        geometry.f_energy + base_inertia, geometry.x, geometry.xdot)
        qdot = geometry.xdot if motion is None else geometry.xdot - motion.reference_velocity
        eps = self.regularization
        speed_squared = ca.dot(qdot, qdot)
        total_metric = geometry.M + forcing.M
        geometric = -cholesky_solve(geometry.M, geometry.f_geometry)
        forced = -cholesky_solve(total_metric, geometry.f_geometry + forcing.f)
        alpha_le = energization_coefficient(geometry.M, geometry.f_geometry, geometry.f_energy, qdot, eps)
        alpha_geometric = -ca.dot(qdot, geometric) / (speed_squared + eps)
        alpha_forced = -ca.dot(qdot, forced) / (speed_squared + eps)
        eta = 0.5 * (ca.tanh(-self.energy_sharpness * (0.5 * speed_squared - self.execution_energy)) + 1)
        alpha_ex = eta * alpha_geometric + (1 - eta) * alpha_forced
        near_goal = 0.5 * (ca.tanh(-self.goal_damping_sharpness * (goal_distance - self.goal_damping_radius)) + 1)
        beta = self.damping + self.goal_damping * near_goal + ca.fmax(0, alpha_ex - alpha_le)
        if motion is None:
            return forced + (alpha_ex - beta) * qdot
        reference = motion.reference_velocity
        momentum = self.base_metric * reference + ca.mtimes(forcing.M, reference) + motion.obstacle_momentum
        environment_velocity = cholesky_solve(total_metric, momentum)
        return forced + (alpha_ex - beta) * (geometry.xdot - environment_velocity)


@dataclass(frozen=True)
class EnvironmentMotion:
    """How the goal reference and the obstacles move, seen from joint space.

    One goal reference serves the whole root: energization, speed control and the base
    energy measure motion relative to the primary goal's reference (the robot's task).
    Moving obstacles need no reference of their own here: each obstacle leaf is already
    pulled dynamically with its obstacle's motion, and the damping's target velocity
    weights each obstacle's velocity by its leaf metric (``obstacle_momentum``).

    Attributes:
        reference_velocity: ``q̇̃`` of the primary goal (n, 1) [rad/s].
        reference_acceleration: ``q̈̃`` of the primary goal (n, 1) [rad/s²].
        obstacle_momentum: ``Σ J_pᵀ M_o ċ_o`` over robot spheres ``p`` and moving
            obstacles ``o`` (n, 1): each obstacle's velocity weighted by its leaf metric.
    """

    reference_velocity: ca.SX
    reference_acceleration: ca.SX
    obstacle_momentum: ca.SX
