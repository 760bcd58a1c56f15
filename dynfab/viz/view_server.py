"""The browser view: a viser server on localhost around a :class:`ViewSession` (live) or a
:class:`ReplaySession` (a recording), with its controls.

A background thread runs the loop: about :data:`FRAME_RATE` times a second it advances
the session by the wall time since the last frame and redraws the scene; the panel's
numbers are refreshed :data:`PANEL_RATE` times a second. GUI and drag callbacks (viser's
threads) and the loop share the session under one lock. Closing the browser tab only
disconnects a client; the server runs until :meth:`View.stop`. With ``perception: camera``
the live view's planner knows the scene through the camera, whose images are rendered in the
loop's thread (:mod:`dynfab.viz.view_camera`), and the view shows the points the planner has;
a replay shows the frustum only.
"""

from __future__ import annotations

import contextlib
import io
import math
import socket
import sys
import threading
import time
from typing import TYPE_CHECKING

import numpy as np

from dynfab.scenario.schema import ScenarioError
from dynfab.viz.replay_session import ReplaySession
from dynfab.viz.robot_visuals import RobotLook
from dynfab.viz.view_camera import CameraView, CameraViewError
from dynfab.viz.view_scene import ViewScene
from dynfab.viz.view_session import ViewSession
from dynfab.viz.view_world import SceneState

if TYPE_CHECKING:
    import viser

HOST = "127.0.0.1"
DEFAULT_PORT = 8080
#: Ports tried after a busy default port.
PORT_ATTEMPTS = 100
FRAME_RATE = 30.0  # [1/s]
PANEL_RATE = 5.0  # [1/s]


class PortError(ValueError):
    """An explicitly requested port is taken, or no port near the default is free."""


def choose_port(requested: int | None) -> tuple[int, str | None]:
    """The port to serve on and, if it is not the one wanted, a line saying why.

    ``requested`` (``--port``) must be free: a taken one is an error, since the user asked
    for it. Without it the default port is used, or the next free one after it.

    Raises:
        PortError: ``requested`` is taken, or none of the :data:`PORT_ATTEMPTS` ports from
            the default on is free.
    """
    if requested is not None:
        if not port_is_free(requested):
            raise PortError(f"--port: port {requested} is taken (by another program); choose another or leave "
                            f"--port out to take the first free one from {DEFAULT_PORT}")
        return requested, None
    for port in range(DEFAULT_PORT, DEFAULT_PORT + PORT_ATTEMPTS):
        if port_is_free(port):
            return port, None if port == DEFAULT_PORT else f"port {DEFAULT_PORT} is taken; serving on {port}"
    raise PortError(f"ports {DEFAULT_PORT} to {DEFAULT_PORT + PORT_ATTEMPTS - 1} are all taken; give one with --port")


def port_is_free(port: int) -> bool:
    """True if a server can listen on ``port`` of :data:`HOST` now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((HOST, port))
        except OSError:
            return False
    return True


class View:
    """A running viser server with a loop thread (subclasses give the session and GUI).

    Attributes:
        server: the viser server.
        port: the port it listens on.
        url: its address.
        scene: the 3-D scene.
        frame_steps: control periods simulated per frame over the last second (live).
    """

    _scene: ViewScene

    def __init__(self, port: int, title: str) -> None:
        import viser

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its own banner; the command prints the URL
            self.server: viser.ViserServer = viser.ViserServer(host=HOST, port=port, label=title, verbose=False)
        self.port = self.server.get_port()
        self.url = f"http://localhost:{self.port}"
        self._lock = threading.RLock()  # GUI values set in the loop call their callbacks at once
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="dynfab-view", daemon=True)

    def start(self) -> None:
        """Start the loop thread."""
        self._thread.start()

    def stop(self) -> None:
        """Stop the loop and the server."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)
        elif self._thread.ident is None:  # the loop never ran: anything rendered, rendered here
            self._close()
        self.server.stop()

    def _loop(self) -> None:
        last = time.perf_counter()
        next_panel = last
        try:
            while not self._stop.is_set():
                now = time.perf_counter()
                with self._lock:
                    self._frame(now - last)
                    if now >= next_panel:
                        self._panel()
                        next_panel = now + 1.0 / PANEL_RATE
                last = now
                self._stop.wait(max(0.0, 1.0 / FRAME_RATE - (time.perf_counter() - now)))
        finally:
            self._close()  # MuJoCo's OpenGL context is freed in the thread it is current in

    def _close(self) -> None:
        """Free what the loop's thread holds (nothing here)."""

    def _frame(self, wall_seconds: float) -> None:
        raise NotImplementedError

    def _panel(self) -> None:
        raise NotImplementedError


