"""A way out of a goal the spheres refuse, planned on the robot's meshes: guidance's last
resort for goals in a pocket of a mesh scene (development MBM kitchen/0005, seed 1: the arm
between the counter and the dishwasher door, where the forearm's and wrist's spheres, up to
2 cm out of their meshes, read 7-14 mm of penetration the meshes clear by 10 mm, and the
nearest configurations the spheres accept lie 0.8 rad and more away).

A tree grows from the goal through configurations free on the meshes
(:class:`~dynfab.robots.mesh_contact.MeshContactCheck`, a boolean check with a security
margin, every straight extension checked at ``resolution``) until one of its nodes is free
on the spheres (``accept``, the planner's own check); its branch, shortcut where a straight
motion is free, is the escape ``e_0 = goal, …, e_k`` (k+1, n) [rad]. Each extension moves
``step`` [rad] from the nearest node toward a sample, uniform within the joint limits or,
with probability ``local_share``, a node plus a normal step of deviation ``local`` [rad]
per joint (the pocket's ways out are a few centimetres wide). The search stops after
``checks`` configurations (a bound independent of the machine's load).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.robots.mesh_contact import MeshContactCheck

__all__ = ["MeshEscapeSettings", "mesh_escape"]


@dataclass(frozen=True)
class MeshEscapeSettings:
    """How the escape tree grows (module docstring).

    Attributes:
        checks: most configurations the tree and its shortcuts check on the meshes [-].
        step: length of one extension [rad].
        resolution: largest distance between checked configurations of a motion [rad].
        local: deviation of a local sample per joint [rad].
        local_share: probability of a local sample [-].
        shortcuts: attempts to shortcut the branch found [-].
        reach: how far from the goal per joint a target the spheres accept is drawn [rad].
        samples: draws for one such target [-].
    """

    checks: int = 20_000
    step: float = 0.05
    resolution: float = 0.01
    local: float = 0.2
    local_share: float = 0.3
    shortcuts: int = 60
    reach: float = 1.0
    samples: int = 50

    def __post_init__(self) -> None:
        for name in ("checks", "step", "resolution", "local", "reach", "samples"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"mesh_escape.{name}: must be finite and > 0, got {value}")
        if not 0.0 <= self.local_share <= 1.0:
            raise ValueError(f"mesh_escape.local_share: must be in [0, 1], got {self.local_share}")
        if self.shortcuts < 0:
            raise ValueError(f"mesh_escape.shortcuts: must be >= 0, got {self.shortcuts}")


def mesh_escape(check: MeshContactCheck, goal: NDArray[np.float64], accept: Callable[[NDArray[np.float64]], bool],
                lower: NDArray[np.float64], upper: NDArray[np.float64], settings: MeshEscapeSettings,
                seed: int = 0) -> NDArray[np.float64] | None:
    """The escape from ``goal`` (free on ``check``) to a configuration ``accept`` takes,
    every configuration between free on ``check`` (module docstring); None if the tree
    found none within ``settings.checks``.

    Args:
        check: the meshes' check, its obstacles set.
        goal: the blocked goal (n,) within ``[lower, upper]`` [rad].
        accept: whether the spheres accept a configuration.
        lower, upper: the joint limits (n,) [rad].
        settings: the tree's settings.
        seed: the sampler's seed.
    """
    goal = np.asarray(goal, dtype=float)
    if not check.free(goal):
        return None
    rng = np.random.default_rng(seed)
    last = check.checks + settings.checks
    nodes, parents = [goal], [-1]
    while check.checks < last:
        if rng.random() < settings.local_share:
            target = np.clip(nodes[int(rng.integers(len(nodes)))] + rng.normal(0.0, settings.local, goal.size),
                             lower, upper)
        else:
            target = _accepted_sample(goal, accept, lower, upper, settings, rng)
        stacked = np.asarray(nodes)
        nearest = int(np.argmin(np.linalg.norm(stacked - target, axis=1)))
        for new in _steps(stacked[nearest], target, settings.step):   # towards it until blocked
            if check.checks >= last or not check.motion_free(nodes[nearest], new, settings.resolution):
                break
            nodes.append(new)
            parents.append(nearest)
            nearest = len(nodes) - 1
            if accept(new):
                branch = [nearest]
                while parents[branch[-1]] >= 0:
                    branch.append(parents[branch[-1]])
                return _shortcut(check, np.asarray(nodes)[branch[::-1]], settings, rng, last)
    return None


def _accepted_sample(goal: NDArray[np.float64], accept: Callable[[NDArray[np.float64]], bool],
                     lower: NDArray[np.float64], upper: NDArray[np.float64], settings: MeshEscapeSettings,
                     rng: np.random.Generator) -> NDArray[np.float64]:
    """A configuration within ``reach`` of ``goal`` per joint (and the limits) that
    ``accept`` takes, of up to ``samples`` uniform draws; the last drawn if none."""
    low, high = np.maximum(lower, goal - settings.reach), np.minimum(upper, goal + settings.reach)
    for _ in range(settings.samples):
        drawn = rng.uniform(low, high)
        if accept(drawn):
            break
    return drawn


def _steps(a: NDArray[np.float64], b: NDArray[np.float64], step: float) -> list[NDArray[np.float64]]:
    """The configurations from ``a`` (excluded) to ``b`` (included), ``step`` [rad] apart."""
    count = max(1, int(np.ceil(float(np.linalg.norm(b - a)) / step)))
    return [a + (b - a) * k / count for k in range(1, count + 1)]


def _shortcut(check: MeshContactCheck, path: NDArray[np.float64], settings: MeshEscapeSettings,
              rng: np.random.Generator, last: int) -> NDArray[np.float64]:
    """``path`` (k, n) with waypoints dropped where the straight motion past them is free,
    its ends kept, within ``settings.shortcuts`` attempts and the check budget ``last``."""
    waypoints = list(path)
    for _ in range(settings.shortcuts):
        if len(waypoints) < 3 or check.checks >= last:
            break
        i, j = sorted(int(k) for k in rng.choice(len(waypoints), size=2, replace=False))
        if j - i >= 2 and check.motion_free(waypoints[i], waypoints[j], settings.resolution):
            del waypoints[i + 1:j]
    return np.asarray(waypoints)
