"""The straight segment of a grasp's approach in joint space: where the robot is along it,
how far beside it, and the obstacles' allowances ahead of it
(:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`,
:class:`~dynfab.motion.guided_fabric.GuidedFabric`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["allowances_ahead", "along_segment", "across_segment", "segment_offset"]


def allowances_ahead(segment: NDArray[np.float64], table: NDArray[np.float64],
                     q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per obstacle, the largest allowance [m] of ``table`` (k, m) at the approach's
    configurations ``segment`` (k, n) [rad] from the robot's (``q``'s projection on the
    segment, less one sample) to the goal (:meth:`~dynfab.motion.guidance.JointGuidance.approach_allowances`)."""
    first = max(0, int(np.floor(along_segment(segment, q) * (len(segment) - 1))) - 1)
    return table[first:].max(axis=0)


def along_segment(segment: NDArray[np.float64], q: NDArray[np.float64]) -> float:
    """Where ``q`` projects on the straight segment from the first to the last configuration
    of ``segment`` (k, n) [rad]: 0 at its start, 1 at its end (clipped) [-]."""
    start, direction = segment[0], segment[-1] - segment[0]
    return float(np.clip(np.dot(q - start, direction) / max(float(np.dot(direction, direction)), 1e-12), 0.0, 1.0))


def segment_offset(segment: NDArray[np.float64], q: NDArray[np.float64]) -> float:
    """Distance [rad] of ``q`` from the straight segment from the first to the last
    configuration of ``segment`` (k, n): from its nearest point."""
    start, direction = segment[0], segment[-1] - segment[0]
    return float(np.linalg.norm(q - (start + along_segment(segment, q) * direction)))


def across_segment(segment: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """The step (n,) [rad] from ``q`` to the line through the first and last configurations
    of ``segment`` (k, n), across it (perpendicular to its direction): the step to the
    nearest point where ``q`` projects inside the segment."""
    direction = segment[-1] - segment[0]
    step = segment[0] - q
    squared = float(np.dot(direction, direction))
    if squared < 1e-12:
        return step
    return step - float(np.dot(step, direction)) / squared * direction
