"""Data that flows through the chain: the per-tick context, the reference, and small helpers."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from robot.names import FORCE_SENSOR_NAMES, NUM_JOINTS
from robot.sensors import Sensors, frozen_array

__all__ = ["BalanceEstimate", "Estimate", "FootCommand", "GaitState", "OdometryEstimate", "Ports", "Reference",
           "StepInProgress", "TickContext", "WalkCommand", "frozen_array", "read_only"]


@dataclass(frozen=True, slots=True)
class WalkCommand:
    """The walking point this tick, as the AutoBalancer takes it (Ports.walk_command, op -> abc: hrpsys goVelocity
    plus the step parameters [OP] V-A lets the operator set while walking); velocities in the feet frame F."""

    vx_m_s: float
    vy_m_s: float
    vtheta_rad_s: float
    max_stride_m: float | None = None  # step length limit (None: the gait generator's own)
    foot_distance_m: float | None = None  # lateral distance between the feet's centres (None: its own)

    @property
    def is_zero(self) -> bool:
        return self.vx_m_s == 0.0 and self.vy_m_s == 0.0 and self.vtheta_rad_s == 0.0


@dataclass(frozen=True, slots=True)
class FootCommand:
    """A foot operational point this tick (Ports.foot_command, op -> abc): the swing sole's offset from the pose it
    rests at, in the feet frame F's axes [m]; the AutoBalancer brings the COM over the other foot first."""

    foot: str  # "rfoot" | "lfoot"
    offset_m: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class OdometryEstimate:
    """One tick of leg odometry (controller.balance.leg_odometry), world frame (Estimate.odometry; immutable, plain
    floats: it travels in snapshots and captures)."""

    stance: int  # the foot carrying the robot: 0 the right sole, 1 the left (the force sensors' order)
    p_stance_world_m: tuple[float, float, float]  # its sole sensor's origin in the world [m]
    stance_yaw_rad: float  # its yaw in the world [rad]
    p_body_world_m: tuple[float, float, float]  # BODY hung from the stance sole by the encoders [m]
    #: the controller's frame (the gait plan's) placed in the world: (x [m], y [m], z [m], yaw [rad]); a point p
    #: of the plan is at Rz(yaw) p + (x, y, z) in the world (control_to_world). The yaw is also BODY's heading
    #: in the world less the KalmanFilter's
    world_from_control: tuple[float, float, float, float]
    switches: int  # stance changes since the start (a step is one)


@dataclass(frozen=True, slots=True)
class GaitState:
    """What the AutoBalancer hands the Stabilizer each tick (hrpsys abc -> st ports), world frame."""

    walking: bool
    support: str  # "both" | "rleg" | "lleg"
    contact: tuple[bool, bool]  # (right, left) soles meant to be on the ground
    p_rsole_world: np.ndarray  # (3,) [m]
    R_rsole_world: np.ndarray  # (3, 3)
    p_lsole_world: np.ndarray  # (3,) [m]
    R_lsole_world: np.ndarray  # (3, 3)
    zmp_world: np.ndarray  # (3,) reference ZMP [m]
    cog_world: np.ndarray  # (3,) x_G^abc [m]
    cog_vel_world: np.ndarray  # (3,) [m/s]
    cog_pc_world: np.ndarray  # (3,) preview-control COG before the hand-force offset (Eq. 6) [m]
    cog_acc_world: np.ndarray | None = None  # (3,) planned COG acceleration [m/s^2]
    base_pos_world: np.ndarray | None = None  # (3,) BODY where the AutoBalancer put it this tick [m]
    base_rpy_rad: np.ndarray | None = None  # (3,) and its roll, pitch, yaw [rad] (op places the upper body on it)
    #: a foot lifted by its operational point: (foot, its sole's offset from its rest place in the world (3,) [m]);
    #: the feet frame F stays where the rest soles put it
    foot_lift: tuple[str, tuple[float, float, float]] | None = None