class LiveView(View):
    """The planner live in the loop (see :class:`ViewSession`), with drag handles,
    play / pause / reset, a planner switch, a time-scale slider and a status panel."""

    def __init__(self, session: ViewSession, look: RobotLook, port: int) -> None:
        super().__init__(port, f"dynfab view: {session.scenario.path.name if session.scenario.path else 'scenario'}")
        self.session = session
        self._camera = CameraView(session.world) if session.scenario.perception == "camera" else None
        session.sensor = None if self._camera is None else self._sensed
        self._scene = ViewScene(self.server, session.world, look, self.drag_goal, self.drag_obstacle)
        self._steps = 0
        self._rate = math.nan
        self._rate_clock = (time.perf_counter(), 0.0)
        gui = self.server.gui
        self._planner = gui.add_dropdown("Planner", session.planners, initial_value=session.planner)
        self._planner.on_update(lambda _: self.switch_planner(self._planner.value))
        self._play = gui.add_button("Pause")
        self._play.on_click(lambda _: self.toggle_play())
        gui.add_button("Reset").on_click(lambda _: self.reset())
        gui.add_button("Goals and obstacles back").on_click(lambda _: self.restore_references())
        self._time_scale = gui.add_slider("Time scale", min=0.1, max=4.0, step=0.1, initial_value=1.0)
        self._time_scale.on_update(lambda _: self._set_time_scale(self._time_scale.value))
        spheres = gui.add_checkbox("Collision spheres", initial_value=False)
        spheres.on_update(lambda _: self._scene.set_spheres_visible(spheres.value))
        self._status = gui.add_markdown("")
        self._scene.update(session.scene(), moving_only=False)
        self._panel()

    @property
    def goal_handles(self) -> dict[int, viser.TransformControlsHandle]:
        return self._scene.goal_handles

    @property
    def obstacle_handles(self) -> dict[int, viser.TransformControlsHandle]:
        return self._scene.obstacle_handles

    def drag_goal(self, k: int, point: np.ndarray) -> None:
        """What goal ``k``'s handle calls: the goal is at ``point`` now."""
        with self._lock:
            self.session.move_goal(k, point)
            self._scene.draw_paths()

    def drag_obstacle(self, k: int, point: np.ndarray) -> None:
        """What obstacle ``k``'s handle calls: its centre is at ``point`` now."""
        with self._lock:
            self.session.move_obstacle(k, point)
            self._scene.draw_paths()

    def toggle_play(self) -> None:
        with self._lock:
            self.session.playing = not self.session.playing
            self._play.label = "Pause" if self.session.playing else "Play"

    def reset(self) -> None:
        with self._lock:
            self.session.reset()
            self._scene.update(self.session.scene(), moving_only=True)

    def restore_references(self) -> None:
        """Goals and obstacles back on the scenario's references (the handles too)."""
        with self._lock:
            self.session.restore_references()
            self._scene.update(self.session.scene(), moving_only=False)
            self._scene.draw_paths()

    def switch_planner(self, name: str) -> None:
        """What the planner switch calls; a planner built for the first time takes a while."""
        if name == self.session.planner:
            return
        self._status.content = f"building the {name} planner ..."
        with self._lock:
            try:
                self.session.switch_planner(name)
            except ScenarioError as error:
                self.session.message = f"{name}: {error.problem}"

    def _set_time_scale(self, value: float) -> None:
        with self._lock:
            self.session.time_scale = float(value)

    def _sensed(self, state: SceneState) -> np.ndarray:
        """The camera's depth image of ``state`` (the session's sensor). A camera that cannot
        render here stops the simulation with the reason (its planner sees only through it);
        the frame of that tick has no returns."""
        assert self._camera is not None
        try:
            return self._camera.depth(state)
        except CameraViewError as error:
            self.session.message = f"the camera cannot render here ({error}); the planner sees only through it"
            self.session.sensor = None
            camera = self.session.scenario.camera
            assert camera is not None
            return np.zeros((camera.height, camera.width))

    def _close(self) -> None:
        if self._camera is not None:
            self._camera.close()

    def _frame(self, wall_seconds: float) -> None:
        self._steps += self.session.advance(wall_seconds)
        self._scene.update(self.session.scene(), moving_only=True)
        self._scene.show_camera_points(self.session.perceived_points())

    def _panel(self) -> None:
        now = time.perf_counter()
        start, t0 = self._rate_clock
        if now - start >= 1.0:
            self._rate = (self.session.t - t0) / (now - start)
            self._rate_clock = (now, self.session.t)
        status = self.session.status()
        goal = "—" if status.goal_distance is None else f"{status.goal_distance:.3f}"
        lines = [f"**t** {status.t:.2f} s · **planner** {status.planner}",
                 f"**clearance** (spheres) {status.clearance:.3f} m" if math.isfinite(status.clearance)
                 else "**clearance** —",
                 f"**distance to goal** {goal}",
                 f"**step time** {status.step_time_ms:.3f} ms · **real time** ×{self._rate:.2f}"]
        if status.message:
            lines.append(f"**stopped:** {status.message}")
        self._status.content = "  \n".join(lines)


