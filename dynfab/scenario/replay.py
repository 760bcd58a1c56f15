"""A recorded run measured again: ``dynfab plot run.npz`` (and the viewer's replay) rebuild
the run's robot and references from its scenario file and compute the same tracks and
metrics as the run did, from the recorded states instead of a new simulation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.recording import Recording, RecordingError
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import RunResult, measure_run, robot_for
from dynfab.scenario.schema import load_scenario, validate_for_robot
from dynfab.sim import Record

__all__ = ["replay_recording"]


def replay_recording(recording: Recording, scenario_path: str | Path | None = None) -> RunResult:
    """The result of the recorded run (no solver times: nothing was solved).

    Args:
        recording: The run, as read by :func:`~dynfab.scenario.recording.load_recording`.
        scenario_path: Its scenario file; None takes the one the recording names.

    Raises:
        RecordingError: The recording names no scenario file (and none was given), or its
            joints are not the robot's.
        ScenarioError: The scenario file is invalid.
    """
    if scenario_path is None:
        if not recording.scenario:
            raise RecordingError("the recording names no scenario file: give it with --scenario FILE")
        scenario_path = recording.scenario
    scenario = load_scenario(scenario_path)
    robot = robot_for(scenario)
    joints = robot.kinematics.joint_names
    if recording.joint_names != joints:
        raise RecordingError(f"the recording's joints ({', '.join(recording.joint_names)}) are not those of the "
                             f"scenario's robot ({', '.join(joints)})")
    scenario = validate_for_robot(scenario, robot)
    record = Record(recording.t, recording.q, recording.qdot, recording.qddot[:-1],
                    np.zeros(max(recording.t.size - 1, 0)))
    return measure_run(scenario, robot, scenario_references(scenario, robot), record, None, mesh_model_for(robot))
