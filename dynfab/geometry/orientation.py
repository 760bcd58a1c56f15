"""Angles between directions and between rotations (numpy), for orientation goals.

Orientation goals compare unit directions: the world direction ``y = R a`` of a link axis
``a`` with a target direction ``d``, or the three columns of a link rotation ``R`` with
those of a target rotation ``R_d``. The angles here are the errors reported by metrics;
the chord lengths (``‖y − d‖``, ``‖R − R_d‖_F``) are what the planner's orientation leaf
drives to zero (:mod:`dynfab.fabric.leaves.orientation`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["direction_angle", "rotation_angle", "unit_vector"]

_MIN_NORM = 1e-9


def unit_vector(values: ArrayLike, what: str = "direction") -> tuple[float, float, float]:
    """``v / ‖v‖`` for a 3-vector ``v``.

    Raises:
        ValueError: not three finite numbers, or a norm below 1e-9 (no direction).
    """
    v = np.asarray(values, dtype=float).reshape(-1)
    if v.size != 3 or not np.isfinite(v).all():
        raise ValueError(f"{what} must be 3 finite numbers, got {v.tolist()}")
    norm = float(np.linalg.norm(v))
    if norm < _MIN_NORM:
        raise ValueError(f"{what} must be a non-zero vector, got {v.tolist()}")
    x, y, z = (float(c) for c in v / norm)
    return (x, y, z)


def direction_angle(u: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
    """Angle between directions ``u`` and ``v`` (shape (..., 3)), in [0, π] [rad].

    ``θ = atan2(‖u × v‖, u · v)``, accurate near 0 and π (unlike ``acos``); the inputs
    need not be unit vectors.
    """
    a = np.asarray(u, dtype=float)
    b = np.asarray(v, dtype=float)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def rotation_angle(rotation: ArrayLike, target: ArrayLike) -> NDArray[np.float64]:
    """Angle of the relative rotation ``R_dᵀ R`` (shape (..., 3, 3)), in [0, π] [rad].

    From the Frobenius chord: ``‖R − R_d‖_F = 2√2 sin(θ/2)``, so
    ``θ = 2 asin(‖R − R_d‖_F / (2√2))`` (accurate near 0).
    """
    chord = np.linalg.norm(np.asarray(rotation, dtype=float) - np.asarray(target, dtype=float), axis=(-2, -1))
    return 2.0 * np.arcsin(np.clip(chord / (2.0 * np.sqrt(2.0)), 0.0, 1.0))