class ReplayView(View):
    """A recording with a time slider, play / pause and a speed slider."""

    def __init__(self, session: ReplaySession, look: RobotLook, port: int, title: str) -> None:
        super().__init__(port, f"dynfab replay: {title}")
        self.session = session
        self._scene = ViewScene(self.server, session.world, look)
        gui = self.server.gui
        dt = session.recording.dt if session.recording.dt > 0 else 0.01
        self._time = gui.add_slider("Time [s]", min=0.0, max=max(session.duration, dt), step=dt, initial_value=0.0)
        self._time.on_update(lambda _: self._seek(self._time.value))
        self._play = gui.add_button("Pause")
        self._play.on_click(lambda _: self._toggle_play())
        speed = gui.add_slider("Speed", min=0.1, max=4.0, step=0.1, initial_value=1.0)
        speed.on_update(lambda _: setattr(self.session, "speed", float(speed.value)))
        spheres = gui.add_checkbox("Collision spheres", initial_value=False)
        spheres.on_update(lambda _: self._scene.set_spheres_visible(spheres.value))
        self._scene.update(session.scene(), moving_only=False)

    def _seek(self, t: float) -> None:
        with self._lock:
            self.session.seek(t)

    def _toggle_play(self) -> None:
        with self._lock:
            if self.session.t >= self.session.duration:
                self.session.seek(0.0)
            self.session.playing = not self.session.playing
            self._play.label = "Pause" if self.session.playing else "Play"

    def _frame(self, wall_seconds: float) -> None:
        playing = self.session.playing
        self.session.advance(wall_seconds)
        if playing and not self.session.playing:
            self._play.label = "Play"
        self._scene.update(self.session.scene(), moving_only=False)

    def _panel(self) -> None:
        if self.session.playing:
            self._time.value = round(self.session.t / self._time.step) * self._time.step
