"""``dynfab plot RUN.npz``: the PNG of a recorded run (``dynfab run --record``), drawn as
``dynfab run --plot`` draws a run: the robot at a few instants, the obstacles, the goal
link's path and the clearance over time."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dynfab.scenario.recording import RecordingError, load_recording
from dynfab.scenario.schema import ScenarioError


def add_plot_parser(commands: argparse._SubParsersAction) -> None:
    plot = commands.add_parser("plot", help="plot a recorded run (dynfab run --record): the robot at a few instants, "
                                            "obstacles, path and clearance")
    plot.add_argument("recording", type=Path, help="a recording written by dynfab run --record")
    plot.add_argument("--scenario", type=Path, help="its scenario file (default: the one the recording names)")
    plot.add_argument("--out", type=Path, help="output PNG (default: the recording's name with .png)")


def plot_command(args: argparse.Namespace) -> int:
    """0 once the PNG is written; 2 on an unreadable recording or scenario."""
    from dynfab.scenario.replay import replay_recording
    from dynfab.viz.result_plot import plot_result

    out = args.out or args.recording.with_suffix(".png")
    try:
        result = replay_recording(load_recording(args.recording), args.scenario)
        if out.parent != Path() and not out.parent.is_dir():
            raise ScenarioError("--out", f"folder {out.parent} does not exist")
    except (RecordingError, ScenarioError) as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return 2
    plot_result(result, out)
    print(f"dynfab: plot written to {out}", file=sys.stderr)
    return 0
