"""What the viewer draws of a robot: triangle meshes fixed in its links.

A robot's look comes, in this order, from

1. the ``<visual>`` elements of its URDF (a scenario's ``robot: {urdf: ...}``): meshes
   (resolved like collision meshes, :mod:`dynfab.robots.mesh_paths`), boxes, cylinders and
   spheres, with the colour of their ``<material>`` when it has one;
2. for the built-in robots, whose URDFs carry no visuals, :mod:`dynfab.viz.builtin_visuals`;
3. otherwise its collision spheres.

Link frames come from the robot's own kinematics (:class:`LinkPoses`), so a mobile base's
pose ``q[:3]`` moves the whole robot and locked or mimic joints sit where the planner
sees them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import trimesh
import yourdfpy

from dynfab.robots.link_meshes import load_mesh_file
from dynfab.robots.mesh_paths import resolve_uri
from dynfab.robots.robot import Robot

#: Colour of robot meshes whose URDF gives none (RGB in 0..1): the MuJoCo model's orange.
ROBOT_COLOR = (0.95, 0.55, 0.1)


@dataclass(frozen=True, eq=False)
class LinkVisual:
    """One mesh fixed in a link.

    Attributes:
        link: the link carrying it.
        mesh: the triangles in the link frame [m].
        color: RGB in 0..1.
    """

    link: str
    mesh: trimesh.Trimesh
    color: tuple[float, float, float] = ROBOT_COLOR


@dataclass(frozen=True)
class RobotLook:
    """The meshes of a robot and where they came from.

    Attributes:
        visuals: the meshes, link by link.
        source: ``"urdf"``, ``"built-in"`` or ``"collision spheres"``.
        missing: mesh URIs that could not be found or read (left out), one line each.
    """

    visuals: tuple[LinkVisual, ...]
    source: str
    missing: tuple[str, ...] = ()


def robot_look(robot: Robot, urdf: Path | None = None, package_dirs: tuple[Path, ...] = ()) -> RobotLook:
    """The meshes of ``robot`` (module docstring); ``urdf`` is the robot's URDF file
    (``None`` for a built-in robot)."""
    from dynfab.viz.builtin_visuals import builtin_visuals

    links = set(robot.kinematics.link_names)
    if urdf is not None:
        visuals, missing = urdf_visuals(urdf, package_dirs)
        source = "urdf"
    else:
        visuals, missing = builtin_visuals(robot.name)
        source = "built-in"
    visuals = tuple(v for v in visuals if v.link in links)
    if not visuals:
        return RobotLook(sphere_visuals(robot), "collision spheres", missing)
    return RobotLook(visuals, source, missing)


def urdf_visuals(urdf: Path, package_dirs: tuple[Path, ...] = ()) -> tuple[tuple[LinkVisual, ...], tuple[str, ...]]:
    """The ``<visual>`` elements of a URDF file as meshes, and the mesh URIs left out."""
    description = yourdfpy.URDF.load(str(urdf), build_scene_graph=False, load_meshes=False,
                                     load_collision_meshes=False).robot
    named_colors = {m.name: m.color.rgba for m in description.materials if m.name and m.color is not None}
    visuals, missing = [], []
    for link in description.links:
        for visual in link.visuals or ():
            mesh = _geometry_mesh(visual.geometry, urdf.parent, package_dirs)
            if isinstance(mesh, str):
                missing.append(f"link '{link.name}': {mesh}")
                continue
            if visual.origin is not None:
                mesh.apply_transform(np.asarray(visual.origin, dtype=float))
            visuals.append(LinkVisual(link.name, mesh, _color(visual.material, named_colors)))
    return tuple(visuals), tuple(missing)


def sphere_visuals(robot: Robot) -> tuple[LinkVisual, ...]:
    """The robot's collision spheres as meshes."""
    visuals = []
    for sphere in robot.collision_spheres:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=sphere.radius)
        mesh.apply_translation(sphere.center)
        visuals.append(LinkVisual(sphere.link, mesh))
    return tuple(visuals)


def mesh_file(uri: str, base_dir: Path | None, package_dirs: tuple[Path, ...] = ()) -> trimesh.Trimesh | str:
    """A mesh file's triangles (a copy), or one line saying why there are none."""
    path = resolve_uri(uri, base_dir, package_dirs)
    if path is None:
        return f"mesh '{uri}' not found"
    try:
        return load_mesh_file(str(path)).copy()
    except Exception as error:  # trimesh raises many kinds of errors on bad files
        return f"mesh '{uri}' cannot be read ({type(error).__name__})"


def _geometry_mesh(geometry: yourdfpy.Geometry, base_dir: Path,
                   package_dirs: tuple[Path, ...]) -> trimesh.Trimesh | str:
    """A URDF geometry as a mesh in its visual frame, or why it has none."""
    if geometry.box is not None:
        return trimesh.creation.box(extents=np.asarray(geometry.box.size, dtype=float))
    if geometry.cylinder is not None:
        return trimesh.creation.cylinder(radius=geometry.cylinder.radius, height=geometry.cylinder.length)
    if geometry.sphere is not None:
        return trimesh.creation.icosphere(subdivisions=2, radius=geometry.sphere.radius)
    if geometry.mesh is None:
        return "a visual without geometry"
    mesh = mesh_file(geometry.mesh.filename, base_dir, package_dirs)
    if not isinstance(mesh, str) and geometry.mesh.scale is not None:
        mesh.apply_scale(np.broadcast_to(np.asarray(geometry.mesh.scale, dtype=float).reshape(-1)[:3], (3,)))
    return mesh


def _color(material: yourdfpy.Material | None, named: dict[str, np.ndarray]) -> tuple[float, float, float]:
    """A visual's RGB: its material's colour, or the robot-level material it names."""
    if material is None:
        return ROBOT_COLOR
    rgba = material.color.rgba if material.color is not None else named.get(material.name or "")
    if rgba is None:
        return ROBOT_COLOR
    r, g, b = (float(x) for x in np.asarray(rgba, dtype=float)[:3])
    return (r, g, b)


class LinkPoses:
    """Poses of some links in the robot's root frame as functions of ``q``.

    Attributes:
        links: the links, in the order of the rows of :meth:`__call__`.
    """

    def __init__(self, robot: Robot, links: tuple[str, ...]) -> None:
        self.links = links
        q = ca.SX.sym("q", robot.dof)
        transforms = [ca.reshape(robot.kinematics.transform(q, link), 16, 1) for link in links]
        self._function = ca.Function("link_poses", [q], [ca.vertcat(*transforms) if transforms else ca.SX(0, 1)])

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """The homogeneous transforms (k, 4, 4) of :attr:`links` at ``q``."""
        flat = np.array(self._function(np.asarray(q, dtype=float))).reshape(-1)
        return flat.reshape(len(self.links), 4, 4).transpose(0, 2, 1)  # CasADi reshapes column-major
