"""The robot side of the operator service: the MuJoCo plant, the controller, the data logger, and the one
place verbs are applied to them (at a tick boundary, wherever the loop runs: the robot process, or a
thread or a test in one process)."""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.service.commands import HostCommands
from app.service.data_logger import DataLogger
from app.service.errors import InvalidArgument, NotFound, Refused, ServiceError
from app.service.estop import EstopAck, PressLog
from app.service.session_recorder import SessionRecorder
from app.service.setpoints import LocalSource, Setpoint, SetpointAck
from app.service.stops import LatchedStop, WalkingStopWatch, motion_stop
from app.service.verbs import RobotInfo, SetParams, Verb
from app.service.verbs.sequence import held_against
from app.session.inputs import outcome_of
from behaviors.perception.worker import prepare as prepare_recognition
from behaviors.registry import BEHAVIORS  # noqa: F401 - imported here, not at the first behaviour's boundary
from behaviors.runner import BehaviorRunner
from controller.core.errors import InvalidCommand, InvalidState, UnknownName, Unreachable
from controller.core.layer import Params
from controller.core.loop import Snapshot
from controller.core.loop_timing import LoopTiming
from controller.operation.foot_point import PointRefused
from controller.system import ControllerSystem
from robot.camera import CAMERA_NICE
from robot.names import JOINT_NAMES
from robot.plant import MujocoPlant, available_scenes
from robot.sensors import GroundTruth, is_fallen

log = logging.getLogger(__name__)


class RunStats:
    """Counters kept over a whole run (updated in the loop thread, read after it stops)."""

    def __init__(self) -> None:
        self.ticks = 0
        self.max_loop_ms = 0.0  # [ms] whole tick, chain + physics
        self.fallen = False
        self.faults: set[str] = set()

    def update(self, obs: Observation) -> None:
        snap = obs.snapshot
        self.ticks += 1
        if snap.loop_ms > self.max_loop_ms:
            self.max_loop_ms = float(snap.loop_ms)
        if obs.fallen:
            self.fallen = True
        fault = snap.safety.fault
        if fault and fault not in self.faults:
            self.faults.add(fault)

    def summary(self) -> dict[str, Any]:
        return {"ticks": self.ticks, "max_loop_ms": self.max_loop_ms, "fallen": self.fallen,
                "faults": sorted(self.faults)}


@dataclass(frozen=True, slots=True)
class Observation:
    """One tick as the simulation sees it: the controller's snapshot and, beside it, the simulator's ground
    truth (for the GUI, the log and tests; the controller never sees it). Reads through to the snapshot."""

    snapshot: Snapshot
    truth: GroundTruth

    @property
    def fallen(self) -> bool:
        return is_fallen(self.truth)

    def __getattr__(self, name: str):
        return getattr(self.snapshot, name)


@dataclass(frozen=True)
class Published:
    """What the robot side publishes after a tick: the snapshot and the loop's own figures, latest wins."""

    seq: int  # increases with every publication of this robot process
    generation: int  # increases with every reset (the chain and the scene may have changed)
    snapshot: Snapshot
    truth: GroundTruth  # the simulator's, beside the snapshot
    timing: LoopTiming
    scene: str
    speed: float | None
    stats: dict[str, Any]
    chain: str  # "kf -> rmfo -> ..."
    published_at_monotonic_s: float
    runs: tuple = ()  # behaviors.runner.RunStatus of the runs kept, oldest first
    setpoint_acks: dict = dataclasses.field(default_factory=dict)  # point -> SetpointAck of its newest setpoint
    recognitions: dict = dataclasses.field(default_factory=dict)  # object -> its latest recognition (as remembered)
    recording: dict | None = None  # the session being recorded (SessionRecorder.status), or None
    last_recording: dict | None = None  # the last session stopped: its status (`finished` once its file is)


#: Owners of parameters: a layer name, or "ic:<limb>" for one hand's impedance.
def _is_limb_owner(owner: str) -> bool:
    return owner.startswith("ic:")


