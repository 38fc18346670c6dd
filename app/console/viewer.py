"""The viser 3D view: MuJoCo bodies moved from ground truth, E-STOP panel, markers and the capture-point plot.

The pieces it draws with live beside it: the MuJoCo geoms (app/console/viewer_meshes.py, which
app/lab/replay_viewer.py plays a recorded session back with), the markers (app/console/viewer_markers.py), the
capture-point plot (app/console/viewer_plots.py), the camera following the robot (app/console/viewer_camera.py)
and the websocket's origin check (app/console/viewer_origin.py); these and the replay are the only modules that
import viser.

It runs in the console process: the geometry comes from the scene's model file, the poses from the robot's
published snapshots, and its buttons call the operator service like every other client. Its websocket only
accepts the console's own origins (a foreign page cannot drive the robot through it)."""

from __future__ import annotations

import logging
import threading
import time

import mujoco
import viser

from app.console.viewer_camera import FOLLOWED_BODY, CameraFollower
from app.console.viewer_markers import (
    MAX_FOOTSTEPS,
    BalanceMarkers,
    RecognitionMarkers,
    footstep_rectangles,
    ray_at_height,
)
from app.console.viewer_meshes import add_model
from app.console.viewer_origin import viser_with_origin_check
from app.console.viewer_plots import PLOT_RANGE_MM, PLOT_RATE_HZ, CpErrorHistory, add_cp_plot, cp_legend
from app.console.viewer_preview import PreviewGhost
from app.console.viser_wakeup import wake_stuck_buffers
from app.service import OperatorService, ServiceError
from robot.plant import scene_path

#: names other modules and the tests take from here (defined in the app.console.viewer_* modules)
__all__ = ["MAX_FOOTSTEPS", "PLOT_RANGE_MM", "PLOT_RATE_HZ", "CameraFollower", "CpErrorHistory", "Viewer", "add_model",
           "footstep_rectangles", "ray_at_height"]

log = logging.getLogger(__name__)

STOP_PANEL_WIDTH_PX = 200  # the 3D view's own E-STOP panel: narrow, in a corner of the view
WAKE_PERIOD_S = 0.5  # [s] how often a viser sender that missed its wake-up is looked for (app/console/viser_wakeup.py)


