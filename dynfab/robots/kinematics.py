"""Symbolic forward kinematics of a URDF kinematic tree with CasADi.

A link pose is the product of the joint transforms on the path from the root,

    T_root_link(q) = prod_j  T_origin_j @ M_j(q_j),

with ``T_origin = [R, xyz; 0, 1]`` (URDF's ``rpy``: ``R = Rz(yaw) Ry(pitch) Rx(roll)``)
and the joint motion ``M`` of :mod:`dynfab.robots.pose_algebra`, which builds the
expressions entry by entry with constants folded (axis-aligned axes and right-angle
origins, all of the Panda, cost nothing beyond the sines and cosines). A locked joint's
motion is a constant.

Each query compiles (once, cached) a CasADi SX ``Function`` of ``q`` and calls it with
the given ``q``, so the same method works for ``SX`` (returns the expression, inlined),
``MX`` (returns a call node) and numbers (returns a numeric ``DM``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Union

import casadi as ca
import numpy as np

from .pose_algebra import (IDENTITY, Pose, Scalar, apply, column, compose, homogeneous, inverse, matrix,
                           motion_pose, origin_pose, sx)
from .urdf import Joint, UrdfModel

__all__ = ["Kinematics", "UnknownLinkError"]

CasadiLike = Union[ca.SX, ca.MX, ca.DM]
Point = tuple[str, tuple[float, float, float]]

class UnknownLinkError(ValueError):
    """A link name that is not part of the kinematic tree."""


class Kinematics:
    """Forward kinematics of a URDF tree (or of the subtree below ``root_link``).

    The *movable* joints are the revolute, continuous and prismatic joints that do not
    mimic another. The *active* ones are the configuration ``q``; the others are *locked*
    at constant values; a mimic joint follows its leader, ``q_j = m q_leader + c``, whether
    the leader is active or locked.

    Attributes:
        model: The parsed URDF.
        root_link: The link whose frame is the reference ("world") frame.
        joint_names: Active joints; ``q[i]`` belongs to ``joint_names[i]``.
        locked: Values of the movable joints that are not active [rad or m].
        dof: Number of active joints.
        lower: Lower position limits, shape (dof,); ``-inf`` if unlimited [rad or m].
        upper: Upper position limits, shape (dof,); ``+inf`` if unlimited [rad or m].
        effort_limits: Effort limits, shape (dof,); ``inf`` if not given [N m or N].
        velocity_limits: Velocity limits, shape (dof,); ``inf`` if not given
            [rad/s or m/s].
        link_names: Links of the tree in depth-first order from the root.
    """

    def __init__(self, model: UrdfModel, root_link: str | None = None,
                 joints: Sequence[str] | None = None,
                 locked: Mapping[str, float] | None = None) -> None:
        """Index the tree below ``root_link`` (the URDF root if ``None``).

        Args:
            model: The parsed URDF.
            root_link: Reference link; the URDF's root if ``None``.
            joints: Active joints in the order of ``q``; ``None``: every movable joint
                in depth-first order from the root.
            locked: Values of movable joints that are not active; the others default to
                0 clipped into their limits [rad or m].

        Raises:
            UnknownLinkError: ``root_link`` is not a link of ``model``.
            ValueError: A name in ``joints`` or ``locked`` that is not a movable joint
                below ``root_link`` (the message lists them), a joint both active and
                locked or named twice, or a non-finite locked value.
        """
        self.model = model
        if root_link is not None and root_link not in model.link_names:
            raise _unknown_link(root_link, model.link_names)
        self.root_link: str = model.root_link if root_link is None else root_link
        self._parent_joint: dict[str, Joint] = {}
        links: list[str] = []
        stack = [self.root_link]
        while stack:
            link = stack.pop()
            links.append(link)
            children = model.child_joints(link)
            for joint in children:
                self._parent_joint[joint.child] = joint
            stack.extend(j.child for j in reversed(children))
        # Depth-first link order; joints are numbered in the order their child is visited.
        movable = [self._parent_joint[link] for link in links[1:]
                   if self._parent_joint[link].is_actuated]
        by_name = {joint.name: joint for joint in movable}
        active = _active_joints(movable, joints)
        self.link_names: tuple[str, ...] = tuple(links)
        self.joint_names: tuple[str, ...] = tuple(j.name for j in active)
        self.dof: int = len(active)
        self._index = {name: i for i, name in enumerate(self.joint_names)}
        self.locked: dict[str, float] = _locked_values(by_name, self._index, locked or {})
        for joint in self._parent_joint.values():
            if joint.mimic is not None and joint.mimic.joint not in by_name:
                raise ValueError(f"joint '{joint.name}' mimics '{joint.mimic.joint}', "
                                 f"which is not below root link '{self.root_link}'")
        self.lower = np.array([_limit(j, "lower") for j in active], dtype=float)
        self.upper = np.array([_limit(j, "upper") for j in active], dtype=float)
        self.velocity_limits = np.array(
            [j.limit.velocity if j.limit is not None else math.inf for j in active],
            dtype=float)
        self.effort_limits = np.array(
            [j.limit.effort if j.limit is not None and j.limit.effort is not None else math.inf
             for j in active], dtype=float)
        for array in (self.lower, self.upper, self.velocity_limits, self.effort_limits):
            array.setflags(write=False)
        self._functions: dict[tuple[object, ...], ca.Function] = {}

    # ------------------------------------------------------------------ public API

    def transform(self, q: object, link: str, parent: str | None = None) -> CasadiLike:
        """Homogeneous transform of ``link`` in the frame of ``parent``.

        Args:
            q: Configuration, shape (dof,): ``ca.SX``, ``ca.MX`` or array-like numbers.
            link: Link whose pose is returned.
            parent: Reference link; the root link if ``None``.

        Returns:
            4x4 ``[[R, p], [0, 0, 0, 1]]`` with ``x_parent = R x_link + p`` [m]; of the
            type of ``q`` (``ca.DM`` for numeric input).

        Raises:
            UnknownLinkError: ``link`` or ``parent`` is not in the tree.
        """
        parent = self._check_links(link, parent)
        key = ("transform", link, parent)
        return self._call(key, q, lambda b: homogeneous(b.relative(link, parent)))

    def rotation(self, q: object, link: str, parent: str | None = None) -> CasadiLike:
        """Rotation matrix R (3x3) of ``link`` in the frame of ``parent`` (root if None).

        Columns are the link's unit axes in ``parent`` coordinates [-].
        """
        parent = self._check_links(link, parent)
        key = ("rotation", link, parent)
        return self._call(key, q, lambda b: matrix(b.relative(link, parent).rot))

    def position(self, q: object, link: str, parent: str | None = None,
                 offset: Sequence[float] = (0.0, 0.0, 0.0)) -> CasadiLike:
        """Position (3x1) of a point fixed in ``link``, in the frame of ``parent``.

        ``p = R_parent_link(q) @ offset + p_parent_link(q)`` [m].

        Args:
            q: Configuration, shape (dof,).
            link: Link carrying the point.
            parent: Reference link; the root link if ``None``.
            offset: Point in ``link`` coordinates [m].
        """
        parent = self._check_links(link, parent)
        point = _as_offset(offset)
        key = ("position", link, parent, point)
        return self._call(
            key, q, lambda b: column(b.point(link, parent, point)))

    def positions(self, q: object, points: Iterable[tuple[str, Sequence[float]]]
                  ) -> CasadiLike:
        """Root-frame positions of several link-fixed points, shape (k, 3) [m].

        Row ``i`` is ``position(q, points[i][0], offset=points[i][1]).T``; the common
        parts of the chains are computed once.

        Args:
            q: Configuration, shape (dof,).
            points: ``(link, offset)`` pairs, ``offset`` in link coordinates [m].
        """
        pts: tuple[Point, ...] = tuple((link, _as_offset(off)) for link, off in points)
        for link, _ in pts:
            self._check_links(link, None)
        key = ("positions", pts)

        def build(b: _Builder) -> ca.SX:
            rows = [apply(b.relative(link, self.root_link), off) for link, off in pts]
            if not rows:
                return ca.SX(0, 3)
            return ca.vertcat(*[ca.horzcat(*[sx(x) for x in row]) for row in rows])

        return self._call(key, q, build)

    # ------------------------------------------------------------------ internals

    def _check_links(self, link: str, parent: str | None) -> str:
        """Validate link names; return the reference link."""
        for name in (link, parent):
            if name is not None and name not in self._parent_joint \
                    and name != self.root_link:
                raise _unknown_link(name, self.link_names)
        return self.root_link if parent is None else parent

    def _call(self, key: tuple[object, ...], q: object,
              build: Callable[[_Builder], ca.SX]) -> CasadiLike:
        """Evaluate (compiling once per ``key``) the SX function ``q -> build(q)``."""
        function = self._functions.get(key)
        if function is None:
            q_sym = ca.SX.sym("q", self.dof)
            function = ca.Function("fk", [q_sym], [build(_Builder(self, q_sym))])
            self._functions[key] = function
        return function(self._as_input(q))

    def _as_input(self, q: object) -> CasadiLike:
        """Check the size of ``q`` and return it as a CasADi column."""
        if isinstance(q, (ca.SX, ca.MX, ca.DM)):
            if q.numel() != self.dof or (q.shape[1] != 1 and q.shape[0] != 1):
                raise ValueError(f"q must have {self.dof} elements, got shape {q.shape}")
            return q if q.shape[1] == 1 else q.T
        array = np.asarray(q, dtype=float).reshape(-1)
        if array.size != self.dof:
            raise ValueError(f"q must have {self.dof} elements, got {array.size}")
        return ca.DM(array)


class _Builder:
    """Builds link poses for one symbolic ``q``, sharing common chain prefixes."""

    def __init__(self, kinematics: Kinematics, q: ca.SX) -> None:
        self._kin = kinematics
        self._q = q
        self._joint_poses: dict[str, Pose] = {}
        self._chains: dict[tuple[str, str], Pose] = {}

    def relative(self, link: str, parent: str) -> Pose:
        """Pose of ``link`` in ``parent``: via their lowest common ancestor."""
        common = self._common_ancestor(link, parent)
        pose = self._chain(common, link)
        if common == parent:
            return pose
        return compose(inverse(self._chain(common, parent)), pose)

    def point(self, link: str, parent: str,
              point: Sequence[Scalar]) -> tuple[Scalar, Scalar, Scalar]:
        """A point of ``link`` in ``parent`` coordinates, applied joint by joint.

        ``p = O_1 M_1 (O_2 M_2 (... point))`` costs a rotated vector per joint instead
        of a 3x3 product, which is cheaper for a single point than :meth:`relative`.
        """
        common = self._common_ancestor(link, parent)
        v = (point[0], point[1], point[2])
        for child in self._ancestors(link)[:-1]:
            if child == common:
                break
            joint = self._kin._parent_joint[child]
            v = apply(self._origin(joint), apply(self._motion(joint), v))
        down = self._ancestors(parent)
        for child in reversed(down[:down.index(common)]):
            joint = self._kin._parent_joint[child]
            v = apply(inverse(self._motion(joint)), apply(inverse(self._origin(joint)), v))
        return v

    def _common_ancestor(self, link: str, parent: str) -> str:
        """The deepest link that is an ancestor of (or equal to) both links."""
        up_parent = set(self._ancestors(parent))
        return next(a for a in self._ancestors(link) if a in up_parent)

    def _ancestors(self, link: str) -> list[str]:
        """``link``, its parent, ..., the root."""
        chain = [link]
        while chain[-1] != self._kin.root_link:
            chain.append(self._kin._parent_joint[chain[-1]].parent)
        return chain

    def _chain(self, base: str, link: str) -> Pose:
        """Pose of ``link`` in its ancestor ``base``, memoised."""
        if link == base:
            return IDENTITY
        key = (base, link)
        if key not in self._chains:
            joint = self._kin._parent_joint[link]
            self._chains[key] = compose(self._chain(base, joint.parent),
                                         self._joint_pose(joint))
        return self._chains[key]

    def _joint_pose(self, joint: Joint) -> Pose:
        """``T_origin @ M(q_joint)``, memoised per joint."""
        if joint.name not in self._joint_poses:
            self._joint_poses[joint.name] = compose(self._origin(joint),
                                                     self._motion(joint))
        return self._joint_poses[joint.name]

    def _origin(self, joint: Joint) -> Pose:
        """The constant origin transform of ``joint``."""
        return origin_pose(joint.origin.xyz, joint.origin.rotation)

    def _motion(self, joint: Joint) -> Pose:
        """The joint motion ``M(q_joint)``, memoised per joint."""
        key = "motion:" + joint.name
        if key not in self._joint_poses:
            self._joint_poses[key] = (IDENTITY if joint.type == "fixed" else
                                      motion_pose(joint, self._joint_value(joint)))
        return self._joint_poses[key]

    def _joint_value(self, joint: Joint) -> Scalar:
        """The joint coordinate: ``q[i]`` if active, a float if locked, ``m v + c`` for a
        mimic joint of leader value ``v``."""
        if joint.mimic is None:
            return self._own_value(joint.name)
        value = self._own_value(joint.mimic.joint)
        if isinstance(value, float):
            return joint.mimic.multiplier * value + joint.mimic.offset
        if joint.mimic.multiplier != 1.0:
            value = joint.mimic.multiplier * value
        if joint.mimic.offset != 0.0:
            value = value + joint.mimic.offset
        return value

    def _own_value(self, name: str) -> Scalar:
        index = self._kin._index.get(name)
        return self._kin.locked[name] if index is None else self._q[index]


def _as_offset(offset: Sequence[float]) -> tuple[float, float, float]:
    """A constant 3-vector of Python floats."""
    values = tuple(float(x) for x in np.asarray(offset, dtype=float).reshape(-1))
    if len(values) != 3:
        raise ValueError(f"offset must have 3 elements, got {len(values)}")
    return (values[0], values[1], values[2])


def _limit(joint: Joint, side: str) -> float:
    """Position limit of an actuated joint; +-inf for continuous or missing limits."""
    if joint.type == "continuous" or joint.limit is None:
        return -math.inf if side == "lower" else math.inf
    return joint.limit.lower if side == "lower" else joint.limit.upper


def _active_joints(movable: list[Joint], names: Sequence[str] | None) -> list[Joint]:
    """The active joints: ``names`` in their order, or every movable joint."""
    if names is None:
        return movable
    by_name = {joint.name: joint for joint in movable}
    valid = ", ".join(by_name) or "none"
    active = []
    for name in names:
        if name not in by_name:
            raise ValueError(f"joints: '{name}' is not a movable joint (movable, non-mimic "
                             f"joints: {valid})")
        if by_name[name] in active:
            raise ValueError(f"joints: '{name}' is named twice")
        active.append(by_name[name])
    return active


def _locked_values(movable: Mapping[str, Joint], active: Mapping[str, int],
                   locked: Mapping[str, float]) -> dict[str, float]:
    """Values of every movable joint that is not active: ``locked`` or 0 in the limits."""
    valid = ", ".join(name for name in movable if name not in active) or "none"
    for name, value in locked.items():
        if name not in movable or name in active:
            why = "is active" if name in active else "is not a movable joint"
            raise ValueError(f"locked: '{name}' {why} (joints that can be locked: {valid})")
        if not math.isfinite(float(value)):
            raise ValueError(f"locked: '{name}' must be a finite number, got {value!r}")
    values = {}
    for name, joint in movable.items():
        if name in active:
            continue
        default = min(max(0.0, _limit(joint, "lower")), _limit(joint, "upper"))
        values[name] = float(locked.get(name, default))
    return values


def _unknown_link(name: str, valid: Iterable[str]) -> UnknownLinkError:
    """The error for an unknown link name, listing the valid ones."""
    return UnknownLinkError(f"unknown link '{name}'; valid links: {', '.join(valid)}")
