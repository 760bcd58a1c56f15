"""Built-in robots (``panda``, ``point``, ``boxer``, ``boxer-panda``) and robots from a
user's URDF file."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from importlib import resources
from typing import Literal

import numpy as np

from .collision_model import auto_collision_model
from .franka import FINGER_JOINT, FINGER_RANGE, OPEN, PANDA_JOINTS
from .kinematics import Kinematics
from .panda_fine_spheres import PANDA_FINE_SPHERES
from .panda_spheres import PANDA_FITTED_PAIRS, PANDA_FITTED_SPHERES, PANDA_PLANNING_PAIRS, PANDA_PLANNING_SPHERES
from .limits import BOXER_ACCELERATION, FRANKA_ACCELERATION, MotionLimits
from .robot import BASE_JOINTS, CollisionSphere, DifferentialDriveBase, Robot, default_limits
from .urdf import load_urdf, parse_urdf

__all__ = ["BUILTIN_ROBOTS", "FINGERED_ROBOTS", "UnknownRobotError", "load_robot", "panda_robot", "robot_from_urdf"]


class UnknownRobotError(ValueError):
    """A robot name that is not built in."""


#: Panda configuration used as default: elbow bent, hand pointing down [rad].
PANDA_DEFAULT_Q = (1.0, 0.0, 0.0, -1.5, 0.0, 1.8675, 0.0)

# Panda collision spheres: (label, link, centre in link frame [m], radius [m]).
# Centres lie on the segments between joint origins (franka_description frames):
# link2 -> link3 runs along link2's -y (0.316 m), link4 -> link5 along link5's -z
# (0.384 m, offset 0.0825 m), link6 -> link7 along link6's +x (0.088 m), and link7 ->
# hand along link7's +z (0.2104 m). The hand frame is the fingertip centre point, the
# hand body lies 0.1034 m behind it and is wide along the hand's y (finger) axis.
# Checked: every joint origin lies inside a sphere at q = 0 and at PANDA_DEFAULT_Q.
_PANDA_SPHERES: tuple[tuple[str, str, tuple[float, float, float], float], ...] = (
    ("base", "panda_link0", (0.0, 0.0, 0.05), 0.08),
    ("column", "panda_link1", (0.0, 0.0, -0.16), 0.08),
    ("shoulder", "panda_link2", (0.0, 0.0, 0.0), 0.08),
    ("upper_arm", "panda_link2", (0.0, -0.14, 0.0), 0.07),
    ("upper_arm_top", "panda_link3", (0.0, 0.0, -0.06), 0.07),
    ("elbow", "panda_link4", (0.0, 0.0, 0.0), 0.08),
    ("forearm_low", "panda_link5", (0.0, 0.0, -0.26), 0.07),
    ("forearm_high", "panda_link5", (0.0, 0.0, -0.13), 0.07),
    ("wrist", "panda_link6", (0.0, 0.0, 0.0), 0.08),
    ("flange", "panda_link7", (0.0, 0.0, 0.04), 0.07),
    ("hand_left", "panda_hand", (0.0, 0.05, -0.08), 0.06),
    ("hand_right", "panda_hand", (0.0, -0.05, -0.08), 0.06),
    ("fingertips", "panda_hand", (0.0, 0.0, -0.02), 0.04),
)

#: Which spheres the built-in ``panda`` uses: ``"fitted"`` (panda_spheres.py: 75 spheres
#: fitted to Franka's collision meshes of the arm, the hand and each finger, none of whose
#: surface points lies more than 5 mm outside them, reaching at most 1 cm out of the hand
#: and fingers and 2 cm elsewhere, and 268 pairs chosen on the meshes; global guidance checks
#: configurations with 101 spheres, links 5 and 6 at 1 cm too, and 373 pairs:
#: :attr:`Robot.planning_robot`) or ``"hand-written"`` (the table above,
#: the default until 2026-11: it leaves 29 % of the mesh surface more than 1 cm and 12 %
#: more than 3 cm outside, up to 8.3 cm at PANDA_DEFAULT_Q, and its pairs let the meshes
#: touch themselves in 11 of 50 Experiment-1 runs). ``panda_robot("hand-written")`` keeps
#: the old model for comparisons with results made with it; ``boxer-panda`` uses the fitted
#: spheres too.
PANDA_SPHERE_MODEL = "fitted"

# Sphere pairs >= 3 joints apart that can touch within the joint limits (found by
# minimising their clearance from the closest of 50,000 random configurations) and
# are apart at q = 0 and at PANDA_DEFAULT_Q. Pairs the joint limits keep apart (e.g.
# hand vs link3/link4, forearm_low vs base) are left out.
_PANDA_TIP = ("hand_left", "hand_right", "fingertips")
_PANDA_SELF_COLLISION: tuple[tuple[str, str], ...] = tuple(
    [(low, high) for low in ("base", "column")
     for high in ("forearm_high", "wrist", "flange") + _PANDA_TIP]
    + [("shoulder", high) for high in ("flange",) + _PANDA_TIP]
    + [("upper_arm", high) for high in _PANDA_TIP])


#: Boxer drive: wheel radius 0.080 m and separation 2 x 0.2436 m from Clearpath's
#: boxer_description (wheels_and_casters.urdf.xacro), speed limits 1.9 m/s and
#: 2.0 rad/s from its diff_drive_controller configuration (boxer_control/config/
#: control.yaml); see the header of data/boxer.urdf.
BOXER_BASE = DifferentialDriveBase(wheel_radius=0.08, wheel_separation=0.4872,
                                   max_forward_speed=1.9, max_yaw_rate=2.0)

#: Boxer-panda default: base at the origin, the Panda's default pose (elbow bent, hand
#: pointing down ahead of and left of the base, 0.93 m above the floor; every arm
#: sphere beyond the shoulder is >= 0.3 m from the base spheres).
BOXER_PANDA_DEFAULT_Q = (0.0, 0.0, 0.0) + PANDA_DEFAULT_Q

# Boxer body spheres: (label, centre in chassis_link [m]). chassis_link is the centre of
# the chassis' bottom face; the body is the box |x| <= 0.3707, |y| <= 0.2755,
# 0 <= z <= 0.2884 (Clearpath's 0.74143 x 0.55093 x 0.2884 m collision box). A 3 x 2
# grid at mid-height: every point of the footprint is within 0.188 m of a centre in x-y
# (planar discs of radius 0.19 cover it), every point of the box within 0.237 m in 3-D
# (spheres of radius 0.24 cover it).
_BOXER_BODY: tuple[tuple[str, tuple[float, float, float]], ...] = tuple(
    (f"body_{row}_{side}", (x, y, 0.1442))
    for row, x in (("front", 0.25), ("mid", 0.0), ("rear", -0.25))
    for side, y in (("left", 0.14), ("right", -0.14)))
#: Radius of the Boxer's footprint discs (planar ``boxer``) [m].
BOXER_DISC_RADIUS = 0.19
#: Radius of the Boxer's body spheres (3-D ``boxer-panda``) [m].
BOXER_SPHERE_RADIUS = 0.24

# Arm spheres that can reach the Boxer's body spheres: indices into PANDA_FITTED_SPHERES
# (from panda_link4 on: the hand and the fingers included) that come within 2 cm of a
# body sphere (indices into _BOXER_BODY) in the closest of 100,000 uniform random arm
# configurations within the joint limits, the hand open and closed (measured 2026-11-25;
# the other arm-body sphere pairs stay at least 2.06 cm apart; panda_link0 sits on the
# plate and is left out, panda_link1 to panda_link3 never come near). At
# BOXER_PANDA_DEFAULT_Q all these pairs are more than 0.5 m apart.
_ALL_BODY = tuple(range(len(_BOXER_BODY)))
_ARM_NEAR_BODY: tuple[tuple[int, tuple[int, ...]], ...] = (
    ((35, (2, 3)),) + tuple((arm, _ALL_BODY) for arm in range(36, 75) if arm != 40))


def load_robot(name: str, fingers: float | None = None) -> Robot:
    """A built-in robot by name.

    Args:
        name: ``"panda"`` (Franka Panda, goal link ``panda_hand``, 7 joints),
            ``"point"`` (planar point robot, goal link ``point``, q = [x, y]),
            ``"boxer"`` (Clearpath Boxer, differential drive, goal link ``base_link``,
            q = [x, y, yaw], planar) or ``"boxer-panda"`` (the Panda on a Boxer, goal
            link ``panda_hand``, q = [x, y, yaw, 7 arm joints]).
        fingers: The Panda's opening per finger [m], ``0 <= fingers <= 0.04`` (Franka's
            limits); None: open (:data:`~dynfab.robots.franka.OPEN`). Only for robots
            with the Panda.

    Raises:
        UnknownRobotError: ``name`` is not built in; the message lists valid names.
        ValueError: ``fingers`` for a robot without fingers, or outside Franka's limits.
    """
    factory = BUILTIN_ROBOTS.get(name)
    if factory is None:
        raise UnknownRobotError(f"unknown robot '{name}'; built-in robots: "
                                f"{', '.join(BUILTIN_ROBOTS)}")
    if fingers is None:
        return factory()
    if name not in FINGERED_ROBOTS:
        raise ValueError(f"fingers: the {name} has no fingers (only {', '.join(FINGERED_ROBOTS)})")
    return FINGERED_ROBOTS[name](fingers)


def robot_from_urdf(path: str | os.PathLike[str], goal_link: str | None = None,
                    spheres: Sequence[CollisionSphere] | Literal["auto"] = "auto",
                    self_collision_pairs: Sequence[tuple[int, int]] | Literal["auto"] | None = None,
                    planar: bool = False,
                    default_q: Sequence[float] | np.ndarray | None = None,
                    base: DifferentialDriveBase | None = None,
                    joints: Sequence[str] | None = None,
                    locked: Mapping[str, float] | None = None,
                    package_dirs: Sequence[str | os.PathLike[str]] = ()) -> Robot:
    """A robot from a URDF file as it ships: ``robot_from_urdf("package://example-robot-data/
    robots/ur_description/urdf/ur5_robot.urdf")`` fits its collision spheres to its meshes
    and selects its self-collision pairs (:func:`~dynfab.robots.collision_model.auto_collision_model`,
    cached: the first call for a robot takes seconds, later ones milliseconds).

    Args:
        path: URDF file, or a ``package://NAME/...`` or ``file://`` URI of it.
        goal_link: End-effector link for position goals; ``None``: the child link of the
            last active joint.
        spheres: Collision spheres (every ``sphere.link`` a link of the URDF), or
            ``"auto"``: fitted to the links' collision meshes.
        self_collision_pairs: Index pairs into ``spheres`` kept apart, or ``"auto"``
            (selected from the spheres); ``None``: ``"auto"`` with automatic spheres, none
            with given ones.
        planar: True if the robot moves in the xy-plane.
        default_q: Default configuration; zeros clipped into the joint limits if None.
        base: The robot's differential-drive base, if it has one; then its URDF must
            start with the joints ``base_x``, ``base_y``, ``base_yaw`` (see
            :class:`~dynfab.robots.robot.Robot`).
        joints: Active joints in the order of ``q``; ``None``: every movable joint
            that does not mimic another, in depth-first order.
        locked: Values of the other movable joints [rad or m]; default 0 clipped into
            their limits.
        package_dirs: Folders where ``package://`` mesh URIs are looked up (besides
            ``DYNFAB_PACKAGE_PATH`` and the URDF's own folder and its parents).

    Raises:
        OSError: The file cannot be read (or a URI names no file).
        UrdfError: The file is not a valid URDF.
        LinkMeshError: ``"auto"`` spheres, and a moving link's mesh is missing or unreadable.
        UnknownLinkError: ``goal_link`` or a sphere's link is not in the URDF.
        ValueError: Unknown names in ``joints`` or ``locked``, wrong ``default_q`` size,
            a pair index out of range, or a ``base`` without the three base joints first.
    """
    model = load_urdf(path, package_dirs)
    kinematics = Kinematics(model, joints=joints, locked=locked)
    if spheres == "auto" or self_collision_pairs == "auto" or (self_collision_pairs is None and spheres == "auto"):
        fitted = auto_collision_model(path, joints=joints, locked=locked, package_dirs=package_dirs,
                                      spheres=None if spheres == "auto" else spheres)
        spheres = fitted.spheres
        if self_collision_pairs in (None, "auto"):
            self_collision_pairs = fitted.self_collision_pairs
    if self_collision_pairs is None:
        self_collision_pairs = ()
    if goal_link is None:
        last = kinematics.joint_names[-1]
        goal_link = next(joint.child for joint in model.joints if joint.name == last)
    if default_q is None:
        default_q = np.clip(np.zeros(kinematics.dof), kinematics.lower, kinematics.upper)
    return Robot(name=model.name or os.path.basename(os.fspath(path)),
                 kinematics=kinematics, goal_link=goal_link,
                 collision_spheres=tuple(spheres),
                 self_collision_pairs=tuple(self_collision_pairs), planar=planar,
                 default_q=np.asarray(default_q, dtype=float), base=base)


def _builtin_kinematics(filename: str, joints: Sequence[str] | None = None,
                        fingers: float | None = None) -> Kinematics:
    """Kinematics of a URDF shipped in ``dynfab/robots/data``; with ``fingers``, the active
    ``joints`` and the Panda's fingers locked at that opening [m]."""
    text = resources.files(__package__).joinpath("data", filename).read_text("utf-8")
    if fingers is None:
        return Kinematics(parse_urdf(text))
    low, high = FINGER_RANGE
    if not low <= fingers <= high:
        raise ValueError(f"fingers: the opening per finger must be within {low:g} ... {high:g} m, got {fingers!r}")
    return Kinematics(parse_urdf(text), joints=joints, locked={FINGER_JOINT: float(fingers)})


def _panda() -> Robot:
    """The Franka Panda, hand open, with the spheres :data:`PANDA_SPHERE_MODEL` names."""
    return panda_robot(PANDA_SPHERE_MODEL)


def panda_robot(sphere_model: str, fingers: float = OPEN) -> Robot:
    """The Franka Panda with its ``"fitted"`` or ``"hand-written"`` collision spheres and
    self-collision pairs (see :data:`PANDA_SPHERE_MODEL`), the fingers locked at
    ``fingers`` [m] per finger (0 closed ... 0.04 open).

    Raises:
        ValueError: Another ``sphere_model``, or ``fingers`` outside 0 ... 0.04.
    """
    if sphere_model not in ("fitted", "hand-written"):
        raise ValueError(f"panda sphere_model must be fitted or hand-written, got {sphere_model!r}")
    kinematics = _builtin_kinematics("panda.urdf", PANDA_JOINTS, fingers)
    planning: tuple[CollisionSphere, ...] | None = None
    planning_pairs: tuple[tuple[int, int], ...] = ()
    fine: tuple[CollisionSphere, ...] | None = None
    if sphere_model == "fitted":
        spheres = _spheres(PANDA_FITTED_SPHERES)
        pairs = PANDA_FITTED_PAIRS
        planning, planning_pairs = _planning_spheres(), PANDA_PLANNING_PAIRS
        fine = _spheres(PANDA_FINE_SPHERES)
    else:
        labels = [label for label, *_ in _PANDA_SPHERES]
        spheres = tuple(CollisionSphere(link, center, radius) for _, link, center, radius in _PANDA_SPHERES)
        pairs = tuple((labels.index(a), labels.index(b)) for a, b in _PANDA_SELF_COLLISION)
    return Robot(name="panda", kinematics=kinematics, goal_link="panda_hand", collision_spheres=spheres,
                 self_collision_pairs=pairs, planar=False, default_q=np.array(PANDA_DEFAULT_Q),
                 limits=_known_limits(kinematics, None), planning_spheres=planning, planning_pairs=planning_pairs,
                 fine_spheres=fine)


def _spheres(table: Sequence[tuple[str, tuple[float, float, float], float]]) -> tuple[CollisionSphere, ...]:
    """The spheres of a table of ``panda_spheres.py``."""
    return tuple(CollisionSphere(link, center, radius) for link, center, radius in table)


def _planning_spheres() -> tuple[CollisionSphere, ...]:
    """Global guidance's spheres: the fabric's, those of the links ``PANDA_PLANNING_SPHERES``
    has (5 and 6) replaced by its tighter ones, in the links' order (which
    ``PANDA_PLANNING_PAIRS`` index)."""
    tighter = {link for link, *_ in PANDA_PLANNING_SPHERES}
    rows = []
    for link in dict.fromkeys(link for link, *_ in PANDA_FITTED_SPHERES):
        rows += [row for row in (PANDA_PLANNING_SPHERES if link in tighter else PANDA_FITTED_SPHERES) if row[0] == link]
    return _spheres(rows)


def _known_limits(kinematics: Kinematics, base: DifferentialDriveBase | None) -> MotionLimits:
    """The description's velocity and effort limits with known acceleration limits: the
    Boxer's from traction for a base (``v``, ``omega``: :data:`BOXER_ACCELERATION`), and
    Franka's published ones for the Panda's joints (the last seven velocity coordinates of
    a robot with an arm)."""
    limits = default_limits(kinematics, base)
    acceleration = np.array(limits.acceleration)
    if base is not None:
        acceleration[:2] = BOXER_ACCELERATION
    if limits.size > (2 if base is not None else 0):
        acceleration[-len(FRANKA_ACCELERATION):] = FRANKA_ACCELERATION
    return limits.overridden(acceleration=acceleration)


def _point() -> Robot:
    """The planar point robot: one 0.1 m sphere, q = [x, y]."""
    return Robot(name="point", kinematics=_builtin_kinematics("point.urdf"),
                 goal_link="point",
                 collision_spheres=(CollisionSphere("point", (0.0, 0.0, 0.0), 0.1),),
                 self_collision_pairs=(), planar=True, default_q=np.zeros(2))


def _boxer() -> Robot:
    """The Clearpath Boxer as a planar robot: six footprint discs, q = [x, y, yaw]."""
    spheres = tuple(CollisionSphere("chassis_link", center, BOXER_DISC_RADIUS)
                    for _, center in _BOXER_BODY)
    kinematics = _builtin_kinematics("boxer.urdf")
    return Robot(name="boxer", kinematics=kinematics,
                 goal_link="base_link", collision_spheres=spheres,
                 self_collision_pairs=(), planar=True, default_q=np.zeros(3),
                 base=BOXER_BASE, limits=_known_limits(kinematics, BOXER_BASE))


def _boxer_panda(fingers: float = OPEN) -> Robot:
    """The Panda on a Boxer: six body spheres, then the Panda's fitted spheres; the fingers
    locked at ``fingers`` [m] per finger.

    Self-collision pairs: the Panda's own, plus the arm spheres that can reach the body
    against the body spheres they can reach (``_ARM_NEAR_BODY``).
    """
    body = tuple(CollisionSphere("chassis_link", center, BOXER_SPHERE_RADIUS) for _, center in _BOXER_BODY)
    arm = _spheres(PANDA_FITTED_SPHERES)
    offset = len(body)
    pairs = tuple((a + offset, b + offset) for a, b in PANDA_FITTED_PAIRS) + tuple(
        (b, a + offset) for a, near in _ARM_NEAR_BODY for b in near)
    kinematics = _builtin_kinematics("boxer_panda.urdf", BASE_JOINTS + PANDA_JOINTS, fingers)
    return Robot(name="boxer-panda", kinematics=kinematics,
                 goal_link="panda_hand", collision_spheres=body + arm,
                 self_collision_pairs=pairs, planar=False,
                 default_q=np.array(BOXER_PANDA_DEFAULT_Q), base=BOXER_BASE,
                 limits=_known_limits(kinematics, BOXER_BASE))


#: Built-in robot names and their constructors.
BUILTIN_ROBOTS: dict[str, Callable[[], Robot]] = {
    "panda": _panda, "point": _point, "boxer": _boxer, "boxer-panda": _boxer_panda}
#: Built-in robots with the Panda's fingers: constructors taking the opening [m].
FINGERED_ROBOTS: dict[str, Callable[[float], Robot]] = {
    "panda": lambda fingers: panda_robot(PANDA_SPHERE_MODEL, fingers), "boxer-panda": _boxer_panda}
