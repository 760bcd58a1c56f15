"""The scenario keys of a depth camera and of what the planner perceives.

```yaml
simulator: mujoco                 # the camera is rendered by MuJoCo
camera: {position: [1.6, -1.4, 1.3], look_at: [0.2, -0.2, 0.35], width: 320, height: 240,
         fov: 60, rate: 30, noise: 0.002, delay: 0.033}
perception: camera                # truth (default) | camera
```

``camera`` describes a :class:`~dynfab.perception.camera_spec.CameraSpec` (its defaults
where a key is left out; ``position`` and ``look_at`` are required), plus
``workspace_margin: 0.3`` [m]: keep only the points within the robot's reach plus that
margin (:func:`~dynfab.perception.workspace.robot_workspace`; a fixed-base robot only, the
nearest-point leaf's range is 0.2 m); left out, every point is kept. With
``perception: camera`` the planner knows the scene only through the camera's point cloud;
the file's obstacles stay in the physics and in the metrics. ``perception: truth`` gives it
the file's obstacles, as without a camera.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import model_validator

from dynfab.perception.camera_spec import CameraSpec, CameraSpecError
from dynfab.scenario.model_types import Choice, Range, ScenarioModel, fail
from dynfab.scenario.ranges import Point3

__all__ = ["PERCEPTION", "PERCEPTIONS", "CameraMapping"]

PERCEPTIONS: tuple[str, ...] = ("truth", "camera")
PERCEPTION = Choice(PERCEPTIONS)
#: Largest image side [pixels] (MuJoCo's offscreen buffer grows to it).
MAX_PIXELS = 4096
#: Largest workspace margin [m].
MAX_MARGIN = 10.0


class CameraMapping(ScenarioModel):
    """``camera: {position, look_at, width, height, fov, rate, noise, delay, workspace_margin}``
    (module docstring)."""

    position: Point3
    look_at: Point3
    width: Annotated[float, Range(0.0, MAX_PIXELS, open_lower=True)] = 320
    height: Annotated[float, Range(0.0, MAX_PIXELS, open_lower=True)] = 240
    fov: Annotated[float, Range(0.0, 180.0, open_lower=True, unit=" deg")] = 60.0
    rate: Annotated[float, Range(0.0, 1e3, open_lower=True, unit=" Hz")] = 30.0
    noise: Annotated[float, Range(0.0, 1.0, unit=" m")] = 0.0
    delay: Annotated[float, Range(0.0, 1.0, unit=" s")] = 0.0
    workspace_margin: Annotated[float, Range(0.0, MAX_MARGIN, unit=" m")] | None = None

    @model_validator(mode="after")
    def _valid(self) -> CameraMapping:
        self.spec()
        return self

    def spec(self) -> CameraSpec:
        """The camera value; its problems raise on the field they name."""
        fields = self.model_dump(exclude={"workspace_margin"})
        for name in ("width", "height"):
            if float(fields[name]).is_integer():
                fields[name] = int(fields[name])
        try:
            return CameraSpec(**fields)
        except CameraSpecError as error:
            name, problem = str(error).split(": ", 1)
            raise fail(problem, name) from None
