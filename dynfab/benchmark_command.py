"""``dynfab benchmark mbm``: run MotionBenchMaker's Panda problems (dynfab/benchmarks/mbm)
and print the per-type table; ``--robot ur5`` runs their scenes with example-robot-data's
UR5 and gripper instead (object removed, a pose goal at the Panda's grasp pose:
:mod:`dynfab.benchmarks.mbm.ur5_case`).

Exit codes: 0 the benchmark finished (whatever its success rate), 2 invalid options, an
output directory of other results or an unusable cluster, 1 a run raised, 130 on Ctrl-C
(rerun the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from dynfab.cli_arguments import ExitStatus, at_least_one, requested_cluster, reported

__all__ = ["add_benchmark_parser", "benchmark_command"]


def add_benchmark_parser(commands: Any) -> None:
    """Register ``benchmark`` on the ``dynfab`` subcommands."""
    from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES
    from dynfab.benchmarks.mbm.variants import VARIANTS
    from dynfab.scenario.schema import PLANNERS

    parser = commands.add_parser("benchmark", help="run a standard benchmark (mbm: MotionBenchMaker's Panda problems) "
                                                   "in parallel, resumable, and write per-type tables")
    parser.add_argument("name", choices=["mbm"], help="mbm: MotionBenchMaker (Chamzas et al., RA-L 2022)")
    parser.add_argument("--robot", choices=("panda", "ur5"), default="panda",
                        help="panda (default): the problems as posed; ur5: example-robot-data's UR5 with its gripper "
                             "at the Panda's base, the object removed, a pose goal at the Panda's grasp pose "
                             "(object-removed only)")
    parser.add_argument("--variant", choices=VARIANTS,
                        help="as-posed (default for panda); object-removed: the object to grasp removed (default "
                             "and only one for ur5); moving-sphere: object removed and a sphere crossing the hand's "
                             "path; points: object removed, the scene given as a point cloud (surfaces every 5 mm, 2 mm "
                             "noise), checked against the true shapes")
    parser.add_argument("--types", type=_types, default=PROBLEM_TYPES, metavar="T1,T2",
                        help=f"problem types, comma-separated (default all of the archive: {','.join(PROBLEM_TYPES)}); "
                             "the mesh scenes kitchen,table_bars (generated from --seed, as-posed only)")
    parser.add_argument("--source", choices=("archive", "generated"), default="archive",
                        help="archive (default): the seven types' problems of the bundled archive (or --archive); "
                             "generated: new problems of theirs, drawn from --seed as MotionBenchMaker's generate does "
                             "from its bundled configs (scene variation, query, collision-free IK on Franka's meshes), "
                             "numbered 1, 2, ... (default 100 per type), in every variant")
    parser.add_argument("--problems", type=at_least_one, metavar="N", help="the first N problems of each type")
    parser.add_argument("--first", type=at_least_one, metavar="K", default=1,
                        help="start at each type's K-th problem (default 1; the shared set numbers them from 9, "
                             "generated ones from 1)")
    parser.add_argument("--archive", type=Path, metavar="PATH",
                        help="read the problems from this archive in VAMP's format (e.g. VAMP's "
                             "resources/panda/problems.tar.bz2, with the problems 1-8 the bundled one leaves out) "
                             "instead of the bundled one")
    parser.add_argument("--planner", choices=[p for p in PLANNERS if p != "mpc"], default="dynamic-fabric",
                        help="the scenarios' planner (default dynamic-fabric)")
    parser.add_argument("--guidance", action=argparse.BooleanOptionalAction,
                        help="set the scenarios' guidance key (default: the schema's default)")
    parser.add_argument("--seed", type=_non_negative, default=0,
                        help="seed of the moving spheres and of the generated problems (mesh scenes, --source "
                             "generated), a non-negative integer (default 0)")
    parser.add_argument("--reference-checks", type=_non_negative, default=0, metavar="N",
                        help="also run MotionBenchMaker's filter on every Panda problem: RRT-Connect on Franka's "
                             "meshes to its goal configuration within N mesh checks (120000: about MBM's 60 s "
                             "here); the tables then give the success among the problems it solves (default 0: "
                             "not run)")
    parser.add_argument("--out", type=Path, help="output directory (default dynfab-benchmarks/mbm-VARIANT, "
                                                 "dynfab-benchmarks/mbm-generated-VARIANT for --source generated)")
    parser.add_argument("--jobs", type=at_least_one, help="worker processes (default: the number of CPUs)")
    parser.add_argument("--workers", type=at_least_one,
                        help="run on Dask: an embedded LocalCluster of this many worker processes")
    parser.add_argument("--scheduler", metavar="tcp://HOST:8786",
                        help="run on the existing Dask cluster of this scheduler (implies Dask)")


def benchmark_command(args: argparse.Namespace) -> int:
    """Run the benchmark ``args`` ask for; print its table (module doc for exit codes)."""
    from dynfab.benchmarks.mbm.benchmark import BenchmarkError, BenchmarkSettings, run_benchmark
    from dynfab.benchmarks.mbm.moveit import ProblemError
    from dynfab.experiments.cluster import ClusterError
    from dynfab.scenario.schema import ScenarioError

    variant = args.variant or ("as-posed" if args.robot == "panda" else "object-removed")
    if args.robot == "ur5" and variant != "object-removed":
        print(f"dynfab: error: --robot ur5 runs the object-removed variant only, not {variant}", file=sys.stderr)
        return 2
    if args.source == "generated" and args.archive is not None:
        print("dynfab: error: --archive reads an archive's problems, --source generated draws new ones: give one",
              file=sys.stderr)
        return 2
    settings = BenchmarkSettings(variant, args.types, args.problems, args.planner, args.guidance, args.seed,
                                 args.first - 1, args.robot, args.archive, args.source, args.reference_checks)
    generated = "generated-" if args.source == "generated" else ""
    out = args.out or Path("dynfab-benchmarks") / f"mbm-{generated}{settings.label}"
    records = reported(lambda: run_benchmark(settings, out, args.jobs, requested_cluster(args.workers, args.scheduler),
                                             sys.stderr),
                       (BenchmarkError, ClusterError, ProblemError, ScenarioError),
                       f"finished runs are in {out / 'runs.jsonl'}, rerun the same command to resume")
    if isinstance(records, ExitStatus):
        return records.code
    print((out / "summary.md").read_text(encoding="utf-8"), end="")
    print(f"dynfab: {len(records)} problems; wrote {out}/runs.jsonl, runs.csv, summary.md, summary.json and "
          f"scenarios/", file=sys.stderr)
    return 0


def _non_negative(text: str) -> int:
    """``--seed``, ``--reference-checks``: a non-negative integer (numpy's seed sequences take
    no negative one)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {value}")
    return value


def _types(text: str) -> tuple[str, ...]:
    """``--types``: comma-separated problem types."""
    from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES

    from dynfab.benchmarks.mbm.scene_configs import SCENE_TYPES

    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in PROBLEM_TYPES + SCENE_TYPES]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"unknown problem type {unknown[0] if unknown else text!r} "
                                         f"(expected some of {', '.join(PROBLEM_TYPES + SCENE_TYPES)})")
    return names
