"""``dynfab view FILE [--port N]``: the live browser view of a scenario, or the replay of a
recording (``RUN.npz`` from ``dynfab run --record``), served by viser on localhost.

Ports: without ``--port`` the view serves on 8080, or on the next free port when 8080 is
taken (and says so); a taken ``--port N`` is an error (exit 2), since it was asked for.
The server keeps running when the browser tab closes; Ctrl-C (or SIGTERM) stops it with
exit code 0. Invalid input (scenario, recording, port, viser missing): one line on stderr,
exit 2.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from dynfab.scenario.recording import RecordingError, load_recording
from dynfab.scenario.schema import ScenarioError, UrdfRobotSpec, load_scenario

if TYPE_CHECKING:
    from dynfab.viz.robot_visuals import RobotLook
    from dynfab.viz.view_server import View
    from dynfab.viz.view_world import ViewWorld

__all__ = ["add_view_parser", "view_command"]


def add_view_parser(commands: argparse._SubParsersAction) -> None:
    """Register ``view`` with the ``dynfab`` subcommands."""
    view = commands.add_parser("view", help="serve the live browser view of a scenario (drag goals and "
                                            "obstacles, switch planners) or replay a recording")
    view.add_argument("file", type=Path, help="scenario YAML file, or a recording RUN.npz to replay")
    view.add_argument("--port", type=_port, help="port on localhost (default 8080, or the next free one)")
    view.add_argument("--scenario", type=Path, help="with a recording: its scenario file (default: the file "
                                                    "the recording names)")


def view_command(args: argparse.Namespace) -> int:
    """Serve until Ctrl-C; 0 then, 2 on invalid input."""
    try:
        import viser  # noqa: F401  (only to say clearly that it is missing)
    except ImportError:
        print("dynfab: error: dynfab view needs viser: pip install 'dynfab[view]'", file=sys.stderr)
        return 2
    from dynfab.viz.view_server import PortError, choose_port

    try:
        port, note = choose_port(args.port)
        view = _open_view(args.file, args.scenario, port)
    except (ScenarioError, RecordingError, PortError) as error:
        print(f"dynfab: error: {error}", file=sys.stderr)
        return 2
    if note is not None:
        print(f"dynfab: {note}", file=sys.stderr)
    print(f"dynfab: view of {args.file.name} at {view.url} (Ctrl-C stops)", flush=True)
    # Ctrl-C (SIGINT) and SIGTERM stop the view, also when it was started with SIGINT
    # ignored (a background job of a non-interactive shell inherits that)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _interrupt)
    view.start()
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        view.stop()
        print("dynfab: view stopped", file=sys.stderr)
    return 0


def _open_view(path: Path, scenario_path: Path | None, port: int) -> View:
    """The live view of a scenario file, or the replay of a ``.npz`` recording.

    Raises:
        ScenarioError, RecordingError: invalid files.
    """
    from dynfab.viz.replay_session import ReplaySession, recording_scenario
    from dynfab.viz.view_server import LiveView, ReplayView
    from dynfab.viz.view_session import ViewSession

    if path.suffix == ".npz":
        recording = load_recording(path)
        replay = ReplaySession(recording, recording_scenario(recording, path, scenario_path))
        return ReplayView(replay, _look(replay.world), port, path.name)
    if scenario_path is not None:
        raise ScenarioError("--scenario", "applies to a recording (.npz) only")
    session = ViewSession(load_scenario(path))
    return LiveView(session, _look(session.world), port)


def _look(world: ViewWorld) -> RobotLook:
    """The robot's meshes; says on stderr which mesh files were left out."""
    from dynfab.viz.robot_visuals import robot_look

    spec = world.scenario.robot
    if isinstance(spec, UrdfRobotSpec):
        look = robot_look(world.robot, spec.urdf, spec.package_dirs)
    else:
        look = robot_look(world.robot)
    for line in look.missing[:3]:
        print(f"dynfab: {line}; left out of the view", file=sys.stderr)
    if look.source == "collision spheres":
        print("dynfab: no visual meshes found; the robot is drawn as its collision spheres", file=sys.stderr)
    return look


def _port(text: str) -> int:
    """A TCP port number from the command line."""
    if not text.isdigit() or not 1 <= int(text) <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port number 1..65535, got {text!r}")
    return int(text)


def _interrupt(signum: int, frame: FrameType | None) -> None:
    """SIGTERM stops the view like Ctrl-C."""
    raise KeyboardInterrupt
