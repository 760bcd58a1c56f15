"""The Panda's collision spheres fitted to Franka's collision meshes (example-robot-data),
made and rewritten by ``python -m dynfab.robots.panda_sphere_fit`` (see that module for the
steps: the fewest spheres per link, the hand body and each finger on their own, with 5 mm
coverage and at most 1 cm bulge at the hand and the fingers, 2 cm elsewhere; a
``panda_link1`` sphere moved onto joint 1's axis where the bound allows; pairs chosen on the
meshes with the hand open and closed, on uniform samples and on samples drawn around their
near contacts).

Claims, checked in tests/test_collision_model.py: no point of the collision meshes lies more
than 5 mm outside the spheres (vertices plus about 1 sample per 4 mm^2); no sphere reaches
more than 1 cm out of the hand's and the fingers' meshes and 2 cm out of the others'
(measured on the spheres' surfaces); on 2000 random configurations, open and closed,
wherever two bodies' meshes touch a kept pair of theirs comes within 5 mm (measured
1.5 mm), and overlaps in 99 % of those configurations (measured 99.4 %); in
tests/test_self_pairs.py, wherever a finger or the hand goes more than 1 cm into
``panda_link0`` or ``panda_link1`` (fresh samples near contact, and two runs where the 123
pairs chosen on uniform samples alone saw nothing: 98 % and 1.5 cm in the check above)
a kept pair overlaps.

Why (issue 19): the previous table (22 spheres, 1 cm coverage, 3 cm bulge, the flange,
hand and closed fingers welded to ``panda_link7`` and fitted with it, 30 pairs) reached up
to 4.0 cm out of the hand, so every MotionBenchMaker grasp goal (the open hand 2-10 mm
around an object) was in collision for the fabric. Now the hand has its own body and
fingers at the opening a scenario sets (``robot: {name: panda, fingers: 0.04}``).

Two tables (2026-11-26, issue 19): the fabric's (``PANDA_FITTED_*``) and global guidance's
(``PANDA_PLANNING_*``), which :attr:`dynfab.robots.robot.Robot.planning_robot` gives the
planner's configuration checks. Guidance's has links 5 and 6 at 1 cm too (22 and 15 spheres
against 7 and 4, 101 in all) and 373 pairs (the selection's slack 7 mm:
``panda_sphere_fit.py`` says why). At 2 cm those links refused three generated MBM goals
free on Franka's meshes (``goal_in_collision``; generated seeds 1 and 2: as posed
bookshelf_small/0005 and cage/0003, object removed table_under_pick/0002); with the tighter
table the two latter plan and are reached, the first is still refused (2.8 mm from a board
on the meshes, link 5's spheres 1.1 mm into it). The fabric keeps the 75: its obstacle
leaves act one per sphere, and with the 101 (three times the leaves at links 5 and 6) the
arm stalled 13 mm from the bars in two of eight fresh cage problems that the 75 reach
(generated seed 3, as posed, problems 1 and 2). The figures below are the fabric's.

What it costs (measured 2026-11-25 on the 2-core machine, ``./run bench``, the scene of
5 spheres, 2 boxes and a pose goal, static fabric, VM): 0.518 ms a step against 0.176 ms
with the previous table, 2.9x (2.8x against the hand-written spheres timed in the same run
as a control for the machine's load); compiled, ``./run bench``'s backends: C step
67 us against 15 us, exported C 31 against 6.9 us, Boxer+Panda 220 against 47 us (about
4.5x). That is above the 2.5x issue 19 accepts without a trade-off. Most of it is the
obstacle leaves of 58 moving spheres (17 on ``panda_link0`` never move and cost nothing
per step); the 123 pairs are about a third (VM: 0.40 ms without them). The trade-off on
the table: the hand and fingers as here (19 spheres at 5 mm / 1 cm, what the grasp goals
need) and the arm at the previous 1 cm / 3 cm (24 spheres), 43 spheres and 65 pairs,
0.33 ms a step in the same scene, 1.9x. The 268 pairs of the near-contact selection
(issue 19, the 123 above missed finger contacts) against the 123, both timed in the same
run beside no pairs (``bench/bench_self_pairs.py``, the same scene, 2000 interleaved
steps, 2026-11-26, load 13-16 on the 2 cores): VM 0.225 against 0.188 ms (1.20x; no
pairs 0.147 ms), compiled C 75 against 58 us (1.29x; no pairs 36 us); the C planner has
122,235 instructions against 94,819 and compiled in 211 s against 101 s (gcc -O1, cold).

On seeds (issue 21): the first fit's parameters (issue 9: 1 cm coverage, 3 cm bulge) were
chosen on Experiment 1 seeds 0-49, the seeds docs/results.md reports; this fit's (5 mm,
1 cm / 2 cm) on MotionBenchMaker's grasp goals, checked on Experiment 1 under MuJoCo, seeds
0-19, and held out there on seeds 20-59 and 100-139 (80/80 without self-collision). The
static fabric alone on kinematic Experiment 1 (docs/results.md, "Tuned constants on
held-out seeds"): seeds 0-49, 50/50 reached, no collision or self-collision on the meshes
(links at least 10.8 mm apart, seed 34); held out, seeds 1000-1049 (``dynfab experiment
exp1 --runs 50 --seed 1000 --planners static-fabric``), 49/50: in seed 1036 the open left
finger rests on ``panda_link0`` from 2.85 s (547 samples, up to 13.6 mm into its mesh) and
the hand stops short. At 5.85 s the three kept pairs of finger and base spheres are
13.6 mm apart while an unkept one (spheres 70 and 9) overlaps by 16.7 mm: the pair
selection's 10,000 random configurations missed this one.

Fitted:

PANDA_FITTED:

    panda_link0       17 spheres, coverage 4.9 mm, bulge 19.9 mm
    panda_link1        6 spheres, coverage 4.5 mm, bulge 19.7 mm
    panda_link2        6 spheres, coverage 4.9 mm, bulge 19.7 mm
    panda_link3        6 spheres, coverage 4.8 mm, bulge 19.9 mm
    panda_link4        6 spheres, coverage 4.9 mm, bulge 19.8 mm
    panda_link5        7 spheres, coverage 4.2 mm, bulge 19.6 mm
    panda_link6        4 spheres, coverage 4.7 mm, bulge 19.8 mm
    panda_link7        4 spheres, coverage 4.7 mm, bulge 19.8 mm
    panda_hand_body   11 spheres, coverage 4.8 mm, bulge 9.8 mm
    panda_leftfinger   4 spheres, coverage 4.1 mm, bulge 9.9 mm
    panda_rightfinger  4 spheres, coverage 4.0 mm, bulge 9.8 mm
    75 spheres, 268 self-collision pairs

PANDA_PLANNING:

    panda_link5       22 spheres, coverage 4.9 mm, bulge 9.9 mm
    panda_link6       15 spheres, coverage 4.8 mm, bulge 9.9 mm
    101 spheres, 373 self-collision pairs
"""

