"""A MuJoCo model (MJCF) of a robot and its obstacles.

The robot's kinematic tree becomes nested bodies, one per URDF link, each placed by its
parent joint's origin; active joints become hinges or slides (limits as ranges
:data:`LIMIT_MARGIN` beyond the URDF's, :data:`ARMATURE` on hinges), locked joints are folded into their body's pose, a mimic
joint of an active leader is a joint tied to it by an equality ``q = m q_leader + c``
(of a locked leader: folded at its value). Each body carries its URDF ``<inertial>``.
A moving body whose mass, with everything below it, is zero makes the model
invalid: :class:`MujocoModelError` names the link (no default mass is invented); a
massless moving link that carries massive ones (a virtual link between two joints) gets
0.1 g and 1e-8 kg m^2.

Collision geometry: a URDF robot's collision meshes (convex hulls, STL files from
:mod:`dynfab.sim.mujoco_meshes`), or the meshes given to :func:`build_scene` for a robot
whose description has none (the built-in ``panda`` and ``boxer-panda`` on Franka's meshes,
:mod:`dynfab.robots.builtin_meshes`, as :mod:`dynfab.scenario.mujoco_runner` builds them);
a robot without meshes (the other built-ins, or the Panda without example-robot-data) its
collision spheres. Obstacles are static bodies or, when they move, mocap bodies whose pose the
simulation sets every physics step (:mod:`dynfab.sim.mjcf_obstacles`: a mesh collides by
convex parts and is seen by cameras whole, a point cloud is not in the physics). Contacts
(bit masks, MuJoCo's ``contype`` / ``conaffinity``): robot geoms touch obstacles; robot
geoms touch each other only in the robot's self-collision pairs (explicit ``<pair>``\\ s);
obstacles never touch each other.

Cameras (``cameras``): fixed ``<camera>``\\ s in the world (:mod:`dynfab.sim.mjcf_cameras`).

A differential-drive base (``robot.base``): the body below ``base_yaw`` floats (a free
joint) on a floor plane at z = 0, carried by two drive wheels (hinges with velocity
actuators, radius and track from :class:`~dynfab.robots.robot.DifferentialDriveBase`,
friction 1; their contact shape is a sphere of the wheel's radius, which rolls on one
point: MuJoCo's cylinder-plane contacts made the base hop) and frictionless casters (the URDF links named ``caster*``, spheres down to
the floor). The floor touches only wheels and casters.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence

import mujoco
import numpy as np
import trimesh

from dynfab.perception.camera_spec import CameraSpec
from dynfab.robots.robot import BASE_JOINTS, Robot
from dynfab.robots.urdf import Joint, UrdfModel
from dynfab.sim.mjcf_cameras import add_camera, camera_name
from dynfab.sim.mjcf_obstacles import add_obstacle
from dynfab.sim.mjcf_values import joint_motion, mjcf_numbers, origin_matrix, pose_attributes
from dynfab.sim.mujoco_meshes import link_mesh_file, mesh_file
from dynfab.sim.mujoco_scene import MujocoModelError, MujocoScene, SceneObstacle
from dynfab.sim.mujoco_warnings import route_warnings_to_stderr

__all__ = ["ARMATURE", "PHYSICS_TIMESTEP", "MujocoModelError", "MujocoScene", "SceneObstacle", "build_scene",
           "camera_name"]

#: Physics step [s] (1 kHz).
PHYSICS_TIMESTEP = 0.001
#: Reflected rotor inertia added to every hinge [kg m^2] (order of a Franka / UR drive).
ARMATURE = 0.1
#: How far MuJoCo's hard joint stops lie beyond the URDF's position limits [rad or m]:
#: the planner and the set-points keep within the URDF's limits, the stops catch what
#: overshoots (MuJoCo's soft stop at the limit itself let joints sink 0.2 mrad into it,
#: where the planner's limit handling chattered).
LIMIT_MARGIN = 0.01
#: Mass [kg] and principal inertia [kg m^2] of a massless URDF link that a joint moves and
#: that carries massive links (x then y of a planar robot); MuJoCo needs some.
_VIRTUAL_MASS, _VIRTUAL_INERTIA = 1e-4, 1e-8
#: Contact bits: robot geoms, obstacles, the floor with wheels and casters.
_ROBOT, _OBSTACLE, _GROUND = 1, 1, 2
#: Velocity gain of a wheel drive [N m s/rad] and its torque limit [N m].
WHEEL_GAIN, WHEEL_TORQUE = 40.0, 40.0
#: Mass of a drive wheel the URDF does not describe (no ``wheel_left_link``) [kg].
_DEFAULT_WHEEL_MASS = 1.0
_ROBOT_RGBA = "0.95 0.55 0.1 1"

route_warnings_to_stderr()


def build_scene(robot: Robot, obstacles: Sequence[SceneObstacle] = (),
                self_collision_links: Sequence[tuple[str, str]] = (),
                link_meshes: Mapping[str, Sequence[trimesh.Trimesh]] | None = None,
                cameras: Sequence[CameraSpec] = ()) -> MujocoScene:
    """Compile ``robot`` among ``obstacles`` into a MuJoCo model (module doc).

    Args:
        robot: The robot (its URDF model, active joints and collision spheres).
        obstacles: The obstacles, in scenario order.
        self_collision_links: Link pairs whose meshes may touch (robots with meshes);
            a robot without meshes uses its ``self_collision_pairs`` of spheres.
        link_meshes: Collision meshes by link, each in its link's frame [m], instead of
            the URDF's (a built-in robot: :func:`dynfab.robots.builtin_meshes.builtin_collision_meshes`);
            None: the URDF's, or the collision spheres if it has none.
        cameras: Depth cameras, fixed in the world: ``<camera>`` ``k`` is named
            :func:`camera_name` ``(k)``, placed and aimed as the spec says, with its vertical
            field of view; the offscreen buffer is made large enough for its image.

    Raises:
        MujocoModelError: A moving link without mass; a collision mesh that is missing.
        TooManyPartsError: A mesh obstacle of more than :data:`~dynfab.sim.mesh_parts.MAX_PARTS`
            convex parts (:func:`~dynfab.sim.mesh_parts.convex_parts`).
    """
    xml = _Builder(robot, link_meshes).xml(obstacles, self_collision_links, cameras)
    try:
        model = mujoco.MjModel.from_xml_string(xml)
    except ValueError as error:
        raise MujocoModelError(f"MuJoCo refused the model: {str(error).splitlines()[0]}") from None
    return _scene(model, robot, obstacles)


def _scene(model: mujoco.MjModel, robot: Robot, obstacles: Sequence[SceneObstacle]) -> MujocoScene:
    """Look up the addresses of the compiled model."""
    kin = robot.kinematics
    names = kin.joint_names[3:] if robot.base is not None else kin.joint_names
    joints = [model.joint(name) for name in names]
    limits = robot.limits.effort
    effort = np.full(len(names), math.inf) if limits is None else limits[len(limits) - len(names):]
    base = model.joint("base_free") if robot.base is not None else None
    wheels = None
    if robot.base is not None:
        wheels = (model.actuator("wheel_left_drive").id, model.actuator("wheel_right_drive").id)
    mocap = tuple(int(model.body(f"obstacle{k}").mocapid[0]) if o.moving else None
                  for k, o in enumerate(obstacles))
    robot_bodies = frozenset(b for b in range(1, model.nbody) if not model.body(b).name.startswith("obstacle"))
    obstacle_of_body = {model.body(f"obstacle{k}").id: k for k in range(len(obstacles))}
    geoms = {geom: obstacle_of_body[int(body)] for geom, body in enumerate(model.geom_bodyid)
             if int(body) in obstacle_of_body}
    return MujocoScene(model=model, joint_qpos=np.array([int(j.qposadr[0]) for j in joints], dtype=int),
                       joint_dof=np.array([int(j.dofadr[0]) for j in joints], dtype=int),
                       joint_actuators=np.array([model.actuator(f"{n}_motor").id for n in names], dtype=int),
                       effort=np.array(effort, dtype=float), lower=kin.lower[kin.dof - len(names):],
                       upper=kin.upper[kin.dof - len(names):],
                       base_qpos=None if base is None else int(base.qposadr[0]),
                       base_dof=None if base is None else int(base.dofadr[0]),
                       wheel_actuators=wheels, base=robot.base,
                       base_speed_limit=None if base is None else np.array(robot.limits.velocity[:2], dtype=float),
                       mocap=mocap, robot_bodies=robot_bodies, obstacle_of_geom=geoms,
                       obstacle_names=tuple(o.name or f"obstacles[{k}]" for k, o in enumerate(obstacles)))


def _mesh_geom(link: str, k: int) -> str:
    """The name of ``link``'s ``k``-th collision mesh geom: ``<link>_collision``, then
    ``<link>_collision1``, ..."""
    return f"{link}_collision" if k == 0 else f"{link}_collision{k}"


class _Builder:
    """Writes the MJCF document of one robot."""

    def __init__(self, robot: Robot, link_meshes: Mapping[str, Sequence[trimesh.Trimesh]] | None = None) -> None:
        self.robot = robot
        self.link_meshes = link_meshes
        self.kin = robot.kinematics
        self.model: UrdfModel = robot.kinematics.model
        self.links = {link.name: link for link in self.model.links}
        self.meshes = link_meshes is not None or any(link.collisions for link in self.model.links)
        self.mesh_geoms: dict[str, list[str]] = {}  # link -> its mesh geoms' names
        self.root = ET.Element("mujoco", model=robot.name)
        ET.SubElement(self.root, "compiler", angle="radian", inertiafromgeom="false", autolimits="true")
        ET.SubElement(self.root, "option", timestep=str(PHYSICS_TIMESTEP), integrator="implicitfast",
                      cone="elliptic", impratio="10", noslip_iterations="5")
        visual = ET.SubElement(self.root, "visual")
        self.buffer = ET.SubElement(visual, "global", offwidth="1280", offheight="720")
        self.asset = ET.SubElement(self.root, "asset")
        self.world = ET.SubElement(self.root, "worldbody")
        ET.SubElement(self.world, "light", pos="0 0 4", dir="0 0 -1", directional="true")
        self.actuator = ET.SubElement(self.root, "actuator")
        self.contact = ET.SubElement(self.root, "contact")
        self.equality = ET.SubElement(self.root, "equality")

    def xml(self, obstacles: Sequence[SceneObstacle], self_collision_links: Sequence[tuple[str, str]],
            cameras: Sequence[CameraSpec] = ()) -> str:
        if self.robot.base is None and self.kin.root_link == "world":  # MuJoCo's name for the world body
            self._geoms(self.world, "world")
            for joint in self.model.child_joints("world"):
                self._child(self.world, joint)
        elif self.robot.base is None:
            self._subtree(self.world, self.kin.root_link, {})
        else:
            self._base()
        for k, obstacle in enumerate(obstacles):
            add_obstacle(self.world, self.asset, k, obstacle, self.robot.planar, _OBSTACLE)
        self._self_pairs(self_collision_links)
        for k, camera in enumerate(cameras):
            add_camera(self.world, self.buffer, k, camera)
        return ET.tostring(self.root, encoding="unicode")

    # ---------------------------------------------------------------- robot tree
    def _subtree(self, parent: ET.Element, link: str, attributes: dict[str, str]) -> None:
        """Body of ``link`` under ``parent``, with its children."""
        body = ET.SubElement(parent, "body", name=link, **attributes)
        self._inertial(body, link)
        self._geoms(body, link)
        for joint in self.model.child_joints(link):
            if self.robot.base is not None and joint.child in ("wheel_left_link", "wheel_right_link"):
                continue
            self._child(body, joint)

    def _child(self, body: ET.Element, joint: Joint) -> None:
        """The body of ``joint``'s child, its pose and its joint."""
        value = self._folded_value(joint)
        transform = origin_matrix(joint)
        if value is not None:
            transform = transform @ joint_motion(joint, value)
        child_attributes = pose_attributes(transform)
        self._subtree(body, joint.child, child_attributes)
        child = body.find(f"body[@name='{joint.child}']")
        if value is None:
            self._check_mass(joint.child)
            self._joint(child, joint)
            if child.find("inertial") is None:
                ET.SubElement(child, "inertial", pos="0 0 0", mass=repr(_VIRTUAL_MASS),
                              diaginertia=mjcf_numbers((_VIRTUAL_INERTIA,) * 3))

    def _folded_value(self, joint: Joint) -> float | None:
        """The constant value of a fixed, locked or led-by-a-locked joint; None if it moves."""
        if joint.type == "fixed":
            return 0.0
        if joint.name in self.kin.locked:
            return self.kin.locked[joint.name]
        if joint.mimic is not None and joint.mimic.joint in self.kin.locked:
            return joint.mimic.multiplier * self.kin.locked[joint.mimic.joint] + joint.mimic.offset
        return None

    def _joint(self, body: ET.Element, joint: Joint) -> None:
        kind = "slide" if joint.type == "prismatic" else "hinge"
        attributes = {"name": joint.name, "type": kind, "axis": mjcf_numbers(joint.axis)}
        if joint.limit is not None and math.isfinite(joint.limit.lower) and joint.type != "continuous":
            attributes["range"] = mjcf_numbers((joint.limit.lower - LIMIT_MARGIN, joint.limit.upper + LIMIT_MARGIN))
        if kind == "hinge":
            attributes["armature"] = str(ARMATURE)
        element = ET.Element("joint", **attributes)
        body.insert(0, element)
        if joint.mimic is not None:
            mimic = joint.mimic
            ET.SubElement(self.equality, "joint", joint1=joint.name, joint2=mimic.joint,
                          polycoef=mjcf_numbers((mimic.offset, mimic.multiplier, 0.0, 0.0, 0.0)))
            return
        ET.SubElement(self.actuator, "motor", name=f"{joint.name}_motor", joint=joint.name, gear="1")

    def _check_mass(self, link: str) -> None:
        """Raise unless the body of a moving joint, with what it carries, has mass."""
        if _subtree_mass(self.model, link) <= 0.0:
            raise MujocoModelError(f"link '{link}' moves but has no <inertial> mass (nor does any link below it); "
                                   "MuJoCo needs one: add an <inertial> to the URDF")

    def _inertial(self, body: ET.Element, link: str) -> None:
        inertial = self.links[link].inertial
        if inertial is None or inertial.mass <= 0.0:
            return
        tensor = inertial.link_frame_inertia()
        full = (tensor[0, 0], tensor[1, 1], tensor[2, 2], tensor[0, 1], tensor[0, 2], tensor[1, 2])
        ET.SubElement(body, "inertial", pos=mjcf_numbers(inertial.origin.xyz), mass=repr(inertial.mass),
                      fullinertia=mjcf_numbers(full))

    def _geoms(self, body: ET.Element, link: str) -> None:
        contact = {"contype": str(_ROBOT), "conaffinity": "0", "rgba": _ROBOT_RGBA}
        if self.meshes:
            if self.link_meshes is None:  # a URDF's meshes: one geom, the hull of their union
                path = link_mesh_file(self.model, link)
                paths = [] if path is None else [path]
            else:  # given meshes: one geom each (MuJoCo collides each one's hull, as the metrics do)
                paths = [mesh_file([mesh]) for mesh in self.link_meshes.get(link, ())]
            for k, path in enumerate(paths):
                name = _mesh_geom(link, k)
                ET.SubElement(self.asset, "mesh", name=f"{name}_mesh", file=str(path))
                ET.SubElement(body, "geom", name=name, type="mesh", mesh=f"{name}_mesh", **contact)
            self.mesh_geoms[link] = [_mesh_geom(link, k) for k in range(len(paths))]
            return
        for i, sphere in enumerate(self.robot.collision_spheres):
            if sphere.link == link:
                ET.SubElement(body, "geom", name=f"sphere{i}", type="sphere", size=repr(sphere.radius),
                              pos=mjcf_numbers(sphere.center), **contact)

    def _self_pairs(self, self_collision_links: Sequence[tuple[str, str]]) -> None:
        if self.meshes:
            pairs = [(a, b) for first, second in self_collision_links
                     for a in self.mesh_geoms.get(first, ()) for b in self.mesh_geoms.get(second, ())]
        else:
            pairs = [(f"sphere{a}", f"sphere{b}") for a, b in self.robot.self_collision_pairs]
        for a, b in pairs:
            ET.SubElement(self.contact, "pair", geom1=a, geom2=b)

    # ---------------------------------------------------------------- base
    def _base(self) -> None:
        """Floor, free-floating body below ``base_yaw``, drive wheels and casters."""
        base = self.robot.base
        joints = {joint.name: joint for joint in self.model.joints}
        ET.SubElement(self.world, "geom", name="floor", type="plane", size="0 0 0.05", rgba="0.85 0.85 0.8 1",
                      contype=str(_GROUND), conaffinity=str(_GROUND))
        yaw_child = joints[BASE_JOINTS[2]].child
        self._subtree(self.world, yaw_child, {"pos": "0 0 0.001"})
        body = self.world.find(f"body[@name='{yaw_child}']")
        body.insert(0, ET.Element("freejoint", name="base_free"))
        for side, sign in (("left", 1.0), ("right", -1.0)):
            link = f"wheel_{side}_link"
            wheel = ET.SubElement(body, "body", name=link, pos=mjcf_numbers((0.0, sign * base.wheel_separation / 2,
                                                                          base.wheel_radius)))
            inertial = self.links[link].inertial if link in self.links else None
            mass = inertial.mass if inertial is not None and inertial.mass > 0 else _DEFAULT_WHEEL_MASS
            axial, radial = 0.5 * mass * base.wheel_radius ** 2, 0.25 * mass * base.wheel_radius ** 2
            ET.SubElement(wheel, "inertial", pos="0 0 0", mass=repr(mass), diaginertia=mjcf_numbers((radial, axial, radial)))
            ET.SubElement(wheel, "joint", name=f"wheel_{side}", type="hinge", axis="0 1 0")
            ET.SubElement(wheel, "geom", name=f"wheel_{side}", type="sphere", size=repr(base.wheel_radius),
                          friction="1 0.005 0.0001",
                          contype=str(_GROUND), conaffinity=str(_GROUND), rgba="0.1 0.1 0.1 1")
            ET.SubElement(self.actuator, "velocity", name=f"wheel_{side}_drive", joint=f"wheel_{side}",
                          kv=str(WHEEL_GAIN), forcerange=f"{-WHEEL_TORQUE} {WHEEL_TORQUE}")
        q = np.zeros(self.kin.dof)
        for element in body.iter("body"):
            name = element.get("name", "")
            if name.startswith("caster") and name in self.links:
                height = float(np.asarray(self.kin.position(q, name)).reshape(-1)[2])
                ET.SubElement(element, "geom", name=f"{name}_wheel", type="sphere", size=repr(height),
                              friction="0 0 0", condim="1", priority="1", contype=str(_GROUND),
                              conaffinity=str(_GROUND),
                              rgba="0.1 0.1 0.1 1")


def _subtree_mass(model: UrdfModel, link: str) -> float:
    """Mass of ``link`` and of every link below it [kg]."""
    links = {entry.name: entry for entry in model.links}
    inertial = links[link].inertial
    mass = 0.0 if inertial is None else inertial.mass
    return mass + sum(_subtree_mass(model, j.child) for j in model.child_joints(link))
