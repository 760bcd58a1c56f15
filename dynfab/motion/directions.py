"""Orientation references: unit directions turning at a constant angular velocity.

An orientation goal's target is a stack of unit world directions ``[d_1; …; d_k]``
(:mod:`dynfab.fabric.leaves.orientation`). :class:`RotatingDirections` turns all of them
together about a fixed world axis, at the angular velocity ``ω`` [rad/s]:

    d_i(t) = R(ω t) d_i(0),   ḋ_i = ω × d_i,   d̈_i = ω × (ω × d_i),

with ``R(ω t)`` the rotation by ``‖ω‖ t`` about ``ω/‖ω‖`` (Rodrigues). With ``ω = 0`` the
directions are at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynfab.motion.trajectories import Samples, Trajectory

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class RotatingDirections(Trajectory):
    """Unit directions turning together with the angular velocity ``ω``.

    Attributes:
        directions: ``d_i(0)``, unit 3-vectors in the world (normalised by the caller).
        angular_velocity: ``ω`` [rad/s] in the world.
    """

    directions: tuple[Vector3, ...]
    angular_velocity: Vector3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        initial = np.asarray(self.directions, dtype=float)
        if initial.ndim != 2 or initial.shape[1] != 3 or initial.shape[0] == 0:
            raise ValueError(f"directions: expected one or more 3-vectors, got {list(self.directions)}")
        if not np.allclose(np.linalg.norm(initial, axis=1), 1.0, atol=1e-9):
            raise ValueError(f"directions: expected unit vectors, got {initial.tolist()}")
        if np.asarray(self.angular_velocity, dtype=float).shape != (3,):
            raise ValueError(f"angular_velocity: expected 3 numbers, got {list(self.angular_velocity)}")

    @property
    def dimension(self) -> int:
        return 3 * len(self.directions)

    def _sample(self, times: np.ndarray) -> Samples:
        omega = np.asarray(self.angular_velocity, dtype=float)
        initial = np.asarray(self.directions, dtype=float)  # (k, 3)
        rotations = _rotations(omega, times)  # (T, 3, 3)
        position = np.einsum("tij,kj->tki", rotations, initial)  # (T, k, 3)
        velocity = np.cross(omega, position)
        acceleration = np.cross(omega, velocity)
        count = times.size
        return position.reshape(count, -1), velocity.reshape(count, -1), acceleration.reshape(count, -1)


def _rotations(omega: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``R(ω t)`` at each time, shape (T, 3, 3): ``I + sin φ K + (1 − cos φ) K²`` with
    ``φ = ‖ω‖ t`` and ``K`` the cross-product matrix of ``ω/‖ω‖``."""
    speed = float(np.linalg.norm(omega))
    identity = np.broadcast_to(np.eye(3), (times.size, 3, 3)).copy()
    if speed == 0.0:
        return identity
    x, y, z = omega / speed
    cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    angle = speed * times[:, None, None]
    return identity + np.sin(angle) * cross + (1.0 - np.cos(angle)) * (cross @ cross)

