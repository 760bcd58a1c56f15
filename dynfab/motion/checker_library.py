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
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from dynfab.fabric.c_backend import Compiler, compile_shared_library, find_compiler, write_atomic
from dynfab.fabric.leaves.surface_points import moving_spheres
from dynfab.robots.collision_model import cache_dir
from dynfab.robots.robot import Robot

__all__ = ["CheckerLibrary", "cached_library", "load_checker_library"]

_FLAGS = ("-O2", "-shared", "-fPIC")
_KERNEL = Path(__file__).with_name("checker_kernel.c")
_DOUBLES = ctypes.POINTER(ctypes.c_double)


class CheckerLibrary:
    """The loaded kernel: ``clearances``, ``first_blocked`` and ``motion_free`` of
    ``checker_kernel.c`` (``first_blocked_unconverted``: ``first_blocked`` with its arguments
    given as ctypes values)."""

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
        self.motion_free = self._library.dynfab_motion_free
        self.motion_free.argtypes = [_DOUBLES, _DOUBLES, ctypes.c_double, _DOUBLES, ctypes.c_int, ctypes.c_double,
                                     ctypes.c_double]
        self.motion_free.restype = ctypes.c_int


def load_checker_library(robot: Robot) -> CheckerLibrary | None:
    """The robot's compiled checker, built on first use; ``None`` without a working C
    compiler (the caller then evaluates the CasADi expression instead)."""
    path = cached_library(_source(robot), "checker", f"the collision checker of {robot.name}")
    return None if path is None else CheckerLibrary(path)


