"""The ``dynfab`` command: ``run`` a scenario file, ``check`` a recorded run, a ``demo``, or
print the scenario files' JSON ``schema``.

Exit codes: 0 success (the run finished, whatever its metrics; a check found nothing),
2 invalid input (one line on stderr naming the field), 3 ``check`` found a collision, a
self-collision or a joint outside its limits, 1 unexpected failure.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING

from dynfab.benchmark_command import add_benchmark_parser, benchmark_command
from dynfab.cli_arguments import ExitStatus, at_least_one, positive_number, requested_cluster, reported
from dynfab.fabric.backends import BACKENDS
from dynfab.plot_command import add_plot_parser, plot_command
from dynfab.scenario.recording import RecordingError, load_recording, run_recording, save_recording
from dynfab.scenario.runner import RunResult, run_scenario
from dynfab.scenario.schema import PLANNERS, BuiltinRobotSpec, Scenario, ScenarioError, load_scenario
from dynfab.tune_command import add_tune_parser, tune_command
from dynfab.view_command import add_view_parser, view_command

if TYPE_CHECKING:
    from dynfab.viz.mujoco_video import VideoRecorder

#: ``dynfab demo NAME``: the bundled scenario, and whether the demo also runs the static
#: baseline on it for comparison.
DEMOS = {
    "spheres": ("panda_spheres.yaml", False),
    "dynamic": ("panda_dynamic.yaml", True),
    "boxer": ("boxer_spheres.yaml", False),
    "mobile": ("boxer_panda_room.yaml", False),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="dynfab", description="Reactive motion generation with optimization fabrics.")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run a scenario file in the embedded simulator",
                              epilog="exit status: 0 goal reached without collision, 1 the run ended without "
                                     "success (the metrics say why: failure), 2 bad input")
    run.add_argument("file", type=Path, help="scenario YAML file")
    run.add_argument("--planner", choices=PLANNERS, help="override the scenario's planner")
    run.add_argument("--simulator", help="override the scenario's simulator: kinematic or mujoco")
    run.add_argument("--control", help="under mujoco, the joints' control interface: torque, velocity or position")
    run.add_argument("--video", type=Path, metavar="RUN.mp4", help="under mujoco, render the run to an MP4 video")
    _output_options(run)
    check = commands.add_parser("check", help="check a recorded run on the robot's collision meshes: collisions, "
                                              "self-collisions, joint limits (exit 3 if any)")
    check.add_argument("recording", type=Path, help="a recording written by dynfab run --record")
    check.add_argument("file", type=Path, help="the scenario YAML file of the run")
    check.add_argument("--json", action="store_true", help="print the findings as one JSON object on stdout")
    demo = commands.add_parser("demo", help="spheres: the Panda reaching a goal among spheres (default); "
                                            "dynamic: following a circle past a moving sphere, DF vs SF; "
                                            "boxer: a differential-drive base among discs; "
                                            "mobile: the Boxer+Panda mobile manipulator in a room")
    demo.add_argument("name", nargs="?", choices=sorted(DEMOS), default="spheres")
    _output_options(demo, default_plot=Path("dynfab-demo.png"))
    experiment = commands.add_parser("experiment", help="run one of the paper's experiments as a seeded series "
                                                        "(parallel, resumable) and summarize it beside the paper")
    experiment.add_argument("name", help="exp1, exp2a, exp2b, exp3, exp4, exp5, exp6 or arms")
    experiment.add_argument("--runs", type=at_least_one, default=50, help="number of seeds (default 50)")
    experiment.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    experiment.add_argument("--out", type=Path, help="output directory (default dynfab-experiments/NAME)")
    experiment.add_argument("--jobs", type=at_least_one, help="worker processes (default: the number of CPUs)")
    experiment.add_argument("--workers", type=at_least_one,
                            help="run on Dask: an embedded LocalCluster of this many worker processes")
    experiment.add_argument("--scheduler", metavar="tcp://HOST:8786",
                            help="run on the existing Dask cluster of this scheduler (implies Dask)")
    experiment.add_argument("--record", action="store_true",
                            help="also write each run's recording to OUT/recordings/ (for dynfab check)")
    experiment.add_argument("--simulator", default="kinematic", help="kinematic (default) or mujoco")
    experiment.add_argument("--control", default="torque", help="under mujoco: torque (default), velocity or position")
    experiment.add_argument("--delay", type=float, default=0.0, help="under mujoco: observation delay [s]")
    experiment.add_argument("--noise", type=float, default=0.0,
                            help="under mujoco: std of the observation noise [rad or m, and per s]")
    experiment.add_argument("--recovery", action="store_true",
                            help="recover from stalls by following a global path (off in the paper's runs)")
    experiment.add_argument("--planners", type=lambda text: tuple(filter(None, text.split(","))), default=(),
                            help="only these of the experiment's planners, comma-separated (default: all), "
                                 "e.g. static-fabric")
    export = commands.add_parser("export", help="write a scenario's fabric planner as self-contained C "
                                                "(NAME.c, NAME.h, example.c, Makefile)")
    export.add_argument("file", type=Path, help="scenario YAML file (static-fabric or dynamic-fabric)")
    export.add_argument("--out", type=Path, required=True, help="output directory")
    export.add_argument("--name", help="prefix of the C symbols (default: the file name, e.g. panda_spheres)")
    spheres = commands.add_parser("spheres", help="fit collision spheres to a URDF's collision geometry, "
                                                  "print their coverage, write them as scenario YAML")
    spheres.add_argument("urdf", help="URDF file, or package://NAME/... (see the README)")
    spheres.add_argument("--out", type=Path, help="write collision_spheres and self_collision_pairs as YAML")
    spheres.add_argument("--plot", type=Path, help="write a PNG of meshes and spheres")
    spheres.add_argument("--tolerance", type=positive_number, default=0.01,
                         help="largest distance of a mesh surface point outside all spheres [m] (default 0.01)")
    spheres.add_argument("--max-bulge", type=positive_number, default=0.02,
                         help="largest distance a sphere reaches out of the body [m] (default 0.02)")
    spheres.add_argument("--fewest", action="store_true",
                         help="the fewest spheres that meet the tolerance (an integer program, 1-2 s per "
                              "link) instead of the greedy cover (about 1.3 times as many on arm links)")
    spheres.add_argument("--package-dir", type=Path, action="append", default=[],
                         help="folder where package:// URIs resolve (repeatable)")
    spheres.add_argument("--joints", nargs="+", help="active joints (default: every movable, non-mimic joint)")
    add_plot_parser(commands)
    add_view_parser(commands)
    commands.add_parser("schema", help="print the JSON Schema of scenario files (for editor completion, see the "
                                       "README)")
    add_tune_parser(commands)
    add_benchmark_parser(commands)
    args = parser.parse_args(argv)
    if args.command == "benchmark":
        return benchmark_command(args)
    if args.command == "tune":
        return tune_command(args)
    if args.command == "schema":
        from dynfab.scenario.schema import ScenarioDocument

        print(json.dumps(ScenarioDocument.model_json_schema(), indent=2))
        return 0
    if args.command == "view":
        return view_command(args)
    if args.command == "spheres":
        from dynfab.geometry.sphere_fitting import SphereFitParameters
        from dynfab.spheres_command import spheres_command

        try:
            parameters = SphereFitParameters(tolerance=args.tolerance, max_bulge=args.max_bulge, fewest=args.fewest)
        except ValueError as error:
            print(f"dynfab: error: {error}", file=sys.stderr)
            return 2
        return spheres_command(args.urdf, args.out, args.plot, parameters, args.package_dir, args.joints)
    if args.command == "experiment":
        return _experiment(args)
    if args.command == "plot":
        return plot_command(args)
    if args.command == "export":
        from dynfab.export_command import export_command

        return export_command(args.file, args.out, args.name)
    if args.command == "check":
        return _check(args.recording, args.file, args.json)
    video = None
    if args.command == "run":
        path, planners = args.file, [args.planner]
    else:
        filename, compare = DEMOS[args.name]
        path = Path(str(files("dynfab.scenario.demos") / filename))
        planners = [None, "static-fabric"] if compare else [None]
    try:
        scenario = load_scenario(path)
        if args.backend is not None:
            scenario = dataclasses.replace(scenario, backend=args.backend)
        if args.command == "run":
            scenario = _with_simulation(scenario, args.simulator, args.control)
            video = _video_recorder(scenario, args.video)
        results = [_run(path, scenario if planner is None else dataclasses.replace(scenario, planner=planner), video)
                   for planner in planners]
    except ScenarioError as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return 2
    if results[0].stop_reason is not None:
        print(f"dynfab: run stopped early: {results[0].stop_reason}; metrics cover the run so far", file=sys.stderr)
    if video is not None:
        video.close()
        print(f"dynfab: video written to {video.path} ({len(video.frames)} frames)", file=sys.stderr)
    _report(results, args.json)
    if args.record is not None:
        try:
            _record(results[0], args.record)
        except OSError as error:
            print(f"dynfab: error: --record: cannot write {args.record} ({error.strerror})", file=sys.stderr)
            return 2
    if args.plot is not None:
        _plot(results, args.plot)
        print(f"dynfab: plot written to {args.plot}", file=sys.stderr)
    if args.command == "run" and not results[0].metrics.success:
        return 1  # ran, but the goal was not reached without collision (the metrics say why)
    return 0


def _experiment(args: argparse.Namespace) -> int:
    """``dynfab experiment``: run the series (local processes, or Dask with ``--workers`` /
    ``--scheduler``), print its summary; 2 for an unknown name, a bad simulation setting, an
    output directory of another series or an unusable cluster, 1 if a run failed, 130 on
    Ctrl-C (resumable)."""
    from dynfab.experiments.cluster import ClusterError
    from dynfab.experiments.settings import setting_name, with_planners, with_setting
    from dynfab.experiments.registry import EXPERIMENTS
    from dynfab.experiments.series import SeriesError, run_series
    from dynfab.scenario.simulation_schema import Simulation

    name, runs, seed, out, jobs, record = args.name, args.runs, args.seed, args.out, args.jobs, args.record
    if name not in EXPERIMENTS:
        print(f"dynfab: error: unknown experiment {name!r} (expected one of {', '.join(EXPERIMENTS)})",
              file=sys.stderr)
        return 2
    try:
        simulation = Simulation(args.simulator, args.control, args.delay, args.noise)
    except ScenarioError as error:
        print(f"dynfab: error: --{error.field}: {error.problem}", file=sys.stderr)
        return 2
    if simulation.simulator == "kinematic" and simulation != Simulation():
        print("dynfab: error: --control, --delay and --noise need --simulator mujoco", file=sys.stderr)
        return 2
    try:
        experiment = with_planners(with_setting(EXPERIMENTS[name], simulation, args.recovery), args.planners)
    except ValueError as error:
        print(f"dynfab: error: --planners: {error}", file=sys.stderr)
        return 2
    if out is None:
        suffix = "" if simulation == Simulation() and not args.recovery else "-" + setting_name(simulation, args.recovery)
        out = Path("dynfab-experiments") / (name + suffix)
    result = reported(lambda: run_series(experiment, runs, seed, out, jobs, progress=sys.stderr, record=record,
                                         cluster=requested_cluster(args.workers, args.scheduler)),
                      (SeriesError, ClusterError),
                      f"finished runs are in {out / 'runs.jsonl'}, rerun the same command to resume")
    if isinstance(result, ExitStatus):
        return result.code
    print((out / "summary.md").read_text(encoding="utf-8"), end="")
    print("\n" + (out / "timings.md").read_text(encoding="utf-8"), end="")
    print(f"dynfab: {result.executed} runs executed; wrote {out}/runs.jsonl, runs.csv, summary.md, summary.json, "
          f"timings.md, timings.json, scenarios/ and plots/", file=sys.stderr)
    return 0


def _record(result: RunResult, path: Path) -> None:
    """Write the run's recording (scenario/recording.py) to ``path``."""
    save_recording(path, run_recording(result.robot, result.record, result.scenario.dt, result.scenario.path))
    print(f"dynfab: recording written to {path}", file=sys.stderr)


