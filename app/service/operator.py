"""The operator service (`OperatorService`): the one door into the robot. HTTP routers, the viser view, the CLI,
the experiments and the benchmarks call its named verbs; it checks each verb once, hands it to the robot (its own
process, or this one) to run at a tick boundary, and returns the result or the service's own error."""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, Protocol

import numpy as np

from app.service.errors import NotFound, Refused, Superseded, Unavailable
from app.service.estop import EstopAck, EstopRequest
from app.service.estop import request_of as estop_request_of
from app.service.host import Observation, Published
from app.service.setpoints import STREAM_STALE_S, PointClaims, Sender, Setpoint, SetpointAck, checked
from app.service.state_document import state_json
from app.service.verbs import (
    CancelRun,
    ChainTiming,
    ClearSequence,
    ConfirmRecognition,
    EnableLayers,
    Footstep,
    GetFootsteps,
    GetLoopTiming,
    GetParams,
    GetRun,
    GoPos,
    GoVelocity,
    InjectFault,
    ListRuns,
    PlaceObject,
    PreviewBehavior,
    Push,
    ReleaseEstop,
    ReleaseMotion,
    Reset,
    RobotInfo,
    RunBehavior,
    SequenceStatus,
    SetFootsteps,
    SetGroupSequence,
    SetJointAngles,
    SetJointAnglesSequence,
    SetParams,
    SetSomeJointAngles,
    SetTargetPose,
    StartImpedance,
    StartLayer,
    StartRecording,
    StepRun,
    StopImpedance,
    StopLayer,
    StopMotion,
    StopRecording,
    Verb,
    WalkEmergencyStop,
    WalkStop,
)
from controller.core.layer import Params
from controller.core.loop import Snapshot
from controller.core.loop_timing import LoopTiming
from controller.walking.footsteps import StepParams

VERB_TIMEOUT_S = 5.0  # [s] a verb not answered by then is reported (the loop may be stuck or gone)
ACK_TIMEOUT_S = 0.5  # [s] a setpoint whose acknowledgement has not come back by then is reported
CAMERA_WAIT_S = 5.0  # [s] a camera request waits this long for a frame (the first one opens the renderer)


class RobotBackend(Protocol):
    """Where the robot runs: app.service.process.RobotProcess (what users run) or local.LocalRobot."""

    exit_reason: str | None
    priority: str

    @property
    def alive(self) -> bool: ...
    def submit(self, verb: Verb): ...
    def estop(self, press: str | None = None, timeout_s: float = 1.0) -> EstopAck: ...
    def latest(self) -> Published | None: ...
    def info(self) -> RobotInfo: ...
    def refresh_info(self, timeout_s: float = 10.0) -> RobotInfo: ...
    def log_rows(self) -> np.ndarray: ...
    def put_setpoint(self, setpoint: Setpoint) -> Setpoint: ...
    def setpoint_seq(self) -> int: ...
    def reset(self, scene: str | None = None, timeout_s: float = 30.0) -> RobotInfo: ...
    def close(self, timeout_s: float = 10.0) -> dict | None: ...


