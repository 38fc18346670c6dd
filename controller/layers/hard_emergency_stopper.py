"""HardEmergencyStopper layer: the operator's e-stop. A latched freeze of the command, after the step in
progress has landed; release blends back to the live input (hrpsys EmergencyStopper recover: Hoff-Arbib
re-planned every tick)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, StepInProgress, TickContext
from controller.interpolation.blend import RecoverBlend

#: the text of HardEmergencyStopperStatus.stopping while a step lands before the freeze
LANDING = "landing the step"
_EPS_S = 1e-9


@dataclass(frozen=True)
class HardEmergencyStopperParams(Params):
    recover_time_s: float = field(default=2.5, metadata={"unit": "s", "min": 0.0, "max": 30.0})
    #: the longest an operator's e-stop lets a step land before it freezes (IEC 60204-1 stop category 1: stop,
    #: then remove power); a walk's swing landing later is cut short to land within it (the AutoBalancer's catch),
    #: or, when it cannot be (this set shorter than the cut swing, the emergency step off), frozen at once
    landing_max_s: float = field(default=0.35, metadata={"unit": "s", "min": 0.0, "max": 0.35})
    #: after an emergency step's touchdown its double support runs on this long before the freeze (within
    #: landing_max_s): frozen at the touchdown the robot still carries the push's momentum (a walk's swing freezes
    #: at its touchdown)
    landing_settle_s: float = field(default=0.1, metadata={"unit": "s", "min": 0.0, "max": 0.35})
    #: standing (not walking), a press with the capture-point error above this is a robot being pushed: its balance
    #: runs on (an emergency step may come) until the error is back under it, or a step has landed
    landing_cp_error_m: float = field(default=0.015, metadata={"unit": "m", "min": 0.0, "max": 0.5})


@dataclass(frozen=True, slots=True)
class HardEmergencyStopperStatus(Status):
    engaged: bool = field(metadata=described(
        "the e-stop is engaged: the joint command is frozen, or will be once the step in progress has landed "
        "(stopping)"))
    reason: str | None = field(metadata=described("why it was engaged: 'operator', 'fault' or 'fallen'"))
    recovering: bool = field(metadata=described("blending back to the live command after a release"))
    recover_remaining_s: float = field(metadata=described("time left of that blend", "s"))
    engage_count: int = field(metadata=described("how many times it was engaged since the start"))
    stopping: str | None = field(default=None, metadata=described(
        "engaged, not frozen yet: 'landing the step' (the balance layers run the step in progress to its "
        "touchdown, at most landing_max_s, then it freezes); null: frozen, or not engaged"))
    landing_remaining_s: float = field(default=0.0, metadata=described(
        "while landing, the time left before the freeze at the latest (landing_max_s after the press)", "s"))


class HardEmergencyStopper(Layer):
    """While engaged, outputs the joint command frozen, whatever comes in, and publishes the `hold` port: from
    the next tick every layer before it holds its motion (walking stops in place, the sequence stops where it
    is), so that the live input stays where the robot is.

    An operator's e-stop during a step lets it land first (a controlled stop): in an emergency step (Ports.step
    catching), in a walk's swing whose foot is down within landing_max_s as planned or cut short (the AutoBalancer
    lands a later swing where the capture point will be: frozen on one foot the robot tips), or standing with a
    capture-point error over landing_cp_error_m (a push: a step may come), the output stays the live command and the
    `landing` port lets the balance layers run on (the motion layers hold; abc plans no step after this one),
    until the swing foot's touchdown (landing_settle_s after it for an emergency step), or the error is back under
    landing_cp_error_m with no step taken, and at the latest landing_max_s after the press; then the command
    freezes where the robot has landed. Standing still, in a walk's double support, or for a fault or a fall it
    freezes at once.

    Engaging is latched: only `release()` ends it, after which the output blends to the live input
    over recover_time_s with zero velocity at both ends; the hold lasts until the blend is over.
    """

    name = "hes"
    description = "HardEmergencyStopper: operator e-stop, latched freeze after the step lands, blended release"
    safe_stop = True

    def __init__(self, q0_rad: np.ndarray, params: HardEmergencyStopperParams | None = None) -> None:
        super().__init__()
        self.params = params or HardEmergencyStopperParams()
        self.engaged = False
        self.q_out = np.array(q0_rad, dtype=float)
        self.q_frozen: np.ndarray | None = None
        self.blend: RecoverBlend | None = None
        self.engage_count = 0
        self.reason: str | None = None
        self.landing = False  # engaged, the step in progress landing before the freeze
        self.landing_deadline_s = 0.0  # [s] control time the freeze comes at the latest
        # what the last tick saw (engage comes between ticks): the step in progress, a pushed robot standing, the
        # next tick's time
        self._step: StepInProgress | None = None
        self._pushed = False
        self._next_tick_s = 0.0

    def set_params(self, params: HardEmergencyStopperParams) -> None:
        self.params = params

    @property
    def stopping(self) -> str | None:
        """Engaged, not frozen yet: what it waits for ('landing the step'); None otherwise."""
        return LANDING if self.landing else None

    def engage(self, q_rad: np.ndarray | None = None, reason: str = "operator") -> None:  # the safe-stop port
        """Engage the stop for `reason`. The operator's lets a step in progress land first (see the class), unless
        it comes during a release blend (the output is not the live command: it freezes where the blend is); a
        fault, a fall or a given posture `q_rad` freeze now (at the last output, or at `q_rad`), also while a
        step lands. Engaging an engaged stopper is otherwise a no-op."""
        if self.engaged:
            if self.landing and (reason != "operator" or q_rad is not None):
                self.reason = reason
                self._freeze(self.q_out if q_rad is None else q_rad)
            return
        self.engaged = True
        self.reason = reason
        self.engage_count += 1
        blending, self.blend = self.blend is not None, None
        if reason == "operator" and q_rad is None and not blending and self._step_to_land():
            self.landing = True
            self.landing_deadline_s = self._next_tick_s + self.params.landing_max_s
            self.q_frozen = None
        else:
            self._freeze(self.q_out if q_rad is None else q_rad)

    def _step_to_land(self) -> bool:
        """At a press: a step is in progress that lands within landing_max_s, as planned or cut short by the
        AutoBalancer (StepInProgress.cut_swing_s), or the push that may need one."""
        step, p = self._step, self.params
        if step is None:
            return self._pushed and p.landing_max_s > 0.0
        t = self._next_tick_s
        left_s = step.touchdown_time_s - t if step.cut_swing_s is None else min(step.touchdown_time_s - t,
                                                                               step.cut_swing_s)
        return left_s < p.landing_max_s - _EPS_S and t < self._freeze_time_s(step) - _EPS_S

    def _freeze(self, q_rad: np.ndarray) -> None:
        self.landing = False
        self.q_frozen = np.array(q_rad, dtype=float)

    def release(self) -> None:
        if not self.engaged:
            raise InvalidState("hard e-stop is not engaged; nothing to release")
        self.engaged = False
        self.reason = None
        if self.landing:  # not frozen yet: the output is the live command already
            self.landing = False
            return
        self.blend = RecoverBlend(self.q_frozen, self.params.recover_time_s, carry_motion=True)
        self.q_frozen = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        ports = ctx.ports
        self._step = ports.step
        self._pushed = self._is_pushed(ports)
        self._next_tick_s = ctx.time_s + ctx.dt_s  # this tick's command holds until then
        if self.landing and self._landed(ctx.time_s, ctx.dt_s, ports.step, self._pushed):
            self._freeze(ref.q_rad)
        # the layers before it hold until the release blend is over: it blends to a still target, and they
        # resume from exactly where the robot then is; while a step lands the balance layers run on
        ports.hold = self.engaged or self.blend is not None
        ports.releasing = self.blend is not None
        ports.landing = self.landing
        if self.landing:
            self.q_out = np.asarray(ref.q_rad)
            return ref
        if self.engaged:
            self.q_out = self.q_frozen
            return ref.with_(q_rad=self.q_frozen)
        if self.blend is not None:
            self.q_out = self.blend.step(ref.q_rad, ctx.dt_s)
            if self.blend.done:
                self.blend = None
            return ref.with_(q_rad=self.q_out)
        self.q_out = np.asarray(ref.q_rad)
        return ref

    def _is_pushed(self, ports) -> bool:
        """Standing (not walking) with a capture-point error over landing_cp_error_m."""
        gait = ports.gait
        return gait is not None and not gait.walking and ports.cp_error_m > self.params.landing_cp_error_m

    def _landed(self, t_s: float, dt_s: float, step: StepInProgress | None, pushed: bool) -> bool:
        """Time to freeze on the command of this tick (from t_s [s] to t_s + dt_s): the step is down (and settled),
        or no step came and the robot is no longer pushed, or the bound ends with this tick."""
        if t_s + dt_s >= self.landing_deadline_s - _EPS_S:
            return True
        if step is None:
            return not pushed
        return t_s >= self._freeze_time_s(step) - _EPS_S

    def _freeze_time_s(self, step: StepInProgress) -> float:
        """When the step is down: its touchdown, and landing_settle_s after it for an emergency step [s]."""
        return step.touchdown_time_s + (self.params.landing_settle_s if step.catching else 0.0)

    def status(self) -> HardEmergencyStopperStatus:
        return HardEmergencyStopperStatus(
            enabled=self.enabled, engaged=self.engaged, reason=self.reason, recovering=self.blend is not None,
            recover_remaining_s=0.0 if self.blend is None else round(self.blend.remaining_s, 4),
            engage_count=self.engage_count, stopping=self.stopping,
            landing_remaining_s=round(max(0.0, self.landing_deadline_s - self._next_tick_s), 4) if self.landing
            else 0.0)
