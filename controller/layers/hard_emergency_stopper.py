"""HardEmergencyStopper layer: the operator's e-stop. A latched freeze of the command; release blends
back to the live input (hrpsys EmergencyStopper recover: Hoff-Arbib re-planned every tick)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext
from controller.interpolation.blend import RecoverBlend


@dataclass(frozen=True)
class HardEmergencyStopperParams(Params):
    recover_time_s: float = field(default=2.5, metadata={"unit": "s", "min": 0.0, "max": 30.0})


@dataclass(frozen=True, slots=True)
class HardEmergencyStopperStatus(Status):
    engaged: bool = field(metadata=described("the joint command is frozen"))
    reason: str | None = field(metadata=described("why it was engaged: 'operator', 'fault' or 'fallen'"))
    recovering: bool = field(metadata=described("blending back to the live command after a release"))
    recover_remaining_s: float = field(metadata=described("time left of that blend", "s"))
    engage_count: int = field(metadata=described("how many times it was engaged since the start"))


class HardEmergencyStopper(Layer):
    """While engaged, outputs the joint command frozen at the moment of engaging, whatever comes in, and
    publishes the `hold` port: from the next tick every layer before it holds its motion (walking stops
    in place, the sequence stops where it is), so that the live input stays where the robot is.

    Engaging is latched: only `release()` ends it, after which the output blends to the live input
    over recover_time_s with zero velocity at both ends; the hold lasts until the blend is over.
    """

    name = "hes"
    description = "HardEmergencyStopper: operator e-stop, latched freeze, blended release"
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

    def set_params(self, params: HardEmergencyStopperParams) -> None:
        self.params = params

    def engage(self, q_rad: np.ndarray | None = None, reason: str = "operator") -> None:  # the safe-stop port
        """Freeze now (at the last output, or at `q_rad`). Engaging an engaged stopper is a no-op."""
        if self.engaged:
            return
        self.engaged = True
        self.reason = reason
        self.engage_count += 1
        self.blend = None
        self.q_frozen = np.array(self.q_out if q_rad is None else q_rad, dtype=float)

    def release(self) -> None:
        if not self.engaged:
            raise InvalidState("hard e-stop is not engaged; nothing to release")
        self.engaged = False
        self.reason = None
        self.blend = RecoverBlend(self.q_frozen, self.params.recover_time_s, carry_motion=True)
        self.q_frozen = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        # the layers before it hold until the release blend is over: it blends to a still target, and they
        # resume from exactly where the robot then is
        ctx.ports.hold = self.engaged or self.blend is not None
        ctx.ports.releasing = self.blend is not None
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

    def status(self) -> HardEmergencyStopperStatus:
        return HardEmergencyStopperStatus(
            enabled=self.enabled, engaged=self.engaged, reason=self.reason, recovering=self.blend is not None,
            recover_remaining_s=0.0 if self.blend is None else round(self.blend.remaining_s, 4),
            engage_count=self.engage_count)
