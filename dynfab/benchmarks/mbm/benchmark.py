"""``dynfab benchmark mbm``: the MBM problems of one variant, in parallel (local processes
or Dask, :mod:`dynfab.experiments.cluster`), resumable, with per-type tables.

:func:`run_benchmark` writes into ``out_dir``:

- ``scenarios/<type>_<NNNN>.yaml``: every valid case's scenario (``dynfab run FILE``
  replays it);
- ``runs.jsonl``: one JSON line per case, appended as it finishes (invalid cases at
  once): ``{"benchmark", "variant", "problem", "type", "number", "digest", "removed",
  "invalid", "metrics", "check", "refused", "wall_time_s"}`` and, with
  ``reference_checks``, ``"reference"`` (:mod:`dynfab.benchmarks.mbm.reference_plan`) (``digest``: of the
  scenario mapping and of dynfab's source, :func:`~dynfab.fabric.fingerprint.package_digest`).
  On start, the cases already in it with the same digest are skipped, so an interrupted
  benchmark resumes; a case recorded from another scenario, or by other code, is an error
  (results of older code are never mixed into a table);
- ``runs.csv``, ``summary.md``, ``summary.json``: :mod:`dynfab.benchmarks.mbm.tables`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import yaml

from dynfab.benchmarks.mbm.conversion import PLANNER
from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.generated_problems import generated_problems
from dynfab.benchmarks.mbm.problem_run import run_case
from dynfab.benchmarks.mbm.problems import PROBLEM_TYPES, Problem, load_problems
from dynfab.benchmarks.mbm.scene_configs import SCENE_TYPES
from dynfab.benchmarks.mbm.scenes import VARIANT as SCENE_VARIANT
from dynfab.benchmarks.mbm.scenes import prepare_scene_case, scene_problems
from dynfab.benchmarks.mbm.tables import write_tables
from dynfab.benchmarks.mbm.ur5 import ur5
from dynfab.benchmarks.mbm.ur5_case import VARIANT as UR5_VARIANT
from dynfab.benchmarks.mbm.ur5_case import prepare_ur5_case
from dynfab.benchmarks.mbm.variants import Case, prepare_case
from dynfab.fabric.fingerprint import package_digest
from dynfab.experiments.cluster import Cluster, series_executor
from dynfab.experiments.series import Progress, RunError, SeriesError, exclusive, log_lines

__all__ = ["SOURCES", "BenchmarkError", "BenchmarkSettings", "run_benchmark"]


#: Problems of a generated type when ``per_type`` is None (MBM's configs ask for 100).
SCENE_PROBLEMS = 100
#: Where the seven primitive types' problems come from: the archive, or drawn from ``seed``
#: (:mod:`dynfab.benchmarks.mbm.generated_problems`).
SOURCES: tuple[str, ...] = ("archive", "generated")


class BenchmarkError(ValueError):
    """``out_dir`` holds results of another benchmark, variant or scenario."""


@dataclass(frozen=True)
class BenchmarkSettings:
    """What to run.

    Attributes:
        variant: ``as-posed``, ``object-removed`` or ``moving-sphere`` (``robot`` panda);
            ``object-removed`` only for the UR5.
        robot: ``panda`` (the problems as posed) or ``ur5`` (:mod:`dynfab.benchmarks.mbm.ur5_case`).
        types: Problem types, in report order: those of the archive and the mesh scenes
            (:mod:`dynfab.benchmarks.mbm.scenes`, generated from ``seed``).
        per_type: The first this many problems of each type; None: all (a generated type:
            :data:`SCENE_PROBLEMS`).
        planner: The scenario's planner.
        guidance: The scenario's ``guidance`` key; None leaves it out (the schema's default).
        seed: Seed of the moving spheres and of the generated problems.
        skip: Problems of each type skipped before the first ``per_type`` (in number order).
        archive: A problems archive in VAMP's format to read instead of the bundled one
            (:func:`~dynfab.benchmarks.mbm.problems.load_problems`); None: the bundled one.
        source: One of :data:`SOURCES`: the seven primitive types read from the archive, or
            new problems of theirs generated from ``seed`` (numbered 1, 2, ...).
        reference_checks: Mesh checks of MotionBenchMaker's filter run on every Panda case
            (:mod:`dynfab.benchmarks.mbm.reference_plan`); 0: not run.
    """

    variant: str = "as-posed"
    types: tuple[str, ...] = PROBLEM_TYPES
    per_type: int | None = None
    planner: str = PLANNER
    guidance: bool | None = None
    seed: int = 0
    skip: int = 0
    robot: str = "panda"
    archive: Path | None = None
    source: str = "archive"
    reference_checks: int = 0

    @property
    def label(self) -> str:
        """The variant's name in records and tables: ``variant``, or ``ur5-object-removed``."""
        return self.variant if self.robot == "panda" else UR5_VARIANT


