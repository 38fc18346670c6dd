"""The EXPO table as the robot knows it ([OP] VI: the table is at a known place): its near edge, its width and
where its legs stand, in the world (odometry) frame, for behaviours that choose where to stand beside it."""

from __future__ import annotations

from dataclasses import dataclass, replace

import robot.generate as gen


@dataclass(frozen=True)
class KnownTable:
    """A table whose near long side faces -x: the side at `near_edge_x_m`, centred on `centre_y_m` [m]."""

    near_edge_x_m: float
    centre_y_m: float = gen.EXPO_TABLE_CENTRE_Y_M
    width_m: float = gen.EXPO_TABLE_SIZE_M[1]  # along y
    leg_size_m: float = gen.EXPO_TABLE_LEG_SIZE_M  # square legs
    leg_inset_m: float = gen.EXPO_TABLE_LEG_INSET_M  # the legs' outer faces from the top's edges

    def shifted(self, dx_m: float, dy_m: float) -> KnownTable:
        """The same table moved by (dx, dy) [m]: where odometry that drifted by that much places it."""
        return replace(self, near_edge_x_m=self.near_edge_x_m + dx_m, centre_y_m=self.centre_y_m + dy_m)

    @property
    def near_leg_face_x_m(self) -> float:
        """World x [m] of the near legs' faces that look at the robot."""
        return self.near_edge_x_m + self.leg_inset_m

    def near_leg_spans_y_m(self) -> tuple[tuple[float, float], ...]:
        """(low, high) world y [m] of each of the two near legs."""
        out = self.width_m / 2 - self.leg_inset_m
        return ((self.centre_y_m - out, self.centre_y_m - out + self.leg_size_m),
                (self.centre_y_m + out - self.leg_size_m, self.centre_y_m + out))
