"""A trajectory moved by a constant offset (a goal or obstacle dragged in the viewer)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dynfab.motion.trajectories import Samples, Trajectory, derived_field
from dynfab.motion.trajectory_values import numbers


@dataclass(frozen=True)
class ShiftedTrajectory(Trajectory):
    """``x̃(t) = x̃_inner(t) + Δ``: the inner reference moved by the constant ``Δ``; its
    velocity and acceleration are the inner ones.

    Attributes:
        inner: the reference that is moved.
        offset: Δ, one number per axis of ``inner`` [m].
    """

    inner: Trajectory
    offset: Sequence[float]
    _offset: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        object.__setattr__(self, "_offset", numbers(self.offset, "offset", self.inner.dimension))

    @property
    def dimension(self) -> int:
        return self.inner.dimension

    def _sample(self, times: np.ndarray) -> Samples:
        position, velocity, acceleration = self.inner.sample(times)
        return position + self._offset, velocity, acceleration
