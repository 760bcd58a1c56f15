"""As posed MBM problems of the shared set that the guided fabric once failed, run end to end
and checked on Franka's meshes: a reference threading a shelf (bookshelf_small/0054), a robot
held beside a can (bookshelf_small/0100) and a grasp a third of a millimetre from a cage wall
(cage/0076)."""

from __future__ import annotations

from typing import Any

from dynfab.benchmarks.mbm.franka import franka
from dynfab.benchmarks.mbm.problem_run import run_case
from dynfab.benchmarks.mbm.problems import load_problems
from dynfab.benchmarks.mbm.variants import prepare_case


def _reached_clean(kind: str, number: int) -> dict[str, Any]:
    """Run as posed problem ``number`` of ``kind``; assert it reached its goal, guided, clean on
    the meshes (no collision, self-collision or joint-limit violation); its metrics."""
    problem = next(p for p in load_problems([kind], per_type=1, skip=number - 9) if p.number == number)
    case = prepare_case(problem, "as-posed", franka())
    assert case.invalid is None
    outcome = run_case(case.mapping)
    metrics, check = outcome["metrics"], outcome["check"]
    assert metrics["goal_reached"] and metrics["guided"], (metrics["failure"], metrics["final_distance"])
    assert check["collisions"] == [] and check["self_collisions"] == [] and check["joint_limit_violations"] == []
    assert check["clearance"] > 0.0
    return metrics


def test_a_reference_between_a_shelfs_floor_roof_and_side_is_followed_to_the_grasp() -> None:
    """bookshelf_small/0054 moves the arm between a shelf's floor, roof and side on its way to
    the grasp. With the static shapes' leaves ranging 10 cm the robot was held 0.15 rad off its
    reference and stalled after 7 plans; with ``GUIDED_SHAPE_RANGE`` (5 cm) it followed the
    first two plans to the goal (since guidance plans with tighter spheres at links 5 and 6,
    session 15, the fourth)."""
    metrics = _reached_clean("bookshelf_small", 54)
    assert metrics["plans"] <= 4 and metrics["fallbacks"] == 0


def test_a_grasp_a_third_of_a_millimetre_from_a_cage_wall_is_reached_without_touching_it() -> None:
    """cage/0076: the goal is 0.29 mm clear of a wall on the meshes. The approach's pull had
    integrated 5.7 mrad by the time the reference ended, and kept the robot up to 2 mrad past
    the segment's line for seconds (decaying in 3 s): a finger 0.65 mm into the wall. With the
    integral dropped once the reference has ended it settles at the goal."""
    _reached_clean("cage", 76)
