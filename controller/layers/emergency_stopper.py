"""EmergencyStopper layer ([MLC] III-E, Eq. 15): stops the planned motion and reverts it by T1 over T2
when the Stabilizer's capture-point flag rises, the AutoBalancer takes an emergency step or the operator says
stop; the balance layers after it keep running. Release blends back to the live plan (hrpsys recover)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext
from controller.interpolation.blend import RecoverBlend
from controller.interpolation.hoff_arbib import quintic_step


@dataclass(frozen=True)
class EmergencyStopperParams(Params):
    # T1: how far back in the planned stream to revert; T2: how long the revert takes ([MLC] Eq. 15)
    t1_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.0, "max": 10.0})
    t2_s: float = field(default=0.5, metadata={"unit": "s", "min": 0.0, "max": 10.0})
    recover_time_s: float = field(default=2.5, metadata={"unit": "s", "min": 0.0, "max": 30.0})


@dataclass(frozen=True, slots=True)
class EmergencyStopperStatus(Status):
    stopped: bool = field(metadata=described("the planned motion is stopped (reverting or holding)"))
    reason: str | None = field(metadata=described(
        "why: 'capture_point' (the Stabilizer's flag), 'emergency_step' (the AutoBalancer's) or 'operator'"))
    flag_time: float | None = field(metadata=described("simulated time of the last stop", "s"))
    recovering: bool = field(metadata=described("blending back to the live plan after a release"))
    t1_s: float = field(metadata=described("T1: how far back the revert goes", "s"))
    t2_s: float = field(metadata=described("T2: how long the revert takes", "s"))
    cp_error_m: float | None = field(default=None, metadata=described(
        "reason 'capture_point': |CP error| of the tick the flag rose (what raised the stop, not the value now)",
        "m"))


def pack(ref: Reference) -> np.ndarray:
    """The SequencePlayer outputs Eq. 15 acts on, as one vector: q, base pos, base rpy, zmp, wrenches."""
    return np.concatenate((ref.q_rad, ref.base_pos_world, ref.base_rpy_rad, ref.zmp_base, ref.wrenches.ravel()))


def unpack(ref: Reference, x: np.ndarray) -> Reference:
    n = len(ref.q_rad)
    return ref.with_(q_rad=x[:n], base_pos_world=x[n:n + 3], base_rpy_rad=x[n + 3:n + 6],
                     zmp_base=x[n + 6:n + 9], wrenches=x[n + 9:].reshape(ref.wrenches.shape))


class MotionReverter:
    """Eq. 15 on a stream of vectors, one sample per tick. Pure maths: no flags, no layer logic.

    `push(t, x_seq)` records the planned stream; `stop(t_emer)` starts a revert to x_seq(t_emer - T1)
    finishing at t_emer + T2 with zero velocity; `output(t, x_seq)` gives x_es(t).
    """

    def __init__(self, params: EmergencyStopperParams, dt_s: float) -> None:
        self.params = params
        self.dt_s = dt_s
        self._history: deque[tuple[float, np.ndarray]] = deque()
        self.stopped = False
        self.t_emer: float | None = None
        self.target: np.ndarray | None = None
        self.x = self.v = self.a = None

    def push(self, t: float, x_seq: np.ndarray) -> None:
        self._history.append((t, x_seq))
        horizon = self.params.t1_s + 2 * self.dt_s
        while len(self._history) > 1 and self._history[1][0] <= t - horizon:
            self._history.popleft()

    def sample_at(self, t: float) -> np.ndarray:
        """The recorded x_seq at time t (the latest sample not after t; the oldest if none)."""
        best = self._history[0][1]
        for ts, xs in self._history:
            if ts <= t + 1e-9:
                best = xs
            else:
                break
        return best

    def stop(self, t_emer: float, x_es_prev: np.ndarray, v_prev: np.ndarray | None = None) -> None:
        self.stopped = True
        self.t_emer = t_emer
        self.target = self.sample_at(t_emer - self.params.t1_s).copy()
        self.x = np.array(x_es_prev, dtype=float)
        self.v = np.zeros_like(self.x) if v_prev is None else np.array(v_prev, dtype=float)
        self.a = np.zeros_like(self.x)

    def output(self, t: float, x_seq: np.ndarray) -> np.ndarray:
        if not self.stopped:
            return x_seq
        dt_rem = self.t_emer + self.params.t2_s - t  # remaining time of the revert [s]
        if dt_rem <= 1e-12:
            self.x, self.v, self.a = self.target.copy(), np.zeros_like(self.x), np.zeros_like(self.x)
            return self.x  # second case: hold x_seq(t_rev)
        # third case: HoffArbib(x_es(t - 1), x_seq(t_rev), dt_rem), re-planned from the current state
        step = min(self.dt_s, dt_rem)
        self.x, self.v, self.a = quintic_step(self.x, self.v, self.a, self.target, dt_rem + step, step)
        return self.x

    def release(self) -> None:
        self.stopped = False
        self.t_emer = None


class EmergencyStopper(Layer):
    """Sits after the SequencePlayer. Autonomous stop from the `cp_flag` port (the Stabilizer's capture-point
    flag, one tick old as in hrpsys) and the `emergency_step` port (the AutoBalancer steps), manual stop from
    `stop_motion()`; latched until `release_motion()`.
    While the hard e-stop holds the chain, the flag is not acted on (nothing moves to revert)."""

    name = "es"
    description = "EmergencyStopper: stop and revert the planned motion (Eq. 15)"

    def __init__(self, dt_s: float, params: EmergencyStopperParams | None = None) -> None:
        super().__init__()
        self.params = params or EmergencyStopperParams()
        self.dt_s = dt_s
        self.reverter = MotionReverter(self.params, dt_s)
        self.blend: RecoverBlend | None = None
        self._requested: str | None = None
        self.reason: str | None = None
        self.flag_time_s: float | None = None
        self.cp_error_m: float | None = None  # reason 'capture_point': |CP error| when the flag rose [m]
        self._last_out: np.ndarray | None = None
        self._prev_out: np.ndarray | None = None
        self._signal_up = False  # the flag or an emergency step on the last tick: a release would re-latch

    def set_params(self, params: EmergencyStopperParams) -> None:
        self.params = params
        self.reverter.params = params

    @property
    def stopped(self) -> bool:
        return self.reverter.stopped

    def stop_motion(self) -> None:
        """Operator stop (hrpsys stopMotion); a no-op when already stopped."""
        self._requested = "operator"

    def release_motion(self) -> None:
        if not self.stopped and self._requested is None:
            raise InvalidState("motion is not stopped; nothing to release")
        if self.stopped and self._signal_up:  # refused, not answered 'released' and latched again next tick
            raise InvalidState("the capture-point flag or an emergency step is still up; the motion stop stays "
                               "latched until it drops (CP error under the release threshold for the hold time)")
        self._requested = None
        if self.stopped:
            self.reverter.release()
            self.blend = RecoverBlend(self._last_out, self.params.recover_time_s)
            self.reason = None
            self.cp_error_m = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if not self.enabled:
            return ref
        x_seq = pack(ref)
        t = ctx.time_s
        self.reverter.push(t, x_seq)
        last = ctx.last_ports
        flag = last.cp_flag and not last.hold
        step = last.emergency_step and not last.hold
        self._signal_up = bool(flag or step)
        if not self.stopped and (flag or step or self._requested):
            self.reason = self._requested or ("emergency_step" if step else "capture_point")
            self.flag_time_s = t
            self.cp_error_m = last.cp_flag_error_m if self.reason == "capture_point" else None
            self._requested = None
            prev = self._last_out if self._last_out is not None else x_seq
            v = None if self._prev_out is None else (prev - self._prev_out) / ctx.dt_s
            self.blend = None
            self.reverter.stop(t, prev, v)
        if self.stopped:
            x = self.reverter.output(t, x_seq)
        elif self.blend is not None:
            x = self.blend.step(x_seq, ctx.dt_s)
            if self.blend.done:
                self.blend = None
        else:
            x = x_seq
        self._prev_out, self._last_out = self._last_out, x
        if self.stopped:  # the layers before (op) freeze their motion and know where the revert went back to
            ctx.ports.motion_stopped = True
            ctx.ports.motion_reverted_to_s = self.reverter.t_emer - self.params.t1_s
        return ref if x is x_seq else unpack(ref, x)

    def status(self) -> EmergencyStopperStatus:
        return EmergencyStopperStatus(enabled=self.enabled, stopped=self.stopped, reason=self.reason,
                                      flag_time=self.flag_time_s, recovering=self.blend is not None,
                                      t1_s=self.params.t1_s, t2_s=self.params.t2_s, cp_error_m=self.cp_error_m)
