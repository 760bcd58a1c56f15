"""Safe arithmetic expressions in one variable ``t`` [s], turned into CasADi SX.

Text from scenario files is never run as Python: it is parsed with
``ast.parse(text, mode="eval")`` and the syntax tree is walked against a whitelist.

Allowed:

- numbers (finite, real), the variable ``t`` and the constants ``pi`` and ``e``;
- unary ``+ -`` and binary ``+ - * / **``;
- calls with positional arguments to the functions of :data:`FUNCTIONS`, with exact arity,
  e.g. ``0.5 + 0.1*sin(0.5*t)`` or ``atan2(sin(t), cos(t))``.

Anything else (attributes, subscripts, other names, keyword arguments, lambdas,
comprehensions, strings, comparisons, conditionals, text longer than
:data:`MAX_LENGTH` characters or nested deeper than :data:`MAX_DEPTH` levels) raises
:class:`ExpressionError` with a one-line message naming the problem and the offending
token. Derivatives of the result follow by CasADi's automatic differentiation.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable
from typing import NoReturn

import casadi as ca

MAX_LENGTH = 500
"""Longest accepted expression [characters]."""

MAX_DEPTH = 100
"""Deepest accepted nesting of the syntax tree (a sum of n terms nests n levels)."""

FUNCTIONS: dict[str, tuple[int, Callable[..., ca.SX]]] = {
    "sin": (1, ca.sin),
    "cos": (1, ca.cos),
    "tan": (1, ca.tan),
    "asin": (1, ca.asin),
    "acos": (1, ca.acos),
    "atan": (1, ca.atan),
    "atan2": (2, ca.atan2),
    "sinh": (1, ca.sinh),
    "cosh": (1, ca.cosh),
    "tanh": (1, ca.tanh),
    "exp": (1, ca.exp),
    "log": (1, ca.log),
    "sqrt": (1, ca.sqrt),
    "abs": (1, ca.fabs),
    "min": (2, ca.fmin),
    "max": (2, ca.fmax),
}
"""Callable names: arity and CasADi implementation (``log`` is natural, ``atan2(y, x)``)."""

CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}
"""Named constants besides the variable ``t``."""

_BINARY: dict[type[ast.operator], Callable[[ca.SX, ca.SX], ca.SX]] = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}

_UNARY: dict[type[ast.unaryop], Callable[[ca.SX], ca.SX]] = {
    ast.UAdd: lambda a: a,
    ast.USub: lambda a: -a,
}

_FORBIDDEN: dict[type[ast.AST], str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscripts",
    ast.Lambda: "lambdas",
    ast.ListComp: "comprehensions",
    ast.SetComp: "comprehensions",
    ast.DictComp: "comprehensions",
    ast.GeneratorExp: "comprehensions",
    ast.Compare: "comparisons",
    ast.BoolOp: "boolean operators",
    ast.IfExp: "conditional expressions",
    ast.NamedExpr: "assignments",
    ast.List: "lists",
    ast.Tuple: "tuples",
    ast.Set: "sets",
    ast.Dict: "mappings",
    ast.JoinedStr: "strings",
    ast.Starred: "starred arguments",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slices",
}


class ExpressionError(ValueError):
    """A rejected expression; the message is one line naming the problem and the token."""


def parse_expression(text: str, t: ca.SX) -> ca.SX:
    """Parse ``text`` into a scalar CasADi expression of the scalar symbol ``t``.

    Args:
        text: Arithmetic in ``t`` [s], e.g. ``"0.5 + 0.1*sin(0.5*t)"``; its unit is the
            caller's (positions: [m]).
        t: A scalar ``ca.SX`` symbol standing for the variable ``t``.

    Returns:
        A 1x1 ``ca.SX`` that depends on ``t`` only (or on nothing, for constants).

    Raises:
        ExpressionError: The text is not a string, too long, not valid syntax, nested too
            deeply, or uses anything outside the whitelist.
        ValueError: ``t`` is not a scalar symbol.
    """
    if not (isinstance(t, ca.SX) and t.is_scalar() and t.is_symbolic()):
        raise ValueError("t must be a scalar ca.SX symbol")
    if not isinstance(text, str):
        raise ExpressionError(f"expected text, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression too long: {len(text)} characters (at most {MAX_LENGTH})")
    if not text.strip():
        raise ExpressionError("empty expression")
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as error:
        where = f" at column {error.offset}" if error.offset else ""
        raise ExpressionError(f"invalid syntax{where}: {error.msg}") from None
    except (ValueError, RecursionError, MemoryError) as error:
        raise ExpressionError(f"cannot parse expression: {type(error).__name__}") from None
    return ca.SX(_Builder(text, t).build(tree.body, depth=1))


class _Builder:
    """Walks a syntax tree node by node, building the SX or rejecting the node."""

    def __init__(self, text: str, t: ca.SX) -> None:
        self._text = text
        self._t = t

    def build(self, node: ast.expr, depth: int) -> ca.SX | float:
        """Return the value of ``node``: an SX, or a float for numeric constants."""
        if depth > MAX_DEPTH:
            self._reject(f"expression nested deeper than {MAX_DEPTH} levels", node)
        if isinstance(node, ast.Constant):
            return self._number(node)
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.UnaryOp):
            if type(node.op) not in _UNARY:
                self._reject("operator not allowed", node)
            return _UNARY[type(node.op)](self.build(node.operand, depth + 1))
        if isinstance(node, ast.BinOp):
            if type(node.op) not in _BINARY:
                self._reject("operator not allowed", node)
            left = self.build(node.left, depth + 1)
            right = self.build(node.right, depth + 1)
            return _BINARY[type(node.op)](ca.SX(left), right)
        if isinstance(node, ast.Call):
            return self._call(node, depth)
        self._reject(f"{_FORBIDDEN.get(type(node), type(node).__name__)} not allowed", node)

    def _number(self, node: ast.Constant) -> float:
        """A finite real literal; strings, booleans, complex numbers and None are rejected."""
        value = node.value
        if isinstance(value, bool) or not isinstance(value, int | float):
            if isinstance(value, str | bytes):
                self._reject("strings not allowed", node)
            self._reject(f"{type(value).__name__} literals not allowed", node)
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            self._reject("number too large", node)
        return number

    def _name(self, node: ast.Name) -> ca.SX | float:
        """The variable ``t`` or a constant of :data:`CONSTANTS`."""
        if node.id == "t":
            return self._t
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        if node.id in FUNCTIONS:
            self._reject("unknown name", node, "functions must be called")
        self._reject("unknown name", node, "allowed: t, " + ", ".join(CONSTANTS))

    def _call(self, node: ast.Call, depth: int) -> ca.SX:
        """A whitelisted function called with exactly its number of positional arguments."""
        if not isinstance(node.func, ast.Name):
            self._reject("only named functions can be called", node.func)
        if node.func.id not in FUNCTIONS:
            self._reject("unknown function", node.func, "allowed: " + ", ".join(FUNCTIONS))
        name = node.func.id
        if node.keywords:
            self._reject("keyword arguments not allowed", node)
        arity, function = FUNCTIONS[name]
        if len(node.args) != arity:
            plural = "s" if arity > 1 else ""
            self._reject(f"{name} takes {arity} argument{plural}, got {len(node.args)}", node)
        return function(*(ca.SX(self.build(argument, depth + 1)) for argument in node.args))

    def _reject(self, problem: str, node: ast.AST, hint: str = "") -> NoReturn:
        """Raise :class:`ExpressionError` quoting the offending source on one line."""
        segment = ast.get_source_segment(self._text, node) or type(node).__name__
        segment = " ".join(segment.split())
        if len(segment) > 40:
            segment = segment[:37] + "..."
        raise ExpressionError(f"{problem}: {segment!r}" + (f" ({hint})" if hint else ""))