@dataclass(frozen=True, slots=True)
class StepInProgress:
    """The step the AutoBalancer is taking, as the hard e-stop needs it to let the step land before it freezes
    (Ports.step): a walk's swing, or a capture-point emergency step from its trigger to its end."""

    touchdown_time_s: float  # control time [s] the swing foot touches (or touched) down: planned, or measured early
    catching: bool  # a capture-point emergency step (its double support after the touchdown still catches the robot)
    #: a walk's swing the hard e-stop's landing would cut short (EmergencyStepping.cut): it lands at most this long
    #: [s] after the next tick instead; None: not cut (it lands as planned, or it cannot be cut)
    cut_swing_s: float | None = None


@dataclass(frozen=True, slots=True)
class BalanceEstimate:
    """The Stabilizer's estimate of the actual balance state in one tick, world frame (what the AutoBalancer's
    emergency step reads next tick): encoders, KalmanFilter attitude and foot sensors, no ground truth."""

    cog_world: np.ndarray  # (3,) actual COG [m]
    cog_vel_world: np.ndarray  # (3,) its low-passed velocity [m/s]
    zmp_world: np.ndarray  # (3,) measured ZMP [m]
    cp_world_xy: np.ndarray  # (2,) actual capture point cog + cog_vel / omega [m]
    omega_1_s: float  # sqrt(g / (z_cog - z_zmp_ref)) [1/s]


@dataclass(frozen=True, slots=True)
class Reference:
    """The command stream passed from layer to layer (hrpsys qRef/basePos/baseRpy/zmp/wrenches).

    Immutable: a layer that changes it returns `ref.with_(q_rad=...)`.
    """

    # an array field states its shape in its metadata: with_ copies, checks and freezes it to that shape
    q_rad: np.ndarray = field(metadata={"shape": (NUM_JOINTS,)})  # joint angles, JOINT_NAMES order
    base_pos_world: np.ndarray = field(metadata={"shape": (3,)})  # BODY position [m]
    base_rpy_rad: np.ndarray = field(metadata={"shape": (3,)})  # BODY roll, pitch, yaw [rad]
    zmp_base: np.ndarray = field(metadata={"shape": (3,)})  # reference ZMP in the BODY frame [m]
    # reference wrenches at the force sensors, world frame [N, N m]
    wrenches: np.ndarray = field(metadata={"shape": (len(FORCE_SENSOR_NAMES), 6)})
    gait: GaitState | None = None  # set by the AutoBalancer

    @staticmethod
    def from_arrays(q_rad, base_pos_world=(0.0, 0.0, 0.0), base_rpy_rad=(0.0, 0.0, 0.0),
                    zmp_base=(0.0, 0.0, 0.0), wrenches=None, gait: GaitState | None = None) -> Reference:
        """The one constructor from array-likes: each array is copied, checked against its field's shape
        and frozen (as in with_)."""
        if wrenches is None:
            wrenches = np.zeros((len(FORCE_SENSOR_NAMES), 6))
        arrays = {"q_rad": q_rad, "base_pos_world": base_pos_world, "base_rpy_rad": base_rpy_rad,
                  "zmp_base": zmp_base, "wrenches": wrenches}
        return Reference(**{k: frozen_array(v, _REFERENCE_SHAPES[k]) for k, v in arrays.items()}, gait=gait)

    def with_(self, **changes) -> Reference:
        """A copy with some fields replaced (arrays are copied and frozen)."""
        shapes = _REFERENCE_SHAPES
        return self._replace({k: (frozen_array(v, shapes[k]) if k in shapes else v) for k, v in changes.items()})

    def with_owned(self, **changes) -> Reference:
        """with_ for arrays the caller has just built and hands over: a float64 array of the right shape
        is frozen in place instead of copied (anything else is copied as in with_)."""
        shapes = _REFERENCE_SHAPES
        out = {}
        for k, v in changes.items():
            shape = shapes.get(k)
            if shape is not None:
                if type(v) is np.ndarray and v.dtype == np.float64 and v.shape == shape:
                    v.setflags(write=False)
                else:
                    v = frozen_array(v, shape)
            out[k] = v
        return self._replace(out)

    def _replace(self, changes: dict) -> Reference:
        if not changes.keys() <= _REFERENCE_FIELDS:
            return replace(self, **changes)  # raises the usual TypeError for unknown fields
        # Every field by keyword, written out: a third faster than a loop over fields(Reference) on the hot
        # path. tests/controller/core/test_types.py fails if a field is missing here.
        get = changes.get
        return Reference(q_rad=get("q_rad", self.q_rad), base_pos_world=get("base_pos_world", self.base_pos_world),
                         base_rpy_rad=get("base_rpy_rad", self.base_rpy_rad), zmp_base=get("zmp_base", self.zmp_base),
                         wrenches=get("wrenches", self.wrenches), gait=get("gait", self.gait))


