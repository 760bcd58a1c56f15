"""Field checks shared by the scenario schema: every value read from a file goes through
one of these, and every violation is a :class:`ScenarioError` whose one-line message starts
with the field path, e.g. ``goal[0].position: expected 3 numbers, got 2``."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import Any, cast

import yaml

from dynfab.describe import describe

__all__ = ["ScenarioError", "TRAJECTORY_TYPES", "check_keys", "check_length", "choice", "freeze", "join", "mapping", "number",
           "optional_text", "positive", "sequence", "text", "trajectory_mapping", "vector", "yaml_problem"]


class ScenarioError(ValueError):
    """An invalid scenario; the message is one line ``<field>: <problem>``.

    Attributes:
        field: Path of the offending field, e.g. ``goal[0].position``.
        problem: What is wrong with it.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


TRAJECTORY_TYPES: tuple[str, ...] = ("linear", "circle", "polynomial", "expression", "spline", "rrt")


def trajectory_mapping(value: object, field: str) -> Mapping[str, Any]:
    """Check a trajectory is a mapping with a known ``type``; return it read-only."""
    data = mapping(value, field)
    if "type" not in data:
        raise ScenarioError(f"{field}.type", "missing required key")
    choice(data["type"], f"{field}.type", TRAJECTORY_TYPES)
    return cast(Mapping[str, Any], freeze(data))


def freeze(value: object) -> object:
    """Return a read-only deep copy: mappings become MappingProxyType, lists tuples."""
    if isinstance(value, Mapping):
        return MappingProxyType({key: freeze(item) for key, item in value.items()})
    if isinstance(value, list | tuple):
        return tuple(freeze(item) for item in value)
    return value


def mapping(value: object, field: str, expected: str = "a mapping") -> Mapping[str, Any]:
    """Return ``value`` if it is a mapping with string keys."""
    if not isinstance(value, Mapping):
        raise ScenarioError(field or "scenario", f"expected {expected}, got {describe(value)}")
    for key in value:
        if not isinstance(key, str):
            raise ScenarioError(field or "scenario", f"keys must be text, got {describe(key)}")
    return value


def check_keys(
    data: Mapping[str, Any], field: str, required: Iterable[str], optional: Iterable[str] = ()
) -> None:
    """Raise on the first unknown key, then on the first missing required key."""
    required = tuple(required)
    allowed = required + tuple(optional)
    for key in data:
        if key not in allowed:
            raise ScenarioError(join(field, key), f"unknown key (allowed: {', '.join(allowed)})")
    for key in required:
        if key not in data:
            raise ScenarioError(join(field, key), "missing required key")


def join(field: str, key: str) -> str:
    """Field path of ``key`` inside ``field`` (the top level has an empty path)."""
    return f"{field}.{key}" if field else key


def sequence(value: object, field: str) -> list[Any]:
    """Return ``value`` if it is a list."""
    if not isinstance(value, list | tuple):
        raise ScenarioError(field, f"expected a list, got {describe(value)}")
    return list(value)


def text(value: object, field: str) -> str:
    """Return ``value`` if it is a non-empty string."""
    if not isinstance(value, str) or not value:
        raise ScenarioError(field, f"expected a non-empty text, got {describe(value)}")
    return value


def optional_text(data: Mapping[str, Any], key: str, field: str) -> str | None:
    """Return ``data[key]`` as a non-empty string, or None if absent."""
    return text(data[key], f"{field}.{key}") if key in data else None


def choice(value: object, field: str, options: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``options``."""
    if not isinstance(value, str) or value not in options:
        raise ScenarioError(field, f"expected one of {', '.join(options)}; got {describe(value)}")
    return value


def number(value: object, field: str) -> float:
    """Return ``value`` as a finite float (booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        hint = ""
        if isinstance(value, str) and _is_float_text(value):
            hint = " (YAML reads 1e-3 as text: write 1.0e-3)"
        raise ScenarioError(field, f"expected a number, got {describe(value)}{hint}")
    result = float(value)
    if not math.isfinite(result):
        raise ScenarioError(field, f"expected a finite number, got {result}")
    return result


def _is_float_text(spelled: str) -> bool:
    """True if ``spelled`` spells a float (e.g. ``1e-3``, which YAML 1.1 keeps as text)."""
    try:
        float(spelled)
    except ValueError:
        return False
    return True


def positive(value: object, field: str) -> float:
    """Return ``value`` as a finite float > 0."""
    result = number(value, field)
    if result <= 0.0:
        raise ScenarioError(field, f"must be positive, got {result:g}")
    return result


def vector(value: object, field: str, lengths: tuple[int, ...] | None = None) -> tuple[float, ...]:
    """Return a non-empty list of finite numbers, optionally of one of ``lengths``."""
    items = sequence(value, field)
    if not items:
        raise ScenarioError(field, "expected numbers, got an empty list")
    if lengths is not None:
        check_length(items, field, lengths)
    return tuple(number(item, f"{field}[{i}]") for i, item in enumerate(items))


def check_length(values: Sequence[object], field: str, lengths: tuple[int, ...], which: str = "") -> None:
    """Raise unless ``values`` has one of the allowed ``lengths``; ``which`` says what they are."""
    if len(values) not in lengths:
        expected = " or ".join(str(n) for n in lengths)
        raise ScenarioError(field, f"expected {expected} numbers{which}, got {len(values)}")


def yaml_problem(error: yaml.YAMLError) -> str:
    """One-line description of a YAML syntax error."""
    if isinstance(error, yaml.MarkedYAMLError) and error.problem_mark is not None:
        mark = error.problem_mark
        problem = error.problem or error.context or "syntax error"
        return f"invalid YAML: {problem} (line {mark.line + 1}, column {mark.column + 1})"
    return "invalid YAML: " + " ".join(str(error).split())
