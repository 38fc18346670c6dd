"""A recorded session played back in the browser (`hrp2-console replay SESSION --view`): the robot drawn from the
recorded telemetry (the simulated BODY pose and the encoders, through the scene's MuJoCo kinematics), the COG,
ZMP and capture points, with a time slider, play / pause and the playback speed. Scene objects stay where the
scene puts them (their poses are not in the log row)."""

from __future__ import annotations

import logging
import math
import threading
import time

import mujoco
import numpy as np
import viser

from app.console.viewer_meshes import add_model
from app.service.log_row import column
from app.session.reader import Session
from robot.names import BASE_LINK, JOINT_NAMES
from robot.plant import scene_path

log = logging.getLogger(__name__)

SPEEDS = ("0.1", "0.25", "0.5", "1", "2", "4", "10")  # playback speeds offered (x real time)
_Q = [column(f"joints/q_meas_rad/{n}") for n in JOINT_NAMES]
_POS = [column(f"base/pos_sim_m/{k}") for k in "xyz"]
_QUAT = [column(f"base/quat_sim/{k}") for k in "wxyz"]
_MARKERS = {"cog": ("balance/cog_act_m", (255, 140, 0), 0.03), "zmp": ("balance/zmp_act_m", (40, 200, 60), 0.02),
            "cp_ref": ("balance/cp_ref_m", (30, 110, 255), 0.015), "cp_act": ("balance/cp_act_m", (230, 30, 60), 0.015)}
_FLAGS = ("hard_stop", "cp_flag", "motion_stop", "walking_stop", "walking", "fall_detected", "fault")


