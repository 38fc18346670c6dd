"""A foot lifted by its operational point while standing ([OP] II-A: the leg as an operational point; Eq. 4:
balance stays the controller's): the reference ZMP is first brought over the stance sole (the COM follows by
preview control, as in a walk's single support), then the swing sole follows the operator's offset; released,
the sole goes back over its rest place, down, and the ZMP back to the feet's middle."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, FootRectangle
from controller.core.types import FootCommand
from controller.interpolation.hoff_arbib import min_jerk

#: [s] the reference ZMP goes from the feet's middle to the stance sole's centre (and back) over this time
SHIFT_TIME_S = 1.2
#: [s] after the shift, the swing foot waits this long before it leaves the floor (the COM settles over the sole)
SETTLE_TIME_S = 0.4
#: [m/s] the swing sole's offset follows the command at most this fast (the operation layer's limits act first;
#: this one bounds a jump, e.g. a revert or a release)
FOOT_RATE_M_S = 0.12
#: [m] the sole moves across the floor only this high above it: lower, only its height follows (no scuffing)
CLEARANCE_M = 0.01
#: [m] coming down over its rest place, the sole counts as in contact this close to the floor (the Stabilizer's
#: force control on both soles lands it: switched at the plan's touchdown, the CP error peaked at 31 mm)
TOUCH_M = 0.005
#: [m] the offset counts as reached within this
AT_M = 1e-4

PHASES = ("idle", "shifting", "lifted", "lowering", "returning")
_SOLES = {"rfoot": HRP2_RIGHT_SOLE, "lfoot": HRP2_LEFT_SOLE}
_STANCE = {"rfoot": "lfoot", "lfoot": "rfoot"}
_SUPPORT = {"rfoot": "lleg", "lfoot": "rleg"}  # the GaitSample's support while that foot is up


def sole_centre_offset_m(sole: FootRectangle) -> tuple[float, float]:
    """The centre of a sole's rectangle in the sole's frame (x forward, y left) [m]."""
    return 0.5 * (sole.front_m - sole.rear_m), 0.5 * (sole.left_m - sole.right_m)


def shifted_zmp(mid_world: np.ndarray, stance_centre_world: np.ndarray, progress: np.ndarray) -> np.ndarray:
    """The reference ZMP(s) at shift progress(es) in [0, 1] (0: the feet's middle, 1: the stance sole's centre),
    along a rest-to-rest minimum-jerk path; (..., 3) [m]."""
    s = np.asarray(min_jerk(progress), dtype=float)[..., None]
    return mid_world + s * (stance_centre_world - mid_world)


def offset_step(offset_m: tuple, goal_m: tuple, max_step_m: float) -> tuple[float, float, float]:
    """The swing sole's offset one tick on toward `goal_m` (straight, at most `max_step_m`), its x-y frozen while
    it is below CLEARANCE_M and the goal is not on the floor under it (lifted first, across, then down)."""
    x, y, z = offset_m
    gx, gy, gz = goal_m
    across = math.hypot(gx - x, gy - y) > AT_M
    if across and z < CLEARANCE_M - AT_M:  # up to the clearance first, then across
        gx, gy, gz = x, y, max(gz, CLEARANCE_M)
    elif across and gz < z:  # across before down
        gz = z
    d = (gx - x, gy - y, gz - z)
    n = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    k = 1.0 if n <= max_step_m else max_step_m / n
    return x + k * d[0], y + k * d[1], z + k * d[2]


class FootLift:
    """The AutoBalancer's foot-lift phases: idle -> shifting (the ZMP to the stance sole, then settling) -> lifted
    (the swing sole at its rest pose + the offset, the support on the stance foot) -> lowering (back over its rest
    place and down) -> returning (the ZMP back to the middle) -> idle. A command during lowering or returning
    goes back up from where it is."""

    def __init__(self, dt_s: float) -> None:
        self.dt_s = dt_s
        self.phase = "idle"
        self.foot: str | None = None
        self.progress = 0.0  # of the ZMP shift, 0..1
        self.settled_s = 0.0  # time spent shifted before lifting
        self.offset_m = (0.0, 0.0, 0.0)  # applied to the swing sole, in F's axes (the soles' mean yaw at rest)
        self.refused: str | None = None  # why the last command was not taken (status)
        #: (the idle sample, the foot, cos and sin of F's yaw, the stance sole's centre, the held preview or None):
        #: the idle sample is one object while standing, so these are computed once per lift (~30 us a tick else)
        self._rest: tuple | None = None

    @property
    def active(self) -> bool:
        return self.phase != "idle"

    def step(self, cmd: FootCommand | None, walking: bool, blocked: str | None = None) -> None:
        """One tick of the phases under `cmd` (None: put the foot down); `walking`/`blocked` (a reason) refuse a
        new lift (the status says why)."""
        dt = self.dt_s
        if cmd is not None and self.foot is not None and cmd.foot != self.foot:
            cmd = None  # the other foot: this one goes down first
        self.refused = None
        if cmd is not None and self.phase == "idle":
            why = "walking" if walking else blocked
            if why is not None:
                self.refused = f"ignored: {why}"
                return
            self.foot, self.phase = cmd.foot, "shifting"
        p = self.phase
        if p == "idle":
            return
        if cmd is not None and p in ("lowering", "returning"):
            p = "lifted" if p == "lowering" else "shifting"
        if p == "shifting" and cmd is None:
            p = "returning"
        elif p == "shifting":
            self.progress = min(1.0, self.progress + dt / SHIFT_TIME_S)
            if self.progress >= 1.0:
                self.settled_s += dt
                if self.settled_s >= SETTLE_TIME_S:
                    p = "lifted"
        elif p == "lifted":
            goal = (0.0, 0.0, 0.0) if cmd is None else (cmd.offset_m[0], cmd.offset_m[1], max(0.0, cmd.offset_m[2]))
            self.offset_m = offset_step(self.offset_m, goal, FOOT_RATE_M_S * dt)
            if cmd is None:
                p = "lowering"
        elif p == "lowering":
            self.offset_m = offset_step(self.offset_m, (0.0, 0.0, 0.0), FOOT_RATE_M_S * dt)
            if max(map(abs, self.offset_m)) <= AT_M:
                self.offset_m, self.settled_s, p = (0.0, 0.0, 0.0), 0.0, "returning"
        elif p == "returning":
            self.settled_s += dt  # on both feet again: a moment before the weight moves (as the lift waits)
            if self.settled_s >= SETTLE_TIME_S:
                self.progress = max(0.0, self.progress - dt / SHIFT_TIME_S)
            if self.progress <= 0.0:
                p, self.foot = "idle", None
        self.phase = p

    @property
    def lifted(self) -> bool:
        """The swing sole is (or may be) off the floor: the support is the stance foot's alone."""
        if self.phase == "lowering":
            x, y, z = self.offset_m
            return z > TOUCH_M or math.hypot(x, y) > AT_M
        return self.phase == "lifted"

    def _stance_centre(self, sample) -> np.ndarray:
        stance = _STANCE[self.foot]
        p, R = ((sample.p_lfoot_world, sample.R_lfoot_world) if stance == "lfoot"
                else (sample.p_rfoot_world, sample.R_rfoot_world))
        cx, cy = sole_centre_offset_m(_SOLES[stance])
        c = p + R @ np.array((cx, cy, 0.0))
        return np.array((c[0], c[1], float(sample.zmp_world[2])))

    def _rest_of(self, sample) -> tuple:
        """The cached rest values of `sample` (see _rest)."""
        r = self._rest
        if r is None or r[0] is not sample or r[1] != self.foot:
            (r0, _, _), (r1, _, _), _ = sample.R_rfoot_world.tolist()
            (l0, _, _), (l1, _, _), _ = sample.R_lfoot_world.tolist()
            yaw = math.atan2(r1 + l1, r0 + l0)
            r = self._rest = (sample, self.foot, math.cos(yaw), math.sin(yaw), self._stance_centre(sample), None)
        return r

    def zmp_preview(self, future: np.ndarray, sample) -> np.ndarray:
        """The idle ZMP preview `future` (n, 3) [m] with the shift in it (the phase's direction continued);
        `sample` the idle GaitSample (the rest soles)."""
        if self.phase == "idle":
            return future
        direction = {"shifting": 1.0, "returning": -1.0}.get(self.phase, 0.0)
        if direction == 0.0 or (direction > 0.0 and self.progress >= 1.0):  # held: one row repeated (as idle)
            rest = self._rest_of(sample)
            held = rest[5]
            if held is None or held.shape != future.shape or held[0, 0] != rest[4][0]:
                held = np.broadcast_to(rest[4], future.shape)  # (held at progress 1: over the stance sole)
                self._rest = (*rest[:5], held)
            return held
        wait_s = max(0.0, SETTLE_TIME_S - self.settled_s) if direction < 0.0 else 0.0  # returning: the pause first
        t_s = np.maximum(0.0, np.arange(len(future)) * self.dt_s - wait_s)
        progress = np.clip(self.progress + direction * t_s / SHIFT_TIME_S, 0.0, 1.0)
        return shifted_zmp(future[0], self._stance_centre(sample), progress)

    def sample(self, g):
        """The idle GaitSample `g` with the shifted ZMP, the swing sole moved by the offset (in F's axes: the soles'
        mean yaw) and the support on the stance foot while lifted; (sample, the offset in the world (3,) or None)."""
        if self.phase == "idle":
            return g, None
        _, _, c, s, centre, _ = self._rest_of(g)
        zmp = centre if self.progress >= 1.0 else shifted_zmp(g.zmp_world, centre, np.float64(self.progress))
        x, y, z = self.offset_m
        off = np.array((c * x - s * y, s * x + c * y, z))
        changes = {"zmp_world": zmp}
        if self.foot == "rfoot":
            changes["p_rfoot_world"] = g.p_rfoot_world + off
        else:
            changes["p_lfoot_world"] = g.p_lfoot_world + off
        if self.lifted:
            changes["support"] = _SUPPORT[self.foot]
            changes["r_lleg"] = 1.0 if self.foot == "rfoot" else 0.0
        return dataclasses.replace(g, **changes), off