def run_benchmark(settings: BenchmarkSettings, out_dir: str | Path, jobs: int | None = None,
                  cluster: Cluster | None = None, progress: IO[str] | None = None) -> list[dict[str, Any]]:
    """Prepare every case, run the valid ones not yet in ``runs.jsonl``, write the tables
    (module doc); the records, in problem order.

    Raises:
        BenchmarkError: ``out_dir`` holds other results, or another run holds its lock.
        RunError: A run raised (the finished ones stay recorded).
        ClusterError: The Dask cluster cannot be used.
        ProblemError, ScenarioError, ValueError: A problem or setting that cannot be converted.
    """
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = _cases(settings, jobs)
    if settings.guidance is not None:
        cases = [dataclasses.replace(case, mapping={**case.mapping, "guidance": settings.guidance}) for case in cases]
    log = out / "runs.jsonl"
    try:
        with exclusive(out):
            done = _load_records(log, settings.label)
            reference = settings.reference_checks if settings.robot == "panda" else 0
            records = {case.problem.name: _fresh(case, done, reference) for case in cases}
            pending = [case for case in cases if records[case.problem.name] is None and case.invalid is None]
            _write_scenarios(out / "scenarios", pending)
            with log.open("a", encoding="utf-8") as file:
                for case in cases:
                    if case.invalid is not None and records[case.problem.name] is None:
                        records[case.problem.name] = _append(file, _record(case, None, reference))
                bar = None if progress is None else Progress(progress, f"mbm {settings.label}", len(cases),
                                                             len(cases) - len(pending))
                for case, outcome in _execute(pending, min(jobs, max(len(pending), 1)), cluster, bar, reference):
                    records[case.problem.name] = _append(file, _record(case, outcome, reference))
            ordered = [records[case.problem.name] for case in cases]
            write_tables(out, settings.label, settings.types, ordered)
    except SeriesError as error:
        raise BenchmarkError(str(error)) from None
    return ordered


def _cases(settings: BenchmarkSettings, jobs: int = 1) -> list[Case]:
    """Every problem of ``settings`` prepared as a case of its robot and variant (generated
    problems drawn over ``jobs`` local processes).

    Raises:
        ValueError: An unknown robot or source, a variant the UR5 does not have, or an
            archive with generated problems.
    """
    scenes = tuple(t for t in settings.types if t in SCENE_TYPES)
    primitive = tuple(t for t in settings.types if t not in SCENE_TYPES)
    if settings.source not in SOURCES:
        raise ValueError(f"unknown source {settings.source!r} (expected one of {', '.join(SOURCES)})")
    if settings.source == "generated" and settings.archive is not None:
        raise ValueError(f"an archive ({settings.archive}) holds problems to read, the generated source draws new "
                         f"ones: give one of them")
    if not primitive:
        problems: tuple[Problem, ...] = ()
    elif settings.source == "generated":
        problems = generated_problems(primitive, settings.per_type or SCENE_PROBLEMS, settings.skip, settings.seed,
                                      franka(), jobs)
    else:
        problems = load_problems(primitive, settings.per_type, archive=settings.archive, skip=settings.skip)
    if scenes and (settings.robot, settings.variant) != ("panda", SCENE_VARIANT):
        raise ValueError(f"the mesh scenes ({', '.join(scenes)}) run the Panda {SCENE_VARIANT} only (their queries "
                         f"name no object to remove)")
    if settings.robot == "panda":
        return [prepare_case(problem, settings.variant, franka(), settings.planner, settings.seed)
                for problem in problems] + [
            prepare_scene_case(problem, settings.planner) for problem in
            scene_problems(scenes, settings.per_type or SCENE_PROBLEMS, settings.skip, settings.seed, franka())]
    if settings.robot != "ur5":
        raise ValueError(f"unknown robot {settings.robot!r} (expected panda or ur5)")
    if settings.variant != "object-removed":
        raise ValueError(f"the UR5 runs the object-removed variant only (its goal is the Panda's grasp pose without "
                         f"the object), not {settings.variant}")
    return [prepare_ur5_case(problem, franka(), ur5(), settings.planner) for problem in problems]


