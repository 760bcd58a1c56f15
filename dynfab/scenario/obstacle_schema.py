"""The ``obstacles:`` entries of a scenario: spheres, boxes, cylinders, capsules,
half-space planes and triangle meshes, each static or moving along a trajectory of its
centre, scenes given as URDFs and point clouds (static; :mod:`dynfab.scenario.scene_files`
reads the files)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal

from pydantic import model_validator

from dynfab.geometry.shapes import (
    IDENTITY_QUATERNION,
    Box,
    Capsule,
    Cylinder,
    Plane,
    Mesh,
    PointCloud,
    Shape,
    ShapeError,
    Sphere,
    quaternion_from_normal,
    unit_quaternion,
)
from dynfab.scenario.model_errors import tagged_union
from dynfab.scenario.model_types import Items, Range, ScenarioModel, Text, Whole, fail
from dynfab.scenario.ranges import Coordinate, Length, Point3
from dynfab.scenario.trajectory_schema import TrajectoryMapping, frozen_trajectory


OBSTACLE_TYPES: tuple[str, ...] = ("sphere", "box", "cylinder", "capsule", "plane", "mesh", "urdf", "points")


ObstacleType = Literal["sphere", "box", "cylinder", "capsule", "plane", "mesh", "points"]


@dataclass(frozen=True)
class ObstacleSpec:
    """An obstacle shape, static (``position``) or moving (``trajectory`` of its centre;
    its orientation stays).

    Attributes:
        type: One of :data:`OBSTACLE_TYPES`.
        radius: Radius of a sphere, cylinder or capsule [m] (> 0); 0 for a box or plane.
        position: Centre [m] (a plane: its ``point``), 2 numbers (planar robots only) or 3;
            None if moving.
        trajectory: Read-only mapping of the centre's motion, with a ``type`` among
            :data:`fields.TRAJECTORY_TYPES`; None if static.
        size: A box's full edge lengths (lx, ly, lz) [m]; None for other shapes.
        length: A cylinder's full length or a capsule's segment length, along the shape's z
            axis [m]; None for other shapes.
        orientation: Unit quaternion (w, x, y, z) of the shape frame (normalised from the
            file); a plane's takes +z onto its ``normal``.
        normal: A plane's unit normal, pointing out of the solid half-space; None otherwise.
        mesh: A mesh's triangles in its frame (scaled); None for other shapes.
        cloud: A point cloud's kept points (world frame; ``position`` the origin); None for
            other shapes.
        source: The scenario file's entry it came from, e.g. ``obstacles[2]`` (a URDF scene's
            geometries all name their entry; a cloud without points has no obstacle, so entries
            and obstacles need not match one to one); empty when made in code: see :meth:`name`.
    """

    type: ObstacleType
    radius: float = 0.0
    position: tuple[float, ...] | None = None
    trajectory: Mapping[str, Any] | None = None
    size: tuple[float, float, float] | None = None
    length: float | None = None
    orientation: tuple[float, float, float, float] = IDENTITY_QUATERNION
    normal: tuple[float, float, float] | None = None
    mesh: Mesh | None = None
    cloud: PointCloud | None = None
    source: str = field(default="", compare=False)

    def name(self, k: int) -> str:
        """How messages and contacts name the scenario's ``k``-th obstacle: its entry in the
        file (:attr:`source`), or ``obstacles[k]`` when it has none."""
        return self.source or f"obstacles[{k}]"

    @property
    def shape(self) -> Shape:
        """The obstacle's geometry in its own frame."""
        if self.type == "sphere":
            return Sphere(self.radius)
        if self.type == "box":
            return Box(self.size)
        if self.type == "cylinder":
            return Cylinder(self.radius, self.length)
        if self.type == "capsule":
            return Capsule(self.radius, self.length)
        if self.type == "mesh":
            assert self.mesh is not None
            return self.mesh
        if self.type == "points":
            assert self.cloud is not None
            return self.cloud
        return Plane()


Placement = Annotated[tuple[Coordinate, ...], Items((2, 3))]
Quaternion = Annotated[tuple[Annotated[float, Range(-1e3, 1e3)], ...], Items((4,))]


class _Placed(ScenarioModel):
    """Exactly one of ``position`` (static, [m]) or ``trajectory`` (moving centre)."""

    @classmethod
    def check_keys(cls, data: Mapping[str, Any]) -> None:
        placement = "point" if "point" in cls.model_fields else "position"
        if (placement in data) == ("trajectory" in data):
            raise fail(f"expected exactly one of '{placement}' (static) or 'trajectory' (moving)")


class SphereMapping(_Placed):
    """``{type: sphere, radius: r [m], position | trajectory}``."""

    type: Literal["sphere"]
    radius: Length
    position: Placement | None = None
    trajectory: TrajectoryMapping | None = None


class BoxMapping(_Placed):
    """``{type: box, size: [lx, ly, lz] [m], orientation: [w, x, y, z], position | trajectory}``."""

    type: Literal["box"]
    size: Annotated[tuple[Length, ...], Items((3,))]
    orientation: Quaternion = IDENTITY_QUATERNION
    position: Placement | None = None
    trajectory: TrajectoryMapping | None = None

    @model_validator(mode="after")
    def _rotation(self) -> BoxMapping:
        return _check_rotation(self)


