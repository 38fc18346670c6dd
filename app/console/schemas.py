"""Pydantic request and response bodies of the HTTP API: types, units and ranges of every field."""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Field

from app.service.verbs import (
    MAX_FOOTSTEP_POS_M,
    MAX_FOOTSTEPS,
    MAX_GO_POS_M,
    MAX_GO_POS_RAD,
    MAX_MOTION_TIME_S,
    MAX_OBJECT_XY_M,
    MAX_OBJECT_Z_M,
    MAX_PUSH_DURATION_S,
    MAX_PUSH_FORCE_N,
    MAX_TARGET_POS_M,
    MIN_MOTION_TIME_S,
    TARGET_LIMBS,
)
from controller.operation.points import POINTS, USED_COMPONENTS
from controller.operation.ranges import (
    SPEED_BOUNDS,
    WALK_FOOT_DISTANCE_RANGE_M,
    WALK_MAX_ANGULAR_RAD_S,
    WALK_MAX_LINEAR_M_S,
    WALK_MAX_STRIDE_RANGE_M,
    component_bounds,
)
from controller.walking.footsteps import StepParams
from robot.names import JOINT_NAMES, NUM_JOINTS
from robot.plant import available_scenes

LIMBS = TARGET_LIMBS
MAX_PUSH_COMPONENT_N = math.floor(MAX_PUSH_FORCE_N / math.sqrt(3.0))  # [N] any such vector is within the magnitude
MAX_GO_POS_DEG = round(math.degrees(MAX_GO_POS_RAD), 6)  # [deg] |theta| of goPos
MAX_VELOCITY_DEG_S = round(math.degrees(WALK_MAX_ANGULAR_RAD_S), 6)  # [deg/s] |vtheta| of goVelocity


