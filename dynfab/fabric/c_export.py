"""Export a planner as self-contained C for C/C++ controllers.

:func:`export_planner` writes, for a planner named ``NAME``:

- ``NAME.h``: the input struct ``NAME_input`` with one named field per quantity (``q``,
  ``qdot``, each goal's position, weights, obstacle slots, ...; see :func:`input_fields`),
  ``NAME_defaults`` (the values the planner was exported with) and ``NAME_compute``;
- ``NAME.c``: the code CasADi generates for the planner function, and the two functions.
  ``NAME_compute`` copies the fields into the packed input by name (no positional
  buffers), refuses non-finite input, and returns the planner's fallback ``q̈ = −k q̇``
  (within the acceleration limits) if the fabric's output is not finite, like
  :meth:`dynfab.fabric.planner.FabricPlanner.compute`;
- ``example.c``: a 30-line program that fills the defaults, prints the command and times
  the call; and a ``Makefile`` that builds it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from dynfab.fabric.c_backend import COMPILE_FLAGS
from dynfab.fabric.parameters import SHAPE_DIMENSIONS
from dynfab.fabric.planner import FabricPlanner

#: what each field holds (by the last word of its name), for the header's comments
_MEANING = {
    "q": "configuration [rad or m] (a base: x, y, yaw first)",
    "qdot": "velocity coordinates [rad/s or m/s] (a base: v, omega first)",
    "goal position": "target: a point [m], joint values [rad] or unit axis directions",
    "position": "centres [m], one row per slot (a plane: a point on it)",
    "velocity": "velocity [m/s] (one row per slot)", "acceleration": "acceleration [m/s^2] (one row per slot)",
    "weight": "goal weights (0 deactivates a goal)", "radius": "radii [m]; 0 marks an unused slot",
    "orientation": "unit quaternions (w, x, y, z); a plane slot with a zero quaternion is unused",
    "dimensions": "sizes [m]: box (lx, ly, lz), cylinder and capsule (radius, length); <= 0: unused",
    "allowance": "how far the robot's spheres may enter each shape [m]; 0: not at all",
    "command": "the previous command (jerk-limited planners): set it to the last output",
}


@dataclass(frozen=True)
class InputField:
    """One field of the exported input struct.

    Attributes:
        name: C identifier.
        offset: start in the packed input ``z``.
        shape: ``(size,)`` or ``(rows, columns)``.
    """

    name: str
    offset: int
    shape: tuple[int, ...]

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))


def input_fields(planner: FabricPlanner) -> tuple[InputField, ...]:
    """The named parts of the planner's input ``z = [q, q̇, p, previous command]`` in order.

    Raises:
        ValueError: if the named parts do not tile ``z`` exactly (a layout this module
            does not know).
    """
    n, nv, size = planner.robot.dof, len(planner.config.limits.names), planner._layout.size
    index = np.arange(size, dtype=float)
    views = planner._layout.views(index)
    named: list[tuple[str, np.ndarray]] = [("goal_weight", views.goal_weight)]
    for derivative in ("position", "velocity", "acceleration"):
        for i, view in enumerate(getattr(views, f"goal_{derivative}") or ()):
            named.append((f"goal{i}_{derivative}", view))
        named.append((f"obstacle_{derivative}", getattr(views, f"obstacle_{derivative}")))
        for kind in SHAPE_DIMENSIONS:
            named.append((f"{kind}_{derivative}", getattr(views.shape_views(kind), derivative)))
    named.append(("obstacle_radius", views.obstacle_radius))
    for kind in SHAPE_DIMENSIONS:
        shapes = views.shape_views(kind)
        named += [(f"{kind}_orientation", shapes.orientation), (f"{kind}_dimensions", shapes.dimensions),
                  (f"{kind}_allowance", shapes.allowance)]
    for leaf, keys in views.leaves.items():
        named += [(f"leaf_{leaf}_{key}", view) for key, view in keys.items()]
    parameters = [InputField(name, n + nv + int(view.flat[0]), view.shape)
                  for name, view in named if isinstance(view, np.ndarray) and view.size > 0]
    fields = [InputField("q", 0, (n,)), InputField("qdot", n, (nv,))]
    fields += sorted(parameters, key=lambda field: field.offset)
    previous = planner._previous_command.size
    if previous:
        fields.append(InputField("previous_command", n + nv + size, (previous,)))
    offset = 0
    for field in fields:
        if field.offset != offset:
            raise ValueError(f"export: field {field.name} starts at {field.offset}, expected {offset}")
        offset += field.size
    if offset != planner._input.size:
        raise ValueError(f"export: the fields cover {offset} of {planner._input.size} inputs")
    return tuple(fields)


def export_planner(planner: FabricPlanner, folder: Path, name: str, source: str, q: np.ndarray,
                   qdot: np.ndarray) -> tuple[Path, ...]:
    """Write ``NAME.h``, ``NAME.c``, ``example.c`` and ``Makefile`` into ``folder``.

    Args:
        planner: a planner on the VM backend; its current parameters are exported as
            the defaults.
        folder: created if missing.
        name: C identifier used as the prefix of every exported symbol.
        source: where the planner came from (quoted in the header).
        q: the joint positions exported as the default (a start state).
        qdot: the joint velocities exported as the default.

    Raises:
        ValueError: for a name that is not a C identifier, or a compiled planner (its
            symbolic function is needed).
    """
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise ValueError(f"export: name must be a C identifier, got {name!r}")
    if planner.backend != "vm":
        raise ValueError("export: needs a planner on the vm backend (its symbolic function)")
    fields = input_fields(planner)
    defaults = planner._input.copy()
    n = planner.robot.dof
    defaults[:n], defaults[n:n + len(qdot)] = q, qdot
    folder.mkdir(parents=True, exist_ok=True)
    files = {f"{name}.h": _header(planner, fields, name, source), f"{name}.c": _source(planner, fields, name, defaults),
             "example.c": _example(name, len(planner.config.limits.names)), "Makefile": _makefile(name)}
    for filename, text in files.items():
        (folder / filename).write_text(text, encoding="utf-8")
    return tuple(folder / filename for filename in files)


def _meaning(name: str) -> str:
    """The header comment of the field ``name``."""
    last = name.rsplit("_", 1)[-1]
    return _MEANING["goal position" if name.startswith("goal") and last == "position" else last]


def _c_array(field: InputField) -> str:
    return field.name + "".join(f"[{extent}]" for extent in field.shape)


def _header(planner: FabricPlanner, fields: tuple[InputField, ...], name: str, source: str) -> str:
    nv, guard = len(planner.config.limits.names), f"{name.upper()}_H"
    members = "\n".join(f"    double {_c_array(field)};  /* {_meaning(field.name)} */" for field in fields)
    return f"""/* {name}: an optimization-fabric planner for the robot '{planner.robot.name}',
 * exported by `dynfab export` from {source}.
 *
 * Fill a {name}_input by field name ({name}_defaults gives the exported values), then
 * {name}_compute writes the commanded acceleration of the {nv} velocity coordinates
 * ({', '.join(planner.config.limits.names)}).
 */
