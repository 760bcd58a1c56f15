"""A trajectory moved by an offset that glides from one value to another (a goal or an
obstacle dragged by hand in the viewer: the drag becomes motion with a velocity, which
the dynamic fabric uses)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dynfab.motion.trajectories import Samples, Trajectory, derived_field
from dynfab.motion.trajectory_values import TrajectoryError, numbers


@dataclass(frozen=True)
class ShiftedTrajectory(Trajectory):
    """``x̃(t) = x̃_inner(t) + Δ(t)``, the offset gliding at a constant rate from ``Δ0`` to
    ``Δ1`` over ``[t0, t0 + τ]``:

        s(t) = clip((t − t0) / τ, 0, 1),   Δ(t) = Δ0 + s(t) (Δ1 − Δ0),
        ẋ̃(t) = ẋ̃_inner(t) + (Δ1 − Δ0) / τ   for t0 ≤ t < t0 + τ (else ẋ̃_inner),
        ẍ̃(t) = ẍ̃_inner(t)   (the glide's start and stop are left out).

    With ``τ = 0`` the offset is ``Δ1`` at every time.

    Attributes:
        inner: the reference that is moved.
        offset: Δ1, one number per axis of ``inner`` [m].
        start_offset: Δ0 [m]; None: Δ1.
        start: t0 [s].
        glide: τ [s] (>= 0).
    """

    inner: Trajectory
    offset: Sequence[float]
    start_offset: Sequence[float] | None = None
    start: float = 0.0
    glide: float = 0.0
    _offset: np.ndarray = derived_field()
    _start_offset: np.ndarray = derived_field()

    def __post_init__(self) -> None:
        d = self.inner.dimension
        offset = numbers(self.offset, "offset", d)
        start_offset = offset if self.start_offset is None else numbers(self.start_offset, "start_offset", d)
        if not (np.isfinite(self.start) and np.isfinite(self.glide) and self.glide >= 0.0):
            raise TrajectoryError("glide", f"expected a finite start and a glide >= 0, got {self.start}, {self.glide}")
        object.__setattr__(self, "_offset", offset)
        object.__setattr__(self, "_start_offset", start_offset)

    @property
    def dimension(self) -> int:
        return self.inner.dimension

    def _sample(self, times: np.ndarray) -> Samples:
        position, velocity, acceleration = self.inner.sample(times)
        change = self._offset - self._start_offset
        if self.glide == 0.0:
            return position + self._offset, velocity, acceleration
        progress = np.clip((times - self.start) / self.glide, 0.0, 1.0)[:, None]
        gliding = ((times >= self.start) & (times < self.start + self.glide))[:, None]
        return (position + self._start_offset + progress * change,
                velocity + np.where(gliding, change / self.glide, 0.0), acceleration)
