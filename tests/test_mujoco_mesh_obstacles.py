"""Mesh and URDF-scene obstacles in MuJoCo's physics: their convex parts cover the surface and
overstate it by at most half a shell, the camera sees the true surface, MBM's kitchen loads,
its collision-free start touches nothing and MuJoCo's contacts agree with coal's clearance,
a guided Panda reaches into a mesh shelf without a contact, and what MuJoCo cannot take is
refused at load naming ``obstacles[k]``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.scene_configs import data_root
from dynfab.benchmarks.mbm.scenes import generate_scene_problem, prepare_scene_case
from dynfab.benchmarks.mbm.validity import static_shapes
from dynfab.geometry.mesh_distance import nearest_on_mesh
from dynfab.geometry.mesh_files import read_mesh
from dynfab.geometry.shapes import Mesh
from dynfab.perception.camera_spec import CameraSpec
from dynfab.perception.depth_camera import DepthCamera
from dynfab.robots import load_robot
from dynfab.robots.builtin_meshes import builtin_collision_meshes
from dynfab.robots.mesh_sweep import sweep_meshes
from dynfab.scenario.exact_metrics import mesh_model_for
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import ScenarioError, scenario_from_dict
from dynfab.sim.depth_render import MujocoDepthRenderer
from dynfab.sim.mesh_parts import SHELL, TooManyPartsError, convex_parts
from dynfab.sim.mjcf_obstacles import COLLISION_GROUP
from dynfab.sim.mujoco_model import SceneObstacle, build_scene

START = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785]
IDENTITY = (1.0, 0.0, 0.0, 0.0)
SCENES = data_root() / "motion_bench_maker" / "configs" / "scenes"


def _shelf() -> trimesh.Trimesh:
    """Two boards and a back: three closed boxes, an open shelf as a whole."""
    boards = [trimesh.creation.box(extents=(0.4, 0.8, 0.02)).apply_translation((0, 0, z)) for z in (0.0, 0.35)]
    back = trimesh.creation.box(extents=(0.02, 0.8, 0.37)).apply_translation((0.2, 0, 0.175))
    return trimesh.util.concatenate([*boards, back])


def _cup() -> Mesh:
    """A box without its top: an open surface, not convex, 0.3 x 0.3 x 0.2 m about its centre."""
    cup = trimesh.creation.box(extents=(0.3, 0.3, 0.2))
    top = np.isclose(cup.triangles_center[:, 2], 0.1)
    return Mesh(cup.vertices, cup.faces[~top], source="cup")


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("mujoco_meshes")
    _shelf().export(folder / "shelf.stl")
    np.save(folder / "wall.npy", np.random.default_rng(0).uniform((0.8, -0.5, 0.0), (0.81, 0.5, 1.0), (2000, 3)))
    return folder


def _scenario(obstacles: list[dict], **extra: object) -> dict:
    return {"robot": "panda", "planner": "static-fabric", "dt": 0.01, "duration": 5.0, "simulator": "mujoco",
            "initial_state": {"q": START},
            "goal": [{"type": "position", "link": "panda_hand", "position": [0.62, 0.0, 0.42], "tolerance": 0.05}],
            "obstacles": obstacles, **extra}


def _inside_hull(points: np.ndarray, vertices: np.ndarray, tolerance: float) -> np.ndarray:
    """Whether each point lies in the convex hull of ``vertices`` (to ``tolerance`` [m])."""
    hull = ConvexHull(vertices)
    return (points @ hull.equations[:, :3].T + hull.equations[:, 3] <= tolerance).all(axis=1)


def _check_cover(mesh: Mesh) -> None:
    """Every surface point of ``mesh`` is in a part, and no part reaches beyond SHELL / 2."""
    parts = convex_parts(mesh)
    samples, _ = trimesh.sample.sample_surface(mesh.triangles, 3000, seed=1)
    covered = np.zeros(len(samples), dtype=bool)
    for part in parts:
        covered |= _inside_hull(samples, part, 1e-9)
    assert covered.all()
    vertices = np.concatenate(parts)
    assert nearest_on_mesh(mesh, vertices).distances.max() <= SHELL / 2 + 1e-9


def test_closed_convex_components_are_one_hull_each_the_rest_a_prism_per_triangle() -> None:
    shelf = Mesh(_shelf().vertices, _shelf().faces)
    assert [len(part) for part in convex_parts(shelf)] == [8, 8, 8]  # three boxes, their corners
    cup = _cup()
    parts = convex_parts(cup)
    assert len(parts) == len(cup.faces) and all(part.shape == (6, 3) for part in parts)
    _check_cover(shelf)
    _check_cover(cup)


@pytest.mark.parametrize("name", ["kitchen/meshes/cupboard.stl", "kitchen/meshes/kitchen_counter.stl",
                                  "kitchen/meshes/cupboard_door_l.stl", "table_bars/meshes/left_bars.stl"])
def test_mbm_meshes_are_covered_by_their_parts(name: str) -> None:
    _check_cover(read_mesh(SCENES / name))


def test_a_mesh_is_convex_parts_that_touch_and_a_whole_visual_mesh_that_does_not() -> None:
    shelf = Mesh(_shelf().vertices, _shelf().faces)
    scene = build_scene(load_robot("panda"), [SceneObstacle(shelf, (0.75, 0.0, 0.25), IDENTITY, False),
                                              SceneObstacle(shelf, (0.0, 0.9, 0.25), IDENTITY, True)])
    model = scene.model
    for k in (0, 1):
        geoms = [g for g, owner in scene.obstacle_of_geom.items() if owner == k]
        parts = [g for g in geoms if model.geom_group[g] == COLLISION_GROUP]
        [visual] = [g for g in geoms if g not in parts]
        assert len(parts) == 3 and all(model.geom_conaffinity[g] == 1 for g in parts)
        assert model.geom_contype[visual] == 0 and model.geom_conaffinity[visual] == 0
        assert model.mesh_facenum[model.geom_dataid[visual]] == 2 * len(shelf.faces)  # both windings
    assert scene.mocap[0] is None and scene.mocap[1] is not None


def test_a_lone_triangle_is_a_solid_the_hand_touches() -> None:
    """A single triangle (no volume at all) is a solid for MuJoCo: the hand cut by its plane
    touches it, 0.3 m below it does not."""
    robot = load_robot("panda")
    triangle = Mesh(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
    hand = np.asarray(robot.kinematics.position(robot.default_q, "panda_hand"), dtype=float).reshape(-1)
    touching = []
    for height in (hand[2], hand[2] + 0.3):  # through the hand, then above it
        at = (hand[0] - 0.2, hand[1] - 0.2, height)
        scene = build_scene(robot, [SceneObstacle(triangle, at, IDENTITY, False)])
        data = mujoco.MjData(scene.model)
        data.qpos[scene.joint_qpos] = robot.default_q
        mujoco.mj_forward(scene.model, data)
        touching.append({int(g) for pair in data.contact.geom[:data.ncon] for g in pair} & set(scene.obstacle_of_geom))
    assert touching[0] and not touching[1]


def test_the_depth_camera_sees_the_mesh_surface_not_its_hulls() -> None:
    """The cup's opening faces the camera: points inside it lie on its bottom, which a hull
    would hide; every point lies on the mesh."""
    robot = load_robot("panda")
    cup = _cup()
    spec = CameraSpec(position=(2.0, 2.0, 1.5), look_at=(2.0, 2.0, 0.0), width=160, height=120, fov=40)
    scene = build_scene(robot, [SceneObstacle(cup, (2.0, 2.0, 0.1), IDENTITY, False)], cameras=[spec])
    data = mujoco.MjData(scene.model)
    data.qpos[scene.joint_qpos] = robot.default_q
    mujoco.mj_forward(scene.model, data)
    renderer = MujocoDepthRenderer(scene.model, spec)
    try:
        depth = renderer.render(data)
    finally:
        renderer.close()
    points = DepthCamera(spec, robot).frame(0.0, depth, robot.default_q).points
    assert len(points) > 1000
    local = points - (2.0, 2.0, 0.1)
    assert nearest_on_mesh(cup, local).distances.max() < 2e-3
    assert (np.abs(local[:, 2] + 0.1) < 2e-3).sum() > 500  # the cup's floor, seen through its opening


def test_mbm_kitchen_loads_into_mujoco_and_its_free_start_touches_nothing() -> None:
    problem = generate_scene_problem("kitchen", 1, 7, franka())
    mapping = {**prepare_scene_case(problem).mapping, "simulator": "mujoco", "duration": 0.05, "guidance": False}
    scenario = scenario_from_dict(mapping)
    assert any(obstacle.type == "mesh" for obstacle in scenario.obstacles)
    result = run_scenario(scenario)
    assert result.metrics.contacts == 0 and not result.metrics.collision


def test_a_guided_panda_reaches_into_a_mesh_shelf_under_mujoco_without_a_contact(files: Path) -> None:
    path = files / "shelf_run.yaml"
    path.write_text(json.dumps(_scenario([{"type": "mesh", "file": "shelf.stl", "position": [0.75, 0.0, 0.25]}])))
    run = subprocess.run([sys.executable, "-m", "dynfab.cli", "run", str(path), "--json"], capture_output=True,
                         text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout)
    assert result["goal_reached"] and result["guided"] and not result["collision"]
    assert result["contacts"] == 0  # MuJoCo's contacts with the shelf's parts
    assert result["clearance"] > 0.0  # Franka's meshes vs the shelf's triangles (coal)


def test_a_point_cloud_stays_out_of_the_physics(files: Path) -> None:
    scenario = scenario_from_dict(_scenario([{"type": "points", "file": "wall.npy"}]), files)
    [cloud] = scenario.obstacles
    scene = build_scene(load_robot("panda"), [SceneObstacle(cloud.shape, (0.0, 0.0, 0.0), IDENTITY, False)])
    assert scene.obstacle_of_geom == {} and scene.mocap == (None,)


@pytest.mark.parametrize(("entries", "extra", "field", "problem"), [
    ([{"type": "sphere", "position": [2, 0, 0], "radius": 0.1}, {"type": "points", "file": "wall.npy"}],
     {"camera": {"position": [2, 0, 1], "look_at": [0, 0, 0]}, "perception": "camera"},
     "obstacles[1]", "a point cloud is not in MuJoCo's physics nor in the camera's images"),
    ([{"type": "mesh", "file": "shelf.stl", "position": [0.75, 0.0, 0.25]}], {}, "obstacles[0].file",
     "becomes 3 convex parts in MuJoCo"),
])
def test_what_mujoco_cannot_take_is_refused_at_load(files: Path, monkeypatch: pytest.MonkeyPatch, entries: list,
                                                    extra: dict, field: str, problem: str) -> None:
    monkeypatch.setattr("dynfab.sim.mesh_parts.MAX_PARTS", 2)
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_scenario(entries, **extra), files)
    assert error.value.field == field and problem in error.value.problem


def test_a_large_open_mesh_is_refused_by_its_part_count() -> None:
    """A 300 x 300 grid surface (180 000 triangles, open): one prism each would be too many."""
    n = 301
    x, y = np.meshgrid(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    corner = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    faces = np.concatenate([np.column_stack([corner, corner + 1, corner + n]),
                            np.column_stack([corner + 1, corner + n + 1, corner + n])])
    with pytest.raises(TooManyPartsError) as error:
        convex_parts(Mesh(vertices, faces, source="grid.stl"))
    assert error.value.parts == 180_000 and "mesh grid.stl becomes 180000 convex parts" in str(error.value)


def test_a_moving_mesh_carries_its_parts_onto_the_hand() -> None:
    """Its mocap body placed on the hand: contact; placed 0.5 m away: none."""
    robot = load_robot("panda")
    shelf = Mesh(_shelf().vertices, _shelf().faces)
    scene = build_scene(robot, [SceneObstacle(shelf, (2.0, 0.0, 0.0), IDENTITY, True)])
    data = mujoco.MjData(scene.model)
    data.qpos[scene.joint_qpos] = robot.default_q
    hand = np.asarray(robot.kinematics.position(robot.default_q, "panda_hand"), dtype=float).reshape(-1)
    touching = []
    for offset in (0.0, 0.5):
        data.mocap_pos[scene.mocap[0]] = hand + (0.0, 0.0, offset)  # the lower board's centre at the hand
        mujoco.mj_forward(scene.model, data)
        touching.append(bool({int(g) for pair in data.contact.geom[:data.ncon] for g in pair}
                             & set(scene.obstacle_of_geom)))
    assert touching == [True, False]


def test_mujoco_contacts_agree_with_the_exact_mesh_metrics_in_the_kitchen() -> None:
    """Along the straight joint-space line from a kitchen problem's start to its goal (through
    the counter): MuJoCo finds a contact where coal's mesh clearance is negative, and none
    where it is above half a shell (1 mm allowed for the two libraries' hulls)."""
    robot = load_robot("panda")
    problem = generate_scene_problem("kitchen", 1, 7, franka())
    scenario = scenario_from_dict(prepare_scene_case(problem).mapping)
    shapes = static_shapes(scenario)
    obstacles = [SceneObstacle(o.shape, tuple(o.position), o.orientation, False) for o in scenario.obstacles]
    scene = build_scene(robot, obstacles, (), builtin_collision_meshes(robot))
    data = mujoco.MjData(scene.model)
    model = mesh_model_for(robot)
    clearances, contacts = [], []
    for q in np.linspace(problem.start, problem.goal, 60):
        data.qpos[scene.joint_qpos] = q
        mujoco.mj_forward(scene.model, data)
        contacts.append(bool({int(g) for pair in data.contact.geom[:data.ncon] for g in pair}
                             & set(scene.obstacle_of_geom)))
        clearances.append(sweep_meshes(model, q[None], shapes).clearance)
    clearance, contact = np.array(clearances), np.array(contacts)
    assert (clearance < -1e-3).sum() >= 10 and (clearance > SHELL / 2 + 1e-3).sum() >= 10
    assert contact[clearance < -1e-3].all() and not contact[clearance > SHELL / 2 + 1e-3].any()
