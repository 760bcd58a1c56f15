"""The Panda's fine spheres: Franka's collision meshes (example-robot-data) covered within
5 mm with no sphere reaching more than 5 mm out of them, on every link (the hand body and
each finger on their own, as in ``panda_spheres.py``), read from
``data/panda_fine_spheres.json`` (one ``[link, [x, y, z], radius]`` per sphere, its fit's
summary per link under ``fitted``), which
``python -m dynfab.robots.panda_sphere_fit --fine`` rewrites.

Global guidance's second look (issue 19): where its spheres (``panda_spheres.py``'s planning
table, 1 cm out at the wrist and the hand, 2 cm elsewhere) find a configuration closer to the
obstacles than the margin, its checker asks these, and a configuration is free if either
table finds it so (:class:`~dynfab.motion.configuration_checker.ConfigurationChecker`). Both
leave at most 5 mm of the meshes outside, so either is as safe as the other; the fine one,
four times the spheres, is only evaluated near obstacles. No pairs: self-collision is the
planning table's.

Why: fresh generated MotionBenchMaker problems that failed with ``goal_in_collision`` or
``no_path`` had goals or ways free on Franka's meshes that the planning spheres refused
(docs/results.md, session 19).
"""

from __future__ import annotations

import json
from importlib import resources

__all__ = ["PANDA_FINE_SPHERES"]

Sphere = tuple[str, tuple[float, float, float], float]


def _read_table() -> tuple[Sphere, ...]:
    """The table's spheres: (link, centre in the link frame [m], radius [m])."""
    text = resources.files("dynfab.robots").joinpath("data/panda_fine_spheres.json").read_text()
    return tuple((str(link), (float(x), float(y), float(z)), float(radius))
                 for link, (x, y, z), radius in json.loads(text)["spheres"])


#: Guidance's second look, every link at FINE_BULGE: (link, centre in the link frame [m], radius [m]).
PANDA_FINE_SPHERES: tuple[Sphere, ...] = _read_table()