def _digest(mapping: dict[str, Any], reference: int = 0) -> str:
    """Of the scenario ``mapping``, of the code that runs it (module docstring) and of the
    ``reference`` filter's checks (0: none)."""
    text = json.dumps(mapping, sort_keys=True) + package_digest() + (f"reference {reference}" if reference else "")
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _record(case: Case, outcome: dict[str, Any] | None, reference: int = 0) -> dict[str, Any]:
    problem = case.problem
    ran = outcome or {"metrics": None, "check": None, "refused": None, "wall_time_s": None}
    return {"benchmark": "mbm", "variant": case.variant, "problem": problem.name, "type": problem.type,
            "number": problem.number, "digest": _digest(case.mapping, reference), "removed": case.removed,
            "invalid": case.invalid, **ran}


def _fresh(case: Case, done: dict[str, dict[str, Any]], reference: int = 0) -> dict[str, Any] | None:
    """The recorded run of ``case``, or None if it has none.

    Raises:
        BenchmarkError: It was recorded from another scenario.
    """
    record = done.get(case.problem.name)
    if record is not None and record["digest"] != _digest(case.mapping, reference):
        raise BenchmarkError(f"{case.problem.name} was recorded from another scenario (other options, or another "
                             f"dynfab version): use another output directory")
    return record


def _load_records(log: Path, variant: str) -> dict[str, dict[str, Any]]:
    records = {}
    for number, line in enumerate(log_lines(log), 1):
        try:
            record = json.loads(line)
            name, kind, recorded, _ = record["problem"], record["benchmark"], record["variant"], record["digest"]
        except (ValueError, KeyError, TypeError) as error:
            raise BenchmarkError(f"{log}:{number}: not a benchmark record ({error})") from None
        if (kind, recorded) != ("mbm", variant):
            raise BenchmarkError(f"{log} holds runs of {kind} {recorded}, not mbm {variant}: use another "
                                 f"output directory")
        records.setdefault(name, record)
    return records


def _append(file: IO[str], record: dict[str, Any]) -> dict[str, Any]:
    file.write(json.dumps(record) + "\n")
    file.flush()
    os.fsync(file.fileno())
    return record


def _write_scenarios(folder: Path, cases: Sequence[Case]) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for case in cases:
        header = (f"# MotionBenchMaker {case.problem.name}, {case.variant}"
                  f"{'' if case.removed is None else f' ({case.removed} removed)'}; obstacles: "
                  f"{', '.join(case.obstacle_names)}\n")
        path = folder / f"{case.problem.type}_{case.problem.number:04d}.yaml"
        path.write_text(header + yaml.safe_dump(case.mapping, sort_keys=False, default_flow_style=None),
                        encoding="utf-8")


def _execute(cases: Sequence[Case], jobs: int, cluster: Cluster | None, bar: Progress | None,
             reference: int = 0) -> Iterator[tuple[Case, dict[str, Any]]]:
    """Run ``cases`` over ``jobs`` processes or the cluster, with the ``reference`` filter's
    checks (0: none); yield ``(case, outcome)`` as each finishes."""
    if bar is not None:
        bar.start()
    if not cases:
        return
    with series_executor(jobs, cluster) as executor:
        futures: dict[Future[dict[str, Any]], Case] = {
            executor.submit(run_case, case.mapping, case.check_obstacles,
                            case.problem.goal if reference else None, reference): case for case in cases}
        remaining = set(futures)
        while remaining:
            finished, remaining = wait(remaining, return_when=FIRST_COMPLETED)
            for future in finished:
                case = futures[future]
                try:
                    outcome = future.result()
                except Exception as error:
                    raise RunError(f"{case.problem.name}: {type(error).__name__}: {error}") from error
                if bar is not None:
                    bar.advance()
                yield case, outcome
