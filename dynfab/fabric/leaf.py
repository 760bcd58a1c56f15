"""The leaf interface: a term of the fabric that the planner builds without knowing its kind.

A leaf is a weighted geometry ``(M_e, M_e h, f_e)`` on a task space ``x = φ(q)``, pulled to
joint space (paper section III: ``(Jᵀ M J, Jᵀ (f + M J̇ q̇))``). A new kind of leaf is a new
file with a frozen dataclass that has

- ``name``: unique among a planner's leaves; it names the leaf's runtime parameters;
- ``parameter_sizes()``: the runtime parameters it reads, ``{name: size}`` (may be empty);
- ``geometry(context)``: its weighted geometry in joint space, built from the
  :class:`LeafContext` (joint symbols, the robot, maps of points on links, the symbols of its
  own parameters).

It is given to the planner in ``PlannerConfig(leaves=(...))``; the planner adds its geometry
to the root sum with the built-in leaves (it is energized and speed-controlled with them),
and its parameters are written at run time through ``planner.parameters.leaves[name][key]``.
:class:`dynfab.fabric.leaves.workspace.WorkspaceBounds` is one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import casadi as ca

from dynfab.fabric.energy import WeightedGeometry
from dynfab.fabric.maps import DifferentialMap
from dynfab.fabric.point_maps import link_point_maps
from dynfab.robots.robot import Robot

__all__ = ["Leaf", "LeafContext"]


@dataclass(frozen=True)
class LeafContext:
    """What a leaf is built from.

    Attributes:
        robot: the robot.
        q: joint position symbols (n, 1) [rad or m].
        qdot: joint velocity symbols (n, 1).
        parameters: the symbols of the leaf's own runtime parameters, by name, each a
            column of the size the leaf declared.
    """

    robot: Robot
    q: ca.SX
    qdot: ca.SX
    parameters: Mapping[str, ca.SX]

    def link_point(self, link: str, offset: Sequence[float] = (0.0, 0.0, 0.0)) -> DifferentialMap:
        """The map ``q ↦ x`` of a point fixed on ``link`` (``offset`` in the link frame [m]),
        with its Jacobian and ``J̇ q̇`` (:mod:`dynfab.fabric.point_maps`).

        Raises:
            UnknownLinkError: ``link`` is not a link of the robot.
        """
        dims = 2 if self.robot.planar else 3
        return link_point_maps(self.robot.kinematics, self.q, self.qdot, [(link, offset)], dims=dims)[0]


@runtime_checkable
class Leaf(Protocol):
    """A fabric leaf the planner builds through this interface (module docstring)."""

    @property
    def name(self) -> str:
        """Unique among the planner's leaves; names its runtime parameters."""

    def parameter_sizes(self) -> Mapping[str, int]:
        """The runtime parameters it reads: ``{name: size}``."""

    def geometry(self, context: LeafContext) -> WeightedGeometry:
        """Its weighted geometry in joint space (``M`` (n, n), forces (n, 1))."""
