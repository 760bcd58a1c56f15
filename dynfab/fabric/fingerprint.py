"""Fingerprints of a planner's inputs: what decides the code a planner compiles to.

A compiled planner (:mod:`dynfab.fabric.c_backend`) is found again in the cache without
rebuilding its CasADi expression when the SHA-256 of its inputs matches:

- the robot: its URDF model (links, joints, origins, axes, limits), root link, active and
  locked joints, collision spheres, self-collision pairs, planarity, base and motion
  limits;
- the planner configuration (every field, the limits in use included);
- the code that turns them into an expression: the source of ``dynfab.geometry``,
  ``dynfab.robots`` and ``dynfab.fabric`` (the layers the planner is built from), and the
  CasADi version.

Values are written out canonically (type names, field names, floats in hexadecimal) so
that equal inputs give equal digests in every process. A value of a type this module does
not know raises :class:`UnknownValueError`: such a planner is built symbolically every
time (its compiled code is still cached by the code's own hash).
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
from collections.abc import Iterable
from pathlib import Path

import casadi as ca
import numpy as np

from dynfab.robots.kinematics import Kinematics

#: the packages whose source decides the planner's expression (fabric imports only these)
_SOURCE_PACKAGES = ("geometry", "robots", "fabric")


class UnknownValueError(TypeError):
    """A value without a canonical form (e.g. a function object)."""


def inputs_digest(*values: object) -> str:
    """SHA-256 (hex) of the canonical form of ``values``, the dynfab source and the CasADi
    version.

    Raises:
        UnknownValueError: if a value (or a part of one) has no canonical form.
    """
    digest = hashlib.sha256()
    digest.update(f"casadi {ca.__version__}\nsource {source_digest()}\n".encode())
    for value in values:
        digest.update(canonical(value).encode())
        digest.update(b"\n")
    return digest.hexdigest()


#: the dynfab package's folder
_ROOT = Path(__file__).resolve().parent.parent


@functools.cache
def source_digest() -> str:
    """SHA-256 (hex) of the ``.py`` files of the packages the planner is built from."""
    return _files_digest(path for package in _SOURCE_PACKAGES for path in sorted((_ROOT / package).rglob("*.py")))


@functools.cache
def package_digest() -> str:
    """SHA-256 (hex) of every ``.py`` and ``.c`` file of the dynfab package: the code a
    recorded result came from (read once per process)."""
    return _files_digest(sorted(p for p in _ROOT.rglob("*") if p.suffix in (".py", ".c") and p.is_file()))


def _files_digest(paths: Iterable[Path]) -> str:
    """SHA-256 (hex) of each file's path (relative to the package) and bytes, in order."""
    digest = hashlib.sha256()
    for path in paths:
        digest.update(str(path.relative_to(_ROOT)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def canonical(value: object) -> str:
    """A text that is equal for equal values (of the types a planner is made of).

    Raises:
        UnknownValueError: for a type without a canonical form.
    """
    if value is None or isinstance(value, (bool, int, str)):
        return repr(value)
    if isinstance(value, float):
        return float(value).hex()
    if isinstance(value, enum.Enum):
        return f"{type(value).__qualname__}.{value.name}"
    if isinstance(value, np.ndarray):
        return f"array{value.shape}[{','.join(canonical(x) for x in value.ravel().tolist())}]"
    if isinstance(value, np.generic):
        return canonical(value.item())
    if isinstance(value, (tuple, list)):
        return f"({','.join(canonical(x) for x in value)})"
    if isinstance(value, dict):
        return "{" + ",".join(f"{canonical(k)}:{canonical(v)}" for k, v in sorted(value.items())) + "}"
    if isinstance(value, Path):
        return f"Path({str(value)!r})"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        parts = ",".join(f"{f.name}={canonical(getattr(value, f.name))}" for f in dataclasses.fields(value))
        return f"{type(value).__module__}.{type(value).__qualname__}({parts})"
    if isinstance(value, Kinematics):
        return (f"Kinematics(model={canonical(value.model)},root={value.root_link!r},"
                f"joints={canonical(value.joint_names)},locked={canonical(value.locked)})")
    raise UnknownValueError(f"no canonical form for a {type(value).__qualname__}")
