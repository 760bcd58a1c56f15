"""Built-in robots (``panda``, ``point``) and robots from a user's URDF file."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from importlib import resources

import numpy as np

from .kinematics import Kinematics
from .robot import CollisionSphere, Robot
from .urdf import UrdfError, parse_urdf

__all__ = ["BUILTIN_ROBOTS", "UnknownRobotError", "load_robot", "robot_from_urdf"]


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


def load_robot(name: str) -> Robot:
    """A built-in robot by name.

    Args:
        name: ``"panda"`` (Franka Panda, goal link ``panda_hand``, 7 joints) or
            ``"point"`` (planar point robot, goal link ``point``, q = [x, y]).

    Raises:
        UnknownRobotError: ``name`` is not built in; the message lists valid names.
    """
    factory = BUILTIN_ROBOTS.get(name)
    if factory is None:
        raise UnknownRobotError(f"unknown robot '{name}'; built-in robots: "
                                f"{', '.join(BUILTIN_ROBOTS)}")
    return factory()


def robot_from_urdf(path: str | os.PathLike[str], goal_link: str,
                    spheres: Sequence[CollisionSphere],
                    self_collision_pairs: Sequence[tuple[int, int]] = (),
                    planar: bool = False,
                    default_q: Sequence[float] | np.ndarray | None = None) -> Robot:
    """A robot from a URDF file with user-given collision spheres.

    Args:
        path: URDF file.
        goal_link: End-effector link for position goals.
        spheres: Collision spheres; every ``sphere.link`` must be a link of the URDF.
        self_collision_pairs: Index pairs into ``spheres`` kept apart.
        planar: True if the robot moves in the xy-plane.
        default_q: Default configuration; zeros clipped into the joint limits if None.

    Raises:
        OSError: The file cannot be read.
        UrdfError: The file is not a valid URDF.
        UnknownLinkError: ``goal_link`` or a sphere's link is not in the URDF.
        ValueError: Wrong ``default_q`` size or a pair index out of range.
    """
    with open(path, encoding="utf-8") as file:
        text = file.read()
    try:
        model = parse_urdf(text)
    except UrdfError as exc:
        raise UrdfError(f"{os.fspath(path)}: {exc}") from None
    kinematics = Kinematics(model)
    if default_q is None:
        default_q = np.clip(np.zeros(kinematics.dof), kinematics.lower, kinematics.upper)
    return Robot(name=model.name or os.path.basename(os.fspath(path)),
                 kinematics=kinematics, goal_link=goal_link,
                 collision_spheres=tuple(spheres),
                 self_collision_pairs=tuple(self_collision_pairs), planar=planar,
                 default_q=np.asarray(default_q, dtype=float))


def _builtin_kinematics(filename: str) -> Kinematics:
    """Kinematics of a URDF shipped in ``dynfab/robots/data``."""
    text = resources.files(__package__).joinpath("data", filename).read_text("utf-8")
    return Kinematics(parse_urdf(text))


def _panda() -> Robot:
    """The Franka Panda with its collision spheres and self-collision pairs."""
    labels = [label for label, *_ in _PANDA_SPHERES]
    spheres = tuple(CollisionSphere(link, center, radius)
                    for _, link, center, radius in _PANDA_SPHERES)
    pairs = tuple((labels.index(a), labels.index(b)) for a, b in _PANDA_SELF_COLLISION)
    return Robot(name="panda", kinematics=_builtin_kinematics("panda.urdf"),
                 goal_link="panda_hand", collision_spheres=spheres,
                 self_collision_pairs=pairs, planar=False,
                 default_q=np.array(PANDA_DEFAULT_Q))


def _point() -> Robot:
    """The planar point robot: one 0.1 m sphere, q = [x, y]."""
    return Robot(name="point", kinematics=_builtin_kinematics("point.urdf"),
                 goal_link="point",
                 collision_spheres=(CollisionSphere("point", (0.0, 0.0, 0.0), 0.1),),
                 self_collision_pairs=(), planar=True, default_q=np.zeros(2))


#: Built-in robot names and their constructors.
BUILTIN_ROBOTS: dict[str, Callable[[], Robot]] = {"panda": _panda, "point": _point}
