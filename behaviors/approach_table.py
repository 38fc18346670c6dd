"""`approach_table`: walk to the predefined standing position in front of the table, whose place is known
(the EXPO scene's table, robot/hrp2/README.md): facing its near long side, a set distance from it."""

from __future__ import annotations

from dataclasses import dataclass, field

from behaviors.base import BehaviorParams, Context
from behaviors.composite import Composite, Plan
from behaviors.walk_to import WalkTo, WalkToParams

#: The table's known place: near long side at x = 2.0 m, centred on y = 0, the robot facing +x.
TABLE_NEAR_EDGE_X_M = 2.0
TABLE_CENTRE_Y_M = 0.0


@dataclass(frozen=True)
class ApproachTableParams(BehaviorParams):
    standoff_m: float = field(default=0.3, metadata={"unit": "m", "min": 0.15, "max": 3.0,
                                                     "doc": "feet centre to the table's near edge"})
    along_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.75, "max": 0.75,
                                                  "doc": "along the edge from its middle (+ to the robot's left)"})
    tolerance_m: float = field(default=0.03, metadata={"unit": "m", "min": 0.005, "max": 0.5})


class ApproachTable(Composite):
    name = "approach_table"
    Params = ApproachTableParams
    summary = "Walk to the standing position in front of the table (standoff_m from its near edge)"
    phases = ("walk",)
    remaining_estimate_s = 2.0

    def points(self) -> tuple[str, ...]:
        return ("walk",)

    def plan(self, ctx: Context) -> Plan:
        p = self.params
        self.set_phase("walk")
        walk = self.require((yield WalkTo(WalkToParams(x_m=TABLE_NEAR_EDGE_X_M - p.standoff_m,
                                                       y_m=TABLE_CENTRE_Y_M + p.along_m, theta_deg=0.0,
                                                       tolerance_m=p.tolerance_m))))
        self.result.update(walk.result)
        return f"at the table: {walk.outcome[1]}"
