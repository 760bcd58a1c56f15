"""Writable views of a planner's runtime parameters that check what is written into them.

Every field of :class:`~dynfab.fabric.parameters.RuntimeParameters` is written one slot at a
time (``params.goal_position[0] = [x, y, z]``). Goals differ in dimension, so their views are
a :class:`GoalViews` tuple that checks the shape it is given; a leaf's parameters are
:class:`LeafViews` by name; a field the planner was not built with is an
:class:`AbsentParameter` that names itself and how to get it.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import NoReturn

import numpy as np


class ParameterError(ValueError):
    """A runtime parameter the planner was not built with, or a value of the wrong shape."""


@dataclass(frozen=True)
class AbsentParameter:
    """A field the planner was not built with: reading a slot, writing one or turning it
    into an array raises :class:`ParameterError` with ``name`` and ``remedy``; it is falsy.

    Attributes:
        name: the field, e.g. ``"obstacle_velocity"``.
        remedy: how to build a planner that has it.
    """

    name: str
    remedy: str

    def _refuse(self) -> NoReturn:
        raise ParameterError(f"{self.name}: this planner has no such parameter; {self.remedy}")

    def __getitem__(self, index: object) -> NoReturn:
        self._refuse()

    def __setitem__(self, index: object, value: object) -> NoReturn:
        self._refuse()

    def __array__(self, *args: object, **kwargs: object) -> NoReturn:
        self._refuse()

    def __bool__(self) -> bool:
        return False


#: what an :class:`AbsentParameter` of a static planner advises
STATIC_REMEDY = "build it with PlannerConfig(..., dynamic=True)"


class LeafViews(Mapping[str, np.ndarray]):
    """The runtime parameters of one leaf (:mod:`dynfab.fabric.leaf`), by name.

    ``views[key] = value`` copies ``value`` into the parameter's view after checking its
    shape; ``views[key]`` is the writable view itself.
    """

    def __init__(self, leaf: str, views: Mapping[str, np.ndarray]) -> None:
        self._leaf = leaf
        self._views = dict(views)

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self._views:
            raise ParameterError(f"leaves[{self._leaf!r}][{key!r}]: no such parameter; "
                                 f"the leaf has {', '.join(map(repr, self._views)) or 'none'}")
        return self._views[key]

    def __setitem__(self, key: str, value: object) -> None:
        view = self[key]
        array = np.asarray(value, dtype=float).reshape(-1) if np.ndim(value) else np.full(1, float(value))
        if array.shape != view.shape:
            raise ParameterError(f"leaves[{self._leaf!r}][{key!r}] must have {view.size} values, got {array.size}")
        view[:] = array

    def __iter__(self) -> Iterator[str]:
        return iter(self._views)

    def __len__(self) -> int:
        return len(self._views)


class LeafParameters(Mapping[str, LeafViews]):
    """The runtime parameters of a planner's leaves (``PlannerConfig.leaves``), by leaf name."""

    def __init__(self, leaves: Mapping[str, LeafViews]) -> None:
        self._leaves = dict(leaves)

    def __getitem__(self, name: str) -> LeafViews:
        if name not in self._leaves:
            raise ParameterError(f"leaves[{name!r}]: the planner has no leaf of that name; "
                                 f"its leaves: {', '.join(map(repr, self._leaves)) or 'none'}")
        return self._leaves[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._leaves)

    def __len__(self) -> int:
        return len(self._leaves)


class GoalViews(tuple[np.ndarray, ...]):
    """One writable view per goal (goals differ in dimension, so this is not one array).

    ``views[i] = value`` copies ``value`` into goal ``i``'s view (as ``views[i][:] = value``
    does), after checking its shape.
    """

    name: str

    def __new__(cls, views: Sequence[np.ndarray], name: str) -> GoalViews:
        made = super().__new__(cls, views)
        made.name = name
        return made

    def __setitem__(self, index: int, value: object) -> None:
        view = self[index]
        array = np.asarray(value, dtype=float)
        if array.shape != view.shape:
            raise ParameterError(f"{self.name}[{index}] must have shape {view.shape} "
                                 f"(the goal's dimension), got {array.shape}")
        view[:] = array