def _check(recording_path: Path, scenario_path: Path, as_json: bool) -> int:
    """``dynfab check``: 0 if the recording is clean, 3 if not, 2 on invalid input."""
    from dynfab.scenario.recording_check import check_recording

    try:
        report = check_recording(load_scenario(scenario_path), load_recording(recording_path))
    except (ScenarioError, RecordingError) as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return 2
    findings = report.to_dict()
    if as_json:
        print(json.dumps(findings))
    else:
        print(f"{recording_path}: {findings['samples']} samples, "
              f"{'no collision, no self-collision, joints within limits' if report.ok else 'VIOLATIONS'}")
        print(f"  clearance {_shown(report.clearance)} m, min self distance {_shown(report.min_self_distance)} m")
        for key in ("collisions", "self_collisions"):
            for c in findings[key]:
                print(f"  {key[:-1].replace('_', '-')}: {c['link']} - {c['other']} from t = {c['first_time']:.3f} s, "
                      f"{c['samples']} samples, distance {c['distance']:.4g} m")
        for v in findings["joint_limit_violations"]:
            print(f"  joint limit: {v['joint']} from t = {v['first_time']:.3f} s, {v['samples']} samples, "
                  f"worst {v['worst']:.6g} outside [{v['lower']:.6g}, {v['upper']:.6g}]")
    return 0 if report.ok else 3