class StrictBody(BaseModel):
    """Request bodies: strict types (no "1" or true for a number), no unknown fields, finite numbers."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


MotionTime = Field(description=f"interpolation time [s], in [{MIN_MOTION_TIME_S:g}, {MAX_MOTION_TIME_S:g}]",
                   ge=MIN_MOTION_TIME_S, le=MAX_MOTION_TIME_S)


JointName = Literal[JOINT_NAMES]  # type: ignore[valid-type]
SceneName = Literal[available_scenes()]  # type: ignore[valid-type]
Angle = Annotated[float, Field(ge=-360.0, le=360.0)]


class JointAnglesRequest(StrictBody):
    angles_deg: Annotated[dict[JointName, Angle], Field(min_length=1)] | Annotated[
        list[Angle], Field(min_length=NUM_JOINTS, max_length=NUM_JOINTS)] = Field(
        description="{joint name: angle [deg]} for some joints, or a list of all 30 angles [deg] in "
                    "JOINT_NAMES order; the joint ranges are checked against the model",
        examples=[{"RARM_JOINT0": -30.0}])
    time: float = MotionTime


class TargetPoseRequest(StrictBody):
    limb: Literal["rarm", "larm", "rleg", "lleg"] = Field(description="the limb to move", examples=["rarm"])
    frame: str | None = Field(default=None, max_length=64,
                              description="reference link (e.g. BODY); default: the SequencePlayer's default frame")
    pos: list[Annotated[float, Field(ge=-MAX_TARGET_POS_M, le=MAX_TARGET_POS_M)]] = Field(
        description=f"target position [m] (x, y, z), each |v| <= {MAX_TARGET_POS_M:g}", min_length=3, max_length=3)
    rpy_deg: list[Annotated[float, Field(ge=-360.0, le=360.0)]] = Field(
        description="target roll, pitch, yaw [deg], each |v| <= 360", min_length=3, max_length=3)
    time: float = MotionTime


class ResetRequest(StrictBody):
    scene: SceneName | None = Field(default=None, description="scene name (GET /api/sim/scenes); default: the "
                                                               "current one")


class PlaceObjectRequest(StrictBody):
    position: list[Annotated[float, Field(ge=-MAX_OBJECT_XY_M, le=MAX_OBJECT_XY_M)]] = Field(
        description=f"[x, y]: standing on what is below (table, box, floor); [x, y, z]: the body origin, z in "
                    f"[0, {MAX_OBJECT_Z_M:g}] [m], world frame; |x|, |y| <= {MAX_OBJECT_XY_M:g} m",
        min_length=2, max_length=3, examples=[[2.2, 0.3]],
        # each item's own range in the schema (JSON Schema 2020-12 prefixItems): z is [0, 3], not [-10, 10]
        json_schema_extra={"prefixItems": [
            {"type": "number", "minimum": -MAX_OBJECT_XY_M, "maximum": MAX_OBJECT_XY_M, "description": "x [m]"},
            {"type": "number", "minimum": -MAX_OBJECT_XY_M, "maximum": MAX_OBJECT_XY_M, "description": "y [m]"},
            {"type": "number", "minimum": 0.0, "maximum": MAX_OBJECT_Z_M, "description": "z [m]"}]})
    yaw_deg: float = Field(default=0.0, ge=-360.0, le=360.0, description="turn about the world z axis [deg]")


class PushRequest(StrictBody):
    body: str = Field(description="MuJoCo body name, e.g. BODY", examples=["BODY"], max_length=64)
    force: list[Annotated[float, Field(ge=-MAX_PUSH_COMPONENT_N, le=MAX_PUSH_COMPONENT_N)]] = Field(
        description=f"world-frame force [N], each component within +-{MAX_PUSH_COMPONENT_N:g} N (so |force| <= "
                    f"{MAX_PUSH_FORCE_N:g} N)", min_length=3, max_length=3,
        examples=[[100.0, 0.0, 0.0]])
    duration: float = Field(description=f"push duration [s], in [{MIN_MOTION_TIME_S:g}, {MAX_PUSH_DURATION_S:g}]",
                            ge=MIN_MOTION_TIME_S, le=MAX_PUSH_DURATION_S)


class FaultRequest(StrictBody):
    kind: Literal["layer", "nan"] = Field(description="'layer': the layer's tick raises from now on (until a "
                                                      "reset); 'nan': the next physics step starts from a NaN "
                                                      "velocity")
    layer: str = Field(default="st", max_length=16, description="the layer that raises (kind 'layer')")


class GoPosRequest(StrictBody):
    x: float = Field(description=f"forward [m], |x| <= {MAX_GO_POS_M:g}, relative to the feet's mid-coords",
                     ge=-MAX_GO_POS_M, le=MAX_GO_POS_M, examples=[0.3])
    y: float = Field(description=f"left [m], |y| <= {MAX_GO_POS_M:g}", ge=-MAX_GO_POS_M, le=MAX_GO_POS_M,
                     examples=[0.0])
    theta_deg: float = Field(description=f"turn [deg], |theta_deg| <= {MAX_GO_POS_DEG:g}",
                             ge=-MAX_GO_POS_DEG, le=MAX_GO_POS_DEG, examples=[0.0])


class GoVelocityRequest(StrictBody):
    vx: float = Field(description=f"forward velocity [m/s], |vx| <= {WALK_MAX_LINEAR_M_S:g}",
                      ge=-WALK_MAX_LINEAR_M_S, le=WALK_MAX_LINEAR_M_S, examples=[0.1])
    vy: float = Field(description=f"left velocity [m/s], |vy| <= {WALK_MAX_LINEAR_M_S:g}",
                      ge=-WALK_MAX_LINEAR_M_S, le=WALK_MAX_LINEAR_M_S, examples=[0.0])
    vtheta_deg: float = Field(description=f"turning velocity [deg/s], |vtheta_deg| <= {MAX_VELOCITY_DEG_S:g}",
                              ge=-MAX_VELOCITY_DEG_S, le=MAX_VELOCITY_DEG_S, examples=[0.0])


FootstepCoord = Annotated[float, Field(ge=-MAX_FOOTSTEP_POS_M, le=MAX_FOOTSTEP_POS_M)]
FootstepAngle = Annotated[float, Field(ge=-MAX_GO_POS_DEG, le=MAX_GO_POS_DEG)]


class FootstepItem(StrictBody):
    leg: Literal["rleg", "lleg"] = Field(description="the leg that lands here", examples=["rleg"])
    pos: list[FootstepCoord] = Field(description=f"sole position [m] (x, y, z), each |v| <= {MAX_FOOTSTEP_POS_M:g}; "
                                                 "relative to the first footstep, which is snapped onto the "
                                                 "current pose of its leg", min_length=3, max_length=3)
    rpy_deg: list[FootstepAngle] = Field(default_factory=lambda: [0.0, 0.0, 0.0],
                                         description=f"sole roll, pitch, yaw [deg], each |v| <= {MAX_GO_POS_DEG:g}",
                                         min_length=3, max_length=3)


def _step_range(name: str, to_shown=float) -> dict:
    """ge / le of a StepParams field, in the request's unit."""
    meta = {f.name: f.metadata for f in dataclasses.fields(StepParams)}[name]
    # rounded inward: a value the schema allows is one StepParams accepts
    return {"ge": math.ceil(to_shown(meta["min"]) * 1e6) / 1e6, "le": math.floor(to_shown(meta["max"]) * 1e6) / 1e6}


