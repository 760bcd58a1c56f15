"""Tagged unions of scenario models (goals, obstacles and trajectories by ``type``) and the
translation of pydantic's first error into a one-line :class:`ScenarioError`.

A union member is tagged ``<name>``; pydantic puts the tag into an error's location, and
:func:`scenario_error` drops it again, so that a field path reads ``goal[0].position``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Union

from pydantic import Discriminator, Tag, ValidationError

from dynfab.describe import describe
from dynfab.scenario.fields import ScenarioError, join

__all__ = ["scenario_error", "tagged_union"]

_DISPATCH = "dispatch"


def tagged_union(members: Mapping[str, Any], key: str | None, expected: str = "a mapping") -> Any:
    """The union of ``members`` chosen by the text at ``key`` of a mapping.

    Args:
        members: Model per tag value, e.g. ``{"sphere": SphereObstacle, ...}``.
        key: The mapping key that holds the tag; None: a text value is the member tagged
            ``name`` and a mapping the member tagged ``mapping`` (the ``robot:`` key).
        expected: What the file should hold, for ``expected ..., got ...``.

    Returns:
        An ``Annotated`` union type for a model field.
    """

    def tag_of(value: Any) -> str | None:
        if key is None:
            kind = "name" if isinstance(value, str) else "mapping" if isinstance(value, Mapping) else None
        else:
            kind = value.get(key) if isinstance(value, Mapping) else None
        return f"<{kind}>" if isinstance(kind, str) and kind in members else None

    tagged = tuple(Annotated[model, Tag(f"<{name}>")] for name, model in members.items())
    context = {"key": key or "", "choices": ", ".join(members), "expected": expected}
    return Annotated[Union[tagged], Discriminator(  # noqa: UP007 - a runtime tuple of members
        tag_of, custom_error_type=_DISPATCH, custom_error_message=f"expected {expected}",
        custom_error_context=context)]


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