def _run(path: Path, scenario: Scenario, video: VideoRecorder | None = None) -> RunResult:
    simulation = scenario.simulation
    under = (f", mujoco with {simulation.control} control" if simulation.simulator == "mujoco" else "")
    spec = scenario.robot
    robot = spec if isinstance(spec, str) else spec.name if isinstance(spec, BuiltinRobotSpec) else "urdf"
    header = (f"dynfab: {path.name}: robot {robot}, "
              f"planner {scenario.planner}, {scenario.duration:g} s at dt {scenario.dt:g} s{under}")
    return run_scenario(scenario, progress=_ProgressBar(header), observer=video)


def _with_simulation(scenario: Scenario, simulator: str | None, control: str | None) -> Scenario:
    """``scenario`` with the command line's ``--simulator`` and ``--control``.

    Raises:
        ScenarioError: An unknown value, or ``--control`` for the kinematic simulator.
    """
    simulation = scenario.simulation
    if simulator is not None:
        simulation = dataclasses.replace(simulation, simulator=simulator)
    if control is not None:
        simulation = dataclasses.replace(simulation, control=control)
        if simulation.simulator != "mujoco":
            raise ScenarioError("--control", "applies to --simulator mujoco only")
    return dataclasses.replace(scenario, simulation=simulation)


