"""The parts of MoveIt's messages that MotionBenchMaker problems use: a planning scene's
collision objects (``scene<NNNN>.yaml``) and a motion plan request's start state and
joint goal (``request<NNNN>.yaml``), read into typed values.

MoveIt writes quaternions ``x, y, z, w``; the values here carry dynfab's ``w, x, y, z``.
A collision object's optional ``pose`` places its primitives:
``world = pose ∘ primitive_pose``. Every malformed field raises :class:`ProblemError`
naming the file and the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from dynfab.geometry.shapes import quaternion_matrix

__all__ = ["ARM_JOINTS", "ProblemError", "SceneObject", "joint_goal", "scene_objects", "start_positions"]

#: The Panda's arm joints, in the order of a dynfab ``panda`` configuration.
ARM_JOINTS: tuple[str, ...] = tuple(f"panda_joint{i}" for i in range(1, 8))

Quaternion = tuple[float, float, float, float]
Vector3 = tuple[float, float, float]


class ProblemError(ValueError):
    """A malformed problem file; the message is one line ``<file>: <field>: <problem>``."""

    def __init__(self, file: str, field: str, problem: str) -> None:
        super().__init__(f"{file}: {field}: {problem}")


@dataclass(frozen=True)
class SceneObject:
    """One primitive of a collision object, placed in the robot's base frame.

    Attributes:
        id: The collision object's ``id`` (e.g. ``Can1``, ``shelf_top``).
        kind: ``box`` or ``cylinder``.
        dimensions: A box's full edge lengths ``(x, y, z)``; a cylinder's ``(height, radius)``
            with its axis along z [m].
        position: Centre [m].
        orientation: Unit quaternion ``(w, x, y, z)``.
    """

    id: str
    kind: Literal["box", "cylinder"]
    dimensions: tuple[float, ...]
    position: Vector3
    orientation: Quaternion


def scene_objects(scene: object, file: str) -> tuple[SceneObject, ...]:
    """Every primitive of ``world.collision_objects`` of a planning scene, in file order."""
    world = _mapping(_mapping(scene, file, "scene").get("world"), file, "world")
    objects = _sequence(world.get("collision_objects"), file, "world.collision_objects")
    found = []
    for i, item in enumerate(objects):
        field = f"world.collision_objects[{i}]"
        entry = _mapping(item, file, field)
        name = entry.get("id")
        if not isinstance(name, str) or not name:
            raise ProblemError(file, f"{field}.id", f"expected a name, got {name!r}")
        parent = _pose(entry["pose"], file, f"{field}.pose") if "pose" in entry else None
        primitives = _sequence(entry.get("primitives"), file, f"{field}.primitives")
        poses = _sequence(entry.get("primitive_poses"), file, f"{field}.primitive_poses")
        if len(poses) != len(primitives):
            raise ProblemError(file, f"{field}.primitive_poses",
                               f"expected one pose per primitive ({len(primitives)}), got {len(poses)}")
        for k, (primitive, pose) in enumerate(zip(primitives, poses)):
            position, orientation = _pose(pose, file, f"{field}.primitive_poses[{k}]")
            if parent is not None:
                position, orientation = _compose(parent, (position, orientation))
            kind, dimensions = _primitive(primitive, file, f"{field}.primitives[{k}]")
            found.append(SceneObject(name, kind, dimensions, position, orientation))
    return tuple(found)


def start_positions(request: object, file: str) -> tuple[float, ...]:
    """The arm joints of ``start_state.joint_state``, in :data:`ARM_JOINTS` order [rad]."""
    field = "start_state.joint_state"
    state = _mapping(_mapping(_mapping(request, file, "request").get("start_state"), file, "start_state")
                     .get("joint_state"), file, field)
    names = _sequence(state.get("name"), file, f"{field}.name")
    values = _numbers(state.get("position"), file, f"{field}.position", len(names))
    by_name = dict(zip(names, values))
    missing = [joint for joint in ARM_JOINTS if joint not in by_name]
    if missing:
        raise ProblemError(file, f"{field}.name", f"lacks {', '.join(missing)}")
    return tuple(by_name[joint] for joint in ARM_JOINTS)


def joint_goal(request: object, file: str) -> tuple[float, ...]:
    """The ``goal_constraints[0].joint_constraints`` positions, in :data:`ARM_JOINTS` order [rad]."""
    goals = _sequence(_mapping(request, file, "request").get("goal_constraints"), file, "goal_constraints")
    if not goals:
        raise ProblemError(file, "goal_constraints", "expected at least one goal, got none")
    field = "goal_constraints[0].joint_constraints"
    constraints = _sequence(_mapping(goals[0], file, "goal_constraints[0]").get("joint_constraints"), file, field)
    by_name = {}
    for i, item in enumerate(constraints):
        entry = _mapping(item, file, f"{field}[{i}]")
        by_name[entry.get("joint_name")] = _number(entry.get("position"), file, f"{field}[{i}].position")
    missing = [joint for joint in ARM_JOINTS if joint not in by_name]
    if missing:
        raise ProblemError(file, field, f"lacks {', '.join(missing)}")
    return tuple(by_name[joint] for joint in ARM_JOINTS)


def _primitive(item: object, file: str, field: str) -> tuple[Literal["box", "cylinder"], tuple[float, ...]]:
    entry = _mapping(item, file, field)
    kind = entry.get("type")
    if kind == "box":
        return "box", _numbers(entry.get("dimensions"), file, f"{field}.dimensions", 3)
    if kind == "cylinder":
        return "cylinder", _numbers(entry.get("dimensions"), file, f"{field}.dimensions", 2)
    raise ProblemError(file, f"{field}.type", f"expected box or cylinder, got {kind!r}")


def _pose(item: object, file: str, field: str) -> tuple[Vector3, Quaternion]:
    """``{position: [x, y, z], orientation: [x, y, z, w]}`` as a position and a unit ``(w, x, y, z)``."""
    entry = _mapping(item, file, field)
    x, y, z = _numbers(entry.get("position"), file, f"{field}.position", 3)
    qx, qy, qz, qw = _numbers(entry.get("orientation"), file, f"{field}.orientation", 4)
    norm = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    if norm < 1e-6:
        raise ProblemError(file, f"{field}.orientation", "expected a unit quaternion [x, y, z, w], got a zero one")
    return (x, y, z), (qw / norm, qx / norm, qy / norm, qz / norm)


def _compose(parent: tuple[Vector3, Quaternion], child: tuple[Vector3, Quaternion]) -> tuple[Vector3, Quaternion]:
    """The pose ``parent ∘ child``: ``p = p_a + R_a p_b``, ``q = q_a q_b``."""
    (pa, qa), (pb, qb) = parent, child
    x, y, z = (float(v) for v in np.array(pa) + quaternion_matrix(qa) @ np.array(pb))
    aw, ax, ay, az = qa
    bw, bx, by, bz = qb
    return (x, y, z), (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                       aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def _mapping(item: object, file: str, field: str) -> Mapping[str, object]:
    if not isinstance(item, Mapping):
        raise ProblemError(file, field, f"expected a mapping, got {type(item).__name__}")
    return item


def _sequence(item: object, file: str, field: str) -> Sequence[object]:
    if not isinstance(item, list):
        raise ProblemError(file, field, f"expected a list, got {type(item).__name__}")
    return item


def _numbers(item: object, file: str, field: str, count: int) -> tuple[float, ...]:
    values = _sequence(item, file, field)
    if len(values) != count:
        raise ProblemError(file, field, f"expected {count} numbers, got {len(values)}")
    return tuple(_number(value, file, f"{field}[{i}]") for i, value in enumerate(values))


def _number(item: object, file: str, field: str) -> float:
    if isinstance(item, bool) or not isinstance(item, int | float) or not math.isfinite(item):
        raise ProblemError(file, field, f"expected a finite number, got {item!r}")
    return float(item)
