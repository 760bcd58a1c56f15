"""How the built-in Panda's collision spheres (``panda_spheres.py``) are made, and the
command that rewrites that file:

    python -m dynfab.robots.panda_sphere_fit > dynfab/robots/panda_spheres.py
    python -m dynfab.robots.panda_sphere_fit --fine > dynfab/robots/data/panda_fine_spheres.json

From Franka's collision meshes as example-robot-data ships them (``panda.urdf``, active
joints ``panda_joint1..7``), whose frames ``panda_link0`` ... ``panda_link7``, ``panda_hand``
(dynfab's ``panda_hand_body``) and the fingers are dynfab's (:mod:`dynfab.robots.franka`;
tests/test_robots.py checks the kinematics):

1. spheres per *link* (:func:`~dynfab.robots.collision_model.fit_link_spheres`), the
   hand and each finger on their own so that the fingers' spheres move with the opening
   a scenario sets: the fewest spheres with no mesh surface point more than 5 mm outside
   (checked on the meshes subdivided to 2 mm edges) and spheres reaching at most
   :data:`HAND_BULGE` out of the meshes at the hand and the fingers, :data:`ARM_BULGE`
   elsewhere (the fit holds its bulge bound by construction; :data:`_HEADROOM` below it,
   for step 3);
2. a sphere of ``panda_link1`` whose centre lies within 1 cm of joint 1's axis is moved
   onto it, its radius grown by the shift (it still holds the old sphere, so coverage
   is kept), if its bulge stays within the bound: a point on that axis never moves, and
   the planner leaves static spheres out of obstacle avoidance (they cost nothing per step);
3. numbers rounded to 0.1 mm, radii rounded up by one more 0.1 mm (coverage is kept, the
   bulge grows by at most 0.3 mm);
4. self-collision pairs on the meshes (:attr:`PANDA_PAIRS`), selected with the hand
   open and closed and united (the fingers are part of the hand's body for the
   selection; the pairs hold at every opening in between to within the fingers' 4 cm
   travel): body pairs whose meshes come within 2 cm in 10,000 random configurations,
   and per pair the fewest sphere pairs that in each of those configurations, and in
   3,000 more drawn around them (0.1 rad per joint, where contacts are dense), see the
   bodies at most 1 cm farther apart than the meshes are (twice the coverage tolerance).

Two tables: the fabric's (``PANDA_FITTED_*``: the hand and fingers at :data:`HAND_BULGE`,
pairs :data:`PANDA_PAIRS`) and global guidance's (``PANDA_PLANNING_*``:
:data:`PLANNING_TIGHT_LINKS` at :data:`HAND_BULGE`, pairs :data:`PLANNING_PAIRS`; the
other links' spheres are the same). Why two: ``panda_spheres.py``.

A third table, ``data/panda_fine_spheres.json`` (``--fine``; read by
``panda_fine_spheres.py``): every link at :data:`FINE_BULGE`, no pairs, guidance's second
look where its spheres say blocked (:attr:`~dynfab.robots.robot.Robot.fine_spheres`).

The summary at the end of ``panda_spheres.py`` is measured on the final (snapped,
rounded) spheres: coverage on the 2 mm check points plus their spacing bound, bulge as
:func:`~dynfab.geometry.sphere_fitting.sphere_bulges` bounds it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from dynfab.geometry.sphere_fitting import SphereFitParameters, check_points, outside_distances, sphere_bulges

from .collision_model import LinkFit, fit_link_spheres
from .franka import DYNFAB_LINKS, OPEN, PANDA_URDF, franka_kinematics
from .link_meshes import link_collision_meshes
from .robot import CollisionSphere
from .self_collision import PairSelection, select_pairs

# PANDA_URDF lives in dynfab.robots.franka; importers of it from here keep working.
__all__ = ["ARM_BULGE", "FINE_BULGE", "HAND_BULGE", "HAND_LINKS", "PANDA_FIT", "PANDA_PAIRS", "PANDA_URDF", "PLANNING_PAIRS",
           "PLANNING_TIGHT_LINKS", "TOLERANCE", "fit_fine", "fit_panda", "measured", "table_module"]

#: Largest distance of a mesh surface point outside the spheres [m]. The seeds these
#: bounds were chosen and checked on, and held-out results: panda_spheres.py.
TOLERANCE = 0.005
#: Largest distance a sphere reaches out of the meshes: hand and fingers, the rest [m].
HAND_BULGE, ARM_BULGE = 0.01, 0.02
#: Largest distance a sphere of the fine table reaches out of the meshes, every link [m].
FINE_BULGE = 0.005
#: Franka's links with the tighter bulge bound.
HAND_LINKS = ("panda_hand", "panda_leftfinger", "panda_rightfinger")
#: ... in guidance's spheres: also the two links before the hand, which enter shelves and
#: boxes with it. At 2 cm their spheres refused three generated MBM goals free on the
#: meshes (``goal_in_collision``; generated seeds 1 and 2: as posed bookshelf_small/0005 and
#: cage/0003, object removed table_under_pick/0002).
PLANNING_TIGHT_LINKS = ("panda_link5", "panda_link6") + HAND_LINKS
#: What step 3 may add to a bulge: 0.2 mm of radius, 0.09 mm of centre shift [m].
_HEADROOM = 3e-4
#: Sphere fit of the arm links (see the module docstring); the check edge of 2 mm leaves
#: 3.8 mm of the 5 mm to the fit.
PANDA_FIT = SphereFitParameters(tolerance=TOLERANCE, max_bulge=ARM_BULGE - _HEADROOM, check_edge=0.002,
                                fewest=True)
#: Pair selection on the meshes, 1 cm slack, 3,000 draws near contact per body pair (see
#: the module docstring). Without the near draws (123 pairs) it missed a finger on
#: ``panda_link0`` (Experiment 1 seed 1036) and in ``panda_link1`` (Experiment 2b seed 3);
#: the draws' count and spread were chosen on random near-contact configurations (not on
#: those runs); tests/test_self_pairs.py checks both runs and fresh near-contact samples.
PANDA_PAIRS = PairSelection(samples=10000, margin=0.02, meshes=True, cover_slack=0.01, near_samples=3000,
                            near_spread=0.1)
#: The pairs of guidance's spheres: :data:`PANDA_PAIRS` at 7 mm slack. At 1 cm (325 pairs),
#: with the smaller spheres of links 5 and 6, they overlapped in 98.5 % of the touching
#: configurations of tests/test_collision_model.py's fresh samples and stayed up to 5.7 mm
#: apart (the test asks 99 % and 5 mm); 7 mm keeps 373 (99.7 %, 0.9 mm).
PLANNING_PAIRS = replace(PANDA_PAIRS, cover_slack=0.007)
#: Largest shift of a ``panda_link1`` sphere onto joint 1's axis [m].
AXIS_SNAP = 0.01
#: Rounding step of the written numbers [m].
_STEP = 1e-4


def fit_panda(tight: Sequence[str] = HAND_LINKS, selection: PairSelection = PANDA_PAIRS
              ) -> tuple[tuple[LinkFit, ...], tuple[tuple[int, int], ...]]:
    """Steps 1-4 of the module docstring: the fits per link (dynfab's link names; spheres
    snapped and rounded; coverage and bulge measured on them) and the sphere pairs.
    ``tight``: the Franka links fitted at :data:`HAND_BULGE`; ``selection``: how the pairs
    are chosen.

    Raises:
        FileNotFoundError: example-robot-data is not installed.
    """
    kinematics = franka_kinematics(OPEN)
    hand = {link: SphereFitParameters(tolerance=TOLERANCE, max_bulge=HAND_BULGE - _HEADROOM,
                                      check_edge=PANDA_FIT.check_edge, fewest=True) for link in tight}
    fits = []
    for fit in fit_link_spheres(kinematics, PANDA_FIT, hand):
        meshes = link_collision_meshes(kinematics.model, fit.link)
        spheres = tuple(_rounded(_onto_axis(s, meshes, HAND_BULGE if fit.link in tight else ARM_BULGE))
                        for s in fit.spheres)
        fits.append(measured(LinkFit(fit.link, spheres, fit.coverage, fit.bulge), meshes))
    spheres = [s for fit in fits for s in fit.spheres]
    pairs = sorted(set(select_pairs(kinematics, spheres, selection))
                   | set(select_pairs(franka_kinematics(0.0), spheres, selection)))
    renamed = tuple(LinkFit(DYNFAB_LINKS[fit.link], tuple(CollisionSphere(DYNFAB_LINKS[s.link], s.center, s.radius)
                                                          for s in fit.spheres), fit.coverage, fit.bulge)
                    for fit in fits)
    return renamed, tuple(pairs)


def fit_fine() -> tuple[LinkFit, ...]:
    """The fine table: every link at :data:`FINE_BULGE` (coverage :data:`TOLERANCE`), snapped
    and rounded as the other tables (step 3; a ``panda_link1`` sphere onto joint 1's axis
    where the bound allows), coverage and bulge measured; dynfab's link names.

    Raises:
        FileNotFoundError: example-robot-data is not installed.
    """
    kinematics = franka_kinematics(OPEN)
    fine = replace(PANDA_FIT, max_bulge=FINE_BULGE - _HEADROOM)
    fits = []
    for fit in fit_link_spheres(kinematics, fine, {link: fine for link in DYNFAB_LINKS}):
        meshes = link_collision_meshes(kinematics.model, fit.link)
        spheres = tuple(_rounded(_onto_axis(s, meshes, FINE_BULGE)) for s in fit.spheres)
        fits.append(measured(LinkFit(fit.link, spheres, fit.coverage, fit.bulge), meshes))
    return tuple(LinkFit(DYNFAB_LINKS[fit.link], tuple(CollisionSphere(DYNFAB_LINKS[s.link], s.center, s.radius)
                                                       for s in fit.spheres), fit.coverage, fit.bulge)
                 for fit in fits)


def measured(fit: LinkFit, meshes: Sequence) -> LinkFit:
    """``fit`` with its coverage and bulge measured on ``meshes`` (its link's, link frame):
    coverage on the meshes' vertices subdivided to :attr:`PANDA_FIT` ``.check_edge`` plus
    ``check_edge / sqrt(3)``, bulge bounded as :func:`sphere_bulges` does [m]."""
    centres = np.array([s.center for s in fit.spheres])
    radii = np.array([s.radius for s in fit.spheres])
    edge = PANDA_FIT.check_edge
    coverage = outside_distances(check_points(meshes, edge), centres, radii).max(initial=0.0) + edge / math.sqrt(3.0)
    bulge = sphere_bulges(meshes, centres, radii).max(initial=0.0)
    return LinkFit(fit.link, fit.spheres, float(coverage), float(bulge))


def _onto_axis(sphere: CollisionSphere, meshes: Sequence, bound: float) -> CollisionSphere:
    """A ``panda_link1`` sphere within :data:`AXIS_SNAP` of the z axis (joint 1) moved onto
    it, if its bulge stays within ``bound`` [m]."""
    x, y, z = sphere.center
    shift = math.hypot(x, y)
    if sphere.link != "panda_link1" or shift > AXIS_SNAP:
        return sphere
    snapped = CollisionSphere(sphere.link, (0.0, 0.0, z), sphere.radius + shift)
    bulge = sphere_bulges(meshes, np.array([snapped.center]), np.array([snapped.radius]))[0]
    return snapped if bulge <= bound - _HEADROOM else sphere


def _rounded(sphere: CollisionSphere) -> CollisionSphere:
    center = tuple(round(x / _STEP) * _STEP for x in sphere.center)
    radius = (math.ceil(sphere.radius / _STEP) + 1) * _STEP
    return CollisionSphere(sphere.link, center, radius)  # type: ignore[arg-type]


#: A table of ``panda_spheres.py``: its name's prefix (``PANDA_FITTED``), what it is for,
#: the fits per link (those written: a table may leave out the links it shares with the
#: one before) and the pairs (into all its spheres, in the links' order; None: a table
#: without pairs, the fine one).
Table = tuple[str, str, Sequence[LinkFit], Sequence[tuple[int, int]] | None]


def table_module(tables: Sequence[Table], docstring: str) -> str:
    """The text of ``panda_spheres.py``: ``docstring``, then each table's spheres
    (``<prefix>_SPHERES``) and pairs (``<prefix>_PAIRS``)."""
    names = sorted(f"{prefix}_{kind}" for prefix, _, _, pairs in tables
                   for kind in (("PAIRS", "SPHERES") if pairs is not None else ("SPHERES",)))
    lines = [f'"""{docstring.strip()}\n"""', "", "from __future__ import annotations", "",
             f"__all__ = [{', '.join(f'{chr(34)}{name}{chr(34)}' for name in names)}]"]
    for prefix, purpose, fits, pairs in tables:
        lines += ["", f"#: {purpose}: (link, centre in the link frame [m], radius [m]).",
                  f"{prefix}_SPHERES: tuple[tuple[str, tuple[float, float, float], float], ...] = ("]
        for fit in fits:
            for s in fit.spheres:
                centre = ", ".join(f"{x:.4f}" for x in s.center)
                lines.append(f'    ("{s.link}", ({centre}), {s.radius:.4f}),')
        lines.append(")")
        if pairs is None:
            continue
        lines += ["", f"#: Index pairs into {prefix}_SPHERES kept apart.",
                  f"{prefix}_PAIRS: tuple[tuple[int, int], ...] = ("]
        cells = [f"({a}, {b})," for a, b in pairs]
        for start in range(0, len(cells), 10):
            lines.append("    " + " ".join(cells[start:start + 10]))
        lines.append(")")
    return "\n".join(lines) + "\n"


def _summary(table: Table, total: int) -> str:
    """The table's name, then :func:`_summary_rows`."""
    return "\n".join([f"{table[0]}:", ""] + ["    " + row for row in _summary_rows(table, total)])


def _summary_rows(table: Table, total: int) -> list[str]:
    """Per link written: sphere count, coverage and bulge, measured on the final spheres;
    then the table's ``total`` spheres and its pairs."""
    _, _, fits, pairs = table
    rows = [f"{fit.link:<17} {len(fit.spheres):>2} spheres, coverage {1000 * fit.coverage:.1f} mm, "
            f"bulge {1000 * fit.bulge:.1f} mm" for fit in fits]
    pairs_text = "no self-collision pairs" if pairs is None else f"{len(pairs)} self-collision pairs"
    return rows + [f"{total} spheres, {pairs_text}"]


def main(argv: Sequence[str] = ()) -> int:
    """Print the regenerated ``panda_spheres.py``: its current docstring up to
    ``Fitted:``, a new summary, the new tables; with ``--fine``, ``data/panda_fine_spheres.json``."""
    if "--fine" in argv:
        return _print_fine()
    from . import panda_spheres

    fabric, fabric_pairs = fit_panda()
    planning, planning_pairs = fit_panda(PLANNING_TIGHT_LINKS, PLANNING_PAIRS)
    wrist = {DYNFAB_LINKS[link] for link in PLANNING_TIGHT_LINKS if link not in HAND_LINKS}
    if [f.spheres for f in fabric if f.link not in wrist] != [f.spheres for f in planning if f.link not in wrist]:
        raise RuntimeError("the two fits differ outside links 5 and 6")
    tables: list[Table] = [("PANDA_FITTED", "The fabric's spheres", fabric, fabric_pairs),
                           ("PANDA_PLANNING", "Global guidance's spheres of links 5 and 6 (the others: "
                            "PANDA_FITTED_SPHERES'; its pairs index them all in the links' order)",
                            [f for f in planning if f.link in wrist],
                            planning_pairs)]
    head, _, _ = (panda_spheres.__doc__ or "").partition("Fitted:")
    summary = "\n\n".join(_summary(table, sum(len(f.spheres) for f in fits))
                            for table, fits in zip(tables, (fabric, planning)))
    print(table_module(tables, f"{head.rstrip()}\n\nFitted:\n\n{summary}"), end="")
    return 0


def _print_fine() -> int:
    """Print the regenerated ``data/panda_fine_spheres.json`` (:func:`fine_table_json`)."""
    fits = fit_fine()
    table: Table = ("PANDA_FINE", "Guidance's second look, every link at FINE_BULGE", fits, None)
    fitted = _summary_rows(table, sum(len(f.spheres) for f in fits))
    print(fine_table_json(fitted, [s for f in fits for s in f.spheres]), end="")
    return 0


def fine_table_json(fitted: Sequence[str], spheres: Sequence[CollisionSphere]) -> str:
    """The text of ``data/panda_fine_spheres.json``: how it was made, the fit's summary rows
    (``fitted``, :func:`_summary_rows`) and one sphere per line, ``[link, [x, y, z], radius]``
    (centre in the link frame [m], radius [m], rounded to 0.1 mm as :func:`_rounded` leaves
    them)."""
    rows = [f'    ["{s.link}", [{", ".join(f"{x:.4f}" for x in s.center)}], {s.radius:.4f}]' for s in spheres]
    head = {"made_by": "python -m dynfab.robots.panda_sphere_fit --fine", "fitted": list(fitted)}
    text = json.dumps(head, indent=2)[:-2]
    return text + ',\n  "spheres": [\n' + ",\n".join(rows) + "\n  ]\n}\n"


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