class RobotHost:
    """Owns the simulation and the control loop. Verbs reach them only through `apply`."""

    def __init__(self, scene: str = "default", dt_control_s: float = 0.005, speed: float | None = 1.0,
                 logger: DataLogger | None = None, start_auto_balancer: bool = True,
                 params: Mapping[str, Mapping[str, Any]] | None = None, setpoints=None) -> None:
        """`params`: a parameter document {owner: {field: value}} (as GET /api/params gives) the chain starts
        with, and starts with again after every reset; checked as a PUT of it would be (InvalidArgument).
        `setpoints`: where the operator's streamed setpoints come from (a `poll()` giving the newest table or
        None; default: a LocalSource for a console in this process)."""
        self.scene = scene
        self.dt_control_s = dt_control_s
        self.logger = logger if logger is not None else DataLogger(12000)
        self.stats = RunStats()
        self.generation = 0
        self._seq = 0
        self._timing: tuple[float, LoopTiming] | None = None
        self.plant = MujocoPlant(scene)
        self.system = ControllerSystem(self.plant, dt_control_s=dt_control_s, on_snapshot=self._on_snapshot,
                                       start_auto_balancer=start_auto_balancer)
        self.observation = Observation(self.loop.snapshot, self.plant.ground_truth())
        self.loop.speed = speed
        self.startup_params = {owner: dict(fields) for owner, fields in (params or {}).items()}
        self.setpoints = setpoints if setpoints is not None else LocalSource()
        self.setpoint_acks: dict[str, SetpointAck] = {}
        self.release_barrier_seq = 0  # setpoints numbered up to this were sent before the last e-stop release
        self._presses = PressLog()  # the e-stop presses of the last moment: a late copy does not re-engage
        self._info: RobotInfo | None = None
        self._runs_cache: tuple[int, tuple] = (-1, ())
        self.recognitions: dict[str, dict] = {}  # object -> its latest recognition (behaviours remember them)
        self._cameras = None  # robot.camera.CameraProcess of `_cameras_scene`, made on the first capture
        self.camera_nice = CAMERA_NICE  # the camera process's nice increment (0 when the loop is real-time)
        self._cameras_scene: str | None = None
        self.captures = 0  # captures made since the last reset (their numbers, from 1)
        self._late_captures: set[int] = set()  # paced: captures whose results were not ready when due
        #: a replay's schedule of the results the recording took late: capture number -> "result_late" (not
        #: entered yet) or "result_entered"; None when not replaying
        self.replayed_captures: dict[int, str] | None = None
        self.walking_stop_watch = WalkingStopWatch()
        self.runner = BehaviorRunner(self._operation_layer, HostCommands(self), dt_control_s,
                                     world_from_control=self.world_from_control, stops=self.latched_stops)
        self.start_auto_balancer = start_auto_balancer
        self.recorder: SessionRecorder | None = None  # the session being recorded, if any
        self.last_recorder: SessionRecorder | None = None  # the last one stopped (its file may still be finishing)
        self._runs_recorded = self.runner.transitions
        self._applying_input = False  # an input verb runs: what it does is recorded as that verb
        self._in_hook = False  # the streamed setpoints are being taken at the start of a tick
        self._install_before_tick()
        self._load_startup_params()

    # ---- behaviours and the operator's setpoints, at every tick boundary ----------------------------------
    def _install_before_tick(self) -> None:
        """Behaviours and setpoints step at the loop's tick boundaries (again after a reset's new chain)."""
        self.loop.before_tick = self._before_tick

    def _operation_layer(self):
        return self.loop.chain.layers.get("op")

    def world_from_control(self) -> tuple[float, float, float, float] | None:
        """The controller's frame in the world after the last tick (leg odometry), or None before one."""
        snap = self.loop.snapshot
        odometry = None if snap is None else snap.odometry
        return None if odometry is None else odometry.world_from_control

    def latched_stops(self) -> tuple[LatchedStop, ...]:
        """The motion stop and the emergency walking stop in force after the last tick, each with what raised
        it, when, and what releases it (app.service.stops)."""
        layers = self.loop.chain.layers
        stops = (motion_stop(layers.get("es")), self.walking_stop_watch.stop())
        return tuple(s for s in stops if s is not None)

    def _before_tick(self, time_s: float) -> None:
        layers = self.loop.chain.layers
        self.walking_stop_watch.observe(time_s, layers.get("abc"), layers.get("st"), self.loop.hard_stop_engaged)
        if self.loop.hard_stop_engaged:  # whatever engaged it (the operator, a fault, a fall)
            op = self._operation_layer()
            if op is not None:
                op.drop_motion()
            if self.runner.active:  # nothing started before the stop goes on after its release
                self.runner.cancel_all("cancelled: the hard e-stop was engaged")
        table = self.setpoints.poll()
        if table:
            self._in_hook = True
            try:
                self.apply_setpoints(table, time_s)
            finally:
                self._in_hook = False
        self.runner.step(time_s)

    def apply_setpoints(self, table: Mapping[str, Setpoint], time_s: float | None = None) -> list[SetpointAck]:
        """Hand each point's setpoint that is newer than the last one applied to the operation layer,
        stamped with the control time `time_s` (default: now, at this boundary); while the hard e-stop is
        engaged, or for a setpoint sent before its release, acknowledge it as ignored instead."""
        op = self._operation_layer()
        if op is None:
            raise NotFound(f"the chain has no operation layer ('op'); present: {self.loop.chain.order()}")
        time_s = float(self.loop.plant.time_s if time_s is None else time_s)
        tick = int(self.loop.tick_count)
        acks = []
        for point, sp in table.items():
            last = self.setpoint_acks.get(point)
            if last is not None and sp.seq and sp.seq <= last.seq:
                continue
            if self.loop.hard_stop_engaged:
                ignored = "hard_stop"
            elif sp.seq and sp.seq <= self.release_barrier_seq:
                ignored = "before_release"
            else:
                ignored = _applied(op, point, sp, time_s)
            self.setpoint_acks[point] = ack = SetpointAck(point, sp.seq, tick, time_s, ignored)
            acks.append(ack)
        recorder = self.recorder
        if recorder is not None and acks and not self._applying_input:
            recorder.setpoints("hook" if self._in_hook else "boundary", time_s, [table[a.point] for a in acks], acks)
        return acks

    def cached_info(self) -> RobotInfo:
        """info(), kept until the next reset or parameter change (for checks inside the loop)."""
        if self._info is None:
            self._info = self.info()
        return self._info

    def __repr__(self) -> str:
        return f"RobotHost(scene={self.scene!r}, speed={self.loop.speed}, generation={self.generation})"

    @property
    def loop(self):
        return self.system.loop

    def _on_snapshot(self, snap: Snapshot) -> None:
        self.observation = obs = Observation(snap, self.plant.ground_truth())
        row = self.logger.record(obs)
        self.stats.update(obs)
        recorder = self.recorder
        if recorder is not None:
            recorder.tick(row, obs.truth.qpos)
            if self.runner.transitions != self._runs_recorded:
                self._runs_recorded = self.runner.transitions
                recorder.runs_changed(snap.time_s, self.runner.runs())

    # ---- when a capture's result enters ------------------------------------------------------------------
    def capture_ready(self, number: int, result: Future) -> bool:
        """Whether capture `number`'s result enters at this boundary (asked at each boundary from the one it is
        due at on). As fast as possible it is waited for, so it enters when due and a seeded run is the same
        every time; paced, only when it is done, so no tick ever waits for a camera or a fit (the session
        records a result that was late and the boundary it entered at, and a replay takes it there)."""
        schedule = self.replayed_captures
        if schedule is not None:
            return schedule.get(number) != "result_late"
        loop = self.loop
        if loop.speed is None or not loop.pacing:
            return True
        done = result.done()
        late = number in self._late_captures
        if not done and not late:
            self._late_captures.add(number)
            self._record_capture(number, "result_late")
        elif done and late:
            self._late_captures.discard(number)
            self._record_capture(number, "result_entered")
        return done

    def _record_capture(self, number: int, what: str) -> None:
        if self.recorder is not None:
            self.recorder.input("capture", "boundary", what, self.loop.plant.time_s, number, {"ok": True})

    # ---- the head cameras ----------------------------------------------------------------------------------
    def cameras(self):
        """The scene's camera rig (narrow_left with depth, 640 x 480), fed copies of the plant state so that no
        tick waits for a rendering. Its renderer runs in a process of its own (robot.camera.CameraProcess):
        MuJoCo's holds the interpreter lock while it works (~0.5 s to make its GL context, 2-5 ms a frame),
        which in this process would stop the loop. Made on the first use (or by start_cameras), kept across a
        reset to the same scene (the objects' poses come with each request)."""
        if self._cameras is None:
            from robot.camera import CameraProcess

            self._cameras = CameraProcess(self.scene, self.plant.model, cameras=("narrow_left",),
                                          prepare=prepare_recognition, nice=self.camera_nice)
            self._cameras_scene = self.scene
        return self._cameras

    def start_cameras(self, timeout_s: float = 60.0) -> None:
        """Make the camera process now and wait for its renderer: starting one takes 1-2 s of CPU, which a
        first recognition while the loop runs at real time would otherwise share with it (ticks late)."""
        self.cameras().wait_ready(timeout_s)

    def close_cameras(self) -> None:
        if self._cameras is not None:
            self._cameras.close()
            self._cameras = None

    # ---- the recognitions the behaviours remember ([OP] II: the human confirms the robot's perception) -------
    def confirm_recognition(self, object_name: str, position_m=None) -> dict:
        """The operator confirms the latest recognition of `object_name`, or corrects its position [m] (world):
        what later behaviours recall. The robot's own estimate stays beside it (estimated_position_m)."""
        rec = self.recognitions.get(object_name)
        if rec is None:
            known = ", ".join(sorted(self.recognitions)) or "none yet"
            raise NotFound(f"no recognition of {object_name!r} to confirm; recognised: {known} (run locate_can or "
                           "locate_trash_box first)")
        new = dict(rec)
        new.setdefault("estimated_position_m", list(rec["position_m"]))
        if position_m is None:
            new["status"] = "confirmed"
        else:
            new["status"] = "corrected"
            new["position_m"] = [round(float(v), 5) for v in position_m]
        self.recognitions[object_name] = new
        return new

    # ---- verbs ---------------------------------------------------------------------------------------
    def apply_input(self, verb: Verb) -> Any:
        """`apply` for a verb from outside the loop (the operator service, a script): the one place a session
        records verbs, with the tick they took effect at and their outcome. (Behaviours call `apply`: their
        commands follow from the recorded RunBehavior and are not inputs.)"""
        recorder = self.recorder
        if recorder is None or not verb.recorded:
            return self.apply(verb)
        time_s = float(self.loop.plant.time_s)
        self._applying_input = True
        try:
            result = self.apply(verb)
        except Exception as exc:
            if self.recorder is recorder:
                recorder.input("verb", "boundary", verb.name, time_s, verb, outcome_of(error=exc))
            raise
        finally:
            self._applying_input = False
        if self.recorder is recorder:
            recorder.input("verb", "boundary", verb.name, time_s, verb, outcome_of(result))
            if verb.name == "set_params":
                recorder.params_changed(time_s, {o: dict(f) for o, f in verb.changes})
        return result

    def apply(self, verb: Verb) -> Any:
        """Run `verb` now (the caller is at a tick boundary); refuse it when it cannot take effect."""
        if verb.motion:
            self._refuse_motion(verb)
        try:
            return verb.run(self)
        except ServiceError:
            raise
        except InvalidState as exc:
            raise Refused("state", str(exc)) from None
        except Unreachable as exc:
            raise Refused("reach", str(exc)) from None
        except UnknownName as exc:
            raise NotFound(str(exc)) from None
        except (InvalidCommand, ValueError) as exc:
            raise InvalidArgument(verb.name, str(exc)) from None

    def _refuse_motion(self, verb: Verb) -> None:
        loop = self.loop
        fall = loop.fall.reason if loop.fall is not None else None
        if fall is not None:
            raise Refused("fallen", f"{verb.name} refused: the robot has fallen ({fall}); reset the simulation")
        if loop.hard_stop_engaged:
            raise Refused("hard_stop", f"{verb.name} refused: the hard e-stop is engaged; release it first")
        if verb.sequence:
            co = loop.chain.layers.get("co")
            if held_against(verb, co):
                pairs = ", ".join("-".join(p) for p in co.pairs[:2])
                raise Refused("collision", f"{verb.name} refused: the CollisionDetector holds the posture "
                                           f"({pairs}); wait until it has recovered")
        if verb.name == "run_behavior":  # no behaviour starts under a latched stop (the runner checks it too)
            stops = self.latched_stops()
            if stops:
                raise Refused(stops[0].reason, f"{verb.behavior} refused: {stops[0].message}")
        if verb.sequence:
            stop = motion_stop(loop.chain.layers.get("es"))
            if stop is not None:
                raise Refused("motion_stop", f"{verb.name} refused: {stop.message}")

    def layer(self, name: str):
        chain = self.loop.chain
        if name not in chain:
            raise NotFound(f"no layer {name!r} in the chain; present: {chain.order()}")
        return chain[name]

    # ---- the e-stop path -----------------------------------------------------------------------------
    def engage_estop(self, press: str | None = None) -> EstopAck:
        """Engage the hard e-stop (app.service.estop: every press engages but a late copy of one released)."""
        loop = self.loop
        now = time.monotonic()
        already = loop.hard_stop_engaged
        first = self._presses.first(press, now)
        released = first is not None and self._presses.released_after(first)
        if first is not None and already and not released:  # the same press, its stop still engaged
            ack = dataclasses.replace(first, copy=True)
        elif first is not None and released and not already:
            ack = EstopAck(tick=loop.tick_count, sim_time_s=float(loop.snapshot.time_s), engaged_at_monotonic_s=now,
                           engaged=False, late_copy=True)
        else:
            if not already:
                loop.safe_stop("operator")
            ack = EstopAck(tick=loop.tick_count, sim_time_s=float(loop.snapshot.time_s), engaged_at_monotonic_s=now,
                           engaged=loop.hard_stop_engaged, already_engaged=already)
            self._presses.pressed(press, ack)
        if self.recorder is not None:
            result = "late copy" if ack.late_copy else "already engaged" if already else "engaged"
            self.recorder.input("estop", "boundary", "estop", loop.plant.time_s, None,
                                {"ok": ack.engaged, "result": result})
        return ack

    def release_estop(self, setpoints_before: int = 0, sent_monotonic_s: float | None = None) -> None:
        """Release the hard e-stop; the operator's setpoints numbered up to `setpoints_before` are never applied,
        those streamed before the stop are forgotten. Refused if sent (`sent_monotonic_s`) before a press since."""
        loop = self.loop
        if loop.fall is not None and loop.fall.reason is not None:
            raise Refused("fallen", f"the robot has fallen ({loop.fall.reason}); only a reset recovers")
        diverged = getattr(self.plant, "diverged", None)
        if diverged:
            raise Refused("diverged", f"the simulation has diverged ({diverged}); only a reset recovers "
                                      "(POST /api/sim/reset)")
        if sent_monotonic_s is not None and self._presses.pressed_since(sent_monotonic_s):
            raise Refused("hard_stop", "not released: an e-stop was pressed after this release was sent; release again")
        self.layer("hes").release()  # InvalidState (-> 409) when not engaged
        self._presses.released(time.monotonic())
        self.release_barrier_seq = max(self.release_barrier_seq, int(setpoints_before))
        op = self._operation_layer()
        if op is not None:
            op.drop_motion()
        loop.clear_fault()

    # ---- parameters ------------------------------------------------------------------------------------
    def param_owners(self) -> list[str]:
        chain = self.loop.chain
        owners = [n for n in chain.order() if isinstance(getattr(chain[n], "params", None), Params)]
        if "ic" in chain:
            owners += [f"ic:{limb}" for limb in chain["ic"].limbs]
        return owners

    def params(self, owner: str) -> Params:
        if _is_limb_owner(owner):
            return self.layer("ic").params[owner[3:]]
        p = getattr(self.layer(owner), "params", None)
        if not isinstance(p, Params):
            raise NotFound(f"layer {owner!r} has no parameters; owners: {', '.join(self.param_owners())}")
        return p

    def set_params(self, owner: str, params: Params) -> None:
        self._info = None
        if _is_limb_owner(owner):
            self.layer("ic").set_params(owner[3:], params)
        else:
            self.layer(owner).set_params(params)

    # ---- the simulation -----------------------------------------------------------------------------------
    def reset(self, scene: str | None = None) -> None:
        """A new plant (in `scene`) and a fresh chain; the log and the statistics of the run go on."""
        scene = self.scene if scene is None else scene
        if scene not in available_scenes():
            raise InvalidArgument("scene", f"unknown scene {scene!r}; available scenes: "
                                           f"{', '.join(available_scenes())}")
        plant = MujocoPlant(scene)
        self.runner.reset("cancelled: the simulation was reset")
        self.walking_stop_watch = WalkingStopWatch()
        restart_cameras = scene != self._cameras_scene and self._cameras is not None
        if scene != self._cameras_scene:
            self.close_cameras()
        self.recognitions.clear()
        self.captures = 0
        self._late_captures.clear()
        self.loop.replace_plant(plant)
        self._info = None
        self._install_before_tick()
        self.plant = plant
        self.observation = Observation(self.loop.snapshot, plant.ground_truth())
        self.scene = scene
        if restart_cameras:  # the new scene's camera process starts now, in the background (1-2 s), not at the
            self.cameras()  # first capture, whose result would then wait for it
        self.generation += 1
        self.logger.clear()
        self.loop.lateness.clear()
        self._load_startup_params()

    # ---- sessions ----------------------------------------------------------------------------------------
    def start_recording(self, path, reset: bool = False) -> dict:
        """Record a session to `path` (MCAP) from now on. A session replays from a fresh simulation, so it
        starts at one: this host's first tick, or a reset (`reset` true: reset now, in the same scene)."""
        if self.recorder is not None:
            raise Refused("state", f"a session is already being recorded ({self.recorder.path.name}); stop it "
                                   "first")
        if reset:
            self.reset()
        if self.loop.tick_count != 0:
            raise Refused("state", "a session starts at a fresh simulation (tick 0): reset first, or start it "
                                   "with the reset")
        header = {"scene": self.scene, "dt_control_s": self.dt_control_s,
                  "start_auto_balancer": self.start_auto_balancer, "startup_params": self.startup_params,
                  "start": "fresh" if self.generation == 0 else "reset", "next_run_id": self.runner.next_id,
                  "params": {o: self.params(o).to_dict() for o in self.param_owners()},
                  "chain": list(self.loop.chain.order())}
        self.recorder = SessionRecorder(path, header)
        self._runs_recorded = self.runner.transitions
        return self.recorder.status()

    def stop_recording(self) -> dict:
        """End the recording: no more ticks; the writer finishes the file while the loop goes on (nothing here
        waits for it: `last_recording_status()["finished"]`, or `last_recorder.wait()` off the loop)."""
        recorder = self.recorder
        if recorder is None:
            raise Refused("state", "no session is being recorded")
        self.recorder = None
        self.last_recorder = recorder
        recorder.close_async()
        return recorder.status()

    def recording_status(self) -> dict | None:
        return None if self.recorder is None else self.recorder.status()

    def last_recording_status(self) -> dict | None:
        return None if self.last_recorder is None else self.last_recorder.status()

    def _load_startup_params(self) -> None:
        if self.startup_params:
            doc = self.startup_params
            SetParams.of(self.info(), doc, {owner: f"{owner}." for owner in doc}).run(self)

    def inject_fault(self, kind: str, layer: str = "st") -> str:
        """Test hook (app.service.verbs.InjectFault): a layer that raises, or a NaN in the physics."""
        if kind == "nan":
            self.plant.inject_nan()
            return "the next physics step starts from a NaN velocity"
        if kind != "layer":
            raise InvalidArgument("kind", f"unknown fault {kind!r}; valid: 'layer', 'nan'")
        target = self.layer(layer)

        def broken_tick(*_args, **_kwargs):
            raise RuntimeError(f"injected fault in layer {layer!r}")

        target.tick = broken_tick  # this chain's instance only: a reset builds a new one
        return f"layer {layer!r} raises from its next tick on"

    def stop_loop(self) -> None:
        self.loop.request_stop()

    def info(self) -> RobotInfo:
        kin = self.system.kin
        m = self.plant.model
        chain = self.loop.chain
        ic = chain.layers.get("ic")
        return RobotInfo(
            scene=self.scene, scenes=tuple(available_scenes()),
            bodies=tuple(m.body(i).name for i in range(1, m.nbody)), joint_names=tuple(JOINT_NAMES),
            q_lower_rad=tuple(float(v) for v in np.asarray(kin.q_lower)),
            q_upper_rad=tuple(float(v) for v in np.asarray(kin.q_upper)),
            chain=tuple(chain.order()), params={o: self.params(o) for o in self.param_owners()},
            impedance_limbs=tuple(ic.limbs) if ic is not None else (), dt_control_s=self.dt_control_s,
            speed=self.loop.speed, objects=tuple(self.plant.placeable_objects()))

    def timing(self, max_age_s: float = 0.2) -> LoopTiming:
        """The loop's lateness figures, recomputed at most every `max_age_s` (a percentile over 12000 ticks
        costs a few hundred microseconds)."""
        now = time.monotonic()
        if self._timing is None or now - self._timing[0] >= max_age_s:
            self._timing = (now, self.loop.timing())
        return self._timing[1]

    def publish(self) -> Published:
        self._seq += 1
        loop = self.loop
        obs = self.observation
        return Published(seq=self._seq, generation=self.generation, snapshot=obs.snapshot, truth=obs.truth,
                         timing=self.timing(),
                         scene=self.scene, speed=loop.speed, stats=self.stats.summary(),
                         chain=loop.chain.describe(), published_at_monotonic_s=time.monotonic(),
                         runs=self.runs(), setpoint_acks=dict(self.setpoint_acks),
                         recognitions=dict(self.recognitions), recording=self.recording_status(),
                         last_recording=self.last_recording_status())

    def runs(self) -> tuple:
        """The runner's runs, the same tuple object until one of them changes (so a reader can compare by
        identity)."""
        version = self.runner.version
        if self._runs_cache[0] != version:
            self._runs_cache = (version, self.runner.runs())
        return self._runs_cache[1]


def _applied(op, point: str, sp: Setpoint, time_s: float) -> str | None:
    """Hand `sp` to the operation layer: None, or "invalid" when its last guard refused it (out of the point's
    ranges: the schemas and the door let none through, an edited session file might), so the loop goes on."""
    try:
        op.set_motion(point, sp.twist(), time_s, sp.walk())
    except PointRefused:  # valid, not now: a foot while walking, the other foot up, a walk with a foot up
        return "state"
    except (InvalidCommand, TypeError, ValueError):
        return "invalid"
    return None