from __future__ import annotations

__all__ = ["PANDA_FITTED_PAIRS", "PANDA_FITTED_SPHERES", "PANDA_PLANNING_PAIRS", "PANDA_PLANNING_SPHERES"]

#: The fabric's spheres: (link, centre in the link frame [m], radius [m]).
PANDA_FITTED_SPHERES: tuple[tuple[str, tuple[float, float, float], float], ...] = (
    ("panda_link0", (0.0326, 0.0220, 0.0291), 0.0484),
    ("panda_link0", (0.0204, -0.0371, 0.0281), 0.0472),
    ("panda_link0", (-0.0086, 0.0666, 0.0206), 0.0404),
    ("panda_link0", (-0.0182, -0.0649, 0.0221), 0.0420),
    ("panda_link0", (-0.0895, -0.0460, 0.0277), 0.0469),
    ("panda_link0", (-0.1297, -0.0370, 0.0118), 0.0317),
    ("panda_link0", (-0.0591, 0.0607, 0.0180), 0.0364),
    ("panda_link0", (0.0231, -0.0078, 0.0422), 0.0610),
    ("panda_link0", (-0.1318, 0.0116, 0.0149), 0.0347),
    ("panda_link0", (-0.0009, -0.0015, 0.0787), 0.0812),
    ("panda_link0", (-0.1079, 0.0414, 0.0235), 0.0427),
    ("panda_link0", (-0.0535, -0.0028, 0.0556), 0.0754),
    ("panda_link0", (-0.0139, -0.0461, 0.0373), 0.0570),
    ("panda_link0", (-0.0953, -0.0420, 0.0281), 0.0457),
    ("panda_link0", (0.0307, 0.0559, 0.0106), 0.0131),
    ("panda_link0", (-0.0515, -0.0659, 0.0164), 0.0236),
    ("panda_link0", (-0.1293, 0.0221, 0.0155), 0.0291),
    ("panda_link1", (0.0002, -0.0053, -0.1365), 0.0742),
    ("panda_link1", (0.0000, -0.0540, -0.0004), 0.0746),
    ("panda_link1", (0.0004, -0.0265, -0.0468), 0.0734),
    ("panda_link1", (0.0000, -0.0394, -0.0724), 0.0737),
    ("panda_link1", (0.0135, 0.0134, -0.1556), 0.0552),
    ("panda_link1", (-0.0097, 0.0043, -0.1481), 0.0635),
    ("panda_link2", (-0.0015, -0.0104, 0.0361), 0.0720),
    ("panda_link2", (0.0000, -0.0720, 0.0312), 0.0735),
    ("panda_link2", (0.0000, -0.1388, 0.0127), 0.0722),
    ("panda_link2", (-0.0019, -0.0128, 0.0752), 0.0650),
    ("panda_link2", (0.0083, -0.1487, -0.0050), 0.0639),
    ("panda_link2", (-0.0037, -0.1445, -0.0039), 0.0692),
    ("panda_link3", (0.0802, 0.0402, -0.0023), 0.0730),
    ("panda_link3", (0.0035, -0.0065, -0.0770), 0.0634),
    ("panda_link3", (0.0346, 0.0201, -0.0536), 0.0772),
    ("panda_link3", (-0.0092, -0.0070, -0.0816), 0.0578),
    ("panda_link3", (-0.0175, 0.0227, -0.0959), 0.0449),
    ("panda_link3", (0.0627, 0.0258, -0.0074), 0.0544),
    ("panda_link4", (-0.0018, 0.0019, 0.0412), 0.0727),
    ("panda_link4", (-0.0905, 0.0871, 0.0141), 0.0556),
    ("panda_link4", (-0.0456, 0.0521, 0.0215), 0.0776),
    ("panda_link4", (-0.0682, 0.0902, -0.0152), 0.0526),
    ("panda_link4", (-0.0911, 0.0818, -0.0057), 0.0613),
    ("panda_link4", (-0.0278, -0.0209, 0.0075), 0.0276),
    ("panda_link5", (0.0049, -0.0071, -0.2182), 0.0622),
    ("panda_link5", (0.0002, 0.0184, -0.2078), 0.0721),
    ("panda_link5", (0.0001, 0.0549, -0.0491), 0.0691),
    ("panda_link5", (-0.0021, -0.0035, -0.2154), 0.0661),
    ("panda_link5", (-0.0001, 0.0396, -0.0960), 0.0689),
    ("panda_link5", (-0.0001, 0.0625, -0.0040), 0.0687),
    ("panda_link5", (0.0000, 0.0342, -0.1471), 0.0699),
    ("panda_link6", (0.0004, 0.0053, 0.0150), 0.0592),
    ("panda_link6", (0.0845, -0.0088, 0.0021), 0.0616),
    ("panda_link6", (0.0681, 0.0382, 0.0042), 0.0607),
    ("panda_link6", (0.0478, -0.0076, 0.0084), 0.0626),
    ("panda_link7", (0.0258, 0.0214, 0.0787), 0.0465),
    ("panda_link7", (0.0476, 0.0479, 0.0826), 0.0333),
    ("panda_link7", (-0.0020, -0.0137, 0.0792), 0.0461),
    ("panda_link7", (-0.0158, 0.0005, 0.0794), 0.0470),
    ("panda_hand_body", (0.0012, -0.0059, 0.0096), 0.0380),
    ("panda_hand_body", (0.0004, 0.0020, 0.0455), 0.0283),
    ("panda_hand_body", (0.0007, -0.0367, 0.0433), 0.0293),
    ("panda_hand_body", (0.0001, 0.0746, 0.0405), 0.0311),
    ("panda_hand_body", (0.0005, 0.0718, 0.0158), 0.0329),
    ("panda_hand_body", (-0.0006, 0.0396, 0.0443), 0.0280),
    ("panda_hand_body", (0.0007, -0.0748, 0.0458), 0.0288),
    ("panda_hand_body", (-0.0001, 0.0405, 0.0154), 0.0369),
    ("panda_hand_body", (-0.0001, -0.0455, 0.0105), 0.0341),
    ("panda_hand_body", (-0.0001, -0.0824, 0.0082), 0.0279),
    ("panda_hand_body", (-0.0003, -0.0727, -0.0047), 0.0242),
    ("panda_leftfinger", (0.0034, 0.0195, 0.0142), 0.0151),
    ("panda_leftfinger", (0.0080, 0.0124, 0.0047), 0.0086),
    ("panda_leftfinger", (-0.0040, 0.0180, 0.0084), 0.0162),
    ("panda_leftfinger", (-0.0020, 0.0082, 0.0419), 0.0158),
    ("panda_rightfinger", (-0.0025, -0.0178, 0.0113), 0.0162),
    ("panda_rightfinger", (0.0008, -0.0169, 0.0171), 0.0134),
    ("panda_rightfinger", (-0.0005, -0.0049, 0.0018), 0.0105),
    ("panda_rightfinger", (0.0026, -0.0086, 0.0426), 0.0159),
)