class StepRequest(StrictBody):
    """Swing parameters; the ranges are those of controller.footsteps.StepParams."""

    step_height: float | None = Field(default=None, description="swing height [m] (default 0.05)",
                                      **_step_range("step_height_m"))
    step_time: float | None = Field(default=None, description="step duration [s] (default 1.0), rounded to whole "
                                                              "control periods (5 ms)", **_step_range("step_time_s"))
    toe_angle_deg: float | None = Field(default=None, description="toe-off angle [deg] (default 0)",
                                        **_step_range("toe_angle_rad", math.degrees))
    heel_angle_deg: float | None = Field(default=None, description="heel-contact angle [deg] (default 0)",
                                         **_step_range("heel_angle_rad", math.degrees))


class FootstepsRequest(StrictBody):
    footsteps: list[FootstepItem] = Field(description=f"1..{MAX_FOOTSTEPS} footsteps; the first is the "
                                                      "current support foot", min_length=1,
                                          max_length=MAX_FOOTSTEPS)
    step: StepRequest | None = Field(default=None, description="swing parameters for every footstep but the "
                                                               "first (default: the planner's)")


class WalkFootsteps(BaseModel):
    walking: bool
    footsteps: list[dict[str, Any]]


class Ok(BaseModel):
    ok: bool = True
    message: str = ""


class ObjectPlaced(Ok):
    name: str = Field(description="the object placed")
    position: list[float] = Field(description="its body origin after placing [m], world frame")


class EstopResponse(Ok):
    tick: int = Field(description="the control tick at which the loop engaged it")
    sim_time_s: float = Field(description="simulated time then [s]")
    engaged_at_monotonic_s: float = Field(description="when the loop engaged it, on the machine's monotonic clock "
                                                      "(CLOCK_MONOTONIC, as Python's time.monotonic) [s]")
    engaged: bool = Field(description="the loop has the hard e-stop engaged (ok says the same)")
    late_copy: bool = Field(False, description="a copy of a press already released, arrived within the copy "
                                               "window of its first copy: nothing was engaged again")
    press_ignored: str | None = Field(None, description="the press id given was malformed and not used (the stop "
                                                        "engaged all the same)")
    reason: str | None = Field(None, description="why it did not engage: late_copy")


class RunCounters(BaseModel):
    ticks: int = Field(description="ticks the robot process has run")
    fallen: bool = Field(description="the robot fell at some tick of the run")
    faults: list[str] = Field(description="every distinct controller fault of the run; empty: none")
    max_loop_ms: float = Field(description="the longest tick, chain and physics [ms]")


class Health(BaseModel):
    robot_alive: bool = Field(description="the robot process runs")
    exit_reason: str | None = Field(description="why it does not (POST /api/sim/reset starts a new one)")
    priority: str = Field(description="the scheduling the robot process got: SCHED_FIFO, a nice value or default")
    scene: str
    run: RunCounters | None = Field(default=None, description="the run's own counters (what the console's summary "
                                                              "prints at exit); null before the first tick is "
                                                              "published or when the robot process is gone")


class LoopTimingResponse(BaseModel):
    ticks: int = Field(description="ticks the lateness figures are taken over")
    lateness_p50_ms: float = Field(description="median tick start-lateness [ms]")
    lateness_p99_ms: float = Field(description="99th percentile tick start-lateness [ms]")
    lateness_max_ms: float = Field(description="largest tick start-lateness [ms]")
    late_ticks_over_1ms: int = Field(description="ticks that began more than 1 ms late")
    speed_last: float | None = Field(description="simulated / wall time of the last finished 1-s window")
    speed_min: float | None = Field(description="the slowest kept 1-s window")
    speed_run: float | None = Field(description="simulated / wall time since the run began (its start, its last "
                                                "reset or speed change)")
    windows: int = Field(description="1-s windows kept")
    paced: bool = Field(description="false when running as fast as possible (lateness is then 0)")
    speed_target: float | None = Field(description="the real-time factor asked for")


