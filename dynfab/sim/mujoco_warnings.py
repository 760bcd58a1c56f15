"""MuJoCo's warnings on stderr, not in a file in the user's working directory.

MuJoCo's own handler prints a warning and appends it to ``MUJOCO_LOG.TXT`` in the current
folder. Every MuJoCo path of dynfab builds its scene with :mod:`dynfab.sim.mujoco_model`,
which calls :func:`route_warnings_to_stderr` when imported.
"""

from __future__ import annotations

import sys

import mujoco

__all__ = ["route_warnings_to_stderr"]


def route_warnings_to_stderr() -> None:
    """Print MuJoCo's warnings as ``mujoco: warning: TEXT`` on stderr, unless a handler is
    already installed (the user's own is kept)."""
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_to_stderr)


def _to_stderr(text: str) -> None:
    print(f"mujoco: warning: {text}", file=sys.stderr)
