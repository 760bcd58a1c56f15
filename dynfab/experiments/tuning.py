"""Tune the ``fabric:`` parameters of an experiment with Optuna (``dynfab tune``).

Each trial draws a ``fabric:`` block from :data:`~dynfab.experiments.tuning_space.SEARCH_SPACE`
(a seeded TPE sampler; the planner's defaults are the first trial), runs the experiment's
*training* scenarios with it (seeds ``train_seed .. train_seed + train - 1`` of the
experiment's sampler) in local processes or on a Dask cluster
(:mod:`dynfab.experiments.cluster`), and scores them
(:mod:`dynfab.experiments.tuning_objective`). At the end the best block and the defaults
run on the *held-out* scenarios (a disjoint seed range) for the report.

The study lives in an SQLite file: rerunning the same command continues it. ``trials`` is
the number of finished trials the study should hold; a trial cut short by a kill is marked
failed and its parameters run again. The study remembers its setup (experiment, planner,
seeds, durations, objective, search space) and refuses another; held-out results are
stored in it too, so a finished study reports at once.
"""

from __future__ import annotations

import dataclasses
import fcntl
import json
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from dynfab.experiments.cluster import Cluster, series_executor
from dynfab.experiments.registry import Experiment
from dynfab.experiments.series import run_scenario_text
from dynfab.experiments.tuning_objective import Evaluation, Objective, evaluate
from dynfab.experiments.tuning_space import SEARCH_SPACE, block_of, default_values, space_description

if TYPE_CHECKING:
    from concurrent.futures import Executor

    import optuna

Block = dict[str, dict[str, float]]


class TuningError(ValueError):
    """The tuning cannot start: optuna missing, a study of another setup, overlapping seeds."""


@dataclass(frozen=True)
class TuningSetup:
    """What a study tunes, and on which scenarios.

    Attributes:
        experiment: the experiment (its sampler draws the scenarios).
        planner: the fabric planner tuned (``static-fabric`` or ``dynamic-fabric``).
        train: number of training scenarios; ``train_seed`` the first one's seed.
        held_out: number of held-out scenarios; ``held_out_seed`` the first one's seed.
        duration: simulated time of every run [s]; ``None`` keeps the experiment's.
        sampler_seed: seed of the TPE sampler.
        objective: how time to goal and clearance are traded.
    """

    experiment: Experiment
    planner: str
    train: int = 40
    train_seed: int = 100_000
    held_out: int = 100
    held_out_seed: int = 0
    duration: float | None = None
    sampler_seed: int = 0
    objective: Objective = Objective()

    def __post_init__(self) -> None:
        if self.planner not in ("static-fabric", "dynamic-fabric"):
            raise TuningError(f"--planner: expected static-fabric or dynamic-fabric, got {self.planner!r}")
        if self.train < 1 or self.held_out < 1:
            raise TuningError(f"--train and --held-out must be >= 1, got {self.train} and {self.held_out}")
        if self.train_seed < self.held_out_seed + self.held_out and self.held_out_seed < self.train_seed + self.train:
            raise TuningError(f"training seeds {_seed_range(self.train_seed, self.train)} overlap held-out seeds "
                              f"{_seed_range(self.held_out_seed, self.held_out)}")

    @property
    def training_seeds(self) -> range:
        return range(self.train_seed, self.train_seed + self.train)

    @property
    def held_out_seeds(self) -> range:
        return range(self.held_out_seed, self.held_out_seed + self.held_out)

    def description(self) -> dict[str, Any]:
        """The setup as plain values, stored with the study."""
        return {"experiment": self.experiment.name, "planner": self.planner, "train": self.train,
                "train_seed": self.train_seed, "held_out": self.held_out, "held_out_seed": self.held_out_seed,
                "duration": self.duration, "sampler_seed": self.sampler_seed,
                "objective": dataclasses.asdict(self.objective), "space": space_description()}

    def scenarios(self, seeds: Sequence[int]) -> list[dict[str, Any]]:
        """The scenario-file mappings of ``seeds`` (without a ``fabric:`` block)."""
        drawn = [dict(self.experiment.sampler(seed, self.planner)) for seed in seeds]
        return drawn if self.duration is None else [{**data, "duration": self.duration} for data in drawn]


@dataclass(frozen=True)
class TuningResult:
    """A finished study.

    Attributes:
        trials: finished trials in the study.
        executed: trials this call ran.
        best_trial: number of the best trial.
        best_block: its ``fabric:`` block.
        training: (defaults, best) on the training scenarios.
        held_out: (defaults, best) on the held-out scenarios.
    """

    trials: int
    executed: int
    best_trial: int
    best_block: Block
    training: tuple[Evaluation, Evaluation]
    held_out: tuple[Evaluation, Evaluation]


