"""Reference trajectories ``x̃(t)`` with ``ẋ̃(t)`` and ``ẍ̃(t)`` (paper section IV-A).

A reference trajectory moves a point of the plane or of space (2 or 3 axes) in time
``t`` [s] since the start of a run: path goals follow one, moving obstacles ride on one.
Positions are in [m], velocities in [m/s], accelerations in [m/s²]. The dynamic pullback
``(M, f − M ẍ̃)`` (paper eq. 13) consumes all three.

Every trajectory is a frozen dataclass whose fields are validated on construction: an
invalid field raises :class:`~dynfab.motion.trajectory_values.TrajectoryError` naming it,
e.g. ``velocity: expected 3 numbers, got 2``.
:func:`dynfab.motion.trajectory_mapping.trajectory_from_mapping` builds one from a scenario
mapping (docs/design.md section 5) and prefixes that name with the mapping's field path.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from dynfab.motion.expression import ExpressionError, parse_expression
from dynfab.motion.trajectory_values import TrajectoryError, numbers, point, positive, scalar, sequence

Samples = tuple[np.ndarray, np.ndarray, np.ndarray]
"""Positions, velocities and accelerations at T times, each of shape (T, d)."""


def derived_field() -> Any:
    """A dataclass field computed in ``__post_init__``: not an argument, not compared."""
    return dataclasses.field(init=False, repr=False, compare=False)


@dataclass(frozen=True, eq=False)
class TrajectoryPoint:
    """The reference at one instant.

    Attributes:
        position: ``x̃(t)`` [m], shape (d,).
        velocity: ``ẋ̃(t)`` [m/s], shape (d,).
        acceleration: ``ẍ̃(t)`` [m/s²], shape (d,).
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


class Trajectory(ABC):
    """A reference ``x̃(t)``; subclasses give :attr:`dimension` and :meth:`_sample`."""

    @property
    @abstractmethod
    def dimension(self) -> int:
        """Number of axes d (2 or 3; any for :class:`StaticPoint`)."""

    @abstractmethod
    def _sample(self, times: np.ndarray) -> Samples:
        """``(x̃, ẋ̃, ẍ̃)`` at the 1-D float array ``times`` [s], each of shape (T, d)."""

    def sample(self, times: ArrayLike) -> Samples:
        """Evaluate at many times at once.

        Args:
            times: 1-D array of T times [s].

        Returns:
            Positions [m], velocities [m/s] and accelerations [m/s²], each (T, d).
        """
        times = np.asarray(times, dtype=float)
        if times.ndim != 1:
            raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
        return self._sample(times)

    def evaluate(self, t: float) -> TrajectoryPoint:
        """``x̃(t)``, ``ẋ̃(t)``, ``ẍ̃(t)`` at one time ``t`` [s]."""
        position, velocity, acceleration = self._sample(np.array([float(t)]))
        return TrajectoryPoint(position[0], velocity[0], acceleration[0])


@dataclass(frozen=True)
class StaticPoint(Trajectory):
    """A point at rest: ``x̃ = P``, ``ẋ̃ = ẍ̃ = 0``.

    Unlike the moving trajectories it takes any number of axes, so that static goals of
    any kind (a subset of axes, a joint configuration) are references too.

    Attributes:
        position: P, one or more numbers [m] (or [rad] for joint configurations).
    """

    position: Sequence[float]
    _position: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        _set(self, "position", numbers(self.position, "position"))

    @property
    def dimension(self) -> int:
        return self._position.size

    def _sample(self, times: np.ndarray) -> Samples:
        zeros = np.zeros((times.size, self.dimension))
        return self._position + zeros, zeros, zeros.copy()


@dataclass(frozen=True)
class LinearTrajectory(Trajectory):
    """Constant velocity: ``x̃(t) = P + V t``, ``ẋ̃ = V``, ``ẍ̃ = 0``.

    Attributes:
        start: P [m], 2 or 3 numbers.
        velocity: V [m/s], as many numbers as ``start``.
    """

    start: Sequence[float]
    velocity: Sequence[float]
    _start: np.ndarray = derived_field()
    _velocity: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        _set(self, "start", point(self.start, "start"))
        _set(self, "velocity", numbers(self.velocity, "velocity", self._start.size))

    @property
    def dimension(self) -> int:
        return self._start.size

    def _sample(self, times: np.ndarray) -> Samples:
        position = self._start + times[:, None] * self._velocity
        velocity = np.broadcast_to(self._velocity, position.shape).copy()
        return position, velocity, np.zeros_like(position)


