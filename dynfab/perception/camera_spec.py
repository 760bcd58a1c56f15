"""A depth camera's placement, optics and timing, as a value.

The camera sits at ``position`` and looks at ``look_at``. Its frame follows OpenGL's and
MuJoCo's convention: ``x`` to the right of the image, ``y`` up, and the camera looks along
``−z``:

    z = (position − look_at) / ‖position − look_at‖,
    x = (u × z) / ‖u × z‖,   y = z × x,

with ``u`` the world's up axis (0, 0, 1), or (0, 1, 0) when the camera looks straight up or
down (then image up is world +y). The pinhole has square pixels and its vertical field of
view ``fov``: the focal length in pixels is

    f = (height / 2) / tan(fov / 2),

and the principal point is the image centre ``(width / 2, height / 2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["CameraSpec", "CameraSpecError"]

#: Below this ``‖u × z‖`` the view counts as vertical and image up becomes world +y.
_VERTICAL = 1e-6


class CameraSpecError(ValueError):
    """A camera field is invalid; the message starts with the field's name."""


@dataclass(frozen=True)
class CameraSpec:
    """A depth camera (module docstring).

    Attributes:
        position: Optical centre in the world frame (3,) [m].
        look_at: A point on the optical axis, in front of the camera (3,) [m].
        width: Image width [pixels], > 0.
        height: Image height [pixels], > 0.
        fov: Vertical field of view [deg], in (0, 180).
        rate: Frames per second of simulated time [Hz], > 0.
        noise: Standard deviation σ of the Gaussian noise on each pixel's depth [m], >= 0.
        delay: Age of a frame when the planner receives it [s], >= 0.
    """

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    width: int = 320
    height: int = 240
    fov: float = 60.0
    rate: float = 30.0
    noise: float = 0.0
    delay: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _point(self.position, "position"))
        object.__setattr__(self, "look_at", _point(self.look_at, "look_at"))
        if np.linalg.norm(np.subtract(self.look_at, self.position)) < 1e-9:
            raise CameraSpecError(f"look_at: must differ from position, both are {list(self.position)}")
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise CameraSpecError(f"{name}: must be a whole number of pixels > 0, got {value!r}")
            object.__setattr__(self, name, int(value))
        fov = _number(self.fov, "fov")
        if not 0.0 < fov < 180.0:
            raise CameraSpecError(f"fov: must lie in (0, 180) degrees, got {self.fov}")
        rate = _number(self.rate, "rate")
        if rate <= 0.0:
            raise CameraSpecError(f"rate: must be > 0 Hz, got {self.rate}")
        for name in ("noise", "delay"):
            if _number(getattr(self, name), name) < 0.0:
                raise CameraSpecError(f"{name}: must be >= 0, got {getattr(self, name)}")
        object.__setattr__(self, "fov", fov)
        object.__setattr__(self, "rate", rate)
        object.__setattr__(self, "noise", float(self.noise))
        object.__setattr__(self, "delay", float(self.delay))

    @property
    def focal(self) -> float:
        """``f = (height / 2) / tan(fov / 2)`` [pixels]."""
        return 0.5 * self.height / math.tan(math.radians(self.fov) / 2.0)

    @property
    def period(self) -> float:
        """Time between frames, ``1 / rate`` [s]."""
        return 1.0 / self.rate

    @property
    def rotation(self) -> NDArray[np.float64]:
        """(3, 3): columns are the camera's x (image right), y (image up) and z (backward)
        axes in the world frame (module docstring)."""
        z = np.subtract(self.position, self.look_at)
        z = z / np.linalg.norm(z)
        up = np.array([0.0, 0.0, 1.0])
        if np.linalg.norm(np.cross(up, z)) < _VERTICAL:
            up = np.array([0.0, 1.0, 0.0])
        x = np.cross(up, z)
        x /= np.linalg.norm(x)
        return np.column_stack([x, np.cross(z, x), z])


def _number(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise CameraSpecError(f"{name}: expected a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise CameraSpecError(f"{name}: expected a finite number, got {number}")
    return number


def _point(values: object, name: str) -> tuple[float, float, float]:
    try:
        array = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise CameraSpecError(f"{name}: expected three numbers [x, y, z], got {values!r}") from None
    if array.size != 3:
        raise CameraSpecError(f"{name}: expected three numbers [x, y, z], got {array.size}")
    for i, value in enumerate(array):
        if not math.isfinite(value):
            raise CameraSpecError(f"{name}[{i}]: expected a finite number, got {value}")
    return (float(array[0]), float(array[1]), float(array[2]))