# computed once from the dataclass (with_ runs several times per tick)
_REFERENCE_FIELDS = frozenset(f.name for f in fields(Reference))
_REFERENCE_SHAPES = {f.name: f.metadata["shape"] for f in fields(Reference) if "shape" in f.metadata}


_EYE_PER_SENSOR = np.tile(np.eye(3), (len(FORCE_SENSOR_NAMES), 1, 1))


@dataclass(slots=True)
class Estimate:
    """What the estimators (kf, rmfo, and later st) know this tick. Filled in chain order."""

    base_rpy_rad: np.ndarray = field(default_factory=lambda: np.zeros(3))  # KalmanFilter attitude
    base_angvel_rad_s: np.ndarray = field(default_factory=lambda: np.zeros(3))  # gyro, BODY frame
    # RemoveForceOffset: external wrench on the part below each sensor, sensor frame [N, N m]
    wrenches_ext: np.ndarray = field(default_factory=lambda: np.zeros((len(FORCE_SENSOR_NAMES), 6)))
    # wrench_ext expressed in the world-aligned frame at the sensor origin (yaw from kinematics)
    wrenches_ext_world: np.ndarray = field(default_factory=lambda: np.zeros((len(FORCE_SENSOR_NAMES), 6)))
    # Measured kinematics (encoders + KF attitude), world-aligned axes with the origin at BODY [m]:
    sensor_pos_from_base: np.ndarray = field(default_factory=lambda: np.zeros((len(FORCE_SENSOR_NAMES), 3)))
    sensor_R_world: np.ndarray = field(default_factory=lambda: _EYE_PER_SENSOR.copy())
    com_from_base: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # Stabilizer: actual COG, its velocity and the ZMP in the world frame (None when it did not run)
    cog_world: np.ndarray | None = None
    cog_vel_world: np.ndarray | None = None
    zmp_world: np.ndarray | None = None
    # the state estimator's leg odometry: the feet and the plan's frame in the world (None when it did not run)
    odometry: OdometryEstimate | None = None

    @staticmethod
    def for_tick() -> Estimate:
        """The loop's fresh Estimate: the same zero defaults, shared and read-only instead of allocated
        every tick (the estimators assign their results; nothing writes into an Estimate's arrays)."""
        z = _READ_ONLY_DEFAULTS
        return Estimate(base_rpy_rad=z[0], base_angvel_rad_s=z[0], wrenches_ext=z[1], wrenches_ext_world=z[1],
                        sensor_pos_from_base=z[2], sensor_R_world=z[3], com_from_base=z[0])


def read_only(a: np.ndarray) -> np.ndarray:
    """`a` itself, made read-only: for an array just built and handed over (frozen_array copies)."""
    a.setflags(write=False)
    return a


_READ_ONLY_DEFAULTS = (read_only(np.zeros(3)), read_only(np.zeros((len(FORCE_SENSOR_NAMES), 6))),
                       read_only(np.zeros((len(FORCE_SENSOR_NAMES), 3))), read_only(_EYE_PER_SENSOR.copy()))


