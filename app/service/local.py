"""The robot in the console's own process, for tests, benchmarks and experiments: the same host and verbs
as the robot process, stepped by the caller (`step`, `run_for`) or by a paced thread (`start`)."""

from __future__ import annotations

from concurrent.futures import Future

import numpy as np

from app.service.errors import ServiceError
from app.service.estop import EstopAck
from app.service.host import Published, RobotHost
from app.service.setpoints import Setpoint, SetpointTable
from app.service.verbs import Reset, RobotInfo, StopRecording, Verb


class LocalRobot:
    """A RobotHost in this process. Without `start()`, verbs run at once (between the caller's ticks);
    with it, they queue for the loop thread's next tick boundary."""

    def __init__(self, scene: str = "default", speed: float | None = None, dt_control_s: float = 0.005,
                 start_auto_balancer: bool = True, params: dict | None = None, record=None) -> None:
        """`record`: a path (.mcap) to record the session to, from the first tick (`stop_recording` or `close`
        finishes the file)."""
        self.host = RobotHost(scene, dt_control_s, speed, start_auto_balancer=start_auto_balancer, params=params)
        self.exit_reason: str | None = None
        self.priority = "default"
        self._published: Published | None = None
        self._setpoints = SetpointTable(self.host.setpoints.put)
        if record is not None:
            self.host.start_recording(str(record))

    def __repr__(self) -> str:
        return f"LocalRobot({self.host!r}, running={self.loop.running})"

    @property
    def loop(self):
        return self.host.loop

    @property
    def system(self):
        return self.host.system

    @property
    def chain(self):
        return self.host.loop.chain

    @property
    def kin(self):
        return self.host.system.kin

    @property
    def plant(self):
        return self.host.plant

    @property
    def scene(self) -> str:
        return self.host.scene

    @property
    def running(self) -> bool:
        return self.loop.running

    @property
    def alive(self) -> bool:
        return True

    # ---- running ------------------------------------------------------------------------------------------
    def start(self) -> None:
        self.loop.start(self.loop.speed)

    def stop(self) -> None:
        self.loop.stop()

    def step(self):
        """One tick; the Observation (the snapshot with the simulator's ground truth beside it)."""
        self.loop.step()
        return self.host.observation

    def run_for(self, seconds: float):
        self.loop.run_for(seconds)
        return self.host.observation

    def run_until(self, predicate, timeout_s: float):
        """Step until `predicate(observation)` holds; TimeoutError after `timeout_s` of simulated time."""
        for _ in range(int(round(timeout_s / self.loop.dt_control_s))):
            obs = self.step()
            if predicate(obs):
                return obs
        raise TimeoutError(f"condition not reached within {timeout_s} s of simulated time")

    @property
    def truth(self):
        return self.host.observation.truth

    # ---- channels -----------------------------------------------------------------------------------------
    def submit(self, verb: Verb) -> Future:
        if self.loop.running:
            return self.loop.submit(lambda: self.host.apply_input(verb))
        fut: Future = Future()
        try:
            fut.set_result(self.host.apply_input(verb))
        except ServiceError as exc:
            fut.set_exception(exc)
        return fut

    def put_setpoint(self, setpoint: Setpoint) -> Setpoint:
        """The operator's newest setpoint for a point (latest value: the loop takes it at its next boundary;
        without the loop thread, at once). Returns it numbered."""
        numbered = self._setpoints.put(setpoint)
        if not self.loop.running:
            table = self.host.setpoints.poll()
            if table:
                self.host.apply_setpoints(table)
        return numbered

    def setpoint_seq(self) -> int:
        return self._setpoints.last_seq

    def estop(self, press: str | None = None, timeout_s: float = 1.0) -> EstopAck:
        if self.loop.running:
            return self.loop.call(lambda: self.host.engage_estop(press), timeout_s=timeout_s)
        return self.host.engage_estop(press)

    def latest(self) -> Published:
        snap = self.loop.snapshot
        cached = self._published
        if (cached is None or cached.snapshot is not snap or cached.generation != self.host.generation
                or cached.setpoint_acks != self.host.setpoint_acks or cached.runs is not self.host.runs()
                or cached.recognitions != self.host.recognitions
                or cached.recording != self.host.recording_status()
                or cached.last_recording != self.host.last_recording_status()):
            cached = self._published = self.host.publish()
        return cached

    def info(self) -> RobotInfo:
        return self.host.info()

    def refresh_info(self, timeout_s: float = 10.0) -> RobotInfo:
        return self.host.info()

    def log_rows(self) -> np.ndarray:
        return self.host.logger.rows()

    def reset(self, scene: str | None = None, timeout_s: float = 30.0) -> RobotInfo:
        self.submit(Reset(scene)).result(timeout=timeout_s)
        return self.host.info()

    def stop_recording(self, timeout_s: float = 30.0) -> dict:
        """End the session being recorded; its status once the file is finished."""
        self.submit(StopRecording()).result()
        return self.host.last_recorder.wait(timeout_s)

    def close(self, timeout_s: float = 10.0) -> dict:
        self.stop()
        self.host.close_cameras()
        if self.host.recorder is not None:
            self.host.stop_recording()
        if self.host.last_recorder is not None:
            self.host.last_recorder.wait(max(timeout_s, 30.0))
        return self.host.stats.summary()