#ifndef {guard}
#define {guard}

#define {name.upper()}_NQ {planner.robot.dof}  /* configuration size */
#define {name.upper()}_NV {nv}  /* velocity coordinates (and commands) */

typedef struct {{
{members}
}} {name}_input;

/* The values the planner was exported with (the scenario's start state and t = 0). */
void {name}_defaults({name}_input* input);

/* Commanded acceleration qddot [rad/s^2 or m/s^2] of the state and parameters in input.
 * Returns 0: the fabric's command; 1: the fabric's output was not finite and qddot is the
 * fallback -{planner.config.fallback_braking:g} * qdot (within the acceleration limits);
 * -1: an input is NaN or infinite (qddot untouched); -2: the generated code needs more work
 * memory than reserved (never seen; please report). Thread-safe, no allocation. */
int {name}_compute(const {name}_input* input, double qddot[{nv}]);

#endif
"""


def _source(planner: FabricPlanner, fields: tuple[InputField, ...], name: str, values: np.ndarray) -> str:
    nv, total = len(planner.config.limits.names), planner._input.size
    evaluator = f"{name}_eval"
    z = ca.SX.sym("z", total)
    function = ca.Function(evaluator, [z], [planner.function(z)], {"cse": True})
    generator = ca.CodeGenerator(name, {"with_header": False})
    generator.add(function)
    limits = planner.config.limits.acceleration if planner.config.bound_command else np.full(nv, np.inf)
    defaults = "\n".join(_default_values(field, values) for field in fields)
    packing = "\n".join(f"    memcpy(z + {field.offset}, input->{field.name}, sizeof input->{field.name});"
                        for field in fields)
    sizes = [max(size, 1) for size in (function.sz_arg(), function.sz_res(), function.sz_iw(), function.sz_w())]
    peaks = ", ".join("HUGE_VAL" if not np.isfinite(a) else repr(float(a)) for a in limits)
    return generator.dump() + f"""
