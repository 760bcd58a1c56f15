"""Rigid transforms with scalar entries, built entry by entry with constants folded.

A :class:`Pose` holds a rotation and a translation whose entries are Python floats
(constants, folded at build time) or 1x1 CasADi SX expressions. Products with exact 0 and
+-1 are skipped, so axis-aligned joint axes and right-angle origins cost nothing beyond
the sines and cosines; rotation entries within 1e-12 of 0 or +-1 are snapped to them
(``cos(pi/2)`` is 6e-17 in floating point). A joint motion ``M(q)`` is a rotation about
the unit axis ``a`` (Rodrigues, ``R = cos(q) I + sin(q) [a]_x + (1 - cos(q)) a a^T``) or a
translation ``q a``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Union

import casadi as ca

from .urdf_model import Joint

Scalar = Union[float, ca.SX]
"""A Python float (constant, folded at build time) or a 1x1 SX expression."""

_SNAP_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Pose:
    """A rigid transform with scalar entries: ``x_parent = rot @ x_child + pos``.

    Attributes:
        rot: Rotation matrix as three rows of three scalars [-].
        pos: Translation as three scalars [m].
    """

    rot: tuple[tuple[Scalar, Scalar, Scalar], ...]
    pos: tuple[Scalar, Scalar, Scalar]


IDENTITY = Pose(rot=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
                  pos=(0.0, 0.0, 0.0))


def lincomb(terms: Iterable[tuple[Scalar, Scalar]]) -> Scalar:
    """``sum(a * b)`` with constants folded and products by 0, +-1 skipped."""
    constant = 0.0
    plus: list[ca.SX] = []
    minus: list[ca.SX] = []
    for a, b in terms:
        a_const, b_const = isinstance(a, float), isinstance(b, float)
        if a_const and b_const:
            constant += a * b
            continue
        if (a_const and a == 0.0) or (b_const and b == 0.0):
            continue
        if a_const or b_const:
            k, e = (a, b) if a_const else (b, a)
            if k == 1.0:
                plus.append(e)
            elif k == -1.0:
                minus.append(e)
            elif k > 0.0:
                plus.append(k * e)
            else:
                minus.append((-k) * e)
        else:
            plus.append(a * b)
    if not plus and not minus:
        return constant
    if plus:
        result = plus[0]
        for e in plus[1:]:
            result = result + e
    else:
        result = -minus[0]
        minus = minus[1:]
    for e in minus:
        result = result - e
    return result + constant if constant != 0.0 else result


def compose(a: Pose, b: Pose) -> Pose:
    """``a @ b``: rotation ``Ra Rb``, translation ``Ra pb + pa``."""
    rot = tuple(tuple(lincomb((a.rot[i][k], b.rot[k][j]) for k in range(3))
                      for j in range(3)) for i in range(3))
    pos = tuple(lincomb([(a.rot[i][k], b.pos[k]) for k in range(3)] + [(1.0, a.pos[i])])
                for i in range(3))
    return Pose(rot=rot, pos=pos)  # type: ignore[arg-type]


def inverse(a: Pose) -> Pose:
    """``a^-1``: rotation ``R^T``, translation ``-R^T p``."""
    rot = tuple(tuple(a.rot[j][i] for j in range(3)) for i in range(3))
    pos = tuple(lincomb([(-1.0, lincomb((rot[i][k], a.pos[k]) for k in range(3)))])
                for i in range(3))
    return Pose(rot=rot, pos=pos)  # type: ignore[arg-type]


def apply(pose: Pose, point: Sequence[Scalar]) -> tuple[Scalar, Scalar, Scalar]:
    """``R @ point + p``."""
    return tuple(lincomb([(pose.rot[i][k], point[k]) for k in range(3)]
                          + [(1.0, pose.pos[i])]) for i in range(3))


def origin_pose(xyz: tuple[float, float, float],
                 rotation: Sequence[Sequence[float]]) -> Pose:
    """Constant pose ``[rotation, xyz]`` with near-0/+-1 rotation entries snapped."""
    snapped = tuple(tuple(snap(float(x)) for x in row) for row in rotation)
    return Pose(rot=snapped, pos=(float(xyz[0]), float(xyz[1]), float(xyz[2])))


def snap(x: float) -> float:
    """Round ``x`` to 0, 1 or -1 if it is within floating-point noise of them."""
    for target in (0.0, 1.0, -1.0):
        if abs(x - target) < _SNAP_TOLERANCE:
            return target
    return float(x)


def motion_pose(joint: Joint, value: Scalar) -> Pose:
    """Joint motion ``M(q)``: Rodrigues rotation or translation along the axis; a float
    ``value`` (a locked joint) gives a constant pose."""
    a = joint.axis
    if joint.type == "prismatic":
        return Pose(rot=IDENTITY.rot,
                     pos=tuple(lincomb([(a[i], value)]) for i in range(3)))  # type: ignore
    if isinstance(value, float):
        c, s = math.cos(value), math.sin(value)
    else:
        c, s = ca.cos(value), ca.sin(value)
    skew = ((0.0, -a[2], a[1]), (a[2], 0.0, -a[0]), (-a[1], a[0], 0.0))
    rot = tuple(tuple(
        lincomb([(snap((1.0 if i == j else 0.0) - a[i] * a[j]), c),
                  (snap(skew[i][j]), s),
                  (snap(a[i] * a[j]), 1.0)])
        for j in range(3)) for i in range(3))
    return Pose(rot=rot, pos=(0.0, 0.0, 0.0))  # type: ignore[arg-type]


def sx(x: Scalar) -> ca.SX:
    """A scalar as a 1x1 SX."""
    return ca.SX(x) if isinstance(x, float) else x


def matrix(rows: Sequence[Sequence[Scalar]]) -> ca.SX:
    """Rows of scalars as an SX matrix."""
    return ca.vertcat(*[ca.horzcat(*[sx(x) for x in row]) for row in rows])


def column(entries: Sequence[Scalar]) -> ca.SX:
    """Scalars as an SX column."""
    return ca.vertcat(*[sx(x) for x in entries])


def homogeneous(pose: Pose) -> ca.SX:
    """``[[R, p], [0, 0, 0, 1]]`` as a 4x4 SX."""
    rows = [list(pose.rot[i]) + [pose.pos[i]] for i in range(3)]
    return matrix(rows + [[0.0, 0.0, 0.0, 1.0]])