class ReplayViewer:
    """A viser server playing `session` back; `slider` (session time [s]) is the one thing that moves the robot:
    playback moves it, and so does the operator dragging it."""

    def __init__(self, session: Session, host: str = "127.0.0.1", port: int = 8080, speed: float = 1.0,
                 rate_hz: float = 25.0) -> None:
        if session.ticks == 0:
            raise ValueError("the session has no whole tick to show")
        self.session = session
        self.dt_s = session.dt_s
        self.rate_hz = float(rate_hz)
        scene = session.header.get("scene", "default")
        self.model = mujoco.MjModel.from_xml_path(str(scene_path(scene)))
        self.data = mujoco.MjData(self.model)
        keys = [self.model.key(i).name for i in range(self.model.nkey)]
        if "home" in keys:
            mujoco.mj_resetDataKeyframe(self.model, self.data, keys.index("home"))
        self._qadr = np.array([self.model.joint(n).qposadr[0] for n in JOINT_NAMES])
        base_joint = self.model.body(BASE_LINK).jntadr[0]
        self._base_adr = int(self.model.jnt_qposadr[base_joint])
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.port = self.server.get_port()
        self.server.scene.set_up_direction("+z")
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self._frames, _ = add_model(self.server.scene, self.model)
        self._markers = {k: self.server.scene.add_icosphere(f"/markers/{k}", radius=r, color=c, subdivisions=1,
                                                            cast_shadow=False, receive_shadow=False)
                         for k, (_, c, r) in _MARKERS.items()}
        self.tick = -1
        self.playing = False
        self._lock = threading.Lock()
        self._build_gui(speed)
        self.seek(0)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="replay-viewer", daemon=True)
        self._thread.start()

    # ---- what is drawn --------------------------------------------------------------------------------------
    def time_of(self, tick: int) -> float:
        """Session time [s] after `tick` (the slider's unit)."""
        return (tick + 1) * self.dt_s

    def tick_at(self, time_s: float) -> int:
        return int(min(self.session.ticks - 1, max(0, round(time_s / self.dt_s) - 1)))

    def seek(self, tick: int) -> None:
        """Draw the robot as it was after `tick`."""
        tick = int(min(self.session.ticks - 1, max(0, tick)))
        row = self.session.rows[tick]
        with self._lock:
            self.tick = tick
            d = self.data
            d.qpos[self._base_adr:self._base_adr + 3] = row[_POS]
            d.qpos[self._base_adr + 3:self._base_adr + 7] = row[_QUAT]
            d.qpos[self._qadr] = row[_Q]
            mujoco.mj_kinematics(self.model, d)
            with self.server.atomic():
                for b, frame in enumerate(self._frames, start=1):
                    frame.position = d.xpos[b]
                    frame.wxyz = d.xquat[b]
                floor = float(row[column("balance/zmp_act_m/z")]) if math.isfinite(row[column("balance/zmp_act_m/z")]) \
                    else 0.0
                for key, (signal, _, _) in _MARKERS.items():
                    xyz = [row[column(f"{signal}/{a}")] for a in "xyz"] if key in ("cog", "zmp") else \
                        [row[column(f"{signal}/x")], row[column(f"{signal}/y")], floor]
                    handle = self._markers[key]
                    ok = all(math.isfinite(v) for v in xyz)
                    if ok:
                        handle.position = np.asarray(xyz, dtype=float)
                    handle.visible = ok
            self._readout.content = self._describe(tick, row)

    def body_position(self, name: str) -> np.ndarray:
        """Where body `name` is drawn now (world [m])."""
        return np.asarray(self._frames[self.model.body(name).id - 1].position, dtype=float)

    def _describe(self, tick: int, row: np.ndarray) -> str:
        flags = [f for f in _FLAGS if row[column(f"flags/{f}")] > 0.5]
        cp = row[column("balance/cp_error_m")]
        inputs = [d["name"] for d in self.session.inputs if int(d["tick"]) == tick + 1]
        text = (f"tick **{tick}** / {self.session.ticks - 1}, controller time {row[0]:.3f} s; "
                f"CP error {'-' if not math.isfinite(cp) else f'{1e3 * cp:.1f} mm'}; "
                f"flags: {', '.join(flags) or 'none'}")
        return text + (f"; inputs next: {', '.join(inputs)}" if inputs else "")

    # ---- the panel ------------------------------------------------------------------------------------------
    def _build_gui(self, speed: float) -> None:
        gui = self.server.gui
        s = self.session
        gui.add_markdown(f"**Session replay**: {s.path.name if s.path else ''} ({s.header.get('scene')}, "
                         f"{s.ticks} ticks, {len(s.inputs)} inputs{'' if s.complete else ', not finished'})")
        end = self.time_of(s.ticks - 1)
        self.slider = gui.add_slider("time [s]", min=self.dt_s, max=max(end, 2 * self.dt_s), step=self.dt_s,
                                     initial_value=self.dt_s)
        self.play = gui.add_button("Play / pause")
        shown = min(SPEEDS, key=lambda v: abs(float(v) - speed))
        self.speed = gui.add_dropdown("speed [x real time]", SPEEDS, initial_value=shown)
        self._readout = gui.add_markdown("")

        @self.slider.on_update
        def _(event) -> None:
            if event.client is not None:  # the operator dragged it: stop playing there
                self.playing = False
            self.seek(self.tick_at(float(self.slider.value)))

        @self.play.on_click
        def _(_event) -> None:
            if not self.playing and self.tick >= self.session.ticks - 1:
                self.slider.value = self.time_of(0)  # at the end: from the start again
            self.playing = not self.playing

    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        last = time.monotonic()
        while not self._stop.wait(period):
            now = time.monotonic()
            wall, last = now - last, now
            if not self.playing:
                continue
            try:
                t = float(self.slider.value) + float(self.speed.value) * wall
                end = self.time_of(self.session.ticks - 1)
                if t >= end:
                    t, self.playing = end, False
                self.slider.value = round(t / self.dt_s) * self.dt_s
            except Exception:  # noqa: BLE001 - keep playing whatever one frame did
                log.exception("replay viewer frame failed")

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.server.stop()