@dataclass(frozen=True)
class CircleTrajectory(Trajectory):
    """Uniform motion on a circle about C in the plane normal to N.

    With θ = ω t + φ and an orthonormal basis (u, v) of that plane::

        x̃(t) = C + R (cos θ u + sin θ v)
        ẋ̃(t) = R ω (−sin θ u + cos θ v)
        ẍ̃(t) = −ω² (x̃(t) − C)

    The basis is fixed by N alone: u is the world axis least aligned with N (the first of
    equals) made orthogonal to N and normalised, v = N / |N| × u; N = (0, 0, 1) gives
    u = (1, 0, 0), v = (0, 1, 0). In 2-D, u = (1, 0) and v = (0, 1).

    Attributes:
        center: C [m], 2 or 3 numbers; with 2 the circle lies in the plane and ``normal``
            is ignored (still checked).
        radius: R [m] > 0.
        angular_velocity: ω [rad/s]; positive turns from u towards v (counter-clockwise
            seen from the tip of N).
        normal: N, 3 numbers, non-zero; any length.
        phase: φ [rad], the angle at t = 0 (0 starts at C + R u).
    """

    center: Sequence[float]
    radius: float
    angular_velocity: float
    normal: Sequence[float] = (0.0, 0.0, 1.0)
    phase: float = 0.0
    _center: np.ndarray = derived_field()
    _radius: float = derived_field()
    _angular_velocity: float = derived_field()
    _normal: np.ndarray = derived_field()
    _phase: float = derived_field()
    _basis: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        _set(self, "center", point(self.center, "center"))
        _set(self, "radius", positive(self.radius, "radius"))
        _set(self, "angular_velocity", scalar(self.angular_velocity, "angular_velocity"))
        _set(self, "normal", numbers(self.normal, "normal", 3))
        _set(self, "phase", scalar(self.phase, "phase"))
        if not np.any(self._normal):
            raise TrajectoryError("normal", "must not be the zero vector")
        object.__setattr__(self, "_basis", _plane_basis(self._normal, self._center.size))

    @property
    def dimension(self) -> int:
        return self._center.size

    def _sample(self, times: np.ndarray) -> Samples:
        angle = self._angular_velocity * times + self._phase
        cos_sin = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        offset = self._radius * cos_sin @ self._basis
        speed = self._radius * self._angular_velocity
        tangent = speed * np.stack([-cos_sin[:, 1], cos_sin[:, 0]], axis=1)
        return self._center + offset, tangent @ self._basis, -(self._angular_velocity**2) * offset


@dataclass(frozen=True)
class PolynomialTrajectory(Trajectory):
    """A polynomial per axis: ``x̃ᵢ = Σₖ cᵢₖ tᵏ``, ``ẋ̃ᵢ = Σₖ k cᵢₖ tᵏ⁻¹``, ....

    Attributes:
        coefficients: One non-empty list per axis (2 or 3 axes), lowest order first:
            ``cᵢ₀`` [m], ``cᵢ₁`` [m/s], ``cᵢ₂`` [m/s²], ...; axes may differ in length.
    """

    coefficients: Sequence[Sequence[float]]
    _powers: np.ndarray = derived_field()
    _matrices: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        axes = sequence(self.coefficients, "coefficients")
        if len(axes) not in (2, 3):
            problem = f"expected 2 or 3 lists (one per axis), got {len(axes)}"
            raise TrajectoryError("coefficients", problem)
        rows = tuple(numbers(axis, f"coefficients[{i}]") for i, axis in enumerate(axes))
        object.__setattr__(self, "coefficients", tuple(tuple(row.tolist()) for row in rows))
        order = max(len(row) for row in rows)
        position = np.zeros((len(rows), order))
        for i, row in enumerate(rows):
            position[i, : len(row)] = row
        k = np.arange(order)
        velocity = np.zeros_like(position)
        acceleration = np.zeros_like(position)
        with np.errstate(over="ignore"):  # an overflowing derivative is refused by the run's check
            velocity[:, :-1] = position[:, 1:] * k[1:]
            acceleration[:, :-1] = velocity[:, 1:] * k[1:]
        object.__setattr__(self, "_powers", k.astype(float))
        object.__setattr__(self, "_matrices", np.stack([position.T, velocity.T, acceleration.T]))

    @property
    def dimension(self) -> int:
        return self._matrices.shape[2]

    def _sample(self, times: np.ndarray) -> Samples:
        powers = times[:, None] ** self._powers
        position, velocity, acceleration = powers @ self._matrices
        return position, velocity, acceleration


