"""Obstacles read from files: ``{type: mesh}`` (a mesh file), ``{type: urdf}`` (a scene
described as a URDF, as MotionBenchMaker ships its scenes) and ``{type: points}`` (a point
cloud: .npy, .ply or .pcd, :mod:`dynfab.geometry.cloud_files`).

A point cloud is downsampled as it is read (:mod:`dynfab.geometry.point_cloud`); its NaN or
infinite rows are dropped and counted on stderr; an empty cloud (no finite point) is no
obstacle (the entry gives none, said on stderr). It is the scene as measured: nothing is
filtered out of it (the robot filter is for clouds taken with the robot in view,
:mod:`dynfab.perception.point_clouds`).

A URDF scene becomes one obstacle per ``<collision>`` element of its links (root first, then down the tree),
each at its pose with the scene's movable joints at the entry's ``joints`` values (the others
at zero: doors closed, drawers in), the scene's root placed by the entry's ``position`` and
``orientation``: boxes, cylinders and spheres stay
primitives (exact distances), meshes become mesh obstacles. A scene is static.

Bad input is refused with a :class:`~dynfab.scenario.fields.ScenarioError` naming the entry's
``file``: a missing file, one that is not a mesh or a URDF, a mesh without triangles or with
too many (:mod:`dynfab.geometry.mesh_files`), a URDF scene whose link names a mesh that is not
found, a ``joints`` name that is no movable joint of the scene or a value outside its limits.
A mesh need not be closed: an open surface is kept away from on both sides (see
:mod:`dynfab.geometry.mesh_shape`).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from dynfab.geometry.cloud_files import CloudFileError, read_points
from dynfab.geometry.mesh_files import MeshFileError, read_mesh
from dynfab.geometry.point_cloud import PointCloud
from dynfab.geometry.shapes import Box, Cylinder, Sphere, quaternion_matrix
from dynfab.robots.mesh_paths import resolve_uri
from dynfab.robots.urdf import load_urdf
from dynfab.robots.urdf_model import CollisionGeometry, Joint, Origin, UrdfError, UrdfModel
from dynfab.scenario.fields import ScenarioError
from dynfab.scenario.model_types import ScenarioModel
from dynfab.scenario.obstacle_schema import MeshMapping, ObstacleSpec, PointsMapping, UrdfMapping, obstacle_spec
from dynfab.scenario.trajectory_schema import frozen_trajectory

__all__ = ["link_poses", "obstacle_specs"]


def obstacle_specs(obstacle: ScenarioModel, base_dir: Path, field: str) -> tuple[ObstacleSpec, ...]:
    """The obstacles of one validated ``obstacles:`` entry (``field``, e.g. ``obstacles[2]``):
    one, or a URDF scene's several."""
    if isinstance(obstacle, MeshMapping):
        return (_mesh_spec(obstacle, base_dir, field),)
    if isinstance(obstacle, UrdfMapping):
        return _scene_specs(obstacle, base_dir, field)
    if isinstance(obstacle, PointsMapping):
        return _points_specs(obstacle, base_dir, field)
    return (obstacle_spec(obstacle),)


def _mesh_spec(entry: MeshMapping, base_dir: Path, field: str) -> ObstacleSpec:
    path = resolve_uri(entry.file, base_dir)
    if path is None:
        raise ScenarioError(f"{field}.file", f"file not found: {entry.file} (a path relative to the scenario file, "
                            "absolute, or package://NAME/...)")
    try:
        mesh = read_mesh(path, (entry.scale,) * 3)
    except MeshFileError as error:
        raise ScenarioError(f"{field}.file", str(error)) from None
    trajectory = None if entry.trajectory is None else frozen_trajectory(entry.trajectory)
    return ObstacleSpec(type="mesh", position=entry.position, trajectory=trajectory,
                        orientation=_unit(entry.orientation), mesh=mesh)


def _points_specs(entry: PointsMapping, base_dir: Path, field: str) -> tuple[ObstacleSpec, ...]:
    path = resolve_uri(entry.file, base_dir)
    if path is None:
        raise ScenarioError(f"{field}.file", f"file not found: {entry.file} (a path relative to the scenario file, "
                            "absolute, or package://NAME/...)")
    try:
        cloud = PointCloud.from_points(read_points(path), entry.voxel, entry.max_points, source=path.name)
    except (CloudFileError, ValueError) as error:
        raise ScenarioError(f"{field}.file", str(error)) from None
    if cloud.dropped:
        print(f"dynfab: {field}.file: {path.name}: {cloud.dropped} NaN or infinite points dropped", file=sys.stderr)
    if cloud.empty:
        print(f"dynfab: {field}.file: {path.name} has no finite point: no obstacle", file=sys.stderr)
        return ()
    return (ObstacleSpec(type="points", position=(0.0, 0.0, 0.0), cloud=cloud),)