/* ---- dynfab: named-argument interface ---- */
#include <string.h>
#include "{name}.h"

void {name}_defaults({name}_input* input) {{
{defaults}
}}

int {name}_compute(const {name}_input* input, double qddot[{nv}]) {{
    static const double peak[{nv}] = {{{peaks}}};
    double z[{total}], out[{nv}];
    const casadi_real* arg[{sizes[0]}];
    casadi_real* res[{sizes[1]}];
    casadi_int iw[{sizes[2]}];
    casadi_real w[{sizes[3]}];  /* the VM's work sizes, at least those of the generated code */
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    int i, finite = 1;
{packing}
    for (i = 0; i < {total}; ++i) if (!isfinite(z[i])) return -1;
    {evaluator}_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    if (sz_arg > {sizes[0]} || sz_res > {sizes[1]} || sz_iw > {sizes[2]} || sz_w > {sizes[3]}) return -2;
    arg[0] = z;
    res[0] = out;
    {evaluator}(arg, res, iw, w, 0);
    for (i = 0; i < {nv}; ++i) finite = finite && isfinite(out[i]);
    for (i = 0; i < {nv}; ++i) {{
        double braking = -{float(planner.config.fallback_braking)!r} * input->qdot[i];
        qddot[i] = finite ? out[i] : (braking > peak[i] ? peak[i] : (braking < -peak[i] ? -peak[i] : braking));
    }}
    return finite ? 0 : 1;
}}
"""


def _default_values(field: InputField, z: np.ndarray) -> str:
    """C statements that copy the exported values of ``field`` into ``input``."""
    values = ", ".join(repr(float(x)) for x in z[field.offset:field.offset + field.size])
    return (f"    {{ static const double v[{field.size}] = {{{values}}};\n"
            f"      memcpy(input->{field.name}, v, sizeof v); }}")


def _example(name: str, nv: int) -> str:
    return f"""/* example.c: fill the planner's input by name, compute a command, time the call.
 * Build and run: make && ./example */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "{name}.h"

static double seconds(void) {{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}}
static int by_value(const void* a, const void* b) {{ return (*(double*)a > *(double*)b) - (*(double*)a < *(double*)b); }}

int main(void) {{
    {name}_input input;
    double qddot[{name.upper()}_NV], block_us[31], start;
    int i, k, status;
    {name}_defaults(&input);  /* the exported start state, goals and obstacles */
    input.qdot[0] += 0.1;     /* e.g. a measured velocity */
    status = {name}_compute(&input, qddot);
    printf("status %d\\nqddot", status);
    for (i = 0; i < {name.upper()}_NV; ++i) printf(" %.17g", qddot[i]);
    for (k = 0; k < 31; ++k) {{  /* the median of 31 blocks of 500 calls */
        for (start = seconds(), i = 0; i < 500; ++i) {name}_compute(&input, qddot);
        block_us[k] = 1e6 * (seconds() - start) / 500;
    }}
    qsort(block_us, 31, sizeof block_us[0], by_value);
    printf("\\nstep_us %.3f\\n", block_us[15]);
    return status < 0;
}}
"""


def _makefile(name: str) -> str:
    flags = " ".join(flag for flag in COMPILE_FLAGS if flag not in ("-shared", "-fPIC"))
    return f"""# Builds the example; link {name}.c into your controller the same way.
# -ffp-contract=off keeps the results equal to dynfab's in Python (no fused multiply-adds).
# -march=native tunes the code for the CPU that builds it (Panda, 5 spheres, 2-core AMD
# EPYC: 4.3 instead of 4.6 us per call); when cross-compiling for the robot's computer, set
# CFLAGS without it, e.g. make CFLAGS="{flags} -Wall".
CC ?= cc
CFLAGS ?= {flags} -march=native -Wall

example: example.c {name}.c {name}.h
\t$(CC) $(CFLAGS) -o $@ example.c {name}.c -lm

clean:
\trm -f example

.PHONY: clean
"""