def cached_library(source: str, what: str, title: str) -> Path | None:
    """The shared library compiled from the C ``source`` (``-O2``), cached in the cache
    folder as ``{what}-{sha256}.so`` under the digest of the source, compiler and flags and
    loaded only if its bytes hash to the digest beside it; compiled on first use with a note
    on stderr naming ``title``. ``None`` without a working C compiler, or if it fails."""
    compiler = find_compiler()
    if compiler is None:
        return None
    key = hashlib.sha256(f"{compiler.path} {compiler.version} {' '.join(_FLAGS)}\n{source}".encode()).hexdigest()
    path = cache_dir() / f"{what}-{key}.so"
    if not _verified(path):
        print(f"dynfab: compiling {title} (once; cached in {path.parent}) ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        try:
            _compile(source, compiler, path, what)
        except (OSError, RuntimeError):
            return None
        print(f"dynfab: compiled {title} in {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    return path


def _source(robot: Robot) -> str:
    """Generated forward kinematics, the robot's constants and the kernel, as one C file."""
    q = ca.SX.sym("q", robot.dof)
    centres = ca.Function("centres", [q], [ca.vec(robot.sphere_centers(q))], {"cse": True})
    generator = ca.CodeGenerator("dynfab_checker", {"with_header": False})
    generator.add(centres)
    radii = ", ".join(repr(float(r)) for r in robot.sphere_radii) or "0.0"
    constants = "\n".join([
        f"#define DYNFAB_DOF {robot.dof}",
        f"#define DYNFAB_SPHERES {len(robot.collision_spheres)}",
        f"#define DYNFAB_PAIRS {len(robot.self_collision_pairs)}",
        f"#define DYNFAB_SZ_ARG {centres.sz_arg()}",
        f"#define DYNFAB_SZ_RES {centres.sz_res()}",
        f"#define DYNFAB_SZ_IW {centres.sz_iw()}",
        f"#define DYNFAB_SZ_W {centres.sz_w()}",
        f"static const double dynfab_radii[] = {{{radii}}};",
        *_groups(robot).constants(),
    ])
    return f"{generator.dump()}\n#include <math.h>\n{constants}\n{_KERNEL.read_text(encoding='utf-8')}"


@dataclass(frozen=True)
class _Groups:
    """The robot's spheres grouped by link, for the kernel's broad phase.

    Attributes:
        start: offsets (G + 1) of each group's spheres in ``members``.
        members: sphere indices in group order.
        radii: per group, the radius [m] of the ball about the centroid of its sphere
            centres that holds its spheres (rigid on the link: measured at the zero
            configuration, 1 µm added for rounding).
        moves: per group, 1 if some joint moves its link, 0 for the base (checked against
            obstacles only if 1).
        pair_start: offsets (B + 1) of each block of self-collision pairs in ``pairs``;
            a block holds the pairs between two groups.
        pair_groups: the two groups (2B) of each block.
        pairs: the self-collision pairs (2P) in block order.
    """

    start: tuple[int, ...]
    members: tuple[int, ...]
    radii: tuple[float, ...]
    moves: tuple[int, ...]
    pair_start: tuple[int, ...]
    pair_groups: tuple[int, ...]
    pairs: tuple[int, ...]

    def constants(self) -> list[str]:
        """The C definitions ``checker_kernel.c`` reads."""
        def listed(values: tuple[int, ...] | tuple[float, ...], empty: str) -> str:
            return ", ".join(map(repr, values)) or empty
        return [f"#define DYNFAB_GROUPS {len(self.radii)}",
                f"#define DYNFAB_BLOCKS {len(self.pair_start) - 1}",
                f"static const int dynfab_group_start[] = {{{listed(self.start, '0')}}};",
                f"static const int dynfab_group_spheres[] = {{{listed(self.members, '0')}}};",
                f"static const double dynfab_group_radius[] = {{{listed(self.radii, '0.0')}}};",
                f"static const int dynfab_group_moves[] = {{{listed(self.moves, '0')}}};",
                f"static const int dynfab_block_start[] = {{{listed(self.pair_start, '0')}}};",
                f"static const int dynfab_block_groups[] = {{{listed(self.pair_groups, '0, 0')}}};",
                f"static const int dynfab_pairs[] = {{{listed(self.pairs, '0, 0')}}};"]


def _groups(robot: Robot) -> _Groups:
    """The robot's spheres and self-collision pairs grouped by link (:class:`_Groups`)."""
    links: dict[str, list[int]] = {}
    for index, sphere in enumerate(robot.collision_spheres):
        links.setdefault(sphere.link, []).append(index)
    centres = np.asarray(robot.sphere_centers(np.zeros(robot.dof)), dtype=float).reshape(-1, 3)
    radii = np.asarray(robot.sphere_radii, dtype=float)
    moving = set(moving_spheres(robot))
    start, members, group_radii, moves = [0], [], [], []
    group_of: dict[int, int] = {}
    for group, indices in enumerate(links.values()):
        centroid = centres[indices].mean(axis=0)
        group_radii.append(float(np.max(np.linalg.norm(centres[indices] - centroid, axis=1) + radii[indices])) + 1e-6)
        moves.append(int(indices[0] in moving))
        members.extend(indices)
        start.append(len(members))
        group_of.update(dict.fromkeys(indices, group))
    blocks: dict[tuple[int, int], list[int]] = {}
    for a, b in robot.self_collision_pairs:
        key = (min(group_of[a], group_of[b]), max(group_of[a], group_of[b]))
        blocks.setdefault(key, []).extend((a, b))
    pair_start, pair_groups, pairs = [0], [], []
    for key, block in blocks.items():
        pair_groups.extend(key)
        pairs.extend(block)
        pair_start.append(len(pairs) // 2)
    return _Groups(tuple(start), tuple(members), tuple(group_radii), tuple(moves), tuple(pair_start), tuple(pair_groups),
                   tuple(pairs))


def _verified(path: Path) -> bool:
    """Whether ``path`` exists and its bytes hash to the digest in its side file."""
    try:
        recorded = path.with_suffix(".sha256").read_text(encoding="utf-8").strip()
        return recorded == hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return False


def _compile(source: str, compiler: Compiler, path: Path, what: str) -> None:
    data = compile_shared_library(source, compiler, _FLAGS, what)
    write_atomic(path, data)
    write_atomic(path.with_suffix(".sha256"), hashlib.sha256(data).hexdigest().encode())


def as_pointer(array: np.ndarray) -> ctypes._Pointer:
    """A ``double*`` to a C-contiguous float64 array (kept alive by the caller)."""
    return array.ctypes.data_as(_DOUBLES)
