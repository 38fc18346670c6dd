"""Where the thrown can ended, from the head's images ([OP] II: the robot shows the operator what it perceives):
step back from the box, look at it and at the floor on either side, recognise the can. Seen outside the lid's
outline, or on the lid: out of the box, with where; within the outline below the lid's top: in; not seen around
the box: in (it fell through the hole, where the box's walls hide it). The verdict is remembered as the can's
recognition, so the camera view shows it over the box."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import BehaviorParams, Context
from behaviors.composite import Composite, Plan, Wait
from behaviors.look_at import LookAt, LookAtParams
from behaviors.perception.models import IN_BOX, OUT_OF_BOX, TRASH_BOX
from behaviors.recognise import Recognise, RecogniseParams
from behaviors.walk_to import WalkTo, WalkToParams

#: The looks [m], world: the box's middle (lid and floor at its foot), then this far on either side of it across
#: the line of sight (the narrow camera's 33 deg cover ~0.8 m at the 1.4 m it looks from).
LOOK_ASIDE_M = 0.45
LOOK_HEIGHT_M = 0.3  # between the floor and the lid [m]
SETTLE_S = 0.3


@dataclass(frozen=True)
class Landing:
    """The verdict and its grounds: the can's recognised position [m] (world) or None when it was not seen."""

    verdict: str
    can_world_m: tuple[float, float, float] | None
    along_m: float | None  # the can from the hole's centre along the box's long side [m]
    across_m: float | None

    def detail(self) -> str:
        if self.can_world_m is None:
            return "not seen around the box: fallen through the hole"
        x, y, _ = self.can_world_m
        where = "inside the lid's outline" if self.verdict == IN_BOX else "outside the box"
        return (f"seen {where} at ({x:.2f}, {y:.2f}) m, {1e3 * self.along_m:+.0f} mm along and "
                f"{1e3 * self.across_m:+.0f} mm across the hole's centre")


def landing_verdict(can_world_m, hole_world_m, box_yaw_deg: float,
                    lid_m: tuple[float, float] = TRASH_BOX.lid_m) -> Landing:
    """In or out from where the can was seen (None: not seen), the hole's centre [m] and the box's yaw [deg]
    (the long side's heading): in when within the lid's outline and below its top."""
    if can_world_m is None:
        return Landing(IN_BOX, None, None, None)
    can, hole = np.asarray(can_world_m, dtype=float), np.asarray(hole_world_m, dtype=float)
    if can.shape != (3,) or hole.shape != (3,):
        raise ValueError(f"can_world_m and hole_world_m must be 3 numbers [m], got {can.shape} and {hole.shape}")
    c, s = math.cos(math.radians(box_yaw_deg)), math.sin(math.radians(box_yaw_deg))
    d = can - hole
    along, across = float(c * d[0] + s * d[1]), float(-s * d[0] + c * d[1])
    inside = abs(along) <= lid_m[0] / 2 and abs(across) <= lid_m[1] / 2 and can[2] < hole[2]
    return Landing(IN_BOX if inside else OUT_OF_BOX, tuple(float(v) for v in can), along, across)


def _m(doc: str, lo: float = -20.0, hi: float = 20.0, unit: str = "m"):
    return field(default=0.0, metadata={"unit": unit, "min": lo, "max": hi, "doc": doc})


@dataclass(frozen=True)
class CheckLandingParams(BehaviorParams):
    hole_x_m: float = _m("the located hole's centre, world x")
    hole_y_m: float = _m("world y")
    hole_z_m: float = _m("world z (the lid's top)", -5.0, 10.0)
    box_yaw_deg: float = _m("the box's long side's heading", -180.0, 180.0, "deg")
    stance_x_m: float = _m("where to look from, world x")
    stance_y_m: float = _m("world y")
    stance_yaw_deg: float = _m("heading there", -180.0, 180.0, "deg")


class CheckLanding(Composite):
    """Run by throw_can after the release, with the box it located and the stance it looked from."""

    name = "check_landing"
    Params = CheckLandingParams
    summary = "Step back, look at the trash box and around it, and say whether the can is in it"
    phases = ("step back", "look", "recognise")
    remaining_estimate_s = 12.0

    def points(self) -> tuple[str, ...]:
        return ("head", "walk")

    def plan(self, ctx: Context) -> Plan:
        p = self.params
        hole = np.array([p.hole_x_m, p.hole_y_m, p.hole_z_m])
        self.set_phase("step back")
        self.require((yield WalkTo(WalkToParams(x_m=p.stance_x_m, y_m=p.stance_y_m, theta_deg=p.stance_yaw_deg))))
        feet = np.asarray(self.view.feet_p_world_m, dtype=float)
        sight = hole[:2] - feet[:2]
        across = np.array([-sight[1], sight[0]]) / max(float(np.linalg.norm(sight)), 1e-6)
        seen = None
        for k, aside in enumerate((0.0, LOOK_ASIDE_M, -LOOK_ASIDE_M)):
            self.set_phase("look")
            point = np.array([*(hole[:2] + aside * across), LOOK_HEIGHT_M])
            self.require((yield LookAt(LookAtParams(x_m=float(point[0]), y_m=float(point[1]), z_m=float(point[2]),
                                                    rate_deg_s=60.0, tolerance_deg=2.0))))
            yield Wait(SETTLE_S)
            self.set_phase("recognise")
            got = yield Recognise(RecogniseParams(object="can", require=False))
            self.result["views_tried"] = k + 1
            if got.found is not None:
                seen = got.found
                break
        landing = landing_verdict(None if seen is None else seen["position_m"], hole, p.box_yaw_deg)
        shown = dict(seen) if seen is not None else {"object": "can", "position_m": [float(v) for v in hole],
                                                     "time_s": round(ctx.time_s, 4)}
        shown.update(status=landing.verdict, verdict_detail=landing.detail())
        ctx.commands.remember("can", shown)
        self.result["landing"] = {"verdict": landing.verdict, "detail": landing.detail(),
                                  "can_world_m": None if seen is None else seen["position_m"]}
        return f"the can landed {landing.verdict}: {landing.detail()}"
