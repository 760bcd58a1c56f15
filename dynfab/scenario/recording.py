"""Recordings of runs as numpy ``.npz`` files (``dynfab run FILE --record OUT.npz``).

A recording holds N + 1 rows for a run of N control steps; row k is the state at
``t[k] = k dt`` and the command the controller gave there:

- ``t`` (N+1,): times [s];
- ``q`` (N+1, n): joint positions [rad or m], base pose (x, y, yaw) first on a mobile base;
- ``qdot`` (N+1, m): velocity coordinates — joint velocities (m = n), or on a
  differential-drive base the actuated velocities ``(v, omega, arm rates)`` (m = n - 1):
  forward speed [m/s] and yaw rate [rad/s], not the rates of x, y, yaw;
- ``qddot`` (N+1, m): the command held over ``[t[k], t[k] + dt)``; the last row, after
  the run's end, is zero;
- ``joint_names`` (n,) and ``velocity_names`` (m,): strings;
- ``dt`` (): the control period [s];
- ``scenario`` (): the absolute path of the run's scenario file, or ``""`` when the run
  was not loaded from a file (``dynfab plot`` and ``dynfab view`` replay from it).
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from dynfab.robots.robot import Robot
from dynfab.sim import Record

__all__ = ["Recording", "RecordingError", "load_recording", "recording_of", "run_recording", "save_recording"]

_ARRAYS = ("t", "q", "qdot", "qddot")


class RecordingError(ValueError):
    """A recording file that cannot be read or misses a key; the message names it."""


@dataclass(frozen=True)
class Recording:
    """A run as written to (or read from) a ``.npz`` file; fields as in the module doc."""

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]
    joint_names: tuple[str, ...]
    velocity_names: tuple[str, ...]
    dt: float
    scenario: str = ""


def recording_of(record: Record, joint_names: tuple[str, ...], velocity_names: tuple[str, ...],
                 dt: float, scenario: Path | None = None) -> Recording:
    """The recording of a simulated run: its N + 1 states and N commands plus a zero row."""
    qddot = np.vstack([record.qddot, np.zeros((1, record.qdot.shape[1]))])
    return Recording(np.array(record.t), np.array(record.q), np.array(record.qdot), qddot,
                     tuple(joint_names), tuple(velocity_names), float(dt),
                     "" if scenario is None else str(Path(scenario).resolve()))


def run_recording(robot: Robot, record: Record, dt: float, scenario: Path | None = None) -> Recording:
    """The recording of a run of ``robot`` (from the file ``scenario``), naming its joints
    and velocity coordinates."""
    joints = robot.kinematics.joint_names
    velocities = ("v", "omega") + joints[3:] if robot.base is not None else joints
    return recording_of(record, joints, velocities, dt, scenario)


def save_recording(path: str | Path, recording: Recording) -> None:
    """Write ``recording`` to ``path`` (numpy ``.npz``, uncompressed)."""
    with open(path, "wb") as file:
        np.savez(file, t=recording.t, q=recording.q, qdot=recording.qdot, qddot=recording.qddot,
                 joint_names=np.array(recording.joint_names, dtype=str),
                 velocity_names=np.array(recording.velocity_names, dtype=str), dt=np.float64(recording.dt),
                 scenario=np.array(recording.scenario, dtype=str))


def load_recording(path: str | Path) -> Recording:
    """Read a recording written by :func:`save_recording` (``velocity_names``, ``dt`` and
    ``scenario`` may be missing: then the joint names, ``t[1] - t[0]`` and ``""``).

    Raises:
        RecordingError: The file cannot be read, a key is missing, or the shapes disagree.
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: np.array(data[key]) for key in data.files}
    except (OSError, ValueError, zipfile.BadZipFile) as error:
        raise RecordingError(f"{path}: cannot read a numpy .npz file ({error})") from None
    for key in (*_ARRAYS, "joint_names"):
        if key not in arrays:
            raise RecordingError(f"{path}: key '{key}' is missing (expected t, q, qdot, qddot, joint_names)")
    t, q, qdot, qddot = (np.asarray(arrays[key], dtype=float) for key in _ARRAYS)
    joint_names = tuple(str(name) for name in arrays["joint_names"].reshape(-1))
    velocity_names = tuple(str(name) for name in arrays.get("velocity_names", np.array(joint_names)).reshape(-1))
    if t.ndim != 1 or q.shape != (t.size, len(joint_names)):
        raise RecordingError(f"{path}: q has shape {q.shape}, expected ({t.size}, {len(joint_names)}) "
                             f"(one row per time, one column per joint name)")
    for key, array in (("qdot", qdot), ("qddot", qddot)):
        if array.shape != (t.size, len(velocity_names)):
            raise RecordingError(f"{path}: {key} has shape {array.shape}, expected ({t.size}, {len(velocity_names)})")
    dt = float(arrays["dt"]) if "dt" in arrays else float(t[1] - t[0]) if t.size > 1 else 0.0
    scenario = str(arrays["scenario"]) if "scenario" in arrays else ""
    return Recording(t, q, qdot, qddot, joint_names, velocity_names, dt, scenario)
