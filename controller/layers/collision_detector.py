"""CollisionDetector layer: self-collision check of the commanded posture; on collision it outputs the
last collision-free posture of the upper body (the legs stay the balancer's), and blends back to the input once the
input is free again ([MLC] III)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext
from controller.interpolation.blend import RecoverBlend
from robot.names import JOINT_NAMES, MJCF_ROBOT


@dataclass(frozen=True)
class CollisionDetectorParams(Params):
    # pairs closer than this count as colliding: the command stops short of contact
    margin_m: float = field(default=0.005, metadata={"unit": "m", "min": 0.0, "max": 0.1})
    recover_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.0, "max": 10.0})


class SelfCollisionChecker:
    """The robot's own geometry (the robot-only MJCF, no world) used as a geometry library:
    put the posture in, get the colliding body pairs out. It never sees the simulation state."""

    def __init__(self, mjcf_path: str | Path = MJCF_ROBOT, margin_m: float = 0.005) -> None:
        self.model = mujoco.MjModel.from_xml_path(str(mjcf_path))
        self.data = mujoco.MjData(self.model)
        self.qpos_adr = np.array([self.model.joint(n).qposadr[0] for n in JOINT_NAMES])
        adr = self.qpos_adr.tolist()
        # the joints' qpos entries as a slice when consecutive (a cheaper write); the qpos view, kept
        self._qpos_index = slice(adr[0], adr[-1] + 1) if adr == list(range(adr[0], adr[0] + len(adr))) else adr
        self._qpos = self.data.qpos
        self._free_geom_margin = self.model.geom_margin.copy()
        self._body_names = [self.model.body(i).name for i in range(self.model.nbody)]
        self._last_key: tuple[bytes, float] | None = None  # (posture, margin) of _last_pairs
        self._last_pairs: list[tuple[str, str]] = []
        self.set_margin(margin_m)

    def set_margin(self, margin_m: float) -> None:
        self.margin_m = float(margin_m)
        self.model.geom_margin[:] = self._free_geom_margin + self.margin_m

    def colliding_pairs(self, q_rad: np.ndarray) -> list[tuple[str, str]]:
        """The body pairs closer than the margin in posture `q_rad`; the last answer is kept for an
        unchanged posture and margin (a pure function of both: a standing command is checked once)."""
        key = (np.asarray(q_rad, dtype=float).tobytes(), self.margin_m)
        if key != self._last_key:
            self._last_pairs = self._colliding_pairs(q_rad)
            self._last_key = key
        return list(self._last_pairs)

    def _colliding_pairs(self, q_rad: np.ndarray) -> list[tuple[str, str]]:
        d = self.data
        self._qpos[self._qpos_index] = q_rad
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        n = d.ncon
        if n == 0:
            return []
        con = d.contact
        close = np.flatnonzero(con.dist[:n] < self.margin_m)
        body = self.model.geom_bodyid
        names = self._body_names
        return [(names[body[con.geom1[i]]], names[body[con.geom2[i]]]) for i in close]


@dataclass(frozen=True, slots=True)
class CollisionDetectorStatus(Status):
    collision: bool = field(metadata=described(
        "the command would collide: the upper body's last collision-free posture is held (the legs balance on)"))
    pairs: tuple[tuple[str, str], ...] = field(metadata=described("colliding body pairs (at most four)"))
    recovering: bool = field(metadata=described("blending back to the live command after a collision"))
    collision_ticks: int = field(metadata=described("ticks spent holding since the start"))


#: the joints a collision never holds: the legs keep following the AutoBalancer and the Stabilizer (campaign seed
#: 6003: an elbow against the chest froze the legs as a foot was about to lift, the COM stayed over the other foot,
#: the capture-point flag rose and stayed up)
BALANCING_JOINTS = np.array(["LEG_JOINT" in n for n in JOINT_NAMES])


class CollisionDetector(Layer):
    name = "co"
    description = "CollisionDetector: holds the upper body's last collision-free posture"

    def __init__(self, q0_rad: np.ndarray, params: CollisionDetectorParams | None = None,
                 checker: SelfCollisionChecker | None = None) -> None:
        super().__init__()
        self.params = params or CollisionDetectorParams()
        self.checker = checker or SelfCollisionChecker(margin_m=self.params.margin_m)
        self.q_safe = np.array(q0_rad, dtype=float)
        self.q_in = self.q_safe  # the last input posture (tick)
        self.in_collision = False
        self.pairs: list[tuple[str, str]] = []
        self.blend: RecoverBlend | None = None
        self.collision_ticks = 0

    def set_params(self, params: CollisionDetectorParams) -> None:
        self.params = params
        self.checker.set_margin(params.margin_m)

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        self.q_in = ref.q_rad  # the input posture, as the motion commands made it (what a new one is checked on)
        if not self.enabled:
            self.q_safe = np.array(ref.q_rad, dtype=float)
            return ref
        if self.in_collision and self.blend is None:
            self.blend = RecoverBlend(self.q_safe, self.params.recover_time_s)
        candidate = self.blend.step(ref.q_rad, ctx.dt_s) if self.blend is not None else np.asarray(ref.q_rad)
        if self.blend is not None:
            candidate = np.where(BALANCING_JOINTS, ref.q_rad, candidate)
        pairs = self.checker.colliding_pairs(candidate)
        if pairs and self.blend is not None and self._legs_moved_into_it(ref, pairs):
            pairs = []  # the way out toward a free input goes on (soak seed 10192: held against a raised thigh)
        if pairs:
            self.pairs = pairs
            self.in_collision = True
            self.blend = None
            self.collision_ticks += 1
            ctx.ports.collision_pairs = tuple(tuple(p) for p in pairs[:4])
            return ref.with_(q_rad=np.where(BALANCING_JOINTS, ref.q_rad, self.q_safe))
        self.in_collision = False
        self.pairs = []
        self.q_safe = np.array(candidate, dtype=float)
        if self.blend is not None:
            if self.blend.done:
                self.blend = None
            return ref.with_(q_rad=candidate)
        return ref

    def _legs_moved_into_it(self, ref: Reference, pairs) -> bool:
        """The held posture collides now (the legs, which it lets through, moved into the held arm), the input is
        free, and this step of the blend toward it collides no more than holding does: holding would never end."""
        held = self.checker.colliding_pairs(np.where(BALANCING_JOINTS, ref.q_rad, self.q_safe))
        return bool(held) and set(pairs) <= set(held) and not self.checker.colliding_pairs(ref.q_rad)

    def status(self) -> CollisionDetectorStatus:
        pairs = tuple(tuple(p) for p in self.pairs[:4])
        return CollisionDetectorStatus(enabled=self.enabled, collision=self.in_collision, pairs=pairs,
                                       recovering=self.blend is not None, collision_ticks=self.collision_ticks)
