"""The Panda's collision spheres fitted to Franka's collision meshes (example-robot-data),
made and rewritten by ``python -m dynfab.robots.panda_sphere_fit`` (see that module for the
steps: the fewest spheres per body with 1 cm coverage and 3 cm bulge (4.0 cm on
``panda_link7``, where the fitter grew a sphere over points it had missed), the flange,
hand and closed fingers fitted with ``panda_link7``, a ``panda_link1`` sphere moved onto
joint 1's axis, pairs chosen on the meshes).

Claims, checked in tests/test_collision_model.py: no point of the collision meshes lies more
than 1.0 cm outside the spheres (vertices plus about 1 sample per 4 mm^2); on 2000 random
configurations, wherever two bodies' meshes touch, one of the kept pairs overlaps.

Why these parameters (measured 2026-11-23 on the 2-core machine; static fabric; Experiment
1 seeds 0-49, each model with its own scenarios; the scene of ``./run bench``: 5 spheres,
2 boxes and a pose goal):

- the 13 hand-written spheres (``panda_robot("hand-written")``) leave up to 8.3 cm of the
  meshes outside and their 19 pairs let the meshes touch themselves in 11 of 50 exp1 runs;
- the first fit (1 cm, at most 2 cm bulge, greedy cover per link, every closest pair: 46
  spheres, 152 pairs) took 2.7 times the scene's step time;
- the fewest-sphere cover with per-body fits needs 22 spheres at 3 cm bulge (19 at 4 cm);
  pairs chosen on the meshes drop the pairs only the spheres' bulge brings together, and
  the covering rule keeps 30 instead of 65; together 1.37-1.41 times the hand-written
  model's step time in the scene (``./run bench``), target 1.5;
- 3 cm bulge keeps the robot about as slim as the hand-written spheres: the surface of
  the sphere union lies on average 1.6 cm (at most 3.9 cm) out of the meshes, against 1.7
  (8.2) cm; exp1: 49/50 reached without collision (one deadlock, seed 34), the meshes
  never touch an obstacle nor themselves (hand-written: 50/50, meshes touch themselves in
  11 runs).

Fitted:

    panda_link0   5 spheres, coverage 1.00 cm, bulge 3.41 cm
    panda_link1   2 spheres, coverage 1.00 cm, bulge 3.19 cm
    panda_link2   2 spheres, coverage 1.00 cm, bulge 3.22 cm
    panda_link3   2 spheres, coverage 1.00 cm, bulge 3.22 cm
    panda_link4   2 spheres, coverage 1.00 cm, bulge 2.77 cm
    panda_link5   3 spheres, coverage 1.00 cm, bulge 3.36 cm
    panda_link6   2 spheres, coverage 1.00 cm, bulge 3.19 cm
    panda_link7   4 spheres, coverage 1.00 cm, bulge 4.03 cm
    22 spheres, 30 self-collision pairs
"""

from __future__ import annotations

__all__ = ["PANDA_FITTED_PAIRS", "PANDA_FITTED_SPHERES"]

#: (link, centre in the link frame [m], radius [m]).
PANDA_FITTED_SPHERES: tuple[tuple[str, tuple[float, float, float], float], ...] = (
    ("panda_link0", (-0.1091, -0.0176, 0.0276), 0.0616),
    ("panda_link0", (-0.0088, 0.0204, 0.0553), 0.0863),
    ("panda_link0", (-0.0859, 0.0342, 0.0337), 0.0658),
    ("panda_link0", (-0.0115, -0.0003, 0.0700), 0.1002),
    ("panda_link0", (-0.0311, -0.0377, 0.0428), 0.0745),
    ("panda_link1", (0.0000, -0.0422, -0.0209), 0.0869),
    ("panda_link1", (0.0000, 0.0000, -0.1288), 0.0903),
    ("panda_link2", (0.0000, -0.1388, 0.0127), 0.0822),
    ("panda_link2", (0.0004, -0.0215, 0.0427), 0.0869),
    ("panda_link3", (0.0177, 0.0103, -0.0652), 0.0865),
    ("panda_link3", (0.0601, 0.0419, -0.0204), 0.0874),
    ("panda_link4", (-0.0705, 0.0706, 0.0083), 0.0803),
    ("panda_link4", (-0.0201, 0.0204, 0.0389), 0.0846),
    ("panda_link5", (0.0001, -0.0092, -0.2199), 0.0710),
    ("panda_link5", (0.0000, 0.0306, -0.1480), 0.0864),
    ("panda_link5", (0.0003, 0.0601, -0.0244), 0.0829),
    ("panda_link6", (0.0738, 0.0030, 0.0030), 0.0740),
    ("panda_link6", (0.0272, -0.0083, 0.0106), 0.0731),
    ("panda_link7", (0.0122, 0.0090, 0.0864), 0.0608),
    ("panda_link7", (-0.0364, -0.0365, 0.1302), 0.0626),
    ("panda_link7", (0.0378, 0.0378, 0.1253), 0.0588),
    ("panda_link7", (-0.0047, -0.0108, 0.1979), 0.0347),
)

#: Index pairs into PANDA_FITTED_SPHERES kept apart.
PANDA_FITTED_PAIRS: tuple[tuple[int, int], ...] = (
    (0, 15), (0, 16), (0, 18), (0, 20), (1, 18), (2, 17), (3, 15), (3, 16), (3, 17), (3, 19),
    (3, 20), (4, 21), (5, 15), (5, 16), (5, 19), (5, 20), (5, 21), (6, 15), (6, 16), (6, 17),
    (6, 18), (6, 19), (8, 14), (8, 16), (8, 19), (8, 20), (8, 21), (14, 19), (14, 20), (15, 20),
)
