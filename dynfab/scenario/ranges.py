"""The documented range of every number in a scenario file (README "Scenario files").

A value outside its range is refused when the file is loaded, naming the field, e.g.
``obstacles[0].radius: must be at most 100 m, got 1e+300``. The ranges are generous for
robots in a room or a hall and keep every later computation finite.
"""

from __future__ import annotations

from typing import Annotated

from dynfab.scenario.model_types import Items, Range

#: Largest |coordinate| of any point: goals, obstacles, trajectory points [m].
MAX_COORDINATE = 1e3
#: Largest radius, box edge, cylinder or capsule length, circle radius [m].
MAX_LENGTH = 1e2
#: Largest |q_i| before the joint limits are checked [rad or m].
MAX_JOINT_VALUE = 1e3
#: Largest |velocity| of a start state, a linear motion or a limit [m/s or rad/s].
MAX_SPEED = 1e2
#: Largest |angular velocity| of a circle or a turning axis goal [rad/s].
MAX_ANGULAR_VELOCITY = 1e2
#: Largest goal ``tolerance`` [m or rad]: a larger one would count as reached at once.
MAX_TOLERANCE = 0.5
#: Largest goal ``weight`` (relative).
MAX_WEIGHT = 1e3
#: Largest control period ``dt`` [s].
MAX_DT = 1.0
#: Longest ``duration`` of a run, a spline or an RRT path [s].
MAX_DURATION = 1e4
#: Shortest ``duration`` of a spline or an RRT path [s].
MIN_PATH_DURATION = 1e-2
#: Most control steps of a run: ``duration / dt`` (the run is recorded in memory).
MAX_STEPS = 200_000
#: Largest |polynomial coefficient| [m/s^k].
MAX_COEFFICIENT = 1e3
#: Most coefficients of one polynomial axis (degree 15).
MAX_COEFFICIENTS = 16
#: Largest acceleration limit [m/s² or rad/s²] and jerk limit [m/s³ or rad/s³].
MAX_ACCELERATION = 1e3
MAX_JERK = 1e5
#: Largest MuJoCo observation ``delay`` [s] and ``noise`` [rad or m, and per s].
MAX_DELAY = 1.0
MAX_NOISE = 1.0
#: Largest ``sphere_tolerance`` of fitted collision spheres [m].
MAX_SPHERE_TOLERANCE = 1.0
#: Most goals, obstacles, collision spheres, waypoints.
MAX_GOALS = 64
MAX_OBSTACLES = 1000
#: Largest RRT ``seed`` (OMPL takes a 32-bit seed).
MAX_SEED = 2**31 - 1

Coordinate = Annotated[float, Range(-MAX_COORDINATE, MAX_COORDINATE, unit=" m")]
Length = Annotated[float, Range(0.0, MAX_LENGTH, open_lower=True, unit=" m")]
Tolerance = Annotated[float, Range(0.0, MAX_TOLERANCE, open_lower=True)]
Weight = Annotated[float, Range(0.0, MAX_WEIGHT, open_lower=True)]
AngularVelocity = Annotated[float, Range(-MAX_ANGULAR_VELOCITY, MAX_ANGULAR_VELOCITY, unit=" rad/s")]
Speed = Annotated[float, Range(-MAX_SPEED, MAX_SPEED)]
PathDuration = Annotated[float, Range(MIN_PATH_DURATION, MAX_DURATION, unit=" s")]
#: A point: 2 numbers (planar robots) or 3 [m].
Point = Annotated[tuple[Coordinate, ...], Items((2, 3))]
#: A point in space [m] (or any 3-vector of coordinates, e.g. a direction).
Point3 = Annotated[tuple[Coordinate, ...], Items((3,))]