class SequenceStatus(BaseModel):
    interpolating: bool


class ChainInfo(BaseModel):
    order: list[str]
    chain: str
    timing: dict[str, dict[str, float | int]]
    tick_ms: dict[str, float | int]
    physics_ms: dict[str, float | int]


class PointRanges(BaseModel):
    """What an operational point takes (controller.operation.ranges), as PUT /api/operator/velocity checks it."""

    linear: list[float] = Field(description="|v| allowed per component (x, y, z) [m/s]; 0: the point does not use it")
    angular: list[float] = Field(description="|v| allowed per component (x, y, z) [deg/s]; 0: the point does not use "
                                             "it")
    max_stride: list[float] | None = Field(default=None, description="walk only: [min, max] step length limit [m]")
    foot_distance: list[float] | None = Field(default=None, description="walk only: [min, max] distance between the "
                                                                        "feet's centres [m]")


def point_ranges() -> dict[str, PointRanges]:
    """Every operational point, in POINTS order, with its ranges."""
    ranges = {}
    for point in POINTS:
        lin, ang = component_bounds(point)
        walk = point == "walk"
        ranges[point] = PointRanges(linear=list(lin), angular=[round(math.degrees(v), 6) for v in ang],
                                    max_stride=list(WALK_MAX_STRIDE_RANGE_M) if walk else None,
                                    foot_distance=list(WALK_FOOT_DISTANCE_RANGE_M) if walk else None)
    return ranges


class ConsoleConfig(BaseModel):
    viewer_port: int | None
    estop_port: int | None = Field(default=None, description=(
        "port of the e-stop's own WebSocket door (same host; send {\"estop\": true}, answered as POST /api/estop "
        "with \"via\": \"door\"): served by the robot process, it does not wait for this server. null: none"))
    joints: list[str]
    joint_limits_deg: dict[str, list[float]]
    scenes: list[str]
    limbs: list[str] = list(LIMBS)
    points: dict[str, PointRanges] = Field(default_factory=point_ranges, description=(
        "the operational points in the order they are solved, each with what it takes (PUT /api/operator/velocity)"))


StateDict = dict[str, Any]


class ExperimentRequest(StrictBody):
    es: bool = Field(default=True, description="run with the EmergencyStopper (false: without, as in [MLC] Fig. 8a)")
    variant: str | None = Field(default=None, description="variant of the experiment (GET /api/experiments); "
                                                          "default: its first")
    save: bool = Field(default=False, description="also keep the CSV and the Fig. 10-style PNG (in the console's "
                                                  "memory; download them from csv_url / png_url)")
    duration_s: float | None = Field(
        default=None, gt=0.0, le=60.0,
        description="stop the script after this many seconds [s] (default: the experiment's whole duration)")
    params: dict[str, Any] | None = Field(
        default=None, description="EmergencyStopper parameters for this run only, named and bounded as in "
                                  "PUT /api/emergency-stopper/params (t1, t2, recover_time [s], cp_threshold_m [m], "
                                  "mode); the others keep their defaults", examples=[{"cp_threshold_m": 0.03}])


class ExperimentInfo(BaseModel):
    name: str
    description: str
    scene: str
    duration_s: float = Field(description="simulated duration of the scripted part [s] (after settling)")
    variants: list[str] = Field(description="the first is the default")
    impedance: list[str] = Field(description="hands whose ImpedanceController runs during the experiment")


class ExperimentList(BaseModel):
    experiments: list[ExperimentInfo]


