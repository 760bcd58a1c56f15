"""Building blocks of the scenario's pydantic models: a base model that refuses anything
but a mapping with known text keys, and field types whose errors are the one-line
problems of docs/design.md section 5.4 (``expected a number, got str 'x'``, ``must be positive,
got -0.1``), each with its documented range in the JSON Schema.

Every problem is raised as ``PydanticCustomError("scenario", ...)``; its context may name
a sub-field (``field``) below the location pydantic reports. :mod:`model_errors` turns
the first error into a :class:`~dynfab.scenario.fields.ScenarioError`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, GetCoreSchemaHandler, GetJsonSchemaHandler, model_validator
from pydantic_core import PydanticCustomError, core_schema

from dynfab.describe import describe

__all__ = ["Choice", "Flag", "Items", "Range", "ScenarioModel", "Text", "Whole", "fail"]


def fail(problem: str, field: str | None = None) -> PydanticCustomError:
    """The error of a scenario problem; ``field`` is a sub-path (``radius``, ``[2]``) below
    the location pydantic reports."""
    return PydanticCustomError("scenario", "{problem}", {"problem": problem, "field": field})


class ScenarioModel(BaseModel):
    """A mapping of the scenario file: text keys, no unknown key, every required key.

    Checked in that order before any value, so that an unknown key is reported first, as
    ``<path>.<key>: unknown key (allowed: ...)``, then a missing one.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)
    #: What the file should hold here, for ``expected ..., got ...``.
    expected: ClassVar[str] = "a mapping"

    @model_validator(mode="before")
    @classmethod
    def _check_keys(cls, data: Any) -> Any:
        if not isinstance(data, Mapping):
            raise fail(f"expected {cls.expected}, got {describe(data)}")
        for key in data:
            if not isinstance(key, str):
                raise fail(f"keys must be text, got {describe(key)}")
        allowed = tuple(cls.model_fields)
        for key in data:
            if key not in allowed:
                raise fail(f"unknown key (allowed: {', '.join(allowed)})", key)
        for name, info in cls.model_fields.items():
            if info.is_required() and name not in data:
                raise fail("missing required key", name)
        cls.check_keys(data)
        return data

    @classmethod
    def check_keys(cls, data: Mapping[str, Any]) -> None:
        """Further checks of which keys are present, before any value is read."""


