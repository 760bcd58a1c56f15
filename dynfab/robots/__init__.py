"""Robot descriptions: URDF parsing, symbolic forward kinematics, built-in robots."""

from .builtin import UnknownRobotError, load_robot, robot_from_urdf
from .kinematics import Kinematics, UnknownLinkError
from .limits import LimitsError, MotionLimits
from .robot import CollisionSphere, Robot
from .urdf import UrdfError, UrdfModel, load_urdf, parse_urdf

__all__ = [
    "CollisionSphere",
    "Kinematics",
    "LimitsError",
    "MotionLimits",
    "Robot",
    "UnknownLinkError",
    "UnknownRobotError",
    "UrdfError",
    "UrdfModel",
    "load_robot",
    "load_urdf",
    "parse_urdf",
    "robot_from_urdf",
]