class ExperimentResponse(BaseModel):
    name: str
    variant: str
    es: bool = Field(description="whether the EmergencyStopper was enabled")
    verdict: Literal["stood", "fell"]
    flag_time_s: float | None = Field(description="when the capture-point flag stopped the motion [s] after the "
                                                  "start of the script; null: never")
    peak_cp_error_m: float = Field(description="largest |CP_ref - CP_act| [m]")
    cp_error_at_flag_m: float | None = Field(description="|CP error| [m] when the flag rose")
    edge_margin_at_flag_m: float | None = Field(description="distance [m] of the actual CP to the support "
                                                            "polygon edge when the flag rose")
    min_edge_margin_m: float | None = Field(description="smallest distance [m] of the actual CP to the support "
                                                        "edge (negative: outside)")
    below_threshold_after_revert_s: float | None = Field(
        description="time [s] from the end of the revert (flag + T2) until the CP error stays below the threshold")
    duration_s: float = Field(description="simulated time run [s] (shorter than planned when the robot fell)")
    outcome: dict[str, Any] = Field(description="task measures of the experiment (valve angle, ...)")
    params: dict[str, Any] = Field(default_factory=dict, description="the EmergencyStopper parameters of the run")
    refused: list[str] = Field(default_factory=list, description="planner commands the robot refused (when, why), "
                                                                 "e.g. the plan's next step after a motion stop")
    faults: list[str] = Field(default_factory=list, description="every distinct controller fault of the run "
                                                                "(its own counters); empty: none")
    emergency_steps: int = Field(default=0, description="capture-point emergency steps the AutoBalancer took")
    run_id: int = Field(description="the run's number in this console")
    csv_url: str | None = Field(default=None, description="where the run's CSV is (with save)")
    png_url: str | None = Field(default=None, description="where the run's Fig. 10-style PNG is (with save)")
    wall_time_s: float = Field(description="wall-clock time the run took [s]")
    real_time_factor: float = Field(description="simulated time / wall time spent simulating (no set-up, no files)")


# ---- the operator's velocities ([OP] Eq. 5's xi_motion) ------------------------------------------------------
def _component(used: bool, limit: float, unit: str, what: str) -> Any:
    if used:
        return Annotated[float, Field(strict=True, ge=-limit, le=limit,
                                      description=f"{what} [{unit}], |v| <= {limit:g}")]
    return Annotated[float, Field(strict=True, ge=0.0, le=0.0, description="not used by this point: 0")]


def _velocity_model(point: str) -> type[BaseModel]:
    from pydantic import create_model

    lin_mask, ang_mask = USED_COMPONENTS[point]
    lin_limit, ang_limit_rad_s = SPEED_BOUNDS[point]
    ang_limit = round(math.degrees(ang_limit_rad_s), 6)
    lin = tuple[tuple(_component(u, lin_limit, "m/s", f"{axis} velocity")
                      for u, axis in zip(lin_mask, "xyz", strict=True))]
    ang = tuple[tuple(_component(u, ang_limit, "deg/s", f"rate about {axis}")
                      for u, axis in zip(ang_mask, "xyz", strict=True))]
    fields: dict[str, Any] = {
        "point": (Literal[point], Field(description="the operational point")),
        # (a JSON array of 3: not strict, so that a list is taken for the tuple; its numbers are strict)
        "linear": (lin, Field(default=(0.0, 0.0, 0.0), strict=False,
                              description="linear velocity, feet frame F [m/s]")),
        "angular": (ang, Field(default=(0.0, 0.0, 0.0), strict=False,
                               description="angular velocity, feet frame F [deg/s]")),
    }
    if point == "walk":
        fields["max_stride"] = (float | None, Field(
            default=None, ge=WALK_MAX_STRIDE_RANGE_M[0], le=WALK_MAX_STRIDE_RANGE_M[1],
            description="step length limit [m] (null: the gait's own)"))
        fields["foot_distance"] = (float | None, Field(
            default=None, ge=WALK_FOOT_DISTANCE_RANGE_M[0], le=WALK_FOOT_DISTANCE_RANGE_M[1],
            description="distance between the feet's centres [m] (null: the gait's own)"))
    docs = {"rhand": "right hand: linear (x, y, z) [m/s], angular (x, y, z) [deg/s]",
            "lhand": "left hand: linear (x, y, z) [m/s], angular (x, y, z) [deg/s]",
            "head": "gaze: angular (0, pitch, yaw) [deg/s], pitch > 0 looks down; linear unused",
            "waist": "waist: linear (0, 0, height rate) [m/s], angular BODY (roll, pitch, yaw) rates [deg/s]",
            "walk": "walking (goVelocity): linear (vx, vy, 0) [m/s], angular (0, 0, vtheta) [deg/s], and the "
                    "step parameters",
            "rfoot": "right sole: linear (x, y, z) [m/s], angular unused; standing only, held up while streamed, "
                     "put down when the stream stops",
            "lfoot": "left sole: linear (x, y, z) [m/s], angular unused; standing only, held up while streamed, "
                     "put down when the stream stops"}
    return create_model(f"{point.capitalize()}Velocity", __base__=StrictBody, __doc__=docs[point], **fields)