#: Index pairs into PANDA_FITTED_SPHERES kept apart.
PANDA_FITTED_PAIRS: tuple[tuple[int, int], ...] = (
    (0, 45), (0, 46), (0, 48), (0, 52), (0, 53), (0, 54), (0, 55), (0, 59), (0, 63), (0, 65),
    (1, 50), (2, 43), (2, 45), (2, 46), (2, 48), (2, 49), (2, 50), (2, 51), (2, 52), (2, 54),
    (2, 55), (2, 57), (2, 60), (2, 62), (2, 64), (2, 66), (2, 69), (2, 72), (3, 45), (3, 46),
    (3, 54), (3, 59), (4, 43), (4, 48), (4, 51), (4, 56), (4, 60), (5, 46), (5, 52), (5, 53),
    (5, 54), (5, 64), (5, 70), (6, 46), (6, 48), (6, 49), (6, 51), (6, 52), (6, 55), (6, 59),
    (6, 60), (6, 64), (6, 65), (6, 74), (7, 43), (7, 45), (7, 46), (7, 49), (7, 52), (7, 54),
    (7, 55), (7, 56), (7, 57), (7, 59), (7, 60), (7, 61), (7, 62), (7, 64), (7, 66), (7, 70),
    (7, 74), (8, 43), (8, 45), (8, 51), (8, 52), (9, 43), (9, 45), (9, 46), (9, 48), (9, 49),
    (9, 50), (9, 51), (9, 52), (9, 54), (9, 55), (9, 56), (9, 57), (9, 58), (9, 59), (9, 60),
    (9, 61), (9, 62), (9, 63), (9, 64), (9, 65), (9, 66), (9, 70), (9, 72), (9, 74), (10, 43),
    (10, 45), (10, 46), (10, 48), (10, 49), (10, 50), (10, 51), (10, 52), (10, 55), (10, 58), (10, 59),
    (10, 62), (10, 63), (10, 65), (10, 70), (10, 71), (11, 43), (11, 45), (11, 46), (11, 48), (11, 49),
    (11, 50), (11, 51), (11, 52), (11, 53), (11, 54), (11, 55), (11, 56), (11, 57), (11, 58), (11, 59),
    (11, 60), (11, 61), (11, 62), (11, 63), (11, 64), (11, 65), (11, 69), (11, 70), (11, 74), (12, 43),
    (12, 45), (12, 48), (12, 49), (12, 50), (12, 51), (12, 52), (12, 53), (12, 54), (12, 55), (12, 57),
    (12, 59), (12, 62), (12, 63), (12, 65), (13, 43), (13, 45), (13, 46), (13, 49), (13, 50), (13, 51),
    (13, 52), (13, 55), (13, 61), (13, 62), (13, 63), (13, 65), (13, 70), (14, 49), (16, 50), (16, 55),
    (16, 70), (17, 43), (17, 45), (17, 46), (17, 48), (17, 49), (17, 50), (17, 52), (17, 53), (17, 54),
    (17, 56), (17, 57), (17, 58), (17, 59), (17, 62), (17, 63), (17, 64), (17, 65), (17, 70), (17, 74),
    (18, 43), (18, 49), (18, 50), (18, 53), (18, 55), (18, 56), (18, 57), (18, 59), (18, 62), (18, 63),
    (18, 64), (18, 65), (18, 66), (18, 70), (18, 74), (19, 56), (19, 57), (19, 58), (19, 60), (19, 61),
    (19, 62), (19, 63), (19, 65), (19, 69), (20, 43), (20, 49), (20, 52), (20, 53), (20, 56), (20, 57),
    (20, 58), (20, 59), (20, 60), (20, 61), (20, 62), (20, 63), (20, 64), (20, 70), (20, 74), (21, 54),
    (22, 56), (23, 43), (23, 57), (23, 58), (23, 59), (23, 60), (23, 61), (23, 62), (23, 63), (23, 64),
    (23, 65), (23, 69), (23, 70), (23, 74), (24, 59), (24, 62), (24, 70), (24, 74), (26, 43), (26, 49),
    (26, 50), (26, 53), (26, 54), (26, 57), (26, 58), (26, 59), (26, 61), (26, 62), (26, 63), (26, 66),
    (26, 70), (26, 74), (28, 70), (28, 74), (45, 53), (45, 55), (45, 65), (46, 52),
)

