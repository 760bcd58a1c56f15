"""The error of an invalid scenario and small helpers shared by the scenario schema: every
violation is a :class:`ScenarioError` whose one-line message starts with the field path,
e.g. ``goal[0].position: expected 3 numbers, got 2``."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType

import yaml

__all__ = ["ScenarioError", "TRAJECTORY_TYPES", "check_length", "freeze", "join", "yaml_problem"]


class ScenarioError(ValueError):
    """An invalid scenario; the message is one line ``<field>: <problem>``.

    Attributes:
        field: Path of the offending field, e.g. ``goal[0].position``.
        problem: What is wrong with it.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{_printable(field)}: {_printable(problem)}")


def _printable(text: str) -> str:
    """``text`` with control characters (a newline in a key of the file, say) written as
    escapes, so that the message stays one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


TRAJECTORY_TYPES: tuple[str, ...] = ("linear", "circle", "polynomial", "expression", "spline", "rrt")


def freeze(value: object) -> object:
    """Return a read-only deep copy: mappings become MappingProxyType, lists tuples."""
    if isinstance(value, Mapping):
        return MappingProxyType({key: freeze(item) for key, item in value.items()})
    if isinstance(value, list | tuple):
        return tuple(freeze(item) for item in value)
    return value


def join(field: str, key: str) -> str:
    """Field path of ``key`` inside ``field`` (the top level has an empty path)."""
    return f"{field}.{key}" if field else key


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
