"""Short descriptions of input values for one-line error messages."""

from __future__ import annotations

from collections.abc import Mapping


def describe(value: object) -> str:
    """``null``, ``boolean true``, ``a list of 3``, ``a mapping`` or ``<type> <repr>`` (at
    most 40 characters of it), for messages like ``radius: expected a number, got str 'x'``."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"boolean {str(value).lower()}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)}"
    if isinstance(value, Mapping):
        return "a mapping"
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"
