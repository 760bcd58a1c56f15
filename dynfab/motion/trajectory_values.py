"""Checks of the values a trajectory is built from; every violation is a
:class:`TrajectoryError` naming the field, e.g. ``velocity: expected 3 numbers, got 2``."""

from __future__ import annotations

import math
from numbers import Real
from typing import Any

import numpy as np

from dynfab.describe import describe

__all__ = ["TrajectoryError", "numbers", "point", "positive", "scalar", "sequence"]


class TrajectoryError(ValueError):
    """An invalid trajectory field; the message is one line ``<field>: <problem>``.

    Attributes:
        field: Path of the offending field, e.g. ``waypoints[2]``.
        problem: What is wrong with it.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


def sequence(value: object, field: str) -> list[Any]:
    """Return ``value`` as a list if it is a list, a tuple or an array (not text)."""
    if isinstance(value, np.ndarray):
        return list(value)
    if not isinstance(value, list | tuple):
        raise TrajectoryError(field, f"expected a list, got {describe(value)}")
    return list(value)


def numbers(value: object, field: str, length: int | None = None) -> np.ndarray:
    """A 1-D float array of finite numbers, non-empty, of ``length`` if given."""
    items = sequence(value, field)
    if length is not None and len(items) != length:
        raise TrajectoryError(field, f"expected {length} numbers, got {len(items)}")
    if not items:
        raise TrajectoryError(field, "expected numbers, got an empty list")
    return np.array([scalar(item, f"{field}[{i}]") for i, item in enumerate(items)])


def point(value: object, field: str) -> np.ndarray:
    """A position in the plane or in space: 2 or 3 finite numbers."""
    values = numbers(value, field)
    if values.size not in (2, 3):
        raise TrajectoryError(field, f"expected 2 or 3 numbers, got {values.size}")
    return values


def scalar(value: object, field: str) -> float:
    """A finite real number (booleans and text are not numbers)."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, Real):
        raise TrajectoryError(field, f"expected a number, got {describe(value)}")
    number = float(value)
    if not math.isfinite(number):
        raise TrajectoryError(field, f"expected a finite number, got {number}")
    return number


def positive(value: object, field: str) -> float:
    """A finite number > 0."""
    number = scalar(value, field)
    if number <= 0.0:
        raise TrajectoryError(field, f"must be positive, got {number:g}")
    return number