@dataclass(slots=True)
class Ports:
    """What layers publish for later layers and for the next tick (hrpsys data ports), besides the reference.

    Each tick the loop hands the chain the ports the previous tick published (`TickContext.last_ports`,
    to read) and a fresh set (`TickContext.ports`, to publish into). A port is written by one layer only;
    the one exception is `hold`, which the loop also raises when a tick faults (the chain stopped before hes
    could publish it, and the loop has just engaged the safe stop).
    """

    hold: bool = False  # hes, and the loop on a fault: the hard e-stop is engaged; the layers before it hold
    #: hes: its release blend is in progress (hold is set too): the balance layers (abc, st) resume at once, so
    #: the stop of a walk the e-stop cut plays under the blend; the motion layers hold until it is over
    releasing: bool = False
    cp_flag: bool = False  # st: the capture-point emergency flag; es stops and reverts the motion on it
    #: st: |CP_ref - CP_act| this tick [m] (0: not estimated, or not balancing: stopped or blending in); hes lets a
    #: pushed robot's balance run on after a press
    cp_error_m: float = 0.0
    cp_flag_error_m: float | None = None  # st: while the flag is raised, |CP error| of the tick it rose [m]
    planned_q_rad: np.ndarray | None = None  # seq: the planned joint stream (30,) [rad], as the snapshot shows it
    cog_acc_world: np.ndarray | None = None  # abc: the planned COG acceleration (3,) [m/s^2]; kf removes it next tick
    gait: GaitState | None = None  # abc: this tick's gait state (soles, contacts, COG); op reads the feet frame from it
    walk_command: WalkCommand | None = None  # op: the walking point, read by abc; None: not driven this tick
    foot_command: FootCommand | None = None  # op: a foot point's offset, read by abc; None: the feet stand
    motion_stopped: bool = False  # es: it holds or reverts the motion (op freezes its integration)
    motion_reverted_to_s: float | None = None  # es: while stopped, the plan time its revert goes back to [s]
    #: co: the body pairs the command would make collide while it holds the last collision-free posture
    #: (empty: the command passes); op shows it to behaviours, whose goal checks would otherwise read the
    #: reference and believe a held motion arrived
    collision_pairs: tuple[tuple[str, str], ...] = ()
    # st: BODY (roll, pitch) [rad] from the kinematics of the soles lying flat where the plan puts them
    # (body_tilt_from_flat_soles); kf takes it as its tilt measurement next tick. None: no sole qualified
    body_tilt_kin_rad: tuple[float, float] | None = None
    # st: the actual COG, its velocity, the ZMP and the capture point (the emergency step's trigger and seed);
    # None when the Stabilizer did not estimate (disabled, or no gait reference)
    balance: BalanceEstimate | None = None
    # abc: a capture-point emergency step is in progress; es stops (and holds) the motion on it
    emergency_step: bool = False
    #: abc: the step in progress (a walk's swing in the air, or an emergency step until it ends); None: none (standing,
    #: a walk's double support). hes reads it to let the step land before it freezes
    step: StepInProgress | None = None
    #: hes: the e-stop is engaged and lets the step in progress land before it freezes (hold is set too): the balance
    #: layers (abc, st) run on, abc plans no step after this one; the motion layers hold
    landing: bool = False


@dataclass(slots=True)
class TickContext:
    """Everything a layer may read in one tick besides the upstream reference."""

    tick: int
    time_s: float
    dt_s: float
    sensors: Sensors
    estimate: Estimate
    last_ports: Ports = field(default_factory=Ports)  # published by the previous tick (read only)
    ports: Ports = field(default_factory=Ports)  # published by this tick's layers

    @property
    def hold(self) -> bool:
        """The hard e-stop was engaged at the end of the last tick: motion-producing layers hold."""
        return self.last_ports.hold

    @property
    def balance_hold(self) -> bool:
        """The hard e-stop holds the command (engaged, neither letting a step land nor releasing): the balance
        layers (abc, st) hold."""
        last = self.last_ports
        return last.hold and not (last.releasing or last.landing)