class Viewer:
    """viser server showing the robot; body poses are pushed in one atomic batch at `rate_hz`."""

    def __init__(self, service: OperatorService, host: str = "127.0.0.1", port: int = 8080, rate_hz: float = 25.0):
        self.service = service
        self.rate_hz = float(rate_hz)
        self._host = host
        self._page_ports: set[int] = set()
        self.server = viser_with_origin_check(host, port, self._page_ports)
        self.port = self.server.get_port()
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.scene.set_up_direction("+z")
        self._frames: list[viser.FrameHandle] = []
        self._scene_nodes: list = []
        self._model_key: tuple[str, ...] = ()
        self._model: mujoco.MjModel | None = None
        self._cp_history = CpErrorHistory()
        self._recognitions = RecognitionMarkers(self.server.scene)
        self._plot_updates = 0
        self._follower = CameraFollower()
        self._balance_markers = BalanceMarkers(self.server.scene)
        self.ghost = PreviewGhost(self.server.scene)  # a behaviour's preview (app/console/viewer_preview.py)
        self._build_scene()
        self._build_gui()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="viser-update", daemon=True)
        self._thread.start()

    def allow_page(self, port: int) -> None:
        """Accept the websocket of the operator page served on `port` of the same host (its /viewer/ iframe)."""
        self._page_ports.add(int(port))

    # ---- scene --------------------------------------------------------------------------------
    def _build_scene(self) -> None:
        for node in self._scene_nodes:
            node.remove()
        model = mujoco.MjModel.from_xml_path(str(scene_path(self.service.info.scene)))
        self._model = model
        self._scene = self.service.info.scene
        names = tuple(model.body(b).name for b in range(model.nbody))
        self._model_key = names
        self._followed = names.index(FOLLOWED_BODY) if FOLLOWED_BODY in names else None
        self._frames, self._scene_nodes = add_model(self.server.scene, model)
        try:
            self._apply_poses(self.service.observation().truth)
        except ServiceError:
            pass

    def _apply_poses(self, truth) -> None:
        with self.server.atomic():
            self._set_body_poses(truth)

    def _set_body_poses(self, truth) -> bool:
        """False (nothing drawn) for a snapshot of another model than the one drawn: around a reset to another
        scene, the scene's name and the snapshots change at different moments."""
        pos, quat = truth.body_pos_world, truth.body_quat_wxyz
        if len(pos) != len(self._frames) + 1:
            return False
        for b, frame in enumerate(self._frames, start=1):
            frame.position = pos[b]
            frame.wxyz = quat[b]
        return True

    def apply_snapshot(self, snap) -> None:
        """Body poses and the balance markers of one observation (a snapshot with the ground truth beside it),
        in one atomic batch."""
        with self.server.atomic():
            if self._set_body_poses(snap.truth):
                self._balance_markers.update(snap)

    # ---- markers (app/console/viewer_markers.py) --------------------------------------------------------
    @property
    def _markers(self) -> dict:
        """The balance markers' handles: name -> viser handle."""
        return self._balance_markers.handles

    @property
    def _recognition_markers(self) -> dict[str, tuple]:
        """object -> (sphere, label, position shown)."""
        return self._recognitions.shown

    def _update_recognitions(self, recognitions) -> None:
        self._recognitions.update(recognitions)

    # ---- GUI ----------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        # the 3D view unobstructed: the main panel (status, CP plot, corrections) starts as a bar, one click away
        gui.main_panel.minimize()
        # its E-STOP stays in sight, in a small panel of its own in the view's top right corner
        stop_panel = gui.add_panel()
        with stop_panel.add_tab("E-STOP"):
            self._estop = gui.add_button("E-STOP", color="red", icon=None, hint="Freeze the joint command now")
            self._release = gui.add_button("Release", color="gray", hint="Release the hard e-stop")
        stop_panel.float(x=-10, y=10, width=STOP_PANEL_WIDTH_PX)
        gui.add_markdown("**HRP-2 No.10**: status (the page's plots panel has the CP error too)")
        self._follow = gui.add_checkbox("follow the robot", True, hint="keep the view on the robot (BODY) as it "
                                        "walks; your orbit and zoom are kept")

        @self._follow.on_update
        def _(_event) -> None:
            self._follower.restart()
        self._time = gui.add_text("time [s]", "0.000", disabled=True)
        self._hard_stop = gui.add_checkbox("hard stop", False, disabled=True)
        self._fallen = gui.add_checkbox("fallen", False, disabled=True)
        self._fault = gui.add_text("fault", "none", disabled=True)
        self._message = gui.add_text("last action", "", disabled=True)
        try:
            self._cp_history.add(self.service.observation())
        except ServiceError:
            pass
        self._cp_plot = add_cp_plot(gui, self._cp_history)
        self._cp_values = gui.add_markdown(cp_legend(self._cp_history))
        # [OP] II: the operator corrects a recognition by clicking where the object is (at its estimated height)
        self._correct_object = gui.add_dropdown("object", ("can", "trash_box"), initial_value="can")
        self._correct_click = gui.add_button("Correct it: click where it is", hint="then click the object in the "
                                             "3D view: its position becomes what later behaviours use")

        @self._correct_click.on_click
        def _(_event) -> None:
            name = self._correct_object.value

            @self.server.scene.on_pointer_event("click")
            def _(event) -> None:
                self.server.scene.remove_pointer_callback()
                self._message.value = self.correct_by_ray(name, event.ray_origin, event.ray_direction)

            self._message.value = f"click where the {name} is"

        @self._estop.on_click
        def _(_event) -> None:
            self.press_estop()

        @self._release.on_click
        def _(_event) -> None:
            self._command("e-stop released", self.service.release_estop)

    def correct_by_ray(self, name: str, origin, direction) -> str:
        """The recognition of `name` moved to where the clicked ray meets its estimated height; what it says."""
        try:
            rec = self.service.recognitions().get(name)
            if rec is None:
                return f"no recognition of {name} to correct (locate it first)"
            p = ray_at_height(origin, direction, float(rec["position_m"][2]))
            if p is None:
                return f"that click does not reach the {name}'s height ({rec['position_m'][2]:.3f} m)"
            self.service.confirm_recognition(name, [float(v) for v in p])
            return f"{name} corrected to ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m"
        except ServiceError as exc:
            return str(exc)

    def press_estop(self) -> None:
        """The panel's E-STOP: every click a new press (app.service.estop), the loop's answer shown."""
        self._command(None, lambda: self.service.estop().message)

    def _command(self, done: str | None, fn) -> None:
        """Runs in viser's thread pool: a verb of the operator service, like an HTTP request."""
        try:
            said = fn()
            self._message.value = done if done is not None else str(said)
        except ServiceError as exc:
            self._message.value = str(exc)
        except Exception as exc:  # noqa: BLE001 - a GUI click never kills anything
            log.exception("viewer command failed")
            self._message.value = f"{type(exc).__name__}: {exc}"

    def _update_gui(self, snap) -> None:
        t = f"{snap.time_s:.3f}"
        if self._time.value != t:
            self._time.value = t
        hard = bool(snap.safety.hard_stop)
        if self._hard_stop.value != hard:
            self._hard_stop.value = hard
        if self._fallen.value != bool(snap.fallen):
            self._fallen.value = bool(snap.fallen)
        fault = snap.fault or "none"
        if self._fault.value != fault:
            self._fault.value = fault

    def follow(self, truth) -> int:
        """The clients' cameras kept on the followed body (when the toggle is on); how many moved."""
        if not self._follow.value or self._followed is None:
            return 0
        clients = self.server.get_clients()
        return self._follower.update({cid: c.camera for cid, c in clients.items()},
                                     truth.body_pos_world[self._followed][:2], atomic=lambda cid: clients[cid].atomic())

    def _update_plot(self, snap) -> None:
        if self._cp_history.add(snap):
            self._cp_plot.data = self._cp_history.data()
            self._plot_updates += 1
            if self._plot_updates % 5 == 0:
                self._cp_values.content = cp_legend(self._cp_history)

    # ---- background update ----------------------------------------------------------------------
    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        last_tick, n = -1, 0
        due = time.monotonic()
        while True:  # on a fixed schedule (the work of a round does not stretch the period)
            due = max(due + period, time.monotonic())
            if self._stop.wait(due - time.monotonic()):
                break
            try:
                if self.service.info.scene != self._scene:
                    self._build_scene()  # the simulation was reset to another scene
                snap = self.service.observation()
                if snap.tick != last_tick:
                    self.apply_snapshot(snap)
                    self.follow(snap.truth)
                    last_tick = snap.tick
                n += 1
                if n % max(1, int(self.rate_hz / 5)) == 0:
                    self._update_gui(snap)
                    self._update_recognitions(self.service.recognitions())
                    self.ghost.update(*self.service.ghost())
                if n % max(1, round(self.rate_hz / PLOT_RATE_HZ)) == 0:
                    self._update_plot(snap)
                if n % max(1, round(self.rate_hz * WAKE_PERIOD_S)) == 0:
                    wake_stuck_buffers(self.server)  # viser 1.1.1's lost wake-up (app/console/viser_wakeup.py)
            except ServiceError:  # the robot process is gone or restarting: try again shortly
                time.sleep(0.5)
            except Exception:  # noqa: BLE001 - keep drawing whatever happens
                log.exception("viewer update failed")
                time.sleep(0.5)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.server.stop()
