"""Compile a planner's CasADi function to C, cache the shared library, load it back.

The generated C (``casadi.CodeGenerator``) is compiled with the system compiler
(``$CC``, else ``gcc``, ``cc`` or ``clang``) and :data:`COMPILE_FLAGS`, then loaded with
``casadi.external``. The cache folder is ``$DYNFAB_CACHE_DIR`` or ``~/.cache/dynfab``
(as for the collision models). It holds two kinds of entries:

- ``planner-<L>.so`` with ``planner-<L>.json``, where ``L`` (the *library key*) is the
  SHA-256 of the generated code, the compiler (path and ``--version`` line) and the
  flags. The JSON stores ``L`` and the SHA-256 of the ``.so`` bytes; the library itself
  returns ``L`` from ``dynfab_library_key()``, so its bytes contain ``L``. A library is
  loaded (``dlopen``) only after all three agree with the key asked for; anything else (a truncated, corrupt or foreign file) is rebuilt,
  never loaded.
- ``planner-inputs-<I>.json``, where ``I`` is the digest of the planner's inputs
  (:func:`dynfab.fabric.fingerprint.inputs_digest` of the robot, the configuration, the
  compiler and the flags). It maps ``I`` to ``L`` and the instruction count, so that a
  planner built before loads without building its CasADi expression at all.

Files are written under a temporary name and renamed into place, so that processes
building the same planner at once never see half a file.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import casadi as ca

from dynfab.robots.collision_model import cache_dir

#: the flags the planner library is compiled with. No fused multiply-adds, so that the C
#: outputs round exactly like the CasADi VM's. -O1: the dynamic Panda planner of the
#: default robot (75 spheres, 5 obstacle slots, 87,608 instructions; 2-core machine under
#: load, 2026-11-26, best of 5 blocks) costs 74 us per call at -O1, 76 us at -O2 and 156 us
#: at -O0, and compiles in 17 s at -O1, 33 s at -O2 and 5 s at -O0 (earlier, a 22-sphere
#: Panda: -O2 3.0 us, -O3 3.0 us, -O2 -march=native 2.6 us). -march=native is left out: a
#: library built with it crashes (illegal instruction) on an older CPU that shares the
#: cache folder.
COMPILE_FLAGS: tuple[str, ...] = ("-O1", "-ffp-contract=off", "-shared", "-fPIC")
#: format of the cache entries; bump when their layout changes
_FORMAT = 1
_FUNCTION_NAME = "fabric"


@dataclass(frozen=True)
class Compiler:
    """A C compiler.

    Attributes:
        path: the executable.
        version: the first line of its ``--version`` output.
    """

    path: str
    version: str


@dataclass(frozen=True)
class CompiledPlanner:
    """A planner function loaded from a compiled library.

    Attributes:
        function: the loaded ``casadi.external`` function (same signature as the source).
        library_key: the cache key of the library (see module docstring).
        n_instructions: SX instructions of the source function.
        compile_s: compile time [s]; 0 when loaded from the cache.
    """

    function: ca.Function
    library_key: str
    n_instructions: int
    compile_s: float


@functools.cache
def find_compiler() -> Compiler | None:
    """``$CC`` or the first of ``gcc``, ``cc``, ``clang`` on the ``PATH``; ``None`` if none runs."""
    names = [os.environ["CC"]] if os.environ.get("CC") else ["gcc", "cc", "clang"]
    for name in names:
        path = shutil.which(name)
        if path is None:
            continue
        try:
            out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30, check=True)
        except (OSError, subprocess.SubprocessError):
            continue
        return Compiler(path, (out.stdout.splitlines() or [""])[0])
    return None


def load_by_inputs(inputs_key: str, compiler: Compiler, cache: Path | None = None) -> CompiledPlanner | None:
    """The library a planner with these inputs compiled to before, or ``None`` (never
    built, or its entry fails verification)."""
    folder = cache_dir() if cache is None else cache
    index = _read_json(folder / f"planner-inputs-{inputs_key}.json")
    if index is None or index.get("format") != _FORMAT or not isinstance(index.get("library_key"), str):
        return None
    function = _load_verified(folder, index["library_key"])
    if function is None:
        return None
    return CompiledPlanner(function, index["library_key"], int(index.get("n_instructions", 0)), 0.0)


def compile_planner(function: ca.Function, compiler: Compiler, inputs_key: str | None = None,
                    cache: Path | None = None) -> CompiledPlanner:
    """Generate C for ``function``, compile it (or load it from the cache) and load it.

    Prints progress and the compile time on stderr when it compiles.

    Args:
        function: a CasADi function named ``fabric`` with one input and one output.
        compiler: the compiler (:func:`find_compiler`).
        inputs_key: if given, also record that these planner inputs compile to this
            library (:func:`load_by_inputs`).
        cache: cache folder; ``$DYNFAB_CACHE_DIR`` or ``~/.cache/dynfab`` if ``None``.

    Raises:
        RuntimeError: if the compiler fails (its last output line is in the message).
        OSError: if the cache folder cannot be written.
    """
    folder = cache_dir() if cache is None else cache
    code = generated_code(function)
    key = library_key(code, compiler)
    loaded = _load_verified(folder, key)
    compile_s = 0.0
    if loaded is None:
        print(f"dynfab: compiling the planner to C ({function.n_instructions()} instructions, "
              f"{Path(compiler.path).name} {' '.join(COMPILE_FLAGS)}) ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        _compile_into_cache(code, key, compiler, folder)
        compile_s = time.perf_counter() - start
        print(f"dynfab: compiled in {compile_s:.1f} s, cached in {folder}", file=sys.stderr, flush=True)
        loaded = _load_verified(folder, key)
        if loaded is None:
            raise RuntimeError(f"planner library {key[:12]} does not verify right after compiling it")
    if inputs_key is not None:
        write_atomic(folder / f"planner-inputs-{inputs_key}.json", json.dumps(
            {"format": _FORMAT, "library_key": key, "n_instructions": function.n_instructions()}).encode())
    return CompiledPlanner(loaded, key, function.n_instructions(), compile_s)


def generated_code(function: ca.Function) -> str:
    """The C source of ``function`` as ``casadi.CodeGenerator`` writes it."""
    generator = ca.CodeGenerator(_FUNCTION_NAME, {"with_header": False})
    generator.add(function)
    return generator.dump()


def library_key(code: str, compiler: Compiler) -> str:
    """SHA-256 (hex) of the code, the compiler and the flags."""
    text = f"format {_FORMAT}\ncompiler {compiler.path} {compiler.version}\nflags {' '.join(COMPILE_FLAGS)}\n{code}"
    return hashlib.sha256(text.encode()).hexdigest()


def compile_shared_library(source: str, compiler: Compiler, flags: tuple[str, ...] = COMPILE_FLAGS,
                           what: str = "planner") -> bytes:
    """The bytes of the shared library ``compiler`` builds from the C ``source`` with ``flags``.

    Raises:
        RuntimeError: if the compiler fails (its last output line is in the message).
    """
    with tempfile.TemporaryDirectory(prefix="dynfab-cc-") as work:
        c_file, so_file = Path(work) / f"{what}.c", Path(work) / f"{what}.so"
        c_file.write_text(source, encoding="utf-8")
        result = subprocess.run([compiler.path, *flags, str(c_file), "-o", str(so_file), "-lm"],
                                capture_output=True, text=True)
        if result.returncode != 0:
            last = (result.stderr.strip().splitlines() or ["(no output)"])[-1]
            raise RuntimeError(f"{compiler.path} failed on the {what} code: {last}")
        return so_file.read_bytes()


def _compile_into_cache(code: str, key: str, compiler: Compiler, folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    source = code + f'\nCASADI_SYMBOL_EXPORT const char* dynfab_library_key(void) {{ return "{key}"; }}\n'
    library = compile_shared_library(source, compiler)
    write_atomic(folder / f"planner-{key}.so", library)
    write_atomic(folder / f"planner-{key}.json", json.dumps(
        {"format": _FORMAT, "library_key": key, "library_sha256": hashlib.sha256(library).hexdigest(),
         "compiler": compiler.path, "compiler_version": compiler.version, "flags": list(COMPILE_FLAGS)}).encode())


def _load_verified(folder: Path, key: str) -> ca.Function | None:
    """Load ``planner-<key>.so`` if its metadata names ``key``, its bytes hash to the
    recorded SHA-256 and carry ``key`` (the string ``dynfab_library_key()`` returns); else
    ``None``. Nothing is loaded (no code runs) before all three checks pass."""
    library = folder / f"planner-{key}.so"
    meta = _read_json(folder / f"planner-{key}.json")
    if meta is None or meta.get("format") != _FORMAT or meta.get("library_key") != key:
        return None
    try:
        data = library.read_bytes()
    except OSError:
        return None
    if hashlib.sha256(data).hexdigest() != meta.get("library_sha256") or key.encode() not in data:
        return None
    return ca.external(_FUNCTION_NAME, str(library))


def _read_json(path: Path) -> dict | None:
    try:
        value = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return value if isinstance(value, dict) else None


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "wb") as file:
            file.write(data)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