#: Global guidance's spheres of links 5 and 6 (the others: PANDA_FITTED_SPHERES'; its pairs index them all in the links' order): (link, centre in the link frame [m], radius [m]).
PANDA_PLANNING_SPHERES: tuple[tuple[str, tuple[float, float, float], float], ...] = (
    ("panda_link5", (0.0020, 0.0080, -0.1893), 0.0609),
    ("panda_link5", (0.0000, 0.0494, -0.0203), 0.0587),
    ("panda_link5", (0.0240, 0.0163, -0.2308), 0.0387),
    ("panda_link5", (0.0347, -0.0052, -0.2421), 0.0274),
    ("panda_link5", (0.0001, 0.0431, -0.0474), 0.0598),
    ("panda_link5", (0.0179, -0.0282, -0.2393), 0.0309),
    ("panda_link5", (0.0003, 0.0399, -0.1716), 0.0577),
    ("panda_link5", (0.0105, 0.0430, 0.0067), 0.0453),
    ("panda_link5", (0.0027, 0.0195, -0.1364), 0.0592),
    ("panda_link5", (-0.0291, -0.0124, -0.2398), 0.0328),
    ("panda_link5", (0.0000, 0.0359, -0.0873), 0.0608),
    ("panda_link5", (0.0001, 0.0650, -0.0597), 0.0598),
    ("panda_link5", (0.0001, 0.0193, -0.2089), 0.0621),
    ("panda_link5", (-0.0364, 0.0107, -0.2463), 0.0263),
    ("panda_link5", (-0.0018, 0.0522, 0.0014), 0.0564),
    ("panda_link5", (0.0000, 0.0746, -0.0050), 0.0592),
    ("panda_link5", (0.0001, 0.0547, -0.1116), 0.0598),
    ("panda_link5", (-0.0070, -0.0281, -0.2361), 0.0345),
    ("panda_link5", (0.0045, 0.0235, -0.1110), 0.0555),
    ("panda_link5", (-0.0011, 0.0551, -0.1164), 0.0559),
    ("panda_link5", (0.0331, -0.0316, -0.2515), 0.0119),
    ("panda_link5", (-0.0093, 0.0137, -0.2173), 0.0543),
    ("panda_link6", (0.0585, -0.0441, -0.0294), 0.0170),
    ("panda_link6", (0.0824, -0.0298, 0.0245), 0.0308),
    ("panda_link6", (0.0850, -0.0060, 0.0005), 0.0522),
    ("panda_link6", (0.0940, -0.0383, -0.0292), 0.0226),
    ("panda_link6", (0.0801, 0.0344, 0.0019), 0.0516),
    ("panda_link6", (-0.0169, 0.0099, 0.0071), 0.0375),
    ("panda_link6", (0.1040, -0.0270, 0.0115), 0.0337),
    ("panda_link6", (0.0139, 0.0119, 0.0141), 0.0503),
    ("panda_link6", (0.0390, 0.0312, 0.0102), 0.0463),
    ("panda_link6", (0.0420, -0.0044, 0.0105), 0.0531),
    ("panda_link6", (0.1064, -0.0280, -0.0071), 0.0331),
    ("panda_link6", (0.0221, -0.0324, -0.0124), 0.0265),
    ("panda_link6", (-0.0054, -0.0077, 0.0144), 0.0471),
    ("panda_link6", (0.0640, 0.0286, 0.0055), 0.0499),
    ("panda_link6", (0.0929, -0.0426, -0.0349), 0.0180),
)