@dataclass(frozen=True)
class _Validated:
    """An annotation whose value is checked by :meth:`check` alone (no coercion)."""

    def check(self, value: Any) -> Any:
        raise NotImplementedError

    def json(self) -> dict[str, Any]:
        raise NotImplementedError

    def __get_pydantic_core_schema__(self, source: Any, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        return core_schema.no_info_plain_validator_function(self.check)

    def __get_pydantic_json_schema__(self, schema: core_schema.CoreSchema, handler: GetJsonSchemaHandler
                                     ) -> dict[str, Any]:
        return self.json()


@dataclass(frozen=True)
class Range(_Validated):
    """A finite real number in ``[lower, upper]`` (``(lower, upper]`` if ``open_lower``).

    Booleans and text are not numbers; the text ``1e-3`` (which YAML 1.1 keeps as text)
    gets a hint. Returns a float.
    """

    lower: float = -math.inf
    upper: float = math.inf
    open_lower: bool = False
    unit: str = ""

    def check(self, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            hint = " (YAML reads 1e-3 as text: write 1.0e-3)" if isinstance(value, str) and _spells_float(value) else ""
            raise fail(f"expected a number, got {describe(value)}{hint}")
        try:
            number = float(value)
        except OverflowError:
            number = math.copysign(math.inf, value)
        if not math.isfinite(number):
            raise fail(f"expected a finite number, got {number}")
        if self.open_lower and self.lower == 0.0 and number <= 0.0:
            raise fail(f"must be positive, got {number:g}")
        if self.open_lower and number <= self.lower:
            raise fail(f"must be greater than {self.lower:g}{self.unit}, got {number:g}")
        if number < self.lower:
            raise fail(f"must be >= {self.lower:g}{self.unit}, got {number:g}")
        if number > self.upper:
            raise fail(f"must be at most {self.upper:g}{self.unit}, got {number:g}")
        return number

    def json(self) -> dict[str, Any]:
        schema: dict[str, Any] = {"type": "number"}
        if math.isfinite(self.lower):
            schema["exclusiveMinimum" if self.open_lower else "minimum"] = self.lower
        if math.isfinite(self.upper):
            schema["maximum"] = self.upper
        return schema


@dataclass(frozen=True)
class Whole(_Validated):
    """An integer in ``[lower, upper]``."""

    lower: int
    upper: int

    def check(self, value: Any) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise fail(f"expected an integer, got {describe(value)}")
        if not self.lower <= value <= self.upper:
            raise fail(f"expected an integer from {self.lower} to {self.upper}, got {_short(value)}")
        return value

    def json(self) -> dict[str, Any]:
        return {"type": "integer", "minimum": self.lower, "maximum": self.upper}


@dataclass(frozen=True)
class Text(_Validated):
    """A non-empty text of at most ``max_length`` characters."""

    max_length: int = 200

    def check(self, value: Any) -> str:
        if not isinstance(value, str) or not value:
            raise fail(f"expected a non-empty text, got {describe(value)}")
        if len(value) > self.max_length:
            raise fail(f"expected at most {self.max_length} characters, got {len(value)}")
        return value

    def json(self) -> dict[str, Any]:
        return {"type": "string", "minLength": 1, "maxLength": self.max_length}


@dataclass(frozen=True)
class Choice(_Validated):
    """One of ``options`` (text); ``problem`` replaces ``expected one of ...`` in the message."""

    options: tuple[str, ...]
    problem: str = ""

    def check(self, value: Any) -> str:
        if not isinstance(value, str) or value not in self.options:
            if self.problem:
                raise fail(f"{self.problem}, got {describe(value)}")
            raise fail(f"expected one of {', '.join(self.options)}; got {describe(value)}")
        return value

    def json(self) -> dict[str, Any]:
        return {"enum": list(self.options)}


@dataclass(frozen=True)
class Flag(_Validated):
    """``true`` or ``false``."""

    def check(self, value: Any) -> bool:
        if not isinstance(value, bool):
            raise fail(f"expected true or false, got {describe(value)}")
        return value

    def json(self) -> dict[str, Any]:
        return {"type": "boolean"}


@dataclass(frozen=True)
class Items:
    """A list (read as a tuple) of at most ``max_items`` values of the annotated element type.

    Attributes:
        lengths: Allowed lengths; None: any from 1 (or 0 if ``allow_empty``) to ``max_items``.
        what: The elements in messages: ``expected 3 numbers, got 2``.
        allow_empty: Whether ``[]`` is valid.
        max_items: Largest length.
    """

    lengths: tuple[int, ...] | None = None
    what: str = "numbers"
    allow_empty: bool = False
    max_items: int = 1000

    def check(self, value: Any) -> Any:
        if not isinstance(value, list | tuple):
            raise fail(f"expected a list, got {describe(value)}")
        if not value and not self.allow_empty:
            raise fail(f"expected {self.what}, got an empty list")
        if self.lengths is not None and len(value) not in self.lengths:
            raise fail(f"expected {' or '.join(map(str, self.lengths))} {self.what}, got {len(value)}")
        if len(value) > self.max_items:
            raise fail(f"expected at most {self.max_items} {self.what}, got {len(value)}")
        return list(value)

    def __get_pydantic_core_schema__(self, source: Any, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        return core_schema.no_info_before_validator_function(
            self.check, core_schema.no_info_after_validator_function(tuple, handler(source)))

    def __get_pydantic_json_schema__(self, schema: core_schema.CoreSchema, handler: GetJsonSchemaHandler
                                     ) -> dict[str, Any]:
        result = handler(schema)
        result.pop("uniqueItems", None)
        lengths = self.lengths or (0 if self.allow_empty else 1, self.max_items)
        result["minItems"], result["maxItems"] = min(lengths), min(max(lengths), self.max_items)
        return result


def _spells_float(spelled: str) -> bool:
    """True if ``spelled`` spells a float in exponent notation without a dot (``1e-3``,
    which YAML 1.1 keeps as text)."""
    return re.fullmatch(r"[-+]?[0-9]+[eE][-+]?[0-9]+", spelled.strip()) is not None


def _short(value: int) -> str:
    """An integer for a message: huge ones in scientific notation."""
    return str(value) if abs(value) < 10**15 else f"{float(value):.3g}"

