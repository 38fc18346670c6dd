"""What `locate_can` and `locate_trash_box` share ([OP] II: the operator says where to look, the robot
locates): point the head there (look_at), let it settle, recognise; if it is not in view, look beside it; when
found, look straight at it and recognise again (a centred, whole view); remember and publish the result."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import BehaviorParams, Context
from behaviors.composite import Composite, Plan, StepFailed, Wait
from behaviors.look_at import LookAt, LookAtParams
from behaviors.recognise import Recognise, RecogniseParams
from behaviors.servo import wrap_rad
from behaviors.walk_to import WalkTo, WalkToParams

VIEW_OFFSETS = (0.0, 1.0, -1.0, 2.0, -2.0)  # views beside the first, in scan_m steps across the line of sight
#: Beyond this bearing from the feet's heading [deg] the robot first turns on the spot to face the look point
#: (the head yaws 45 deg at most).
TURN_BEYOND_DEG = 30.0


def locate_params(look_x_m: float, look_y_m: float, look_z_m: float):
    """A Params class for a locating behaviour whose look point defaults to (look_x_m, look_y_m, look_z_m)
    (world)."""

    @dataclass(frozen=True)
    class LocateParams(BehaviorParams):
        x_m: float = field(default=look_x_m, metadata={"unit": "m", "min": -20.0, "max": 20.0,
                                                  "doc": "where to look first, world x"})
        y_m: float = field(default=look_y_m, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "world y"})
        z_m: float = field(default=look_z_m, metadata={"unit": "m", "min": -5.0, "max": 10.0, "doc": "world z"})
        views: int = field(default=3, metadata={"unit": "-", "min": 1, "max": len(VIEW_OFFSETS),
                                                "doc": "views to try: there, then beside it alternately"})
        scan_m: float = field(default=0.45, metadata={"unit": "m", "min": 0.05, "max": 2.0,
                                                      "doc": "spacing of the views across the line of sight"})
        settle_s: float = field(default=0.3, metadata={"unit": "s", "min": 0.0, "max": 3.0,
                                                       "doc": "the head settles this long before an image"})
        rate_deg_s: float = field(default=60.0, metadata={"unit": "deg/s", "min": 5.0, "max": 90.0,
                                                          "doc": "peak gaze rate"})

    return LocateParams


class LocateObject(Composite):
    """Base of the locating behaviours; subclasses set `object_name`, `name`, `Params`, `summary`."""

    object_name: str
    phases = ("look", "recognise", "centre", "confirm")
    remaining_estimate_s = 8.0

    def points(self) -> tuple[str, ...]:
        return ("head", "walk")

    def preview(self, ctx: Context, predicted, into, phase: str):
        """Taken as finding the object where it is remembered (the plan that follows reads the memory); not
        remembered yet, what follows cannot be planned before it is located."""
        ctx.commands.recalled(self.object_name)  # the preview's commands end the preview when it is not there
        return predicted

    def _look(self, target) -> LookAt:
        return LookAt(LookAtParams(x_m=float(target[0]), y_m=float(target[1]), z_m=float(target[2]),
                                   rate_deg_s=self.params.rate_deg_s, tolerance_deg=2.0))

    def plan(self, ctx: Context) -> Plan:
        p = self.params
        view = ctx.require_view()
        target = np.array([p.x_m, p.y_m, p.z_m])
        sight = target[:2] - np.asarray(view.feet_p_world_m)[:2]
        n = np.linalg.norm(sight)
        across = np.array([-sight[1], sight[0]]) / n if n > 1e-6 else np.array([0.0, 1.0])
        bearing = math.atan2(sight[1], sight[0])
        if abs(wrap_rad(bearing - view.feet_yaw_rad)) > math.radians(TURN_BEYOND_DEG):
            self.set_phase("look")
            feet = np.asarray(view.feet_p_world_m)
            self.require((yield WalkTo(WalkToParams(x_m=float(feet[0]), y_m=float(feet[1]),
                                                    theta_deg=math.degrees(bearing)))))
        found = None
        for k, offset in enumerate(VIEW_OFFSETS[:p.views]):
            self.set_phase("look")
            point = target.copy()
            point[:2] += offset * p.scan_m * across
            self.require((yield self._look(point)))
            yield Wait(p.settle_s)
            self.set_phase("recognise")
            seen = yield Recognise(RecogniseParams(object=self.object_name, require=False))
            self.result["views_tried"] = k + 1
            if seen.found is not None:
                found = seen.found
                break
        if found is None:
            raise StepFailed(f"no {self.object_name} in {p.views} view(s) around ({p.x_m:.2f}, {p.y_m:.2f}) m")
        self.set_phase("centre")  # look straight at it: a whole view near the image centre
        self.require((yield self._look(found["position_m"])))
        yield Wait(p.settle_s)
        self.set_phase("confirm")
        again = yield Recognise(RecogniseParams(object=self.object_name, require=False))
        if again.found is not None and not again.found["at_border"]:
            found = again.found
        feet = np.asarray(self.view.feet_p_world_m)
        found = {**found, "from_m": round(float(np.linalg.norm(np.asarray(found["position_m"][:2]) - feet[:2])), 4)}
        ctx.commands.remember(self.object_name, found)
        self.result["recognition"] = found
        x, y, z = found["position_m"]
        sx, sy, _ = found["sigma_m"]
        return (f"{self.object_name} at ({x:.3f}, {y:.3f}, {z:.3f}) m, "
                f"sigma {1e3 * math.hypot(sx, sy):.1f} mm")