def _video_recorder(scenario: Scenario, path: Path | None) -> VideoRecorder | None:
    """The recorder of ``--video``, or None without it."""
    if path is None:
        return None
    if scenario.simulation.simulator != "mujoco":
        raise ScenarioError("--video", "renders MuJoCo runs: add --simulator mujoco")
    if path.parent != Path() and not path.parent.is_dir():
        raise ScenarioError("--video", f"folder {path.parent} does not exist")
    from dynfab.viz.mujoco_video import VideoRecorder, prepare_headless_rendering

    prepare_headless_rendering()
    return VideoRecorder(path)


def _output_options(parser: argparse.ArgumentParser, default_plot: Path | None = None) -> None:
    parser.add_argument("--json", action="store_true", help="print the metrics as one JSON object on stdout")
    parser.add_argument("--backend", choices=BACKENDS,
                        help="override the scenario's backend: c (compiled C, cached; the default) or vm (CasADi VM)")
    parser.add_argument("--plot", type=Path, default=default_plot, help="write a PNG of the run")
    parser.add_argument("--record", type=Path, metavar="OUT.npz",
                        help="write t, q, qdot, qddot (one row per control step) and joint_names of the (first) run")


class _ProgressBar:
    """Progress on stderr: a header once the run starts (so that an invalid scenario
    prints nothing but its error), then a bar redrawn at each percent on a terminal,
    otherwise one line per quarter of the run."""

    def __init__(self, header: str) -> None:
        self._header: str | None = header
        self._last = -1
        self._step = 1 if sys.stderr.isatty() else 25

    def __call__(self, step: int, total: int) -> None:
        if self._header is not None:
            print(self._header, file=sys.stderr)
            self._header = None
        percent = 100 * step // total // self._step * self._step
        if percent == self._last:
            return
        self._last = percent
        bar = "#" * (percent // 4)
        if self._step == 1:
            print(f"\r  simulating [{bar:<25}] {percent:3d}%", end="\n" if step == total else "", file=sys.stderr)
        else:
            print(f"  simulating [{bar:<25}] {percent:3d}%", file=sys.stderr)


def _report(results: list[RunResult], as_json: bool) -> None:
    """One run: its metrics (JSON or a table). Several: one column (or JSON key) each."""
    metrics = [result.metrics.to_dict() for result in results]
    if as_json:
        if len(results) == 1:
            print(json.dumps(metrics[0]))
        else:
            print(json.dumps({result.scenario.planner: m for result, m in zip(results, metrics)}))
        return
    width = max(len(key) for key in metrics[0])
    if len(results) > 1:
        print(f"{'':>{width}}  " + "".join(f"{result.scenario.planner:>16}" for result in results))
    for key in metrics[0]:
        print(f"{key:>{width}}: " + "".join(f"{_shown(m[key]):>16}" for m in metrics))


def _shown(value: object) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _plot(results: list[RunResult], path: Path) -> None:
    """One run's plot, or the runs of a comparing demo one above the other."""
    from dynfab.viz.result_plot import plot_result, plot_results

    if len(results) == 1:
        plot_result(results[0], path)
    else:
        plot_results(results, path)


if __name__ == "__main__":
    sys.exit(main())
