"""The log's row: one tick's telemetry as a flat float64 vector, its named columns grouped into the signals of
the MCAP channels (joints, base pose, COG/ZMP/CP ref and act, flags, wrenches, footsteps, operational-point
targets), and the filler that copies an Observation into it on the hot path.

The layout is data, written once (`SIGNALS`): the DataLogger's ring, its CSV export, the MCAP channels and
their JSON schemas, the session reader and the replay's bit-for-bit comparison all derive from it. A value
that does not exist this tick (no gait reference, an operational point not operated, no footstep) is NaN;
flags are 0.0 / 1.0."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES

XYZ = ("x", "y", "z")
RPY = ("roll", "pitch", "yaw")
WRENCH = ("fx", "fy", "fz", "tx", "ty", "tz")
#: footsteps not landed yet kept in the row (the plan may hold more: the next ones are what a plot shows)
ROW_FOOTSTEPS = 6
FOOTSTEP = ("leg", "x", "y", "z", "yaw")  # leg: +1 rleg, -1 lleg, NaN no footstep
LEG_CODE = {"rleg": 1.0, "lleg": -1.0}
#: the operation layer's target layout per point (controller.layers.operation.PointStatus.target)
OP_TARGETS = {"rhand": (*XYZ, *RPY), "lhand": (*XYZ, *RPY), "head": ("pitch", "yaw"),
              "waist": ("height", *RPY), "walk": ("vx", "vy", "vtheta")}


@dataclass(frozen=True)
class Signal:
    """Some columns of the row, published together as one field of one MCAP channel's message.

    `key` is the field's path in the message ("act.rfsensor" nests {"act": {"rfsensor": {...}}}); `names` are
    its components (an object {name: value}), or () for one scalar value. `kind` "bool" is a flag (0/1 in the
    row, true/false in the message); a float NaN is null in the message."""

    topic: str
    key: str
    names: tuple[str, ...]
    unit: str
    description: str
    kind: str = "float"

    @property
    def width(self) -> int:
        return max(1, len(self.names))

    def column_names(self) -> list[str]:
        base = f"{self.topic.strip('/')}/{self.key}"
        return [base] if not self.names else [f"{base}/{n}" for n in self.names]


def _sig(topic, key, names, unit, description, kind="float") -> Signal:
    return Signal(topic, key, tuple(names), unit, description, kind)


#: Channels published at every tick; the others (ON_CHANGE_TOPICS) only when their columns change.
TICK_TOPICS = ("/joints", "/base", "/balance", "/flags", "/wrenches")
ON_CHANGE_TOPICS = ("/footsteps", "/operation/targets")

SIGNALS: tuple[Signal, ...] = (
    _sig("/joints", "q_cmd_rad", JOINT_NAMES, "rad", "command written to the servos (JOINT_NAMES order)"),
    _sig("/joints", "q_meas_rad", JOINT_NAMES, "rad", "encoders"),
    _sig("/base", "rpy_est_rad", RPY, "rad", "BODY attitude estimated by the KalmanFilter"),
    _sig("/base", "pos_ref_m", XYZ, "m", "BODY position in the final reference (world)"),
    _sig("/base", "rpy_ref_rad", RPY, "rad", "BODY roll, pitch, yaw in the final reference"),
    _sig("/base", "pos_sim_m", XYZ, "m", "BODY position in the simulation (ground truth, world)"),
    _sig("/base", "quat_sim", ("w", "x", "y", "z"), "-", "BODY orientation in the simulation (ground truth)"),
    _sig("/balance", "cog_act_m", XYZ, "m", "COG estimated from the encoders and the attitude (world)"),
    _sig("/balance", "cog_ref_m", XYZ, "m", "AutoBalancer's planned COG x_G^abc (world); null without a gait"),
    _sig("/balance", "zmp_act_m", XYZ, "m", "ZMP measured by the foot F/T sensors (world)"),
    _sig("/balance", "zmp_ref_m", XYZ, "m", "AutoBalancer's reference ZMP (world); null without a gait"),
    _sig("/balance", "cp_act_m", ("x", "y"), "m", "actual capture point (Stabilizer, world); null without st"),
    _sig("/balance", "cp_ref_m", ("x", "y"), "m", "reference capture point (Stabilizer, world)"),
    _sig("/balance", "cp_error_m", (), "m", "|cp_ref - cp_act|"),
    _sig("/flags", "hard_stop", (), "-", "the operator's hard e-stop (or a fault, a fall) freezes the command",
         "bool"),
    _sig("/flags", "cp_flag", (), "-", "the Stabilizer's capture-point emergency flag", "bool"),
    _sig("/flags", "motion_stop", (), "-", "the EmergencyStopper holds the planned motion", "bool"),
    _sig("/flags", "walking_stop", (), "-", "the AutoBalancer's emergency walking stop is in force", "bool"),
    _sig("/flags", "walking", (), "-", "a walk is in progress", "bool"),
    _sig("/flags", "fall_detected", (), "-", "the FallDetector says the robot has fallen (its own sensors)",
         "bool"),
    _sig("/flags", "fallen_sim", (), "-", "fallen according to the simulation (ground truth)", "bool"),
    _sig("/flags", "fault", (), "-", "a controller fault is reported", "bool"),
    *(_sig("/wrenches", f"act.{s}", WRENCH, "N, N m", f"{s}: offsets and the parts below removed (sensor frame)")
      for s in FORCE_SENSOR_NAMES),
    *(_sig("/wrenches", f"ref.{s}", WRENCH, "N, N m", f"{s}: reference wrench (world frame)")
      for s in FORCE_SENSOR_NAMES),
    *(_sig("/footsteps", f"next.{i}", FOOTSTEP, "m, rad", f"footstep {i + 1} not landed yet (leg +1 rleg, -1 lleg)")
      for i in range(ROW_FOOTSTEPS)),
    *(_sig("/operation/targets", point, names, "m, rad (walk: m/s, rad/s)",
           f"{point}'s target in the feet frame F; null when not operated") for point, names in OP_TARGETS.items()),
)


def _layout() -> tuple[dict[Signal, slice], list[str]]:
    slices, header, i = {}, ["time_s"], 1
    for s in SIGNALS:
        slices[s] = slice(i, i + s.width)
        header += s.column_names()
        i += s.width
    return slices, header


SLICES, COLUMNS = _layout()
ROW_LENGTH = len(COLUMNS)


def signal(topic: str, key: str) -> Signal:
    for s in SIGNALS:
        if s.topic == topic and s.key == key:
            return s
    raise KeyError(f"no signal {key!r} on {topic!r}; valid: {[(s.topic, s.key) for s in SIGNALS]}")


def column(name: str) -> int:
    """The row index of a column ("joints/q_cmd_rad/RLEG_JOINT0", "time_s", ...)."""
    try:
        return COLUMNS.index(name)
    except ValueError:
        raise KeyError(f"no column {name!r}; e.g. {COLUMNS[:3]} ... ({ROW_LENGTH} columns)") from None


def _at(topic: str, key: str) -> slice:
    return SLICES[signal(topic, key)]


class RowFiller:
    """Copies one Observation (the snapshot with the simulator's truth beside it) into a row, ROW_LENGTH
    float64. Keeps the last footsteps and operation targets it converted: the layers publish those as the same
    object until they change, so a tick that changed neither copies 51 numbers instead of converting them."""

    def __init__(self) -> None:
        nan = math.nan
        self._footsteps_key = None
        self._footsteps = np.full(ROW_FOOTSTEPS * len(FOOTSTEP), nan)
        self._op_key = None
        self._targets = np.full(sum(len(n) for n in OP_TARGETS.values()), nan)
        s = SLICES
        self._q_cmd, self._q_meas = _at("/joints", "q_cmd_rad"), _at("/joints", "q_meas_rad")
        self._rpy_est, self._pos_ref = _at("/base", "rpy_est_rad"), _at("/base", "pos_ref_m")
        self._rpy_ref, self._pos_sim = _at("/base", "rpy_ref_rad"), _at("/base", "pos_sim_m")
        self._quat_sim = _at("/base", "quat_sim")
        self._cog_act, self._cog_ref = _at("/balance", "cog_act_m"), _at("/balance", "cog_ref_m")
        self._zmp_act, self._zmp_ref = _at("/balance", "zmp_act_m"), _at("/balance", "zmp_ref_m")
        self._cp = slice(s[signal("/balance", "cp_act_m")].start, s[signal("/balance", "cp_error_m")].stop)
        self._flags = slice(s[signal("/flags", "hard_stop")].start, s[signal("/flags", "fault")].stop)
        n = len(FORCE_SENSOR_NAMES) * len(WRENCH)
        first = s[signal("/wrenches", f"act.{FORCE_SENSOR_NAMES[0]}")].start
        self._w_act, self._w_ref = slice(first, first + n), slice(first + n, first + 2 * n)
        first = s[signal("/footsteps", "next.0")].start
        self._steps = slice(first, first + self._footsteps.size)
        first = s[signal("/operation/targets", next(iter(OP_TARGETS)))].start
        self._op = slice(first, first + self._targets.size)

    def fill(self, row: np.ndarray, obs) -> None:
        snap = obs.snapshot
        truth = obs.truth
        ref = snap.reference
        layers = snap.layers
        row[0] = snap.time_s
        row[self._q_cmd] = snap.q_cmd_rad
        row[self._q_meas] = snap.q_meas_rad
        row[self._rpy_est] = snap.base_rpy_est_rad
        row[self._pos_ref] = ref.base_pos_world
        row[self._rpy_ref] = ref.base_rpy_rad
        row[self._pos_sim] = truth.base_pos_world
        row[self._quat_sim] = truth.base_quat_wxyz
        row[self._cog_act] = snap.cog_world
        row[self._zmp_act] = snap.zmp_world
        gait = ref.gait
        if gait is None:
            row[self._cog_ref] = math.nan
            row[self._zmp_ref] = math.nan
        else:
            row[self._cog_ref] = gait.cog_world
            row[self._zmp_ref] = gait.zmp_world
        st = layers.get("st")
        es = layers.get("es")
        abc = layers.get("abc")
        if st is None:
            row[self._cp] = math.nan
        else:
            (rx, ry), (ax, ay) = st.cp_ref, st.cp_act
            row[self._cp] = (ax, ay, rx, ry, st.cp_error_norm)
        safety = snap.safety
        row[self._flags] = (safety.hard_stop, st is not None and st.emergency, es is not None and es.stopped,
                            abc is not None and abc.walking_stop, abc is not None and abc.walking,
                            safety.fall is not None, obs.fallen, safety.fault is not None)
        row[self._w_act] = snap.wrenches_ext.reshape(-1)
        row[self._w_ref] = ref.wrenches.reshape(-1)
        steps = None if abc is None else abc.footsteps
        if steps is not self._footsteps_key:
            self._footsteps_key = steps
            self._footsteps = footsteps_columns(steps or ())
        row[self._steps] = self._footsteps
        op = layers.get("op")
        if op is not self._op_key:
            self._op_key = op
            self._targets = targets_columns(None if op is None else op.points)
        row[self._op] = self._targets


def footsteps_columns(steps) -> np.ndarray:
    """The row's footstep columns of the first ROW_FOOTSTEPS of `steps` (AutoBalancer FootstepStatus)."""
    out = np.full(ROW_FOOTSTEPS * len(FOOTSTEP), math.nan)
    for i, f in enumerate(steps[:ROW_FOOTSTEPS]):
        k = i * len(FOOTSTEP)
        out[k:k + len(FOOTSTEP)] = (LEG_CODE.get(f.leg, math.nan), *f.pos, f.rpy[2])
    return out


def targets_columns(points) -> np.ndarray:
    """The row's operation-target columns of an OperationStatus.points mapping (None: nothing operated)."""
    parts = []
    for point, names in OP_TARGETS.items():
        status = None if points is None else points.get(point)
        target = None if status is None else status.target
        parts.append(np.full(len(names), math.nan) if target is None else np.asarray(target, dtype=float))
    return np.concatenate(parts)
