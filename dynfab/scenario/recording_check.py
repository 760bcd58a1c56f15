"""An independent check of a recorded run (``dynfab check RUN.npz SCENARIO``).

From nothing but the scenario file and the recorded configurations ``q`` it recomputes,
on the robot's collision meshes and the obstacles' exact shapes
(:func:`dynfab.robots.mesh_sweep.sweep_meshes`, every sample):

- collisions: each (link, obstacle) that touched, with the samples and the depth;
- self-collisions: each checked link pair that touched
  (the pairs of :mod:`dynfab.robots.mesh_collision`);
- joint-limit violations: each joint whose recorded value left
  ``[lower - JOINT_LIMIT_TOLERANCE, upper + JOINT_LIMIT_TOLERANCE]``.

It needs a robot with collision meshes (a URDF with ``<collision>`` geometry, not planar).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynfab.robots.mesh_sweep import Contact, sweep_meshes
from dynfab.scenario.exact_metrics import mesh_model_for, obstacle_shapes
from dynfab.scenario.recording import Recording
from dynfab.scenario.references import scenario_references
from dynfab.scenario.runner import obstacle_centres, robot_for
from dynfab.scenario.schema import Scenario, ScenarioError, validate_for_robot
from dynfab.scenario.joint_limits import JOINT_LIMIT_TOLERANCE

__all__ = ["CheckReport", "LimitViolation", "check_recording"]


@dataclass(frozen=True)
class LimitViolation:
    """A joint outside its limits during some samples.

    Attributes:
        joint: Joint name.
        samples: Indices of the samples outside, increasing.
        worst: The recorded value farthest outside [rad or m].
        lower: Lower limit [rad or m].
        upper: Upper limit [rad or m].
    """

    joint: str
    samples: tuple[int, ...]
    worst: float
    lower: float
    upper: float


@dataclass(frozen=True)
class CheckReport:
    """What the check found.

    Attributes:
        samples: Number of recorded samples checked.
        clearance: Smallest link-obstacle distance [m]; None without obstacles.
        min_self_distance: Smallest distance between checked links [m]; None without pairs.
        collisions: Link-obstacle contacts.
        self_collisions: Contacts between checked links.
        limit_violations: Joints outside their limits.
        times: The recorded times [s], to date the samples.
    """

    samples: int
    clearance: float | None
    min_self_distance: float | None
    collisions: tuple[Contact, ...]
    self_collisions: tuple[Contact, ...]
    limit_violations: tuple[LimitViolation, ...]
    times: tuple[float, ...]

    @property
    def ok(self) -> bool:
        """No collision, no self-collision, no joint outside its limits."""
        return not (self.collisions or self.self_collisions or self.limit_violations)

    def to_dict(self) -> dict[str, object]:
        """A JSON-ready summary: each finding with its first time [s] and sample count."""
        def contact(c: Contact) -> dict[str, object]:
            return {"link": c.first, "other": c.second, "first_time": self.times[c.samples[0]],
                    "samples": len(c.samples), "distance": c.depth}

        return {
            "ok": self.ok, "samples": self.samples, "clearance": self.clearance,
            "min_self_distance": self.min_self_distance,
            "collisions": [contact(c) for c in self.collisions],
            "self_collisions": [contact(c) for c in self.self_collisions],
            "joint_limit_violations": [
                {"joint": v.joint, "first_time": self.times[v.samples[0]], "samples": len(v.samples),
                 "worst": v.worst, "lower": v.lower, "upper": v.upper} for v in self.limit_violations],
        }


def check_recording(scenario: Scenario, recording: Recording) -> CheckReport:
    """Check a recorded run of ``scenario`` on the real meshes (module doc).

    Raises:
        ScenarioError: The scenario is invalid, its robot has no collision meshes, or the
            recording's joints are not the robot's (``joint_names``).
    """
    robot = robot_for(scenario)
    scenario = validate_for_robot(scenario, robot)
    model = mesh_model_for(robot)
    if model is None:
        raise ScenarioError("robot", f"'{robot.name}' has no collision meshes to check against "
                                     "(a URDF robot with <collision> geometry is needed)")
    joints = robot.kinematics.joint_names
    if recording.joint_names != joints:
        raise ScenarioError("joint_names", f"the recording has joints {', '.join(recording.joint_names)}; "
                                           f"the scenario's robot has {', '.join(joints)}")
    references = scenario_references(scenario, robot)
    centres = obstacle_centres(references, recording.t)
    sweep = sweep_meshes(model, recording.q, obstacle_shapes(scenario.obstacles, centres, lowered=True))
    violations = []
    for i, joint in enumerate(joints):
        lower, upper = float(robot.kinematics.lower[i]), float(robot.kinematics.upper[i])
        values = recording.q[:, i]
        outside = np.flatnonzero((values < lower - JOINT_LIMIT_TOLERANCE) | (values > upper + JOINT_LIMIT_TOLERANCE))
        if outside.size:
            excess = np.maximum(lower - values[outside], values[outside] - upper)
            violations.append(LimitViolation(joint, tuple(int(k) for k in outside),
                                             float(values[outside][np.argmax(excess)]), lower, upper))
    return CheckReport(len(recording.t), sweep.clearance, sweep.min_self_distance, sweep.obstacle_contacts,
                       sweep.self_contacts, tuple(violations), tuple(float(t) for t in recording.t))
