"""``dynfab spheres`` and ``collision_spheres: auto`` in scenario files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from dynfab.cli import main
from dynfab.robots import Kinematics, load_urdf
from robot_files import arm_urdf

THREE_LINKS = Path(__file__).parent / "data" / "three_links.urdf"
UR5_Q = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]


@pytest.fixture()
def shared_cache(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The persistent cache test_collision_model.py fills (fits are keyed by content)."""
    folder = Path(request.config.cache.mkdir("dynfab-collision-models"))
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(folder))
    return folder


def test_spheres_prints_coverage_writes_yaml_and_a_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path / "cache"))
    out, plot = tmp_path / "spheres.yaml", tmp_path / "spheres.png"
    assert main(["spheres", str(THREE_LINKS), "--out", str(out), "--plot", str(plot), "--tolerance", "0.02"]) == 0
    table = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split()[1:] for line in table[1:-2]}
    assert set(rows) == {"a", "b"}  # base and c have no collision geometry
    assert all(float(outside) <= 2.0 and int(count) >= 1 for count, outside, _ in rows.values())
    assert "meets the 2 cm target" in table[-1]
    data = yaml.safe_load(out.read_text())
    assert set(data) == {"collision_spheres", "self_collision_pairs"}
    assert sum(int(rows[link][0]) for link in rows) == len(data["collision_spheres"])
    assert data["self_collision_pairs"] == []  # a and b are neighbours
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["spheres", str(THREE_LINKS), "--tolerance", "0.02"]) == 0
    assert "(from cache)" in capsys.readouterr().out


def test_spheres_with_bad_input_exits_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["spheres", str(tmp_path / "missing.urdf")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert main(["spheres", str(THREE_LINKS), "--joints", "j1", "nope"]) == 2
    assert "nope" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["spheres", str(THREE_LINKS), "--tolerance", "-1"])


def _ur5_scenario(robot_extra: dict[str, object]) -> dict[str, object]:
    kinematics = Kinematics(load_urdf(arm_urdf("ur5")))
    start = np.array(kinematics.position(UR5_Q, "tool0")).ravel()
    return {"robot": {"urdf": str(arm_urdf("ur5")), "goal_link": "tool0", **robot_extra},
            "planner": "static-fabric", "dt": 0.01, "duration": 4.0,
            "initial_state": {"q": UR5_Q},
            "goal": [{"type": "position", "position": (start + [0.0, 0.15, -0.1]).tolist(), "tolerance": 0.03}],
            "obstacles": [{"type": "sphere", "position": (start + [0.3, -0.3, 0.3]).tolist(), "radius": 0.05}]}


def _run(tmp_path: Path, scenario: dict[str, object], capsys: pytest.CaptureFixture[str]) -> dict[str, object]:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario))
    assert main(["run", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_written_yaml_runs_as_a_scenario_like_auto(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   shared_cache: Path) -> None:
    out = tmp_path / "ur5.yaml"
    assert main(["spheres", "package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    pasted = _run(tmp_path, _ur5_scenario(yaml.safe_load(out.read_text())), capsys)
    auto = _run(tmp_path, _ur5_scenario({"collision_spheres": "auto"}), capsys)
    for metrics in (pasted, auto):
        assert metrics["goal_reached"] and not metrics["collision"], metrics
    # same spheres (the YAML rounds to 0.1 mm and pads radii by 0.1 mm)
    assert auto["clearance"] == pytest.approx(pasted["clearance"], abs=5e-4)


@pytest.mark.parametrize(("robot_extra", "message"), [
    ({"collision_spheres": "automatic"}, "robot.collision_spheres: expected auto or a list"),
    ({"collision_spheres": "auto", "self_collision_pairs": [[0, 1]]},
     "robot.self_collision_pairs: index pairs need explicit collision_spheres"),
    ({"sphere_tolerance": 0.02}, "robot.sphere_tolerance: only applies to collision_spheres: auto"),
    ({"collision_spheres": "auto", "sphere_tolerance": -1}, "robot.sphere_tolerance"),
])
def test_auto_keys_errors_name_the_field(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                         robot_extra: dict[str, object], message: str) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(_ur5_scenario(robot_extra)))
    assert main(["run", str(path), "--json"]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1


def test_auto_with_a_missing_mesh_names_the_link(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path / "cache"))
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(THREE_LINKS.read_text().replace(
        "<!--MESH-->", '<collision><geometry><mesh filename="gone.stl"/></geometry></collision>'))
    scenario = {"robot": {"urdf": str(urdf), "goal_link": "c", "collision_spheres": "auto"},
                "planner": "static-fabric", "dt": 0.01, "duration": 0.1,
                "initial_state": {"q": [0.0, 0.5, 0.5]},
                "goal": [{"type": "position", "position": [1.0, 1.0, 0.0]}]}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario))
    assert main(["run", str(path)]) == 2
    assert "robot.collision_spheres: link 'c'" in capsys.readouterr().err


def test_a_urdf_without_collision_geometry_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arm = Path(__file__).parent.parent / "examples" / "custom_urdf" / "arm.urdf"
    assert main(["spheres", str(arm)]) == 2
    assert "no link of arm.urdf below 'base_link' has <collision> geometry" in capsys.readouterr().err
    scenario = {"robot": {"urdf": str(arm), "goal_link": "tool", "collision_spheres": "auto"},
                "planner": "static-fabric", "dt": 0.01, "duration": 0.1, "initial_state": {"q": [0, 0, 0]},
                "goal": [{"type": "position", "position": [0.3, 0.1, 0.3]}]}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario), encoding="utf-8")
    assert main(["run", str(path)]) == 2
    assert capsys.readouterr().err.startswith("dynfab: error: robot.collision_spheres: no link of arm.urdf")


def test_fewest_needs_fewer_spheres_at_the_same_coverage(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """``--fewest`` solves the cover exactly: on three short links, the last one a ring
    (where the greedy cover takes 27 spheres and the exact one 25; tolerance 1 cm, bulge
    3 cm), fewer spheres than the greedy cover, every link within the tolerance, and the
    YAML says how it was made."""
    import trimesh

    monkeypatch.setenv("DYNFAB_CACHE_DIR", str(tmp_path / "cache"))
    trimesh.creation.annulus(0.05, 0.1, 0.08).export(tmp_path / "ring.stl")
    urdf = tmp_path / "ring_arm.urdf"
    urdf.write_text(THREE_LINKS.read_text().replace("1.0 0.1 0.1", "0.3 0.1 0.1").replace(
        "<!--MESH-->", '<collision><geometry><mesh filename="ring.stl"/></geometry></collision>'))
    totals = {}
    for flag in ([], ["--fewest"]):
        out = tmp_path / f"ring{len(flag)}.yaml"
        assert main(["spheres", str(urdf), "--max-bulge", "0.03", "--out", str(out), *flag]) == 0
        table = capsys.readouterr().out.splitlines()
        count, outside = table[-2].split()[1:3]
        assert float(outside) <= 1.0 and "meets the 1 cm target" in table[-1]
        totals[bool(flag)] = int(count)
        assert out.read_text().startswith(f"# generated by: dynfab spheres ring_arm.urdf --tolerance 0.01 "
                                          f"--max-bulge 0.03{' --fewest' if flag else ''}\n")
    assert totals[True] < totals[False], totals


def test_a_tolerance_finer_than_the_coverage_check_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["spheres", str(THREE_LINKS), "--tolerance", "0.001"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "check_edge" in err[0]
