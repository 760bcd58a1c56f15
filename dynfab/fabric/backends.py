"""How a planner's function is evaluated: the CasADi virtual machine or compiled C.

The default is ``"c"``: a planner step costs several times less compiled (``./run bench``
measures both), and the first build of a planner pays the compiler once (seconds to a
minute, with a line on stderr; the library is cached). ``DYNFAB_BACKEND=vm`` in the
environment makes the VM the default (the test suite does that: it builds hundreds of
planners once each); ``PlannerConfig(backend=...)`` and a scenario's ``backend:`` choose
per planner.

``"vm"`` builds the SX function (or loads it from the cache folder, by the planner's
inputs) and lets CasADi interpret it. ``"c"`` compiles it
(:mod:`dynfab.fabric.c_backend`), and on a cache hit by the planner's inputs
(:mod:`dynfab.fabric.fingerprint`) skips building the expression altogether. Without a C
compiler, if it fails on the code, or if the cache folder cannot be written, ``"c"`` falls
back to the VM with one warning line on stderr.
"""

from __future__ import annotations

import hashlib
import os
import sys
import zlib
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from dynfab.fabric import c_backend
from dynfab.fabric.fingerprint import UnknownValueError, inputs_digest

#: the evaluation backends a planner can ask for
BACKENDS: tuple[str, ...] = ("vm", "c")

#: the environment variable that sets :func:`default_backend`
BACKEND_VARIABLE = "DYNFAB_BACKEND"


def default_backend() -> str:
    """``$DYNFAB_BACKEND`` if set, else ``"c"``.

    Raises:
        ValueError: ``$DYNFAB_BACKEND`` is not one of :data:`BACKENDS`.
    """
    return _configured_backend("c")


def series_backend() -> str:
    """``$DYNFAB_BACKEND`` if set, else ``"vm"``: the backend of the runs of an experiment
    series or a benchmark whose scenarios do not choose one. Their planners differ from run
    to run (each scenario's obstacle count sizes its slots) and a run is seconds long, so a
    compile per planner (17 s to minutes) would cost more than it saves.

    Raises:
        ValueError: ``$DYNFAB_BACKEND`` is not one of :data:`BACKENDS`.
    """
    return _configured_backend("vm")


def _configured_backend(otherwise: str) -> str:
    backend = os.environ.get(BACKEND_VARIABLE, otherwise).strip() or otherwise
    if backend not in BACKENDS:
        raise ValueError(f"${BACKEND_VARIABLE} must be one of {', '.join(BACKENDS)}, got {backend!r}")
    return backend


@dataclass(frozen=True)
class PlannerFunction:
    """The planner's function ``z ↦ q̈`` ready to evaluate.

    Attributes:
        function: the CasADi function (SX, or ``casadi.external`` of the compiled library).
        backend: the backend in use: ``"vm"`` or ``"c"`` (``"vm"`` after a fallback).
        n_instructions: SX instructions of the function.
        compile_s: time spent in the C compiler [s] (0 for the VM or a cache hit).
        from_cache: the compiled library came from the cache.
    """

    function: ca.Function
    backend: str
    n_instructions: int
    compile_s: float = 0.0
    from_cache: bool = False


def planner_function(backend: str, build: Callable[[], ca.Function], inputs: tuple[object, ...]) -> PlannerFunction:
    """The planner function on ``backend``.

    Args:
        backend: one of :data:`BACKENDS`.
        build: builds the SX function (called unless the compiled one is cached).
        inputs: what the function is built from (robot, configuration), for the cache
            key by inputs.
    """
    if backend == "vm":
        function = _cached_vm_function(build, inputs)
        return PlannerFunction(function, "vm", function.n_instructions())
    compiler = c_backend.find_compiler()
    if compiler is None:
        print("dynfab: warning: backend 'c' needs a C compiler (none of $CC, gcc, cc, clang found); "
              "using the CasADi VM", file=sys.stderr)
        function = build()
        return PlannerFunction(function, "vm", function.n_instructions())
    try:
        inputs_key = inputs_digest(*inputs, compiler, c_backend.COMPILE_FLAGS)
    except UnknownValueError:
        inputs_key = None
    if inputs_key is not None:
        cached = c_backend.load_by_inputs(inputs_key, compiler)
        if cached is not None:
            return PlannerFunction(cached.function, "c", cached.n_instructions, 0.0, True)
    function = build()
    try:
        compiled = c_backend.compile_planner(function, compiler, inputs_key)
    except (RuntimeError, OSError) as error:  # the compiler failed, or the cache is not writable
        print(f"dynfab: warning: {error}; using the CasADi VM", file=sys.stderr)
        return PlannerFunction(function, "vm", function.n_instructions())
    return PlannerFunction(compiled.function, "c", compiled.n_instructions, compiled.compile_s,
                           compiled.compile_s == 0.0)


def _cached_vm_function(build: Callable[[], ca.Function], inputs: tuple[object, ...]) -> ca.Function:
    """The SX function, from the cache folder if a planner with these inputs was built
    before (CasADi's serialization, zlib-compressed, loaded only if its SHA-256 matches the
    one recorded beside it), else built and stored there. Building a Panda planner with 75
    spheres and 20 shape slots takes 9-16 s; loading it about 0.6 s."""
    try:
        key = inputs_digest(*inputs, "vm")
    except UnknownValueError:
        return build()
    folder = c_backend.cache_dir()
    path, digest_path = folder / f"planner-vm-{key}.casadi.z", folder / f"planner-vm-{key}.sha256"
    try:
        data = path.read_bytes()
        if hashlib.sha256(data).hexdigest() == digest_path.read_text(encoding="utf-8").strip():
            return ca.Function.deserialize(zlib.decompress(data).decode())
    except (OSError, RuntimeError, zlib.error, UnicodeDecodeError):
        pass
    function = build()
    data = zlib.compress(function.serialize().encode(), 1)
    try:
        c_backend.write_atomic(path, data)
        c_backend.write_atomic(digest_path, hashlib.sha256(data).hexdigest().encode())
    except OSError:
        pass  # an unwritable cache only costs the next build
    return function