class CylinderMapping(_Placed):
    """``{type: cylinder, radius: r [m], length: l [m] along z, orientation, position | trajectory}``."""

    type: Literal["cylinder"]
    radius: Length
    length: Length
    orientation: Quaternion = IDENTITY_QUATERNION
    position: Placement | None = None
    trajectory: TrajectoryMapping | None = None

    @model_validator(mode="after")
    def _rotation(self) -> CylinderMapping:
        return _check_rotation(self)


class CapsuleMapping(CylinderMapping):
    """``{type: capsule, radius: r [m], length: l [m] of the z segment, orientation, position | trajectory}``."""

    type: Literal["capsule"]  # type: ignore[assignment]


class PlaneMapping(_Placed):
    """``{type: plane, normal: n, point | trajectory}``: the solid half-space behind ``point``."""

    type: Literal["plane"]
    normal: Point3
    point: Placement | None = None
    trajectory: TrajectoryMapping | None = None

    @model_validator(mode="after")
    def _normal_not_zero(self) -> PlaneMapping:
        if math.hypot(*self.normal) < 1e-9:
            raise fail(f"expected a non-zero vector, got {list(self.normal)}", "normal")
        return self


MeshScale = Annotated[float, Range(0.0, 1e3, open_lower=True)]
FileName = Annotated[str, Text(4096)]


class MeshMapping(_Placed):
    """``{type: mesh, file: shelf.stl, scale: s, orientation: [w, x, y, z], position | trajectory}``:
    the file's triangles (relative to the scenario file), scaled by ``s`` about the file's
    origin, which ``position`` places."""

    type: Literal["mesh"]
    file: FileName
    scale: MeshScale = 1.0
    orientation: Quaternion = IDENTITY_QUATERNION
    position: Point3 | None = None
    trajectory: TrajectoryMapping | None = None

    @model_validator(mode="after")
    def _rotation(self) -> MeshMapping:
        return _check_rotation(self)


JointValue = Annotated[float, Range(-1e3, 1e3)]


class UrdfMapping(ScenarioModel):
    """``{type: urdf, file: kitchen.urdf, position, orientation, package_dirs: [...], joints: {name: value}}``:
    every link's collision geometry at the pose of the scene's joints (``joints``: values of
    its movable joints [rad or m], within their limits; the others at zero), the scene's
    root placed at ``position`` (static)."""

    type: Literal["urdf"]
    file: FileName
    position: Point3 = (0.0, 0.0, 0.0)
    orientation: Quaternion = IDENTITY_QUATERNION
    package_dirs: Annotated[tuple[FileName, ...], Items(what="folders", allow_empty=True)] = ()
    joints: dict[Annotated[str, Text(256)], JointValue] = {}

    @model_validator(mode="after")
    def _rotation(self) -> UrdfMapping:
        return _check_rotation(self)


Voxel = Annotated[float, Range(0.001, 1.0)]
CloudCap = Annotated[int, Whole(1, 10_000_000)]


class PointsMapping(ScenarioModel):
    """``{type: points, file: cloud.npy, voxel: h, max_points: M}``: measured surface points
    (.npy N×3, .ply or .pcd; metres, world frame; relative to the scenario file), static,
    downsampled to one point per voxel of edge ``h`` [m], at most ``M`` kept
    (:mod:`dynfab.geometry.point_cloud`)."""

    type: Literal["points"]
    file: FileName
    voxel: Voxel = 0.01
    max_points: CloudCap = 1_000_000


def _check_rotation(shape: BoxMapping | CylinderMapping | MeshMapping | UrdfMapping) -> Any:
    """Refuse a zero quaternion (any other is normalised)."""
    try:
        unit_quaternion(shape.orientation)
    except ShapeError:
        raise fail(f"expected a non-zero quaternion [w, x, y, z], got {list(shape.orientation)}",
                   "orientation") from None
    return shape


ObstacleMapping = tagged_union({"sphere": SphereMapping, "box": BoxMapping, "cylinder": CylinderMapping,
                                "capsule": CapsuleMapping, "plane": PlaneMapping, "mesh": MeshMapping,
                                "urdf": UrdfMapping, "points": PointsMapping}, "type")


def obstacle_spec(obstacle: ScenarioModel) -> ObstacleSpec:
    """The obstacle value of a validated ``obstacles:`` entry of a primitive shape (meshes and
    URDF scenes read files: :mod:`dynfab.scenario.scene_files`)."""
    assert isinstance(obstacle, _Placed) and not isinstance(obstacle, MeshMapping)
    values = obstacle.model_dump(exclude={"trajectory"})
    normal = None
    orientation = unit_quaternion(values.get("orientation", IDENTITY_QUATERNION))
    if isinstance(obstacle, PlaneMapping):
        length = math.hypot(*obstacle.normal)
        x, y, z = (number / length for number in obstacle.normal)
        normal = (x, y, z)
        orientation = quaternion_from_normal(normal)
    trajectory = obstacle.trajectory
    return ObstacleSpec(
        type=values["type"],
        radius=values.get("radius", 0.0),
        position=values.get("point", values.get("position")),
        trajectory=None if trajectory is None else frozen_trajectory(trajectory),
        size=values.get("size"),
        length=values.get("length"),
        orientation=orientation,
        normal=normal,
    )
