"""One benchmark run, in a worker process: the scenario on dynfab's built-in Panda (or the
URDF robot it names, e.g. the UR5), then its recording checked on Franka's meshes (the
URDF robot's own meshes) as ``dynfab check`` checks URDF robots
(:func:`dynfab.scenario.recording_check.check_recording`: collisions, self-collisions,
joint limits at every sample).

The run's outcome travels back as a JSON-ready mapping:
``{"metrics": Metrics.to_dict() | None, "check": CheckReport.to_dict() | None,
"refused": str | None, "wall_time_s": float}``; ``refused`` is the one-line reason when
dynfab refused the scenario (``ScenarioError``: e.g. its collision spheres find the start
in collision where the meshes do not). Asked for, MotionBenchMaker's filter on the same
problem adds ``"reference"`` (:func:`~dynfab.benchmarks.mbm.reference_plan.reference_plan`,
against the obstacles the run is checked against).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from dynfab.benchmarks.mbm.franka import franka_robot_mapping
from dynfab.benchmarks.mbm.reference_plan import reference_plan
from dynfab.fabric.backends import series_backend
from dynfab.scenario.recording import run_recording
from dynfab.scenario.recording_check import check_recording
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict

__all__ = ["run_case"]


def run_case(mapping: dict[str, Any], check_obstacles: Sequence[dict[str, Any]] | None = None,
             reference_goal: Sequence[float] | None = None, reference_checks: int = 0) -> dict[str, Any]:
    """Run the scenario ``mapping`` and check it on the meshes (module doc), against
    ``check_obstacles`` (scenario obstacle mappings) if given, else its own obstacles; with
    a ``reference_goal`` (the problem's goal configuration [rad]), also MotionBenchMaker's
    filter within ``reference_checks`` mesh checks."""
    mapping = {"backend": series_backend(), **mapping}
    truth = mapping["obstacles"] if check_obstacles is None else list(check_obstacles)
    filtered = ({} if reference_goal is None else
                {"reference": reference_plan({**mapping, "obstacles": truth}, reference_goal, reference_checks)})
    start = time.perf_counter()
    try:
        result = run_scenario(scenario_from_dict(mapping))
    except ScenarioError as error:
        return {"metrics": None, "check": None, "refused": str(error), "wall_time_s": time.perf_counter() - start,
                **filtered}
    recording = run_recording(result.robot, result.record, result.scenario.dt)
    measured = franka_robot_mapping() if mapping["robot"] == "panda" else mapping["robot"]
    check = check_recording(scenario_from_dict({**mapping, "robot": measured, "obstacles": truth}), recording)
    return {"metrics": result.metrics.to_dict(), "check": check.to_dict(), "refused": None,
            "wall_time_s": time.perf_counter() - start, **filtered}
