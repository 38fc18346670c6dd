"""[OP] Eq. 5 per tick: the operator's streamed twists (after the dead-man) plus the behaviours' (one tick only)."""

from __future__ import annotations

from collections.abc import Mapping

from controller.operation.deadman import StreamedSetpoints
from controller.operation.points import Twist, sum_per_point


class CommandSum:
    """The two sources of a point's twist and their sum. The behaviours' twists count for the next `take` only;
    `motion` and `behavior` keep what the last `take` summed (for the status)."""

    __slots__ = ("streamed", "_behavior", "_behavior_walk", "motion", "behavior")

    def __init__(self) -> None:
        self.streamed = StreamedSetpoints()
        self._behavior: dict[str, Twist] = {}
        self._behavior_walk = None  # the behaviours' walking step parameters (a WalkCommand), until replaced
        self.motion: dict[str, Twist] = {}  # the operator's twists of the last take, after the dead-man
        self.behavior: dict[str, Twist] = {}  # the behaviours' twists of the last take

    def set_behavior(self, twists: Mapping[str, Twist], walk_steps=None) -> None:
        """The behaviours' sum per point (checked by the caller) for the next take only."""
        self._behavior = dict(twists)
        self._behavior_walk = walk_steps

    def drop_behavior(self) -> None:
        self._behavior = {}

    def take(self, time_s: float, deadman_timeout_s: float, deadman_ramp_s: float) -> tuple[dict[str, Twist], bool]:
        """(the summed twist per point at control time `time_s` [s], whether a source is or was non-empty: the
        status' twists may have changed); the behaviours' twists are used up."""
        motion = self.streamed.live(time_s, deadman_timeout_s, deadman_ramp_s)
        behavior = self._behavior
        if behavior:
            self._behavior = {}
        changed = bool(motion or behavior or self.motion or self.behavior)
        self.motion, self.behavior = motion, behavior
        return (sum_per_point(motion, behavior) if behavior else motion), changed

    def walk_steps(self):
        """The walking point's step parameters: the operator's, else the behaviours' (None: the gait's own)."""
        return self.streamed.walk_steps or self._behavior_walk
