"""Plots that show the robot (issue 13 item 3): snapshots of the body at the right
instants and places, drawn in every view, and ``dynfab plot`` on a recorded run whose
replayed metrics equal the run's; the clearance drawn is the one the metrics report
(issue 21 item 5)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from dynfab.cli import main
from dynfab.robots import load_robot
from dynfab.scenario.recording import load_recording
from dynfab.scenario.replay import replay_recording
from dynfab.scenario.runner import run_scenario
from dynfab.scenario.schema import load_scenario
from dynfab.viz.body_drawing import draw_body_projection
from dynfab.viz.result_plot import plot_result
from dynfab.viz.robot_snapshots import robot_snapshots, snapshot_indices

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PNG = b"\x89PNG\r\n\x1a\n"


def test_snapshots_are_evenly_spaced_plus_the_closest_approach() -> None:
    clearance = np.array([5.0, 4.0, 3.0, 0.5, 2.0, 3.0, 4.0, 4.5, 5.0, 6.0, 7.0])
    rows, closest = snapshot_indices(11, clearance, count=3)
    assert rows == (0, 3, 5, 10) and closest == 1
    assert snapshot_indices(11, np.full(11, np.inf), count=2) == ((0, 10), None)
    assert snapshot_indices(11, None, count=2) == ((0, 10), None)


def test_snapshot_segments_join_link_origins_and_spheres_sit_on_their_links() -> None:
    robot = load_robot("panda")
    kin = robot.kinematics
    rng = np.random.default_rng(3)
    qs = rng.uniform(kin.lower, kin.upper, size=(9, kin.dof))
    snapshots = robot_snapshots(robot, qs, np.arange(9) * 0.1, count=3)
    assert snapshots.segments.shape[:2] == (3, len([j for j in kin.model.joints if j.child in kin.link_names]))
    for k, row in enumerate((0, 4, 8)):
        assert snapshots.times[k] == pytest.approx(0.1 * row)
        hand = np.array(kin.position(qs[row], "panda_hand"), dtype=float).ravel()
        assert np.min(np.linalg.norm(snapshots.segments[k].reshape(-1, 3) - hand, axis=1)) < 1e-12
        for sphere, centre in zip(robot.collision_spheres, snapshots.sphere_centres[k]):
            expected = np.array(kin.position(qs[row], sphere.link, offset=sphere.center), dtype=float).ravel()
            np.testing.assert_allclose(centre, expected, atol=1e-12)


def test_every_snapshot_is_drawn_with_its_spheres() -> None:
    robot = load_robot("panda")
    snapshots = robot_snapshots(robot, np.tile(robot.default_q, (5, 1)), np.arange(5.0), count=2)
    ax = Figure().add_subplot()
    draw_body_projection(ax, (0, 1), snapshots, np.zeros((5, 0, 3)), np.zeros(0), np.arange(5.0))
    segments = snapshots.segments.shape[1]
    assert len(ax.lines) == 2 * segments
    assert len(ax.patches) == 2 * len(robot.collision_spheres)


def test_plot_of_a_recorded_run_replays_its_metrics(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = EXAMPLES / "panda_moving_obstacles.yaml"
    recording = tmp_path / "run.npz"
    assert main(["run", str(scenario), "--record", str(recording), "--json"]) == 0
    capsys.readouterr()
    assert main(["plot", str(recording)]) == 0
    assert (tmp_path / "run.png").read_bytes()[:8] == PNG
    replayed = replay_recording(load_recording(recording)).metrics.to_dict()
    original = run_scenario(load_scenario(scenario)).metrics.to_dict()
    for key in ("solver_time_ms", "guided", "plans", "plan_time_ms", "recovered", "fallbacks",
                "goal_moved"):   # the controller's
        replayed.pop(key), original.pop(key)
    assert replayed == original


def test_plot_needs_a_readable_recording_that_names_its_scenario(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    assert main(["plot", str(bad)]) == 2
    assert "cannot read" in capsys.readouterr().err
    recording = tmp_path / "run.npz"
    t = np.arange(3) * 0.01
    np.savez(recording, t=t, q=np.zeros((3, 7)), qdot=np.zeros((3, 7)), qddot=np.zeros((3, 7)),
             joint_names=np.array([f"panda_joint{i}" for i in range(1, 8)]))
    assert main(["plot", str(recording)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--scenario" in err[0]
    assert main(["plot", str(recording), "--scenario", str(EXAMPLES / "boxer_spheres.yaml")]) == 2
    assert "are not those of the scenario's robot" in capsys.readouterr().err


def _clearance_panel(figure: Figure):
    """The clearance axes of a run's figure: its title names what it draws."""
    return next(ax for ax in figure.axes if "clearance" in ax.get_title())


def test_the_plot_draws_the_mesh_clearance_the_metrics_report(tmp_path: Path) -> None:
    """The built-in Panda is measured on Franka's meshes: the plotted clearance is theirs
    (not the planner's spheres, which reach up to 2 cm out of the meshes) and says so."""
    scenario = load_scenario(EXAMPLES / "panda_table_box.yaml")
    result = run_scenario(dataclasses.replace(scenario, duration=1.0))
    assert result.mesh_sweep is not None
    metrics = result.metrics
    assert metrics.sphere_clearance < metrics.clearance - 1e-3   # the two figures differ here
    panel = _clearance_panel(plot_result(result, tmp_path / "run.png"))
    drawn = panel.lines[0].get_ydata()
    assert drawn.min() == pytest.approx(metrics.clearance, abs=1e-12)
    assert len(drawn) == len(result.record.t)
    assert panel.get_title() == f"mesh clearance (min {metrics.clearance:+.3f} m)"
    assert panel.get_ylabel() == "mesh clearance [m]"


def test_a_robot_measured_by_spheres_plots_its_sphere_clearance(tmp_path: Path) -> None:
    result = run_scenario(load_scenario(EXAMPLES / "point_spheres.yaml"))
    assert result.mesh_sweep is None
    panel = _clearance_panel(plot_result(result, tmp_path / "run.png"))
    assert panel.lines[0].get_ydata().min() == pytest.approx(result.metrics.clearance, abs=1e-12)
    assert panel.get_title().startswith("sphere clearance (min ")


def test_the_dynamic_demo_plots_both_of_its_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """``dynfab demo dynamic`` runs the dynamic fabric and its static baseline: both are
    drawn, one above the other, each with its clearance and tracking error (the demo's
    scenario shortened to 1 s)."""
    from dynfab import cli
    from dynfab.viz import result_plot

    monkeypatch.setattr(cli, "load_scenario", lambda path: dataclasses.replace(load_scenario(path), duration=1.0))
    figures: list[Figure] = []
    plot_results = result_plot.plot_results
    monkeypatch.setattr(result_plot, "plot_results", lambda *args: figures.append(plot_results(*args)) or figures[-1])
    png = tmp_path / "demo.png"
    assert main(["demo", "dynamic", "--plot", str(png), "--json"]) == 0
    capsys.readouterr()
    assert png.read_bytes()[:8] == PNG
    [figure] = figures
    titles = [subfigure.get_suptitle() for subfigure in figure.subfigs]
    assert [title.split(":")[0] for title in titles] == ["panda, dynamic-fabric", "panda, static-fabric"]
    for subfigure in figure.subfigs:
        panels = [ax.get_title() for ax in subfigure.axes]
        assert any(title.startswith("mesh clearance") for title in panels), panels
        assert any("tracking error" in title for title in panels), panels
