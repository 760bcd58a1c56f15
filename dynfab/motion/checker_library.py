"""Build and load the compiled configuration checker of a robot (``checker_kernel.c``).

The library is one C file: CasADi's generated code of the robot's sphere centres
``q ↦ p_1..k`` (forward kinematics), the robot's constants (radii, self-collision pairs,
work sizes of the generated function) and the hand-written kernel, which adds a broad
phase and an early exit that a CasADi expression cannot have. It is compiled with the
planner's compiler (:func:`dynfab.fabric.c_backend.find_compiler`) and cached in the
cache folder under the SHA-256 of the source, compiler and flags; a cached file is
loaded only if its bytes hash to the digest written beside it (a truncated or corrupt
file is rebuilt, never loaded).
"""

from __future__ import annotations

import ctypes
import hashlib
from pathlib import Path

import casadi as ca
import numpy as np

from dynfab.fabric.c_backend import Compiler, compile_shared_library, find_compiler, write_atomic
from dynfab.robots.collision_model import cache_dir
from dynfab.robots.robot import Robot

__all__ = ["CheckerLibrary", "load_checker_library"]

_FLAGS = ("-O2", "-shared", "-fPIC")
_KERNEL = Path(__file__).with_name("checker_kernel.c")
_DOUBLES = ctypes.POINTER(ctypes.c_double)


class CheckerLibrary:
    """The loaded kernel: ``clearances`` and ``first_blocked`` of ``checker_kernel.c``
    (``first_blocked_unconverted``: the latter, its arguments given as ctypes values)."""

    def __init__(self, path: Path) -> None:
        self._library = ctypes.CDLL(str(path))
        self.clearances = self._library.dynfab_clearances
        self.clearances.argtypes = [_DOUBLES, ctypes.c_int, _DOUBLES, ctypes.c_int, _DOUBLES]
        self.clearances.restype = None
        self.first_blocked = self._library.dynfab_first_blocked
        self.first_blocked.argtypes = [_DOUBLES, ctypes.c_int, _DOUBLES, ctypes.c_int, ctypes.c_double,
                                       ctypes.c_double]
        self.first_blocked.restype = ctypes.c_int
        # the same function without argtypes: no conversion of the arguments (ConfigurationChecker.free,
        # the planner's per-configuration call: 2.7 instead of 3.4 µs on an MBM scene), so each
        # must be passed as its ctypes type (c_void_p, c_int, c_void_p, c_int, c_double, c_double)
        self.first_blocked_unconverted = self._library["dynfab_first_blocked"]
        self.first_blocked_unconverted.restype = ctypes.c_int


def load_checker_library(robot: Robot) -> CheckerLibrary | None:
    """The robot's compiled checker, built on first use; ``None`` without a working C
    compiler (the caller then evaluates the CasADi expression instead)."""
    compiler = find_compiler()
    if compiler is None:
        return None
    source = _source(robot)
    key = hashlib.sha256(f"{compiler.path} {compiler.version} {' '.join(_FLAGS)}\n{source}".encode()).hexdigest()
    path = cache_dir() / f"checker-{key}.so"
    if not _verified(path, key):
        try:
            _compile(source, compiler, path)
        except (OSError, RuntimeError):
            return None
    return CheckerLibrary(path)


def _source(robot: Robot) -> str:
    """Generated forward kinematics, the robot's constants and the kernel, as one C file."""
    q = ca.SX.sym("q", robot.dof)
    centres = ca.Function("centres", [q], [ca.vec(robot.sphere_centers(q))], {"cse": True})
    generator = ca.CodeGenerator("dynfab_checker", {"with_header": False})
    generator.add(centres)
    radii = ", ".join(repr(float(r)) for r in robot.sphere_radii) or "0.0"
    pairs = ", ".join(f"{a}, {b}" for a, b in robot.self_collision_pairs) or "0, 0"
    constants = "\n".join([
        f"#define DYNFAB_DOF {robot.dof}",
        f"#define DYNFAB_SPHERES {len(robot.collision_spheres)}",
        f"#define DYNFAB_PAIRS {len(robot.self_collision_pairs)}",
        f"#define DYNFAB_SZ_ARG {centres.sz_arg()}",
        f"#define DYNFAB_SZ_RES {centres.sz_res()}",
        f"#define DYNFAB_SZ_IW {centres.sz_iw()}",
        f"#define DYNFAB_SZ_W {centres.sz_w()}",
        f"static const double dynfab_radii[] = {{{radii}}};",
        f"static const int dynfab_pairs[] = {{{pairs}}};",
    ])
    return f"{generator.dump()}\n#include <math.h>\n{constants}\n{_KERNEL.read_text(encoding='utf-8')}"


def _verified(path: Path, key: str) -> bool:
    """Whether ``path`` exists and its bytes carry the key's digest in its side file."""
    try:
        recorded = path.with_suffix(".sha256").read_text(encoding="utf-8").strip()
        return recorded == hashlib.sha256(path.read_bytes()).hexdigest() and path.stem == f"checker-{key}"
    except OSError:
        return False


def _compile(source: str, compiler: Compiler, path: Path) -> None:
    data = compile_shared_library(source, compiler, _FLAGS, "checker")
    write_atomic(path, data)
    write_atomic(path.with_suffix(".sha256"), hashlib.sha256(data).hexdigest().encode())


def as_pointer(array: np.ndarray) -> ctypes._Pointer:
    """A ``double*`` to a C-contiguous float64 array (kept alive by the caller)."""
    return array.ctypes.data_as(_DOUBLES)
