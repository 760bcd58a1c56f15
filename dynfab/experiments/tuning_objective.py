"""The objective of ``dynfab tune``: success rate first, then time to goal and clearance.

For ``N`` runs of one fabric block, with ``s`` successes (goal reached, no collision),
per-run time to goal ``t_i`` [s] (the run's duration ``T_i`` if the goal was never reached)
and per-run clearance ``c_i`` [m] (the minimum over the run, clipped to ``[0, c_cap]``):

    score = s / N + (T̄ − t̄ + κ c̄) / ((N + 1) (T̄ + κ c_cap)),

with means ``t̄``, ``c̄``, ``T̄`` over the runs and ``κ`` the worth of clearance in time
(:attr:`Objective.clearance_worth`, default 10 s/m: 1 cm of clearance is worth 0.1 s). The
second term lies in ``[0, 1/(N + 1))``, below the ``1/N`` of one success, so the score
orders blocks lexicographically: more successes always win, and among equal success counts
a faster, clearer motion wins. Clearance above ``c_cap`` (default 0.3 m) earns nothing:
a run far from every obstacle should not pull the parameters.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Objective:
    """How time to goal and clearance are traded (module docstring).

    Attributes:
        clearance_worth: ``κ``, seconds of time to goal that 1 m of clearance is worth [s/m].
        clearance_cap: ``c_cap``, clearance beyond which a run earns nothing more [m].
    """

    clearance_worth: float = 10.0
    clearance_cap: float = 0.3

    def __post_init__(self) -> None:
        if not (self.clearance_worth >= 0 and self.clearance_cap > 0):
            raise ValueError(f"Objective: expected clearance_worth >= 0 and clearance_cap > 0, got "
                             f"{self.clearance_worth}, {self.clearance_cap}")


@dataclass(frozen=True)
class Evaluation:
    """One fabric block on a set of scenarios.

    Attributes:
        runs: how many runs.
        successes: runs that reached the goal without collision.
        collisions: runs with a collision.
        deadlocks: runs that neither reached the goal nor collided.
        time_to_goal: ``t̄``, mean time to goal, a run's duration if unreached [s].
        clearance: ``c̄``, mean of the runs' clearances clipped to ``[0, c_cap]`` [m].
        score: the objective (module docstring).
    """

    runs: int
    successes: int
    collisions: int
    deadlocks: int
    time_to_goal: float
    clearance: float
    score: float


def evaluate(metrics: Sequence[Mapping[str, Any]], durations: Sequence[float],
             objective: Objective = Objective()) -> Evaluation:
    """The evaluation of runs given their metrics (as ``dynfab run --json`` prints them) and
    durations [s].

    Raises:
        ValueError: no runs, or not one duration per run.
    """
    n = len(metrics)
    if n == 0 or len(durations) != n:
        raise ValueError(f"evaluate: expected one duration per run and at least one run, got {n} runs and "
                         f"{len(durations)} durations")
    successes = sum(bool(m["success"]) for m in metrics)
    collisions = sum(bool(m["collision"]) for m in metrics)
    reached = [m["time_to_goal"] is not None and bool(m["goal_reached"]) for m in metrics]
    times = [float(m["time_to_goal"]) if ok else float(d) for m, ok, d in zip(metrics, reached, durations)]
    clearances = [min(max(_clearance(m), 0.0), objective.clearance_cap) for m in metrics]
    mean_time, mean_clearance = sum(times) / n, sum(clearances) / n
    horizon = sum(durations) / n
    kappa = objective.clearance_worth
    tie = (horizon - mean_time + kappa * mean_clearance) / ((n + 1) * (horizon + kappa * objective.clearance_cap))
    return Evaluation(runs=n, successes=successes, collisions=collisions,
                      deadlocks=sum(not ok and not m["collision"] for m, ok in zip(metrics, reached)),
                      time_to_goal=mean_time, clearance=mean_clearance, score=successes / n + tie)


def _clearance(metrics: Mapping[str, Any]) -> float:
    """The run's clearance [m]; a run without obstacles (``None`` or infinite) has all of it."""
    value = metrics["clearance"]
    return float("inf") if value is None else float(value)