#: Index pairs into PANDA_PLANNING_SPHERES kept apart.
PANDA_PLANNING_PAIRS: tuple[tuple[int, int], ...] = (
    (0, 51), (0, 55), (0, 56), (0, 65), (0, 71), (0, 72), (0, 73), (0, 78), (0, 79), (0, 80),
    (0, 81), (0, 86), (0, 89), (0, 91), (1, 56), (1, 85), (1, 100), (2, 42), (2, 51), (2, 52),
    (2, 56), (2, 65), (2, 70), (2, 72), (2, 76), (2, 78), (2, 80), (2, 81), (2, 83), (2, 86),
    (2, 87), (2, 88), (2, 90), (2, 92), (2, 93), (2, 100), (3, 56), (3, 74), (3, 75), (3, 80),
    (4, 45), (4, 49), (4, 51), (4, 52), (4, 56), (4, 65), (4, 70), (4, 72), (4, 76), (4, 80),
    (4, 82), (4, 86), (4, 88), (5, 42), (5, 51), (5, 52), (5, 57), (5, 65), (5, 67), (5, 70),
    (5, 76), (5, 78), (5, 81), (5, 86), (5, 88), (5, 89), (5, 90), (6, 55), (6, 65), (6, 70),
    (6, 72), (6, 76), (6, 78), (6, 81), (6, 85), (6, 86), (6, 90), (6, 91), (7, 45), (7, 52),
    (7, 65), (7, 67), (7, 70), (7, 72), (7, 75), (7, 78), (7, 79), (7, 80), (7, 81), (7, 82),
    (7, 83), (7, 85), (7, 88), (7, 90), (7, 92), (7, 96), (8, 45), (8, 51), (8, 56), (8, 65),
    (8, 68), (8, 71), (8, 72), (8, 76), (8, 78), (8, 85), (8, 96), (9, 42), (9, 45), (9, 51),
    (9, 52), (9, 55), (9, 56), (9, 57), (9, 65), (9, 66), (9, 67), (9, 68), (9, 69), (9, 70),
    (9, 71), (9, 72), (9, 74), (9, 75), (9, 76), (9, 78), (9, 79), (9, 80), (9, 81), (9, 82),
    (9, 83), (9, 84), (9, 85), (9, 86), (9, 87), (9, 88), (9, 89), (9, 90), (9, 91), (9, 92),
    (9, 96), (9, 100), (10, 42), (10, 45), (10, 52), (10, 56), (10, 57), (10, 65), (10, 67), (10, 70),
    (10, 71), (10, 72), (10, 76), (10, 78), (10, 79), (10, 80), (10, 81), (10, 84), (10, 85), (10, 86),
    (10, 88), (10, 89), (10, 91), (10, 96), (10, 100), (11, 42), (11, 45), (11, 48), (11, 51), (11, 52),
    (11, 55), (11, 56), (11, 57), (11, 64), (11, 65), (11, 67), (11, 68), (11, 69), (11, 70), (11, 71),
    (11, 72), (11, 73), (11, 74), (11, 75), (11, 76), (11, 78), (11, 79), (11, 80), (11, 81), (11, 82),
    (11, 83), (11, 84), (11, 85), (11, 86), (11, 87), (11, 88), (11, 89), (11, 90), (11, 91), (11, 93),
    (11, 96), (11, 100), (12, 42), (12, 45), (12, 51), (12, 52), (12, 59), (12, 65), (12, 67), (12, 71),
    (12, 72), (12, 77), (12, 78), (12, 79), (12, 80), (12, 81), (12, 83), (12, 85), (12, 88), (12, 89),
    (12, 91), (12, 96), (12, 100), (13, 42), (13, 51), (13, 52), (13, 55), (13, 65), (13, 71), (13, 72),
    (13, 78), (13, 80), (13, 81), (13, 87), (13, 89), (13, 90), (13, 91), (13, 93), (13, 96), (13, 100),
    (15, 45), (15, 51), (15, 85), (16, 81), (17, 45), (17, 51), (17, 52), (17, 56), (17, 65), (17, 66),
    (17, 67), (17, 70), (17, 72), (17, 73), (17, 75), (17, 78), (17, 80), (17, 82), (17, 83), (17, 84),
    (17, 85), (17, 86), (17, 88), (17, 89), (17, 90), (17, 91), (17, 96), (17, 100), (18, 45), (18, 52),
    (18, 67), (18, 69), (18, 77), (18, 79), (18, 81), (18, 82), (18, 83), (18, 85), (18, 86), (18, 88),
    (18, 89), (18, 90), (18, 91), (18, 92), (18, 96), (18, 100), (19, 79), (19, 82), (19, 83), (19, 84),
    (19, 85), (19, 87), (19, 88), (19, 89), (19, 91), (19, 95), (19, 96), (19, 100), (20, 56), (20, 65),
    (20, 67), (20, 78), (20, 79), (20, 80), (20, 82), (20, 83), (20, 84), (20, 85), (20, 86), (20, 87),
    (20, 88), (20, 89), (20, 90), (20, 91), (20, 92), (20, 93), (20, 96), (20, 98), (20, 100), (21, 42),
    (21, 68), (21, 73), (21, 75), (21, 80), (22, 67), (22, 69), (22, 79), (22, 87), (23, 52), (23, 83),
    (23, 85), (23, 86), (23, 87), (23, 88), (23, 89), (23, 90), (23, 91), (23, 93), (23, 96), (23, 100),
    (24, 85), (24, 88), (24, 96), (24, 100), (25, 96), (25, 100), (26, 52), (26, 63), (26, 64), (26, 67),
    (26, 69), (26, 70), (26, 77), (26, 79), (26, 80), (26, 83), (26, 84), (26, 85), (26, 86), (26, 87),
    (26, 88), (26, 89), (26, 90), (26, 92), (26, 93), (26, 96), (26, 100), (42, 78), (45, 80), (45, 81),
    (51, 79), (51, 81), (59, 91),
)
