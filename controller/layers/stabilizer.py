"""Stabilizer layer ([MLC] III-D): LIP state feedback (Eq. 7-8) on the actual COG, COG velocity and
ZMP; QP force-moment distribution to the feet (Eq. 9-14); foot force-moment damping control (Eq. 3
with m = 0); body attitude control; the capture-point error and the emergency flag ([MLC] III-E)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    FootRectangle,
    point_in_convex_polygon,
    shrink_polygon,
    support_polygon,
)
from controller.balance.force_distribution import FootPolygon, ForceDistributionQP, alpha_from_zmp
from controller.balance.hand_force_cog_offset import cog_offset_against_hand_forces
from controller.balance.state_estimation import (
    ActualStateEstimator,
    body_tilt_from_flat_soles,
    lip_velocity_filter_step,
)
from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import BalanceEstimate, GaitState, Reference, TickContext
from controller.interpolation.blend import Transition
from controller.kinematics.leg_ik import LEG_INDICES, LLEG, RLEG, leg_ik_floats
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rpy_to_rows
from robot.names import FORCE_SENSOR_NAMES

FEET = (FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor"))
HANDS = (FORCE_SENSOR_NAMES.index("rhsensor"), FORCE_SENSOR_NAMES.index("lhsensor"))
HAND_FORCE_DEADBAND_N = 2.0  # [N] hand forces below this count as none (sensor noise and offset residue)
# [m] smallest COG height above the ZMP taken for omega = sqrt(g / h): keeps the capture point finite when the
# estimate says the COG is at or below the ground (a fallen robot, a bad sensor), far below any real 0.6-0.8 m
MIN_LIP_HEIGHT_M = 0.1
# [s] time constant with which a swing foot's damping offset returns to the plan (hrpsys-like: quickly, so the
# foot lands as planned; 16 ticks of 5 ms)
SWING_FOOT_RETURN_TIME_CONST_S = 0.08
EMERGENCY_MODES = ("cp_error", "cp_support", "none")
# consecutive joint indices of each leg as slices (assignment through a slice is cheaper)
_LEG_SLICES = {leg: (slice(int(i[0]), int(i[-1]) + 1) if np.array_equal(i, np.arange(i[0], i[-1] + 1)) else i)
               for leg, i in LEG_INDICES.items()}


@dataclass(frozen=True)
class StabilizerParams(Params):
    # LIP state feedback u = zmp_ref + k1 (cog_ref - cog) + k2 (cogvel_ref - cogvel) + k3 (zmp_ref - zmp):
    # hrpsys's EEFM gains (pole placement for the LIP with a first-order ZMP lag, Kajita 2010) x 0.9
    k1: float = field(default=-1.41429 * 0.9, metadata={"unit": "-", "min": -20.0, "max": 0.0})
    k2: float = field(default=-0.404082 * 0.9, metadata={"unit": "s", "min": -5.0, "max": 0.0})
    k3: float = field(default=-0.18 * 0.9, metadata={"unit": "-", "min": -2.0, "max": 0.0})
    # foot moment damping control d(rpy)/dt = (tau_act - tau_ref) / D - rpy / T. D is scheduled: soft
    # standing (more push margin: 26 N s forward stands), stiff walking (D = 300 walking sideways
    # drives the COP to the sole edge at each support switch and tips the robot over; 3000 walks)
    rot_damping_gain: float = field(default=300.0, metadata={"unit": "N m s/rad", "min": 1.0, "max": 1e6})
    # standing, the pitch (about y) apart (hrpsys has a gain per axis): softer, so after a forward push the
    # foot that tipped onto its toe lands without slapping the heel down (300: the ZMP then jumps to the heel
    # edge and the capture point rings; 150 lands it flat); roll keeps 300 (150 drops a 40 N s side push);
    # with the hands loaded pitch uses rot_damping_gain too
    rot_damping_gain_pitch: float = field(default=150.0, metadata={"unit": "N m s/rad", "min": 1.0, "max": 1e6})
    rot_damping_gain_walking: float = field(default=3000.0, metadata={"unit": "N m s/rad", "min": 1.0, "max": 1e6})
    # during the AutoBalancer's capture-point emergency step (Ports.emergency_step): the walking gain keeps the
    # landed foot's sole from following the ZMP it is asked for (after a 30 N s backward push the load stays on
    # the front foot and the CP runs past the landed heel: falls with 1500-3000, stands with 300-1000)
    rot_damping_gain_emergency_step: float = field(default=1000.0, metadata={"unit": "N m s/rad", "min": 1.0,
                                                                              "max": 1e6})
    rot_time_const_s: float = field(default=1.5, metadata={"unit": "s", "min": 0.01, "max": 100.0})
    rot_limit_deg: float = field(default=10.0, metadata={"unit": "deg", "min": 0.0, "max": 30.0})
    # foot vertical force difference control
    z_damping_gain: float = field(default=35000.0, metadata={"unit": "N s/m", "min": 100.0, "max": 1e7})
    z_time_const_s: float = field(default=1.5, metadata={"unit": "s", "min": 0.01, "max": 100.0})
    z_limit_m: float = field(default=0.025, metadata={"unit": "m", "min": 0.0, "max": 0.1})
    # body attitude control d(rpy)/dt = k (ref - act) - rpy / T. Off by default: when the robot tips
    # about a foot edge the loop integrates that tilt into the hips and pushes it over (measured:
    # a 40 N s sideways push falls with hrpsys's 0.5, stands with 0; forward 28 N s likewise)
    body_attitude_gain: float = field(default=0.0, metadata={"unit": "1/s", "min": 0.0, "max": 20.0})
    body_attitude_time_const_s: float = field(default=1e3, metadata={"unit": "s", "min": 0.01, "max": 1e6})
    # while walking (no emergency step) on a sole flat and loaded with its pressure inside its edges (as
    # body_tilt_from_flat_soles), the COG velocity filter predicts with the LIP's acceleration omega^2 (static
    # balance point - measured ZMP) and low-passes only the finite difference's departure from it. Without it
    # the lag of the walk's own accelerations read as CP error (toe-heel walk p99 28-31 mm; with it 17.4 mm).
    # Standing it is the low-pass alone, as tuned for the pushes and the emergency step (with the prediction
    # the 1.5x backward step's stand tilted 11.9 deg against 6.6). 10 Hz read an e-stop release mid-walk as
    # 43 mm (the simulation's CP error: 24-26 mm).
    cogvel_cutoff_hz: float = field(default=4.0, metadata={"unit": "Hz", "min": 0.1, "max": 100.0})
    cogvel_lip_prediction: bool = field(default=True, metadata={"unit": "-"})
    contact_threshold_n: float = field(default=25.0, metadata={"unit": "N", "min": 0.0, "max": 500.0})
    transition_time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    # emergency flag: "cp_error" = |CP_ref - CP_act| > threshold ([MLC]); "cp_support" = actual CP
    # outside the support polygon shrunk by cp_margin_m (later hrpsys); "none"
    emergency_mode: str = field(default="cp_error", metadata={"choices": EMERGENCY_MODES})
    cp_threshold_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.001, "max": 0.5})
    cp_margin_m: float = field(default=0.03, metadata={"unit": "m", "min": 0.0, "max": 0.1})
    # the flag while walking too (hrpsys: off): with the tilt measured by the flat soles (KalmanFilter
    # use_sole_tilt) and the LIP-predicted COG velocity the walking CP error stays under 25 mm on the standard
    # walks (p99 14-18 mm), so a rise means a push; the AutoBalancer stops the walk on it (walking_stop_on_cp_flag)
    estop_while_walking: bool = field(default=True, metadata={"unit": "-"})
    # the flag's hysteresis ("cp_error" mode): once up it stays up until |cp_error| has stayed below
    # cp_release_ratio x cp_threshold_m for cp_release_s, no emergency step being taken meanwhile (one rise per
    # disturbance, not one per threshold crossing)
    cp_release_ratio: float = field(default=0.5, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    cp_release_s: float = field(default=0.5, metadata={"unit": "s", "min": 0.0, "max": 10.0})


@dataclass(frozen=True, slots=True)
class StabilizerStatus(Status):
    active: bool = field(metadata=described("the Stabilizer is running (started)"))
    weight: float = field(metadata=described("start/stop blend weight, 0..1", "-"))
    cp_ref: tuple[float, float] = field(metadata=described("reference capture point x, y (world)", "m"))
    cp_act: tuple[float, float] = field(metadata=described("actual capture point x, y (world, estimated)", "m"))
    cp_error: tuple[float, float] = field(metadata=described("cp_ref - cp_act", "m"))
    cp_error_norm: float = field(metadata=described("|cp_ref - cp_act|", "m"))
    cp_threshold_m: float = field(metadata=described("the emergency flag's threshold on |cp_error|", "m"))
    emergency: bool = field(metadata=described("the capture-point emergency flag"))
    flag_rose_at: float | None = field(metadata=described("simulated time the flag last rose", "s"))
    d_foot_rpy_deg: tuple[tuple[float, float], tuple[float, float]] = field(metadata=described(
        "foot damping control's roll, pitch of the right and the left sole", "deg"))
    dz_diff_m: float = field(metadata=described("right minus left sole height offset of the force control", "m"))
    new_zmp: tuple[float, float, float] = field(metadata=described("ZMP the feet are asked to realise (world)", "m"))
    flag_cp_error_m: float | None = field(default=None, metadata=described(
        "|cp_error| of the tick the flag last rose (what raised it; cp_error_norm is the value now)", "m"))


def _matmul3(A, B) -> tuple[tuple[float, float, float], ...]:
    """A @ B for 3x3 matrices given as rows of floats."""
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = B
    return tuple((a0 * b00 + a1 * b10 + a2 * b20, a0 * b01 + a1 * b11 + a2 * b21, a0 * b02 + a1 * b12 + a2 * b22)
                 for a0, a1, a2 in A)


class Stabilizer(Layer):
    """Modifies the legs of the AutoBalancer's posture so the measured ZMP and COG track the reference.

    Without a gait reference (AutoBalancer stopped) it only estimates and passes the reference through.
    """

    name = "st"
    description = "Stabilizer: LIP feedback, QP force distribution, foot damping, CP emergency flag"

    def __init__(self, dt_s: float, params: StabilizerParams | None = None, active: bool = True,
                 kinematics: RobotKinematics | None = None, estimator: ActualStateEstimator | None = None) -> None:
        super().__init__()
        self.params = params or StabilizerParams()
        self.dt_s = dt_s
        self.kin = kinematics or RobotKinematics()
        # the system's one estimator of the actual COG and ZMP (the loop uses it when this layer does not run)
        self.estimator = estimator if estimator is not None else ActualStateEstimator(self.kin)
        self.total_mass = self.kin.total_mass
        self.soles: tuple[FootRectangle, FootRectangle] = (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE)
        self.d_foot_rpy = np.zeros((2, 2))  # (foot, [roll, pitch]) [rad]
        self.dz_diff = 0.0  # right minus left sole height offset [m]
        self.d_body_rp = np.zeros(2)  # [rad]
        self._prev_cog: np.ndarray | None = None
        #: last tick: walking (no emergency step) on a sole flat and loaded with its pressure inside its edges
        self._lip_predicts = False
        self.act_cogvel = np.zeros(3)
        self.active = False
        self._transition: Transition | None = None  # start / stop blend of the weight
        self.weight = 0.0
        self.cp_ref = np.zeros(2)
        self.cp_act = np.zeros(2)
        self.cp_error = np.zeros(2)
        self.omega_1_s = math.sqrt(GRAVITY_M_S2 / 0.8)  # [1/s] the LIP's, from the last estimate
        self.emergency = False
        self._flag_low_s = 0.0  # [s] the raised flag's error has been below the release level this long
        self.flag_rose_at_s: float | None = None
        self.flag_cp_error_m: float | None = None  # |CP error| of the tick the flag last rose [m]
        self.new_zmp = np.zeros(3)
        self.projected = False
        self._qp: ForceDistributionQP | None = None
        self._qp_key: tuple | None = None
        self._qp_raw_key: tuple | None = None  # the unrounded key of the last call
        self._last_out: Reference | None = None  # what the last working tick output (repeated while held)
        if active:
            self.start()

    # ---- operations ------------------------------------------------------------------------
    def start(self) -> None:
        if self.active:
            raise InvalidState("Stabilizer is already running")
        self.active = True
        self._transition = Transition(self.weight, 1.0, self.params.transition_time_s, "sigmoid")

    def stop(self) -> None:
        if not self.active:
            raise InvalidState("Stabilizer is not running")
        self.active = False
        self._transition = Transition(self.weight, 0.0, self.params.transition_time_s, "sigmoid")

    def set_params(self, params: StabilizerParams) -> None:
        self.params = params

    # ---- tick --------------------------------------------------------------------------------
    def _advance_transition(self, dt: float) -> None:
        if self._transition is None:
            return
        self.weight = self._transition.step(dt)
        if self._transition.done:
            self._transition = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        """[MLC] III-D in its steps: estimate, capture points and the flag, LIP feedback (Eq. 7-8), force
        distribution (Eq. 9-14), foot control (Eq. 3 with m = 0) and the legs re-solved for it."""
        if not self.enabled:  # pass-through (no estimate either: the loop's state estimator runs)
            self.emergency = False
            return ref
        dt = ctx.dt_s
        est = ctx.estimate
        self._advance_transition(dt)
        cog, zmp = self._estimate(ctx, ref)  # always: the operator and the emergency flag need them
        gait = ref.gait
        if gait is None:
            self.emergency = False
            return ref
        self._capture_points(cog, gait)
        ctx.ports.balance = BalanceEstimate(cog_world=cog, cog_vel_world=self.act_cogvel, zmp_world=zmp,
                                            cp_world_xy=self.cp_act, omega_1_s=self.omega_1_s)
        ctx.ports.body_tilt_kin_rad = self._body_tilt_kin(est, gait)
        self._lip_predicts = gait.walking and ctx.ports.body_tilt_kin_rad is not None and not ctx.ports.emergency_step
        foot_wrenches = self._foot_wrenches(est)
        contact_act = tuple(w[2] > self.params.contact_threshold_n for w in foot_wrenches)
        if ctx.balance_hold and self._last_out is not None:
            # the hard e-stop freezes the command: estimate only, integrate nothing, raise no flag
            self.emergency = False
            return self._last_out
        self._update_emergency(ctx.time_s, gait, contact_act, ctx.ports.emergency_step)
        ctx.ports.cp_flag = self.emergency
        if self.active and self._transition is None:  # balancing (the flag's condition too)
            ex, ey = self.cp_error.tolist()
            ctx.ports.cp_error_m = math.hypot(ex, ey)
        ctx.ports.cp_flag_error_m = self.flag_cp_error_m if self.emergency else None
        if self.weight <= 0.0:
            self._last_out = ref
            return ref
        zmp_new_xy = self._lip_feedback(cog, zmp, est, gait)
        contact_idx = [i for i in (0, 1) if gait.contact[i]]
        forces = self._distribute(zmp_new_xy, contact_idx, gait)
        self._foot_damping(dt, contact_idx, contact_act, foot_wrenches, forces, gait.walking, self._hands_loaded(est),
                           ctx.ports.emergency_step)
        self._force_difference(dt, contact_idx, contact_act, foot_wrenches, forces)
        self._body_attitude(dt, est, ref)
        self._last_out = self._legs(ref, gait)
        return self._last_out

    # ---- the steps of a tick ------------------------------------------------------------------------
    def _estimate(self, ctx: TickContext, ref: Reference) -> tuple[np.ndarray, np.ndarray]:
        """Actual COG and ZMP (world) from the encoders, the KF attitude and the foot sensors, and the COG
        velocity as a first-order low-pass of its finite difference; written into the tick's Estimate."""
        est = ctx.estimate
        dt = ctx.dt_s
        cog, zmp = self.estimator(ctx.sensors, est, ref)
        if self._prev_cog is None:
            self._prev_cog = cog
        alpha = 1.0 - math.exp(-2.0 * math.pi * self.params.cogvel_cutoff_hz * dt)
        cx, cy, cz = cog.tolist()
        px, py, pz = self._prev_cog.tolist()
        # last tick's COG as this tick's anchor places it: a switch of the planned contacts moves the estimate
        # by the two anchors' disagreement (1-2 mm at a toe-heel landing), which is no velocity
        sx, sy, sz = self.estimator.anchor_shift_world
        px, py, pz = px + sx, py + sy, pz + sz
        vx, vy, vz = self.act_cogvel.tolist()
        accel = (0.0, 0.0)
        if self.params.cogvel_lip_prediction and self._lip_predicts:  # the LIP's acceleration, last tick's omega
            sbp = self.static_balance_point(cog, est, float(zmp[2])).tolist()
            zx, zy = zmp[:2].tolist()
            w2 = self.omega_1_s * self.omega_1_s
            accel = (w2 * (sbp[0] - zx), w2 * (sbp[1] - zy))
        vx, vy = lip_velocity_filter_step((vx, vy), ((cx - px) / dt, (cy - py) / dt), alpha, accel, dt)
        vz = vz + alpha * ((cz - pz) / dt - vz)
        self.act_cogvel = np.array((vx, vy, vz))
        self._prev_cog = cog
        est.cog_world, est.zmp_world, est.cog_vel_world = cog, zmp, self.act_cogvel
        return cog, zmp

    def _capture_points(self, cog: np.ndarray, gait: GaitState) -> None:
        """cp = x + v / omega with omega = sqrt(g / (z_cog - z_zmp)) ([MLC] III-E), reference and actual."""
        cz = float(cog[2])
        height = max(MIN_LIP_HEIGHT_M, cz - float(gait.zmp_world[2]))
        omega = self.omega_1_s = math.sqrt(GRAVITY_M_S2 / height)
        gcx, gcy = gait.cog_world[:2].tolist()
        gvx, gvy, _ = gait.cog_vel_world.tolist()
        cx, cy = cog[:2].tolist()
        vx, vy, _ = self.act_cogvel.tolist()
        cp_ref = (gcx + gvx / omega, gcy + gvy / omega)
        cp_act = (cx + vx / omega, cy + vy / omega)
        self.cp_ref = np.array(cp_ref)
        self.cp_act = np.array(cp_act)
        self.cp_error = np.array((cp_ref[0] - cp_act[0], cp_ref[1] - cp_act[1]))

    def _body_tilt_kin(self, est, gait: GaitState) -> tuple[float, float] | None:
        """BODY roll, pitch [rad] from the soles planned flat on the ground that carry load well inside their
        edges (body_tilt_from_flat_soles); None when none does. The KalmanFilter reads it next tick: at a
        landing the accelerometer feels accelerations no plan knows and reads them as tilt."""
        R_est = rpy_to_rows(*est.base_rpy_rad.tolist())
        R_meas = est.sensor_R_world
        return body_tilt_from_flat_soles(R_est, (gait.R_rsole_world, gait.R_lsole_world),
                                         (R_meas[FEET[0]], R_meas[FEET[1]]),
                                         (est.wrenches_ext[FEET[0]], est.wrenches_ext[FEET[1]]), self.soles,
                                         gait.contact)

    @staticmethod
    def _foot_wrenches(est) -> tuple[list[float], list[float]]:
        """The measured external wrenches of the right and the left sole (world-aligned) [N, N m]."""
        wrenches = est.wrenches_ext_world.tolist()
        return wrenches[FEET[0]], wrenches[FEET[1]]

    def _lip_feedback(self, cog: np.ndarray, zmp: np.ndarray, est, gait: GaitState) -> tuple[float, float]:
        """Eq. 8: the ZMP the feet should realise, u = zmp_ref + k1 (x_ref - x) + k2 (v_ref - v) + k3 (zmp_ref -
        zmp), blended in by the start/stop weight. References as the paper says: p_G^pc (preview COG, before
        the hand-force offset) and p_zmp^abc. The actual side is the static balance point, the COG shifted
        by the measured hand forces (hrpsys does the same): with hands loaded the LIP's "COG" is where the
        ZMP would sit at rest."""
        p = self.params
        w = self.weight
        zr = gait.zmp_world.tolist()
        sbp = self.static_balance_point(cog, est, zr[2]).tolist()
        pc = gait.cog_pc_world.tolist()
        zm = zmp.tolist()
        act_vel = self.act_cogvel.tolist()
        gv = gait.cog_vel_world.tolist()
        k1, k2, k3 = p.k1, p.k2, p.k3
        nzx, nzy = (zr[j] + w * (k1 * (pc[j] - sbp[j]) + k2 * (gv[j] - act_vel[j]) + k3 * (zr[j] - zm[j]))
                    for j in range(2))
        return nzx, nzy

    def _distribute(self, zmp_new_xy: tuple[float, float], contact_idx: list[int], gait: GaitState):
        """Eq. 9-14: the QP distributes the total force and moment over the soles meant to be in contact,
        weighted by the ZMP's place between the feet (alpha); returns the per-foot forces and moments."""
        soles_world = ((gait.p_rsole_world, gait.R_rsole_world), (gait.p_lsole_world, gait.R_lsole_world))
        qp = self._force_qp(contact_idx, soles_world)
        if len(contact_idx) == 2:
            qp.set_alpha(alpha_from_zmp(zmp_new_xy, gait.p_rsole_world[:2].tolist(), gait.p_lsole_world[:2].tolist()))
        forces = qp.solve(np.array(zmp_new_xy), self.total_mass * GRAVITY_M_S2)
        zx, zy = forces.zmp_world_xy.tolist()
        self.new_zmp = np.array((zx, zy, float(gait.zmp_world[2])))
        self.projected = forces.projected
        return forces

    def _foot_damping(self, dt: float, contact_idx: list[int], contact_act, foot_wrenches, forces,
                      walking: bool, hands_loaded: bool = False, emergency_step: bool = False) -> None:
        """Eq. 3 with m = 0 on each sole's roll and pitch: d(rpy)/dt = (tau_act - tau_ref) / D - rpy / T for a
        foot in contact; a swing foot returns to the plan with SWING_FOOT_RETURN_TIME_CONST_S."""
        p = self.params
        # (roll, pitch); with the hands loaded (a sustained moment: a wall, a door) pitch keeps the roll's gain,
        # the soft pitch let the soles drift under it (the door push-plan's CP error crept back over the threshold)
        pitch = p.rot_damping_gain if hands_loaded else p.rot_damping_gain_pitch
        if emergency_step:
            damping = (p.rot_damping_gain_emergency_step, p.rot_damping_gain_emergency_step)
        else:
            damping = ((p.rot_damping_gain_walking, p.rot_damping_gain_walking) if walking
                       else (p.rot_damping_gain, pitch))
        T_rot = p.rot_time_const_s
        d_foot = self.d_foot_rpy.tolist()
        n_xy = forces.n_xy_nm.tolist()
        for k, i in enumerate(contact_idx):
            d = d_foot[i]
            if contact_act[i]:
                ta = (foot_wrenches[i][3], foot_wrenches[i][4])
                tau_ref = (-n_xy[k][0], -n_xy[k][1])  # ground-reaction moment about the sole origin
                rate = [(ta[j] - tau_ref[j]) / damping[j] - d[j] / T_rot for j in range(2)]
            else:
                rate = [-d[j] / T_rot for j in range(2)]
            d_foot[i] = [d[j] + rate[j] * dt for j in range(2)]
        for i in range(2):
            if i not in contact_idx:
                d = d_foot[i]
                d_foot[i] = [d[j] - d[j] * dt / SWING_FOOT_RETURN_TIME_CONST_S for j in range(2)]
        lim = math.radians(p.rot_limit_deg)
        self.d_foot_rpy[:] = [[min(max(roll, -lim), lim), min(max(pitch, -lim), lim)] for roll, pitch in d_foot]

    def _force_difference(self, dt: float, contact_idx: list[int], contact_act, foot_wrenches, forces) -> None:
        """Foot vertical force difference control (Kajita 2010): with both feet down the right-minus-left
        height offset follows the error of the force difference, else it decays; limited to +-2 z_limit_m
        (z_limit_m for each foot)."""
        p = self.params
        if len(contact_idx) == 2 and contact_act[0] and contact_act[1]:
            fz_ref = forces.fz_n.tolist()
            df_ref = fz_ref[0] - fz_ref[1]
            df_act = foot_wrenches[0][2] - foot_wrenches[1][2]
            self.dz_diff += ((df_act - df_ref) / p.z_damping_gain - self.dz_diff / p.z_time_const_s) * dt
        else:
            self.dz_diff -= self.dz_diff / p.z_time_const_s * dt
        self.dz_diff = float(min(max(self.dz_diff, -2 * p.z_limit_m), 2 * p.z_limit_m))

    def _body_attitude(self, dt: float, est, ref: Reference) -> None:
        """BODY roll and pitch: d(rpy)/dt = k (ref - act) - rpy / T, limited as the feet (rot_limit_deg)."""
        p = self.params
        lim = math.radians(p.rot_limit_deg)
        act_rp = est.base_rpy_rad[:2].tolist()
        ref_rpy = ref.base_rpy_rad.tolist()
        gain, T_body = p.body_attitude_gain, p.body_attitude_time_const_s
        db = self.d_body_rp.tolist()
        self.d_body_rp[:] = [min(max(db[j] + (gain * (ref_rpy[j] - act_rp[j]) - db[j] / T_body) * dt, -lim), lim)
                             for j in range(2)]

    def _legs(self, ref: Reference, gait: GaitState) -> Reference:
        """The legs re-solved (closed form) for the sole targets turned by the foot damping, moved by the force
        difference, under the BODY attitude of the attitude control (roll and pitch; yaw is not controlled)."""
        w = self.weight
        ref_rpy = ref.base_rpy_rad.tolist()
        db = self.d_body_rp.tolist()
        d_foot = self.d_foot_rpy.tolist()
        R_body = rpy_to_rows(ref_rpy[0] + w * db[0], ref_rpy[1] + w * db[1], ref_rpy[2])
        base = ref.base_pos_world.tolist()
        q = np.array(ref.q_rad, dtype=float)
        dz = (0.5 * w * self.dz_diff, -0.5 * w * self.dz_diff)
        soles = ((RLEG, "rleg", gait.p_rsole_world, gait.R_rsole_world),
                 (LLEG, "lleg", gait.p_lsole_world, gait.R_lsole_world))
        for i, (geom, leg, p_sole, R_sole) in enumerate(soles):
            pos = p_sole.tolist()
            R_mod = _matmul3(rpy_to_rows(w * d_foot[i][0], w * d_foot[i][1], 0.0), R_sole.tolist())
            q[_LEG_SLICES[leg]], _ = leg_ik_floats(geom, base, R_body, (pos[0], pos[1], pos[2] + dz[i]), R_mod)
        return ref.with_owned(q_rad=q)

    def _force_qp(self, idx: list[int], soles_world) -> ForceDistributionQP:
        """The QP for the feet in contact, rebuilt only when they move (a support switch or a new step)."""
        raw = tuple((i, *soles_world[i][0][:2].tolist(), float(soles_world[i][1][1, 0])) for i in idx)
        if raw == self._qp_raw_key:  # the same soles as last tick (a standing foot): the same QP
            return self._qp
        self._qp_raw_key = raw
        # np.round(x, 6) on floats: rint(x * 1e6) / 1e6 (Python's round(float) rounds half to even as rint)
        key = tuple((i, round(x * 1e6) / 1e6, round(y * 1e6) / 1e6, round(r10, 6)) for i, x, y, r10 in raw)
        if key != self._qp_key:
            polygons = []
            for i in idx:
                pos, R = soles_world[i]
                yaw = math.atan2(R[1, 0], R[0, 0])
                polygons.append(FootPolygon(self.soles[i].corners_world((pos[0], pos[1], yaw)), pos[:2]))
            self._qp = ForceDistributionQP(polygons)
            self._qp_key = key
        return self._qp

    @staticmethod
    def _hands_loaded(est) -> bool:
        """A measured hand force component beyond HAND_FORCE_DEADBAND_N."""
        rows = est.wrenches_ext_world.tolist()
        return any(abs(v) > HAND_FORCE_DEADBAND_N for i in HANDS for v in rows[i][:3])  # np.any(abs(f) > band)

    def static_balance_point(self, cog: np.ndarray, est, zmp_z: float) -> np.ndarray:
        """COG (3,) moved to where the measured hand forces put the ZMP of a robot at rest [m]."""
        rows = est.wrenches_ext_world.tolist()
        if not any(abs(v) > HAND_FORCE_DEADBAND_N for i in HANDS for v in rows[i][:3]):  # np.any(abs(f) > band)
            return cog
        f_on = est.wrenches_ext_world[list(HANDS), :3]
        if not abs(sum(rows[i][2] for i in HANDS)) < self.total_mass * GRAVITY_M_S2:
            # hands carrying the robot's whole weight (or a sensor spike saying so): no balance point on
            # the feet exists, so this tick balances the plain COG rather than faulting the loop
            return cog
        hands = est.sensor_pos_from_base[list(HANDS)] + self.estimator.base_pos_world
        # Eq. 6 evaluated with the force on the robot is the static ZMP (see hand_force_cog_offset)
        xy = cog_offset_against_hand_forces(cog[:2], self.total_mass, hands, -f_on, zmp_z, GRAVITY_M_S2)
        return np.array([xy[0], xy[1], cog[2]])

    def _update_emergency(self, time_s: float, gait, contact_act: np.ndarray, stepping: bool = False) -> None:
        """The flag; `stepping`: the AutoBalancer's emergency step is being taken (its plan follows the measured
        state, so the error is small meanwhile: the disturbance is not over until the step is)."""
        p = self.params
        settled = self.active and self._transition is None  # hrpsys: only in MODE_ST, transition done
        if p.emergency_mode == "none" or not settled or (gait.walking and not p.estop_while_walking):
            flag = False
        elif not any(contact_act):  # in the air: no flag rises, and one up stays up (both feet unloaded a moment)
            flag = self.emergency
        elif p.emergency_mode == "cp_error":
            ex, ey = self.cp_error.tolist()
            error = math.hypot(ex, ey)
            flag = error > p.cp_threshold_m
            if flag:
                self._flag_low_s = 0.0
            elif self.emergency:  # up: it falls once the error has stayed low long enough
                low = error < p.cp_release_ratio * p.cp_threshold_m and not stepping
                self._flag_low_s = self._flag_low_s + self.dt_s if low else 0.0
                flag = self._flag_low_s < p.cp_release_s
        else:
            feet = []
            for i, (pos, R) in enumerate(((gait.p_rsole_world, gait.R_rsole_world),
                                          (gait.p_lsole_world, gait.R_lsole_world))):
                if contact_act[i]:
                    feet.append(((pos[0], pos[1], math.atan2(R[1, 0], R[0, 0])), self.soles[i]))
            poly = shrink_polygon(support_polygon(feet), p.cp_margin_m)
            flag = poly.shape[0] < 3 or not point_in_convex_polygon(self.cp_act, poly)
        if flag and not self.emergency:
            self.flag_rose_at_s = time_s
            self.flag_cp_error_m = float(np.hypot(*self.cp_error))
        self.emergency = flag

    def status(self) -> StabilizerStatus:
        ex, ey = cp_error = tuple(self.cp_error.tolist())
        (r_roll, r_pitch), (l_roll, l_pitch) = self.d_foot_rpy.tolist()  # (foot, [roll, pitch]) [rad]
        deg = math.degrees
        return StabilizerStatus(
            enabled=self.enabled, active=self.active, weight=round(self.weight, 4),
            cp_ref=tuple(self.cp_ref.tolist()), cp_act=tuple(self.cp_act.tolist()), cp_error=cp_error,
            cp_error_norm=math.hypot(ex, ey), cp_threshold_m=self.params.cp_threshold_m,
            emergency=self.emergency, flag_rose_at=self.flag_rose_at_s, flag_cp_error_m=self.flag_cp_error_m,
            d_foot_rpy_deg=((deg(r_roll), deg(r_pitch)), (deg(l_roll), deg(l_pitch))), dz_diff_m=self.dz_diff,
            new_zmp=tuple(self.new_zmp.tolist()))