def _scene_specs(entry: UrdfMapping, base_dir: Path, field: str) -> tuple[ObstacleSpec, ...]:
    package_dirs = [base_dir / folder for folder in entry.package_dirs]
    path = resolve_uri(entry.file, base_dir, package_dirs)
    if path is None:
        raise ScenarioError(f"{field}.file", f"file not found: {entry.file} (a path relative to the scenario file, "
                            "absolute, or package://NAME/... found through package_dirs)")
    try:
        model = load_urdf(path, package_dirs)
    except (OSError, UrdfError) as error:
        raise ScenarioError(f"{field}.file", str(error).splitlines()[0]) from None
    scene = _matrix(entry.position, quaternion_matrix(_unit(entry.orientation)))
    specs = []
    for link, pose in link_poses(model, _joint_values(model, entry.joints, field)).items():
        for geometry in next(entry for entry in model.links if entry.name == link).collisions:
            specs.append(_geometry_spec(geometry, scene @ pose @ _origin(geometry.origin), link, field))
    if not specs:
        raise ScenarioError(f"{field}.file", f"{path.name} has no <collision> geometry: the scene would be empty")
    return tuple(specs)


def _geometry_spec(geometry: CollisionGeometry, pose: NDArray[np.float64], link: str, field: str) -> ObstacleSpec:
    """One collision geometry placed at ``pose`` (4x4) as an obstacle."""
    position = tuple(float(v) for v in pose[:3, 3])
    w_last = Rotation.from_matrix(pose[:3, :3]).as_quat()
    orientation = (float(w_last[3]), float(w_last[0]), float(w_last[1]), float(w_last[2]))
    shape = geometry.shape
    if isinstance(shape, Box):
        return ObstacleSpec(type="box", position=position, size=shape.size, orientation=orientation)
    if isinstance(shape, Cylinder):
        return ObstacleSpec(type="cylinder", position=position, radius=shape.radius, length=shape.length,
                            orientation=orientation)
    if isinstance(shape, Sphere):
        return ObstacleSpec(type="sphere", position=position, radius=shape.radius)
    if shape.path is None:
        raise ScenarioError(f"{field}.file", f"link '{link}': collision mesh '{shape.uri}' not found (give the folder "
                            "that holds its package in package_dirs or DYNFAB_PACKAGE_PATH)")
    try:
        mesh = read_mesh(shape.path, shape.scale)
    except MeshFileError as error:
        raise ScenarioError(f"{field}.file", f"link '{link}': {error}") from None
    return ObstacleSpec(type="mesh", position=position, orientation=orientation, mesh=mesh)


def _joint_values(model: UrdfModel, values: dict[str, float], field: str) -> dict[str, float]:
    """``values`` checked against the scene's movable joints and their limits.

    Raises:
        ScenarioError: A name that is no movable joint of the scene, or a value outside its limits.
    """
    movable = {joint.name: joint for joint in model.joints if joint.is_actuated}
    for name, value in values.items():
        joint = movable.get(name)
        if joint is None:
            raise ScenarioError(f"{field}.joints.{name}", f"no movable joint of the scene is named {name!r} "
                                f"(movable: {', '.join(movable) or 'none'})")
        limit = joint.limit
        if joint.type != "continuous" and limit is not None and not limit.lower <= value <= limit.upper:
            raise ScenarioError(f"{field}.joints.{name}", f"{value:g} is outside the joint's limits "
                                f"[{limit.lower:g}, {limit.upper:g}]")
    return values


def link_poses(model: UrdfModel, values: dict[str, float]) -> dict[str, NDArray[np.float64]]:
    """Every link's pose in the scene's root frame, root first: ``T_child = T_parent T_origin M(q)``
    with ``M`` the rotation by ``q`` [rad] about a revolute or continuous joint's axis, or the
    translation by ``q`` [m] along a prismatic joint's; ``q`` from ``values`` (zero if absent)."""
    poses = {model.root_link: np.eye(4)}
    pending = [model.root_link]
    while pending:
        parent = pending.pop(0)
        for joint in model.child_joints(parent):
            poses[joint.child] = poses[parent] @ _origin(joint.origin) @ _motion(joint, values.get(joint.name, 0.0))
            pending.append(joint.child)
    return poses


def _motion(joint: Joint, value: float) -> NDArray[np.float64]:
    """``M(q)`` of ``joint`` at ``value`` (see :func:`link_poses`); the identity for fixed joints."""
    axis = np.asarray(joint.axis, dtype=float)
    if joint.type in ("revolute", "continuous"):
        return _matrix((0.0, 0.0, 0.0), Rotation.from_rotvec(value * axis).as_matrix())
    if joint.type == "prismatic":
        return _matrix(tuple(value * axis), np.eye(3))
    return np.eye(4)


def _origin(origin: Origin) -> NDArray[np.float64]:
    return _matrix(origin.xyz, np.array(origin.rotation))


def _matrix(position: tuple[float, ...], rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = position
    return matrix


def _unit(quaternion: tuple[float, ...]) -> tuple[float, float, float, float]:
    w, x, y, z = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    return (float(w), float(x), float(y), float(z))
