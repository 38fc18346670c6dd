"""HardEmergencyStopper layer: the operator's e-stop. A latched freeze of the command; release blends
back to the live input (hrpsys EmergencyStopper recover: Hoff-Arbib re-planned every tick)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.blend import RecoverBlend
from controller.errors import InvalidState
from controller.layer import Layer, Params
from controller.types import Reference, TickContext


@dataclass(frozen=True)
class HardEmergencyStopperParams(Params):
    recover_time_s: float = field(default=2.5, metadata={"unit": "s", "min": 0.0, "max": 30.0})


class HardEmergencyStopper(Layer):
    """While engaged, outputs the joint command frozen at the moment of engaging, whatever comes in.

    Engaging is latched: only `release()` ends it, after which the output blends to the live input
    over recover_time_s with zero velocity at both ends.
    """

    name = "hes"
    description = "HardEmergencyStopper: operator e-stop, latched freeze, blended release"

    def __init__(self, q0_rad: np.ndarray, params: HardEmergencyStopperParams | None = None) -> None:
        super().__init__()
        self.params = params or HardEmergencyStopperParams()
        self.engaged = False
        self.q_out = np.array(q0_rad, dtype=float)
        self.q_frozen: np.ndarray | None = None
        self.blend: RecoverBlend | None = None
        self.engage_count = 0

    def set_params(self, params: HardEmergencyStopperParams) -> None:
        self.params = params

    def engage(self, q_rad: np.ndarray | None = None) -> None:
        """Freeze now (at the last output, or at `q_rad`). Engaging an engaged stopper is a no-op."""
        if self.engaged:
            return
        self.engaged = True
        self.engage_count += 1
        self.blend = None
        self.q_frozen = np.array(self.q_out if q_rad is None else q_rad, dtype=float)

    def release(self) -> None:
        if not self.engaged:
            raise InvalidState("hard e-stop is not engaged; nothing to release")
        self.engaged = False
        self.blend = RecoverBlend(self.q_frozen, self.params.recover_time_s)
        self.q_frozen = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
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

    def reset(self, ctx: TickContext, ref: Reference) -> None:
        self.engaged, self.blend, self.q_frozen = False, None, None
        self.q_out = np.array(ref.q_rad, dtype=float)

    def status(self) -> dict:
        return {"enabled": self.enabled, "engaged": self.engaged, "recovering": self.blend is not None,
                "recover_remaining_s": 0.0 if self.blend is None else round(self.blend.remaining_s, 4),
                "engage_count": self.engage_count}