def tune(setup: TuningSetup, trials: int, study_path: Path, jobs: int = 1, cluster: Cluster | None = None,
         progress: Callable[[str], None] = lambda line: None) -> TuningResult:
    """Run the study at ``study_path`` until it holds ``trials`` finished trials, then
    evaluate the best block and the defaults on the held-out scenarios (module docstring).

    Raises:
        TuningError: optuna is missing, the study holds another setup or another process
            tunes it, or ``trials`` < 1.
        ClusterError: the Dask cluster cannot be used.
    """
    if trials < 1:
        raise TuningError(f"--trials must be >= 1, got {trials}")
    optuna = _optuna()
    study_path.parent.mkdir(parents=True, exist_ok=True)
    with _exclusive(study_path), series_executor(jobs, cluster) as executor:
        study = _study(optuna, setup, study_path)
        distributions = {d.key: optuna.distributions.FloatDistribution(d.low, d.high, log=d.log) for d in SEARCH_SPACE}
        done = _finished(study, optuna)
        progress(f"tuning {setup.experiment.name} ({setup.planner}) in {study_path}: {trials} trials "
                 f"({len(done)} finished) on {setup.train} training scenarios, then {setup.held_out} held-out")
        training_scenarios = setup.scenarios(setup.training_seeds)
        executed = 0
        while len(done) < trials:
            trial = study.ask(distributions)
            block = block_of(trial.params)
            start = time.perf_counter()
            try:
                evaluation = run_block(executor, training_scenarios, block, setup.objective)
            except BaseException:  # Ctrl-C or a failed run: the trial runs again on the next call
                _fail_and_requeue(study, optuna, trial.number, trial.params, trial.user_attrs)
                raise
            trial.set_user_attr("evaluation", dataclasses.asdict(evaluation))
            study.tell(trial, evaluation.score)
            executed += 1
            done = _finished(study, optuna)
            progress(f"trial {trial.number} ({len(done)}/{trials}): {_summary(evaluation)}; best score "
                     f"{study.best_value:.5f} (trial {study.best_trial.number}); {time.perf_counter() - start:.1f} s")
        best = study.best_trial
        best_block = block_of(best.params)
        default = next(t for t in done if t.user_attrs.get("default"))
        training = (Evaluation(**default.user_attrs["evaluation"]), Evaluation(**best.user_attrs["evaluation"]))
        held_out = tuple(_held_out(study, executor, setup, block, progress) for block in ({}, best_block))
    return TuningResult(len(done), executed, best.number, best_block, training, held_out)  # type: ignore[arg-type]


def run_block(executor: Executor, scenarios: Sequence[dict[str, Any]], block: Block,
              objective: Objective) -> Evaluation:
    """Run ``scenarios`` (scenario-file mappings) with the ``fabric:`` block ``block`` (none
    if empty) on ``executor`` and evaluate them."""
    texts = [yaml.safe_dump({**data, "fabric": block} if block else data, sort_keys=False) for data in scenarios]
    futures = [executor.submit(run_scenario_text, text, str(Path.cwd()), False) for text in texts]
    metrics = [future.result()[0] for future in futures]
    return evaluate(metrics, [float(data["duration"]) for data in scenarios], objective)


def _optuna() -> Any:
    try:
        import optuna
    except ImportError:
        raise TuningError("dynfab tune needs optuna: pip install 'dynfab[tune]'") from None
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna


def _study(optuna: Any, setup: TuningSetup, path: Path) -> optuna.Study:
    """The study at ``path`` (created with the defaults as its first trial); trials a kill
    left running are marked failed and their parameters queued again. The sampler's seed is
    the setup's plus the number of trials the study already holds.

    Raises:
        TuningError: the study was made for another setup.
    """
    study = optuna.create_study(storage=f"sqlite:///{path.resolve()}", direction="maximize",
                                study_name="dynfab-tune", load_if_exists=True)
    # a resumed study must not draw the first session's random trials again
    study.sampler = optuna.samplers.TPESampler(seed=setup.sampler_seed + len(study.trials), multivariate=True)
    described = json.loads(json.dumps(setup.description()))
    stored = study.user_attrs.get("setup")
    if stored is None:
        study.set_user_attr("setup", described)
        defaults = default_values(setup.scenarios([setup.train_seed])[0])
        study.enqueue_trial(defaults, user_attrs={"default": True})
    elif stored != described:
        changed = sorted(key for key in described if stored.get(key) != described[key])
        raise TuningError(f"--study: {path} tunes another setup (differs in {', '.join(changed)}); "
                          f"use another --study file")
    for trial in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
        _fail_and_requeue(study, optuna, trial.number, trial.params, trial.user_attrs)
    return study


def _fail_and_requeue(study: optuna.Study, optuna: Any, number: int, params: dict[str, Any],
                      user_attrs: dict[str, Any]) -> None:
    """Mark trial ``number`` failed and queue its parameters again (the defaults stay the
    defaults)."""
    study.tell(number, state=optuna.trial.TrialState.FAIL)
    study.enqueue_trial(params, user_attrs={key: value for key, value in user_attrs.items() if key == "default"})


def _finished(study: optuna.Study, optuna: Any) -> list[optuna.trial.FrozenTrial]:
    return study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))


def _held_out(study: optuna.Study, executor: Executor, setup: TuningSetup, block: Block,
              progress: Callable[[str], None]) -> Evaluation:
    """``block`` on the held-out scenarios, run once and then read from the study."""
    key = "held_out " + json.dumps(block, sort_keys=True)
    stored = study.user_attrs.get(key)
    if stored is not None:
        return Evaluation(**stored)
    start = time.perf_counter()
    evaluation = run_block(executor, setup.scenarios(setup.held_out_seeds), block, setup.objective)
    study.set_user_attr(key, dataclasses.asdict(evaluation))
    progress(f"held-out, {'tuned' if block else 'defaults'}: {_summary(evaluation)}; "
             f"{time.perf_counter() - start:.1f} s")
    return evaluation


def _summary(evaluation: Evaluation) -> str:
    return (f"{evaluation.successes}/{evaluation.runs} succeeded, time to goal {evaluation.time_to_goal:.2f} s, "
            f"clearance {evaluation.clearance:.3f} m, score {evaluation.score:.5f}")


@contextmanager
def _exclusive(study_path: Path) -> Iterator[None]:
    """Hold ``<study>.lock``: one process tunes a study at a time.

    Raises:
        TuningError: another process holds it.
    """
    lock = study_path.with_name(study_path.name + ".lock")
    with lock.open("w") as file:
        try:
            fcntl.flock(file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise TuningError(f"--study: another dynfab tune is running on {study_path}") from None
        yield


def _seed_range(first: int, count: int) -> str:
    return f"{first}..{first + count - 1}"
