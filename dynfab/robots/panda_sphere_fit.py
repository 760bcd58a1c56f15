"""How the built-in Panda's collision spheres (``panda_spheres.py``) are made, and the
command that rewrites that file:

    python -m dynfab.robots.panda_sphere_fit > dynfab/robots/panda_spheres.py

From Franka's collision meshes as example-robot-data ships them (``panda.urdf``, active
joints ``panda_joint1..7``, the fingers locked closed), whose frames ``panda_link0`` ...
``panda_link7`` are dynfab's (tests/test_robots.py checks the kinematics):

1. spheres per *body* (:func:`~dynfab.robots.collision_model.fit_body_spheres`): the
   flange, hand and closed fingers are welded to ``panda_link7`` and fitted with it;
   the fewest spheres (:attr:`PANDA_FIT`) with no mesh surface point more than 1 cm
   outside and spheres reaching at most 3 cm out of the meshes (the fitter's last step may
   grow a sphere over points it missed: 4.0 cm on ``panda_link7``);
2. a sphere of ``panda_link1`` whose centre lies within 1 cm of joint 1's axis is moved
   onto it, its radius grown by the shift (it still holds the old sphere, so coverage
   is kept): a point on that axis never moves, and the planner leaves static spheres
   out of obstacle avoidance (they cost nothing per step);
3. numbers rounded to 0.1 mm, radii rounded up by one more 0.1 mm (coverage is kept);
4. self-collision pairs on the meshes (:attr:`PANDA_PAIRS`): body pairs whose meshes come
   within 2 cm in 10,000 random configurations, and per pair the fewest sphere pairs that
   in each of those configurations see the bodies at most 2 cm farther apart than the
   meshes are (2 cm = twice the coverage tolerance: what 1 cm coverage of both surfaces
   can guarantee).

Why these choices (static fabric, exp1 and the benchmark scene of ``./run bench``: 5
spheres, 2 boxes, a pose goal) is in the module docstring of ``panda_spheres.py``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from dynfab.geometry.sphere_fitting import SphereFitParameters

from .collision_model import LinkFit, fit_body_spheres
from .kinematics import Kinematics
from .mesh_paths import resolve_uri
from .robot import CollisionSphere
from .self_collision import PairSelection, select_pairs
from .urdf import load_urdf

__all__ = ["PANDA_FIT", "PANDA_JOINTS", "PANDA_PAIRS", "PANDA_URDF", "fit_panda", "franka_kinematics", "table_module"]

#: Franka's Panda description as example-robot-data ships it.
PANDA_URDF = "package://example-robot-data/robots/panda_description/urdf/panda.urdf"
#: The arm's joints (the fingers are locked closed).
PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
#: Sphere fit: 1 cm coverage, at most 3 cm out of the meshes, the fewest spheres.
PANDA_FIT = SphereFitParameters(tolerance=0.01, max_bulge=0.03, fewest=True)
#: Pair selection on the meshes, 2 cm slack (see the module docstring).
PANDA_PAIRS = PairSelection(samples=10000, margin=0.02, meshes=True, cover_slack=0.02)
#: Largest shift of a ``panda_link1`` sphere onto joint 1's axis [m].
AXIS_SNAP = 0.01
#: Rounding step of the written numbers [m].
_STEP = 1e-4


def franka_kinematics() -> Kinematics:
    """Kinematics of example-robot-data's Panda with the arm joints active.

    Raises:
        FileNotFoundError: example-robot-data is not installed.
    """
    path = resolve_uri(PANDA_URDF, None)
    if path is None:
        raise FileNotFoundError(f"{PANDA_URDF}: install dynfab[robots] (example-robot-data)")
    return Kinematics(load_urdf(path), joints=PANDA_JOINTS)


def fit_panda(kinematics: Kinematics) -> tuple[tuple[LinkFit, ...], tuple[tuple[int, int], ...]]:
    """Steps 1-4 of the module docstring: the fits per body (spheres snapped and rounded;
    coverage and bulge as fitted) and the sphere pairs."""
    fits = tuple(replace(fit, spheres=tuple(_rounded(_onto_axis(s)) for s in fit.spheres))
                 for fit in fit_body_spheres(kinematics, PANDA_FIT))
    spheres = [s for fit in fits for s in fit.spheres]
    return fits, select_pairs(kinematics, spheres, PANDA_PAIRS)


def _onto_axis(sphere: CollisionSphere) -> CollisionSphere:
    """A ``panda_link1`` sphere within :data:`AXIS_SNAP` of the z axis (joint 1) moved onto it."""
    x, y, z = sphere.center
    shift = math.hypot(x, y)
    if sphere.link != "panda_link1" or shift > AXIS_SNAP:
        return sphere
    return CollisionSphere(sphere.link, (0.0, 0.0, z), sphere.radius + shift)


def _rounded(sphere: CollisionSphere) -> CollisionSphere:
    center = tuple(round(x / _STEP) * _STEP for x in sphere.center)
    radius = (math.ceil(sphere.radius / _STEP) + 1) * _STEP
    return CollisionSphere(sphere.link, center, radius)  # type: ignore[arg-type]


def table_module(fits: Sequence[LinkFit], pairs: Sequence[tuple[int, int]], docstring: str) -> str:
    """The text of ``panda_spheres.py``: ``docstring``, then the spheres and pairs."""
    lines = [f'"""{docstring.strip()}\n"""', "", "from __future__ import annotations", "",
             '__all__ = ["PANDA_FITTED_PAIRS", "PANDA_FITTED_SPHERES"]', "",
             "#: (link, centre in the link frame [m], radius [m]).",
             "PANDA_FITTED_SPHERES: tuple[tuple[str, tuple[float, float, float], float], ...] = ("]
    for fit in fits:
        for s in fit.spheres:
            centre = ", ".join(f"{x:.4f}" for x in s.center)
            lines.append(f'    ("{s.link}", ({centre}), {s.radius:.4f}),')
    lines += [")", "", "#: Index pairs into PANDA_FITTED_SPHERES kept apart.",
              "PANDA_FITTED_PAIRS: tuple[tuple[int, int], ...] = ("]
    cells = [f"({a}, {b})," for a, b in pairs]
    for start in range(0, len(cells), 10):
        lines.append("    " + " ".join(cells[start:start + 10]))
    lines.append(")")
    return "\n".join(lines) + "\n"


def _summary(fits: Sequence[LinkFit], pairs: Sequence[tuple[int, int]]) -> str:
    """Per body: sphere count, coverage and bulge as fitted (snapping and rounding only
    grow radii: coverage stays, bulge grows by at most the shift plus 0.2 mm)."""
    rows = [f"    {fit.link:<12} {len(fit.spheres):>2} spheres, coverage {100 * fit.coverage:.2f} cm, "
            f"bulge {100 * fit.bulge:.2f} cm" for fit in fits]
    total = sum(len(fit.spheres) for fit in fits)
    return "\n".join(rows + [f"    {total} spheres, {len(pairs)} self-collision pairs"])


def main() -> int:
    """Print the regenerated ``panda_spheres.py``: its current docstring up to
    ``Fitted:``, a new summary, the new tables."""
    from . import panda_spheres

    fits, pairs = fit_panda(franka_kinematics())
    head, _, _ = (panda_spheres.__doc__ or "").partition("Fitted:")
    print(table_module(fits, pairs, f"{head.rstrip()}\n\nFitted:\n\n{_summary(fits, pairs)}"), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
