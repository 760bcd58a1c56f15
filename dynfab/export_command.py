"""``dynfab export SCENARIO --out DIR``: a scenario's fabric planner as self-contained C.

The planner is the one ``dynfab run`` would build for the scenario; its start state and the
goals and obstacles at t = 0 become the exported defaults
(:mod:`dynfab.fabric.c_export`).
"""

from __future__ import annotations

import dataclasses
import re
import sys
from pathlib import Path

from dynfab.fabric.c_export import export_planner
from dynfab.scenario.controllers import FabricController, make_controller
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import robot_for
from dynfab.scenario.schema import ScenarioError, load_scenario, validate_for_robot

__all__ = ["export_command"]


def export_command(path: Path, out: Path, name: str | None) -> int:
    """Export the planner of the scenario at ``path`` into ``out``; 0 on success, 2 on
    invalid input (one line on stderr)."""
    name = name if name is not None else re.sub(r"\W", "_", path.stem)
    if not re.fullmatch(r"[A-Za-z_]\w*", name, flags=re.ASCII):
        print(f"dynfab: error: --name: must be a C identifier, got {name!r}", file=sys.stderr)
        return 2
    try:
        scenario = dataclasses.replace(load_scenario(path), backend="vm")
        robot = robot_for(scenario)
        scenario = validate_for_robot(scenario, robot)
        controller = make_controller(scenario, robot, scenario_references(scenario, robot))
        if not isinstance(controller, FabricController):
            raise ScenarioError("planner", f"export needs a fabric planner, got {scenario.planner!r}")
        files = export_planner(controller.planner, out, name, str(path), scenario.initial_state.q,
                               scenario.initial_state.qdot)
    except ScenarioError as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"dynfab: error: --out: cannot write {out} ({error.strerror})", file=sys.stderr)
        return 2
    print(f"dynfab: wrote {', '.join(str(file) for file in files)}; build the example with: make -C {out}",
          file=sys.stderr)
    return 0