@dataclass(frozen=True)
class ExpressionTrajectory(Trajectory):
    """One safe arithmetic expression in ``t`` per axis (:mod:`dynfab.motion.expression`).

    ``ẋ̃`` and ``ẍ̃`` are exact, by CasADi's automatic differentiation. One CasADi
    function ``t ↦ [x̃, ẋ̃, ẍ̃]`` is compiled on construction; :meth:`evaluate` calls it
    through preallocated buffers, so instances must not be shared between threads.

    Attributes:
        expressions: 2 or 3 expressions giving the axes in [m], e.g.
            ``("0.5 + 0.1*sin(0.5*t)", "0.2*t", "0.3")``. The value and both derivatives
            must be finite at t = 0.
    """

    expressions: Sequence[str]
    _function: ca.Function = derived_field()
    _time: np.ndarray = derived_field()
    _result: np.ndarray = derived_field()
    _buffer: Any = derived_field()
    _run: Callable[[], None] = derived_field()

    def __post_init__(self) -> None:
        texts = sequence(self.expressions, "expressions")
        if len(texts) not in (2, 3):
            problem = f"expected 2 or 3 expressions (one per axis), got {len(texts)}"
            raise TrajectoryError("expressions", problem)
        t = ca.SX.sym("t")
        axes = []
        for i, text in enumerate(texts):
            try:
                axes.append(parse_expression(text, t))
            except ExpressionError as error:
                raise TrajectoryError(f"expressions[{i}]", str(error)) from None
        position = ca.vertcat(*axes)
        velocity = ca.jacobian(position, t)
        acceleration = ca.jacobian(velocity, t)
        # Dense output: the buffer interface writes nonzeros only, so no structural zeros.
        stacked = ca.densify(ca.horzcat(position, velocity, acceleration))
        function = ca.Function("reference", [t], [stacked])
        object.__setattr__(self, "expressions", tuple(texts))
        object.__setattr__(self, "_function", function)
        self._bind_buffers()
        self.evaluate(0.0)
        infinite = np.flatnonzero(~np.all(np.isfinite(self._result), axis=0))
        if infinite.size:
            problem = "value or derivatives not finite at t = 0"
            raise TrajectoryError(f"expressions[{infinite[0]}]", problem)

    def __reduce__(self) -> tuple[type[ExpressionTrajectory], tuple[tuple[str, ...]]]:
        """Copy and pickle by the expressions; the compiled function is rebuilt."""
        return ExpressionTrajectory, (tuple(self.expressions),)

    def _bind_buffers(self) -> None:
        """Attach the time and result arrays to the compiled function's buffer interface."""
        buffer, call = self._function.buffer()
        time = np.zeros(1)
        result = np.zeros((3, len(self.expressions)))  # CasADi's column-major (d, 3) output
        buffer.set_arg(0, memoryview(time))
        buffer.set_res(0, memoryview(result))
        object.__setattr__(self, "_time", time)
        object.__setattr__(self, "_result", result)
        object.__setattr__(self, "_buffer", buffer)
        object.__setattr__(self, "_run", call)

    @property
    def dimension(self) -> int:
        return self._result.shape[1]

    def evaluate(self, t: float) -> TrajectoryPoint:
        """``x̃(t)``, ``ẋ̃(t)``, ``ẍ̃(t)`` at one time ``t`` [s], through the buffers."""
        self._time[0] = t
        self._run()
        position, velocity, acceleration = self._result.copy()
        return TrajectoryPoint(position, velocity, acceleration)

    def _sample(self, times: np.ndarray) -> Samples:
        if times.size == 0:
            empty = np.zeros((0, self.dimension))
            return empty, empty.copy(), empty.copy()
        # Called with T columns, the function runs once per column: output (d, 3 T).
        stacked = np.asarray(self._function(ca.DM(times).T)).reshape(self.dimension, times.size, 3)
        return stacked[:, :, 0].T.copy(), stacked[:, :, 1].T.copy(), stacked[:, :, 2].T.copy()


def _set(instance: Trajectory, name: str, value: Any) -> None:
    """Store a validated field: the public one as given type, ``_name`` as numpy."""
    public = tuple(value.tolist()) if isinstance(value, np.ndarray) else value
    object.__setattr__(instance, name, public)
    object.__setattr__(instance, f"_{name}", value)


def _plane_basis(normal: np.ndarray, dimension: int) -> np.ndarray:
    """Rows u, v: an orthonormal basis of the plane normal to ``normal`` (see CircleTrajectory)."""
    if dimension == 2:
        return np.eye(2)
    n = normal / np.linalg.norm(normal)
    axis = np.eye(3)[int(np.argmin(np.abs(n)))]
    u = axis - (axis @ n) * n
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(n, u)])
