"""Per-arm table of an ``arms-pose`` series: ``python -m dynfab.experiments.arm_table DIR``
reads ``DIR/runs.jsonl`` and prints one Markdown row per arm (seed ``s`` is arm
``POSE_ARM_NAMES[s % 6]``) and one for all: success, collisions and self-collisions on the
meshes, runs guided, plans, failures by reason, minimum mesh clearance and self distance,
time to goal and first-plan time."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dynfab.experiments.arms_pose import POSE_ARM_NAMES

HEADER = ("| arm | success | collisions | self-collisions | guided | failures | min clearance [m] "
          "| min self distance [m] | time to goal [s] | plan time median (max) [ms] |\n"
          "|---|---|---|---|---|---|---|---|---|---|")


@dataclass(frozen=True)
class ArmRow:
    """The runs of one arm (or all), as one table row."""

    name: str
    runs: tuple[dict[str, Any], ...]

    def render(self) -> str:
        """The Markdown row."""
        n = len(self.runs)
        count = lambda key: sum(bool(m.get(key)) for m in self.runs)  # noqa: E731
        failures: dict[str, int] = {}
        for m in self.runs:
            if not m["success"]:
                reason = m.get("failure") or ("collision" if m["collision"] or m["self_collision"] else "not reached")
                failures[reason] = failures.get(reason, 0) + 1
        times = [m["time_to_goal"] for m in self.runs if m["time_to_goal"] is not None]
        plans = [m["plan_time_ms"] for m in self.runs if m.get("plan_time_ms") is not None]
        time_text = f"{np.mean(times):.2f} ± {np.std(times):.2f}" if times else "-"
        plan_text = f"{np.median(plans):.0f} ({np.max(plans):.0f})" if plans else "-"
        return (f"| {self.name} | {count('success')}/{n} | {count('collision')} | {count('self_collision')} "
                f"| {count('guided')}/{n} | {', '.join(f'{k} {v}' for k, v in sorted(failures.items())) or '-'} "
                f"| {_minimum(self.runs, 'clearance')} | {_minimum(self.runs, 'min_self_distance')} "
                f"| {time_text} | {plan_text} |")

def _minimum(runs: Sequence[dict[str, Any]], key: str) -> str:
    values = [m[key] for m in runs if m.get(key) is not None]
    return f"{min(values):.3f}" if values else "-"


def arm_table(runs_jsonl: Path) -> str:
    """The Markdown table of a series' ``runs.jsonl`` (module docstring)."""
    lines = [json.loads(line) for line in runs_jsonl.read_text(encoding="utf-8").splitlines() if line.strip()]
    by_arm: dict[str, list[dict[str, Any]]] = {name: [] for name in POSE_ARM_NAMES}
    for line in lines:
        by_arm[POSE_ARM_NAMES[line["seed"] % len(POSE_ARM_NAMES)]].append(line["metrics"])
    rows = [ArmRow(name, tuple(runs)) for name, runs in by_arm.items() if runs]
    rows.append(ArmRow("all", tuple(m for runs in by_arm.values() for m in runs)))
    return "\n".join([HEADER] + [row.render() for row in rows])


if __name__ == "__main__":
    print(arm_table(Path(sys.argv[1]) / "runs.jsonl"))
