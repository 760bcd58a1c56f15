"""A recorded run (``dynfab run FILE --record RUN.npz``) replayed in the view: the robot at
the recorded states, goals and obstacles where the scenario puts them at the same times."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dynfab.robots.robot import Robot
from dynfab.scenario.recording import Recording, RecordingError
from dynfab.scenario.schema import Scenario, ScenarioError, load_scenario
from dynfab.viz.view_world import SceneState, ViewWorld


def recording_scenario(recording: Recording, path: Path, override: Path | None) -> Scenario:
    """The scenario of a recording: ``override`` if given, else the file the recording names.

    Raises:
        RecordingError: the recording names no scenario (an older recording) and none is given.
        ScenarioError: the scenario file is invalid.
    """
    if override is not None:
        return load_scenario(override)
    if not recording.scenario:
        raise RecordingError(f"{path}: names no scenario file; give one with --scenario FILE")
    if not Path(recording.scenario).is_file():
        raise RecordingError(f"{path}: its scenario file {recording.scenario} does not exist; give one with "
                             "--scenario FILE")
    return load_scenario(recording.scenario)


class ReplaySession:
    """A recording on the scenario's robot, at a chosen time.

    Attributes:
        world: the scenario's robot and references.
        recording: the run.
        t: the time shown [s], within the recording.
        playing: True while the replay advances by itself.
        speed: replayed seconds per wall second (> 0).
    """

    def __init__(self, recording: Recording, scenario: Scenario, robot: Robot | None = None) -> None:
        """Raises:
            ScenarioError: the scenario does not fit its robot, or its robot's joints are
                not the recording's (the message names both lists).
        """
        self.world = ViewWorld(scenario, robot)
        joints = self.world.robot.kinematics.joint_names
        if tuple(recording.joint_names) != tuple(joints):
            raise ScenarioError("robot", f"the recording's joints ({', '.join(recording.joint_names)}) are not the "
                                f"scenario robot's ({', '.join(joints)})")
        self.recording = recording
        self.t = 0.0
        self.playing = True
        self.speed = 1.0

    @property
    def duration(self) -> float:
        """Time of the last recorded state [s]."""
        return float(self.recording.t[-1])

    def seek(self, t: float) -> None:
        """Show time ``t`` [s], clipped into the recording."""
        self.t = float(np.clip(t, 0.0, self.duration))

    def advance(self, wall_seconds: float) -> None:
        """Move on by ``wall_seconds × speed`` when playing; stops at the end."""
        if not self.playing:
            return
        self.seek(self.t + wall_seconds * self.speed)
        if self.t >= self.duration:
            self.playing = False

    def scene(self) -> SceneState:
        """The recorded state at the latest sample not after :attr:`t`."""
        index = max(int(np.searchsorted(self.recording.t, self.t, side="right")) - 1, 0)
        return self.world.state(float(self.recording.t[index]), self.recording.q[index])