class OperatorService:
    """The named verbs of the console, in SI units (m, s, rad, N)."""

    def __init__(self, robot: RobotBackend) -> None:
        self.robot = robot
        self._info = robot.info()
        self._state_lock = threading.Lock()
        self._state_cache: tuple[tuple[int, int], dict, bytes] | None = None
        self._camera = None  # the camera view, made when first watched
        self._claims = PointClaims()  # who streams to which point, whose each recent setpoint was
        self._claims_lock = threading.Lock()
        self._ghost: tuple[int, dict | None] = (0, None)  # the last preview the 3D view draws (version, preview)

    def __repr__(self) -> str:
        return f"OperatorService({self.robot!r})"

    # ---- the door --------------------------------------------------------------------------------------
    @property
    def info(self) -> RobotInfo:
        return self._info

    def run(self, verb: Verb, timeout_s: float = VERB_TIMEOUT_S) -> Any:
        """Check `verb` against the robot, run it at the next tick boundary, return its result."""
        verb.check(self._info)
        fut = self.robot.submit(verb)
        try:
            return fut.result(timeout=timeout_s)
        except FutureTimeout:
            raise Unavailable(f"the robot did not answer {verb.name} within {timeout_s:g} s") from None

    # ---- safety ----------------------------------------------------------------------------------------
    def estop(self, press: EstopRequest | object = None) -> EstopAck:
        """The hard e-stop, through its own channel: returns once the loop has handled it (app.service.estop: it
        engages unless it is a late copy of a press already released). A malformed `press` id does not stop the
        stop: it engages, and the answer says the id was ignored."""
        request = press if isinstance(press, EstopRequest) else estop_request_of(press)
        ack = self.robot.estop(request.press)
        return ack if request.press_ignored is None else dataclasses.replace(ack, press_ignored=request.press_ignored)

    def release_estop(self) -> str:
        """Release the hard e-stop: nothing the operator streamed before the release runs after it."""
        return self.run(ReleaseEstop(self.robot.setpoint_seq(), time.monotonic()))

    def stop_motion(self) -> str:
        return self.run(StopMotion())

    def release_motion(self) -> str:
        return self.run(ReleaseMotion())

    # ---- walking ---------------------------------------------------------------------------------------
    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> str:
        return self.run(GoPos(x_m, y_m, theta_rad))

    def go_velocity(self, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float) -> str:
        return self.run(GoVelocity(vx_m_s, vy_m_s, vtheta_rad_s))

    def walk_stop(self) -> str:
        return self.run(WalkStop())

    def walk_emergency_stop(self) -> str:
        return self.run(WalkEmergencyStop())

    def set_footsteps(self, footsteps: Sequence[Footstep], step: StepParams | None = None) -> str:
        return self.run(SetFootsteps(tuple(footsteps), step))

    def footsteps(self) -> tuple[bool, tuple]:
        """(walking, the footsteps not landed yet)."""
        return self.run(GetFootsteps())

    # ---- the sequence player ---------------------------------------------------------------------------
    def set_joint_angles(self, q_rad: Sequence[float], time_s: float) -> str:
        return self.run(SetJointAngles(tuple(float(v) for v in q_rad), float(time_s)))

    def set_joint_angles_sequence(self, q_seq_rad: Sequence[Sequence[float]], times_s: Sequence[float]) -> str:
        return self.run(SetJointAnglesSequence(tuple(tuple(float(v) for v in q) for q in q_seq_rad),
                                               tuple(float(t) for t in times_s)))

    def set_group_sequence(self, group: str, goals_rad: Sequence[Sequence[float]], times_s: Sequence[float]) -> str:
        return self.run(SetGroupSequence(group, tuple(tuple(float(v) for v in g) for g in goals_rad),
                                         tuple(float(t) for t in times_s)))

    def set_some_joint_angles(self, angles_rad: Mapping[str, float], time_s: float) -> str:
        return self.run(SetSomeJointAngles(tuple((n, float(v)) for n, v in angles_rad.items()), float(time_s)))

    def set_target_pose(self, limb: str, pos_m: Sequence[float], rpy_rad: Sequence[float], time_s: float,
                        frame: str | None = None) -> str:
        return self.run(SetTargetPose(limb, tuple(map(float, pos_m)), tuple(map(float, rpy_rad)), float(time_s),
                                      frame))

    def clear_sequence(self) -> str:
        return self.run(ClearSequence())

    def is_interpolating(self) -> bool:
        return self.run(SequenceStatus())

    # ---- layers ------------------------------------------------------------------------------------------
    def start_layer(self, layer: str) -> str:
        return self.run(StartLayer(layer))

    def stop_layer(self, layer: str) -> str:
        return self.run(StopLayer(layer))

    def enable_layers(self, enabled: Mapping[str, bool]) -> str:
        return self.run(EnableLayers(tuple(enabled.items())))

    def start_impedance(self, limb: str) -> str:
        return self.run(StartImpedance(limb))

    def stop_impedance(self, limb: str) -> str:
        return self.run(StopImpedance(limb))

    def params(self, *owners: str) -> dict[str, Params]:
        """The current parameters of `owners` (layer names, "ic:<limb>"), or of every layer."""
        unknown = [o for o in owners if o not in self._info.params]
        if unknown:
            raise NotFound(f"no parameters {unknown[0]!r}; valid: {', '.join(self._info.params)}")
        return self.run(GetParams(tuple(owners)))

    def set_params(self, changes: Mapping[str, Mapping[str, Any]], prefixes: Mapping[str, str] | None = None
                   ) -> dict[str, Params]:
        """Replace some fields of some owners' parameters, all or none, at one tick boundary; returns the new
        parameters. Errors name the field (after the owner's prefix) and what is allowed."""
        new = self.run(SetParams.of(self._params_now(changes), changes, prefixes))
        self._info = _with_params(self._info, new)
        return new

    def _params_now(self, changes: Mapping[str, Any]) -> RobotInfo:
        """The info with the current parameters of the owners about to change (another client may have
        changed them since the info was taken)."""
        owners = tuple(o for o in changes if o in self._info.params)
        return _with_params(self._info, self.run(GetParams(owners))) if owners else self._info

    # ---- the operator's velocities and the behaviours ([OP] Eq. 5) -------------------------------------------
    def _refuse_setpoint(self) -> float:
        """A fall refuses a setpoint as it refuses a motion verb (the robot's latest published safety state).
        Returns the published control time [s]."""
        if "op" not in self._info.chain:
            raise NotFound(f"the chain has no operation layer ('op'); present: {', '.join(self._info.chain)}")
        snapshot = self.published().snapshot
        safety = snapshot.safety
        if safety.fall is not None:
            raise Refused("fallen", f"operator velocity refused: the robot has fallen ({safety.fall}); reset the "
                                    "simulation")
        # (the hard e-stop is the robot's to judge, at the tick the setpoint reaches: it acknowledges the setpoint
        # as ignored; a published state up to 20 ms old would refuse the first setpoints after a release)
        return snapshot.time_s

    def put_setpoint(self, setpoint: Setpoint, sender: Sender | None = None, override: bool = False) -> Setpoint:
        """Hand the operator's newest velocity for one point to the robot's latest-value channel (no queue);
        returns it numbered. `sender`: the client it comes from; PointTaken when another client streams to the
        point (unless `override`: the operator lock's holder); None (the console's own scripts) is not checked.
        `setpoint_outcome` tells when it reached the loop and whether it was applied."""
        if sender is None:  # the console's own (scripts, the viewer's sticks): no request schema checked it
            checked(setpoint)
        now_s = self._refuse_setpoint()
        abc = self.published().snapshot.layers.get("abc")
        if setpoint.point in ("rfoot", "lfoot") and abc is not None and abc.walking and not setpoint.is_zero():
            raise Refused("state", f"{setpoint.point}: refused while walking (the gait owns the feet); stop the "
                                   "walk first")
        with self._claims_lock:
            self._claims.stale_s = self._stream_stale_s()
            self._claims.claim(setpoint, sender, now_s, override)
            numbered = self.robot.put_setpoint(setpoint)
            self._claims.record(numbered, sender)
        return numbered

    def _stream_stale_s(self) -> float:
        """[s] of control time: a point's stream has stopped after this long without a setpoint, the dead-man's
        timeout and ramp."""
        op = self._info.params.get("op")
        if op is None:
            return STREAM_STALE_S
        return max(0.05, float(op.deadman_timeout_s) + float(op.deadman_ramp_s))

    def end_stream(self, stream: int) -> list[str]:
        """The WebSocket stream `stream` closed: the points it streamed to are free for other clients."""
        with self._claims_lock:
            return self._claims.release(stream)

    def point_owner(self, point: str) -> str | None:
        """The display name of the client streaming to `point` now (None: nobody)."""
        now_s = self.published().snapshot.time_s
        with self._claims_lock:
            owner = self._claims.owner(point, now_s)
        return None if owner is None else owner.name

    def setpoint_ack(self, point: str) -> SetpointAck | None:
        """The newest setpoint of `point` the robot has applied (as last published)."""
        return self.published().setpoint_acks.get(point)

    def setpoint_outcome(self, numbered: Setpoint, sender: Sender | None, ack: SetpointAck | None
                         ) -> SetpointAck | None:
        """The answer to `numbered` (put by `sender`), given the robot's newest acknowledgement of its point:
        None while it has not reached the robot; `ack` when it, or a newer setpoint of the same client, reached
        the operation layer; Refused with the robot's reason when what reached it was ignored (the hard
        e-stop: so also when the acknowledged setpoint is a newer one); Superseded when another client's newer
        setpoint came after it (naming that client)."""
        if ack is None or ack.seq < numbered.seq:
            return None
        if ack.ignored is not None:
            raise Refused(ack.ignored, ignored_message(ack.ignored))
        if ack.seq == numbered.seq:
            return ack
        with self._claims_lock:
            newer = self._claims.sender_of(numbered.point, ack.seq)
        if (sender is None and newer is None) or (sender is not None and sender.same_client(newer)):
            return ack
        who = f"{newer.name!r}" if newer is not None else "another client"
        raise Superseded(numbered.point, None if newer is None else newer.name,
                         f"setpoint {numbered.seq} of {numbered.point!r} superseded: {who} sent a newer one "
                         f"({ack.seq}) that the robot applied instead; yours did not stay in effect")

    def operator_velocity(self, setpoint: Setpoint, sender: Sender | None = None, override: bool = False,
                          timeout_s: float = ACK_TIMEOUT_S) -> SetpointAck:
        """Put a setpoint and wait until the robot has applied it (the tick it reached): see `put_setpoint`
        and `setpoint_outcome` for what is refused (PointTaken, Refused "hard_stop" / "before_release",
        Superseded); Unavailable when no acknowledgement came within `timeout_s`."""
        return self.wait_setpoint(self.put_setpoint(setpoint, sender, override), sender, timeout_s)

    def wait_setpoint(self, numbered: Setpoint, sender: Sender | None = None, timeout_s: float = ACK_TIMEOUT_S
                      ) -> SetpointAck:
        """Wait for the outcome of a setpoint put (`setpoint_outcome`): the acknowledgement when applied, else
        its refusal; Unavailable when none came within `timeout_s`."""
        import time

        deadline = time.monotonic() + timeout_s
        while True:
            ack = self.setpoint_outcome(numbered, sender, self.setpoint_ack(numbered.point))
            if ack is not None:
                return ack
            if time.monotonic() > deadline:
                raise Unavailable(f"the robot did not acknowledge the {numbered.point} setpoint within "
                                  f"{timeout_s:g} s")
            time.sleep(0.002)

    def run_behavior(self, name: str, params: Mapping[str, Any] | None = None, mode: str = "run") -> int:
        """Start a behaviour; its run id. Parameters are plain JSON values (see list_behaviors); `mode` "step"
        holds it before each phase until `step_run`."""
        return self.run(RunBehavior(name, tuple((params or {}).items()), mode))

    def preview_behavior(self, name: str, params: Mapping[str, Any] | None = None) -> dict:
        """What a behaviour would do if it started now (behaviors.preview); kept as the 3D view's ghost."""
        preview = self.run(PreviewBehavior(name, tuple((params or {}).items())))
        self._ghost = (self._ghost[0] + 1, preview)
        return preview

    def clear_preview(self) -> None:
        self._ghost = (self._ghost[0] + 1, None)

    def ghost(self) -> tuple[int, dict | None]:
        """(version, the last preview or None once cleared): the 3D view redraws when the version changes."""
        return self._ghost

    def step_run(self, run_id: int):
        return self.run(StepRun(int(run_id)))

    def cancel_run(self, run_id: int):
        return self.run(CancelRun(int(run_id)))

    def get_run(self, run_id: int):
        return self.run(GetRun(int(run_id)))

    def runs(self):
        return self.run(ListRuns())

    def list_behaviors(self) -> list[dict]:
        from app.service.verbs import list_behaviors

        return list_behaviors()

    # ---- the camera view and the recognitions --------------------------------------------------------------
    @property
    def camera(self):
        """The wide head camera's view (app.service.camera_feed.CameraFeed), made on first use."""
        if self._camera is None:
            from app.service.camera_feed import CameraFeed

            with self._state_lock:
                if self._camera is None:
                    self._camera = CameraFeed(self.published)
        return self._camera

    def camera_frame(self, newer_than_s: float = 0.5, timeout_s: float = CAMERA_WAIT_S):
        """A frame of the camera view rendered at most `newer_than_s` before this call (wall time) or showing the
        latest publication, waiting up to `timeout_s` for one (the first one opens the renderer); Unavailable
        when none came."""
        import time

        start = time.monotonic()
        feed = self.camera
        while True:
            pub = self.published()  # Unavailable if the robot process is gone
            feed.watch()
            frame = feed.latest
            if frame is not None and (frame.requested_at_monotonic_s >= start - newer_than_s
                                      or frame.source == (pub.generation, pub.seq)):  # nothing newer to show
                return frame
            if time.monotonic() - start > timeout_s:
                raise Unavailable(f"no camera frame within {timeout_s:g} s"
                                  + (f": {feed.error}" if feed.error else ""))
            time.sleep(0.01)

    def latest_camera_frame(self, rate_hz: float = 10.0):
        """The newest frame, however old, or None (renews the watch at `rate_hz`; never waits)."""
        feed = self.camera
        feed.watch(rate_hz=rate_hz)
        return feed.latest

    def recognitions(self) -> dict[str, dict]:
        """The latest recognition of each object, as the behaviours recall them (as last published)."""
        return dict(self.published().recognitions)

    def confirm_recognition(self, object_name: str, position_m: Sequence[float] | None = None) -> dict:
        """Confirm the latest recognition of an object, or correct its position (world) [m]."""
        pos = None if position_m is None else tuple(float(v) for v in position_m)
        return self.run(ConfirmRecognition(object_name, pos))

    # ---- the simulation --------------------------------------------------------------------------------
    def push(self, body: str, force_n: Sequence[float], duration_s: float) -> str:
        return self.run(Push(body, tuple(map(float, force_n)), float(duration_s)))

    def inject_fault(self, kind: str, layer: str = "st") -> str:
        """Test hook: `layer`'s tick raises from now on ("layer"), or a NaN in the physics ("nan")."""
        return self.run(InjectFault(kind, layer))

    def places(self) -> dict:
        """The named places the robot knows (behaviors.places): the scene's known ones, the located objects."""
        from behaviors.places import places

        return places(self.objects, self.recognitions())

    def place(self, name: str):
        """The place called `name` (behaviors.places.Place); NotFound listing the valid names."""
        from behaviors.places import UnknownPlace, resolve

        try:
            return resolve(name, self.objects, self.recognitions())
        except UnknownPlace as exc:
            raise NotFound(str(exc)) from None

    @property
    def objects(self) -> tuple[str, ...]:
        """The current scene's placeable objects."""
        return self._info.objects

    def place_object(self, name: str, position_m: Sequence[float], yaw_rad: float = 0.0
                     ) -> tuple[float, float, float]:
        """Put a scene object at (x, y) on what is below it or at (x, y, z) [m], yawed [rad]; the body position."""
        return self.run(PlaceObject(name, tuple(position_m), yaw_rad))

    def reset(self, scene: str | None = None) -> str:
        """Restart the simulation (a new robot process if the old one died)."""
        if scene is not None:
            Reset(scene).check(self._info)
        self._info = self.robot.reset(scene)
        with self._state_lock:
            self._state_cache = None
        return f"simulation reset (scene {self._info.scene!r})"

    # ---- sessions ----------------------------------------------------------------------------------------
    def start_recording(self, path: str, timeout_s: float = 30.0) -> dict:
        """Reset the simulation (same scene) and record a session to `path` (an MCAP file the robot writes) from
        its first tick; the recording's status. Refused (state) while a session is being recorded."""
        status = self.run(StartRecording(str(path), reset=True), timeout_s=timeout_s)
        self._info = self.robot.refresh_info()  # the reset put the start parameters back
        with self._state_lock:
            self._state_cache = None
        return status

    def stop_recording(self, timeout_s: float = 30.0) -> dict:
        """End the session being recorded; its status once the file is finished (Refused when none is). The robot
        does not wait for the file: this waits, reading the published status."""
        import time

        stopped = self.run(StopRecording(), timeout_s=timeout_s)
        deadline = time.monotonic() + timeout_s
        while True:
            last = self.published().last_recording
            if last is not None and last["path"] == stopped["path"] and last["finished"]:
                return last
            if time.monotonic() > deadline:
                raise Unavailable(f"the session file {stopped['name']} was not finished within {timeout_s:g} s")
            time.sleep(0.02)

    def recording(self) -> dict | None:
        """The session being recorded (path, ticks, inputs, error) as last published, or None."""
        return self.published().recording

    # ---- reading -------------------------------------------------------------------------------------------
    def published(self) -> Published:
        if not self.robot.alive:
            raise Unavailable(f"{self.robot.exit_reason or 'the robot process is not running'}; "
                              "POST /api/sim/reset starts a new one")
        pub = self.robot.latest()
        if pub is None:
            raise Unavailable("the robot has not published a snapshot yet")
        return pub

    def snapshot(self) -> Snapshot:
        return self.published().snapshot

    def observation(self) -> Observation:
        """The latest snapshot with the simulator's ground truth beside it (for the GUI)."""
        pub = self.published()
        return Observation(pub.snapshot, pub.truth)

    def timing(self, last_s: float | None = None) -> LoopTiming:
        """The loop's figures as last published, or computed now over the last `last_s` seconds."""
        if last_s is None:
            return self.published().timing
        return self.run(GetLoopTiming(float(last_s)))

    def state(self) -> dict[str, Any]:
        """The latest snapshot as the /api/state document (built once per snapshot)."""
        return self._state()[0]

    def state_json(self) -> bytes:
        return self._state()[1]

    def _state(self) -> tuple[dict, bytes]:
        pub = self.published()
        key = (pub.generation, pub.seq)
        cache = self._state_cache
        if cache is not None and cache[0] == key:
            return cache[1], cache[2]
        with self._state_lock:
            cache = self._state_cache
            if cache is not None and cache[0] == key:
                return cache[1], cache[2]
            doc, body = state_json(pub)
            self._state_cache = (key, doc, body)
            return doc, body

    def chain_timing(self) -> dict:
        return self.run(ChainTiming())

    def log_rows(self) -> np.ndarray:
        return self.robot.log_rows()

    def close(self) -> dict | None:
        if self._camera is not None:
            self._camera.close()
        return self.robot.close()


def ignored_message(reason: str) -> str:
    """What an ignored setpoint's acknowledgement says."""
    if reason == "hard_stop":
        return "setpoint ignored: the hard e-stop is engaged; release it first"
    if reason == "before_release":
        return "setpoint ignored: it was sent before the hard e-stop's release (nothing runs that was sent before)"
    if reason == "invalid":
        return "setpoint ignored: outside the point's ranges (the operation layer's check; see GET /api/config)"
    if reason == "state":
        return ("setpoint ignored: the point may not be driven now (a foot while walking, the other foot operated, "
                "or the walking point while a foot is operated)")
    return f"setpoint ignored ({reason})"


def _with_params(info: RobotInfo, params: Mapping[str, Params]) -> RobotInfo:
    import dataclasses

    return dataclasses.replace(info, params={**info.params, **params})


def degrees_to_radians(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(math.radians(float(v)) for v in values)
