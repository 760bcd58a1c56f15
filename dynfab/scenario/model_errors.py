"""Tagged unions of scenario models (goals, obstacles and trajectories by ``type``) and the
translation of pydantic's first error into a one-line :class:`ScenarioError`.

A union member is tagged ``<name>``; pydantic puts the tag into an error's location, and
:func:`scenario_error` drops it again, so that a field path reads ``goal[0].position``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Annotated, Any, Union

from pydantic import Discriminator, Tag, ValidationError
from pydantic_core import PydanticCustomError

from dynfab.describe import describe
from dynfab.scenario.fields import ScenarioError, join

__all__ = ["checked", "scenario_error", "tagged_union"]

_DISPATCH = "dispatch"


def tagged_union(members: Mapping[str, Any], key: str | None, expected: str = "a mapping",
                 kind_of: Callable[[Any], str | None] | None = None) -> Any:
    """The union of ``members`` chosen by the text at ``key`` of a mapping, or by ``kind_of``.

    Args:
        members: Type per tag value, e.g. ``{"sphere": SphereMapping, ...}``.
        key: The mapping key that holds the tag; None: ``kind_of`` chooses.
        expected: What the file should hold, for ``expected ..., got ...``.
        kind_of: Without ``key``: the member for a raw value, or None if none fits.

    Returns:
        An ``Annotated`` union type for a model field.
    """

    def tag_of(value: Any) -> str | None:
        if key is None:
            kind = kind_of(value) if kind_of is not None else None
        else:
            kind = value.get(key) if isinstance(value, Mapping) else None
        return f"<{kind}>" if isinstance(kind, str) and kind in members else None

    tagged = tuple(Annotated[model, Tag(f"<{name}>")] for name, model in members.items())
    context = _Context(key=key or "", choices=", ".join(members), expected=expected)
    return Annotated[Union[tagged], Discriminator(  # noqa: UP007 - a runtime tuple of members
        tag_of, custom_error_type=_DISPATCH, custom_error_message=f"expected {expected}",
        custom_error_context=context)]


class _Context(dict[str, str]):
    """An error context that can be hashed, as ``X | None`` of an annotated union needs."""

    def __hash__(self) -> int:  # type: ignore[override]
        return hash(tuple(sorted(self.items())))


def scenario_error(error: ValidationError) -> ScenarioError:
    """The first problem of a failed validation, as ``<field path>: <problem>``."""
    first = error.errors(include_url=False)[0]
    field = _path(first["loc"])
    context = first.get("ctx") or {}
    kind = first["type"]
    if kind == "scenario":
        problem = str(context["problem"])
        if context.get("field"):
            field = _below(field, str(context["field"]))
    elif kind == _DISPATCH:
        field, problem = _dispatch_problem(field, first["input"], context)
    else:
        problem = " ".join(str(first["msg"]).split())
    return ScenarioError(field or "scenario", problem)


def checked(check: Callable[[Any], Any], value: Any, field: str) -> Any:
    """``check(value)`` (e.g. ``Range(...).check``) with its problem as a ScenarioError on ``field``."""
    try:
        return check(value)
    except PydanticCustomError as error:
        raise ScenarioError(field, str((error.context or {})["problem"])) from None


def _dispatch_problem(field: str, value: Any, context: Mapping[str, Any]) -> tuple[str, str]:
    """Where and what is wrong with the value of a tagged union."""
    key = context["key"]
    if not key or not isinstance(value, Mapping):
        return field, f"expected {context['expected']}, got {describe(value)}"
    if key not in value:
        return join(field, key), "missing required key"
    return join(field, key), f"expected one of {context['choices']}; got {describe(value[key])}"


def _path(location: tuple[int | str, ...]) -> str:
    """``("goal", 0, "<path>", "trajectory")`` -> ``goal[0].trajectory``."""
    path = ""
    for part in location:
        if isinstance(part, int):
            path += f"[{part}]"
        elif not part.startswith("<"):
            path = join(path, part)
    return path


def _below(field: str, sub: str) -> str:
    """``field`` followed by a key (``radius``) or an index (``[2]``)."""
    return field + sub if sub.startswith("[") else join(field, sub)