def _velocity_request() -> Any:
    models = tuple(_velocity_model(p) for p in POINTS)
    return Annotated[Union[models], Field(discriminator="point")]  # noqa: UP007 - built at run time

OperatorVelocityRequest = _velocity_request()


class OperatorAck(BaseModel):
    ok: bool = True
    point: str = Field(description="the operational point")
    seq: int = Field(description="this setpoint's sequence number")
    applied_seq: int = Field(description="the newest setpoint of the point the robot has applied (>= seq)")
    tick: int = Field(description="the control tick it was applied before")
    time_s: float = Field(description="that tick's control time, the dead-man's stamp [s]")


# ---- behaviours -----------------------------------------------------------------------------------------------
class RunStarted(BaseModel):
    ok: bool = True
    id: int = Field(description="the run id (GET /api/behaviors/runs/{id})")
    message: str = ""


class BehaviorParamDoc(BaseModel):
    name: str
    type: Literal["number", "integer", "boolean", "string", "array"]
    default: Any = None
    unit: str | None = None
    min: float | None = None
    max: float | None = None
    choices: list[Any] | None = None
    doc: str | None = None
    place: Literal["x", "y", "z"] | None = Field(
        default=None, description="this parameter is that coordinate of a point (world [m]) that a named place "
                                  "(GET /api/places) may give")


class BehaviorDoc(BaseModel):
    name: str
    summary: str
    params: list[BehaviorParamDoc]


# ---- the operator lock ---------------------------------------------------------------------------------------
class LockRequest(StrictBody):
    client: str = Field(pattern=r"^[A-Za-z0-9._:-]{1,64}$", min_length=1, max_length=64, examples=["page-1"],
                        description="this client's display name (1 to 64 of A-Z a-z 0-9 . _ : -), shown to "
                                    "every client; it proves nothing: the lease token answered does")


class OperatorLockState(BaseModel):
    model_config = ConfigDict(extra="forbid")

    holder: str | None = Field(description="the client in control; null: nobody, any client may control")
    lease_s: float = Field(description="a holder without a WebSocket keeps the lock this long after its last "
                                       "request [s]")
    grace_s: float = Field(description="kept this long after the holder's last WebSocket closed [s]")
    expires_in_s: float | None = Field(description="when it goes unless renewed [s]; null while the holder has a "
                                                   "WebSocket open, or when free")
    connected: bool = Field(description="the holder has a WebSocket open (/ws/operator or /ws/telemetry with "
                                        "?lock_token=)")


class OperatorLockLease(OperatorLockState):
    """The lock as its taker sees it: with the lease token, which only POST /api/operator/lock answers."""

    token: str = Field(description="the lease token: secret, the holder's only proof. Send it as the X-Lock-Token "
                                   "header of its control requests (and DELETE /api/operator/lock) and as "
                                   "?lock_token= of its WebSockets; a renewal (POST with it) answers the same one")


class CommandRecord(BaseModel):
    """A control request as the console's journal keeps it (app.console.command_journal)."""

    model_config = ConfigDict(extra="forbid")

    seq: int = Field(description="numbered in arrival order, from 1 (a restarted console starts again)")
    client: str = Field(description="the sender's X-Client-Id; 'anonymous@<address>' without one")
    request: str = Field(description="method and path, e.g. 'POST /api/walk/go-pos'")
    body: str = Field(description="the request's JSON, cut to 160 characters ('' without a body)")
    status: int = Field(description="the HTTP status it was answered with")
    answer: str = Field(description="the answer's message, or the error's detail (cut to 160 characters)")
    count: int = Field(description="how many times in a row the client sent it, each within 0.5 s of the last "
                                   "(a stream of setpoints is one entry)")
