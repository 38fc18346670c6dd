"""The /api/state response schema, generated from the layers' frozen status dataclasses (units in the field
descriptions) so that it and the document (app.service.state_document, built in the robot's service) cannot drift
apart; and what the console adds to the document (its lock and journal)."""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from typing import Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, create_model

from app.console.schemas import CommandRecord, OperatorLockState
from app.service.state_document import jsonable, state_document, state_json  # noqa: F401 - the routers' names
from behaviors.causes import RUN_CAUSES
from controller.core.layer import Status


def with_console_state(body: bytes, lock, journal=None) -> bytes:
    """The encoded state document with what the console adds beside the robot's snapshot: its `lock` state
    (app.console.operator_lock) as operator_lock, its `journal` (app.console.command_journal) as commands."""
    parts = [body[:-1]]
    if lock is not None:
        parts += [b',"operator_lock":', json.dumps(lock.state().to_dict()).encode()]
    if journal is not None:
        parts += [b',"commands":', journal.encoded()]
    return body if len(parts) == 1 else b"".join((*parts, b"}"))


# ---- the response schema ------------------------------------------------------------------------------------
class _Doc(BaseModel):
    model_config = ConfigDict(extra="forbid")


def _annotation(tp: Any) -> Any:
    """A dataclass field type as a pydantic annotation: nested status dataclasses become models."""
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp):
        return status_model(tp)
    if origin is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return list[_annotation(args[0])]
        return list[Union[tuple(_annotation(a) for a in set(args))]]  # noqa: UP007 - built at run time
    if origin in (Union, types.UnionType):
        return Union[tuple(_annotation(a) for a in typing.get_args(tp))]  # noqa: UP007
    if origin is dict:
        k, v = typing.get_args(tp)
        return dict[k, _annotation(v)]
    return tp


_MODELS: dict[type, type[BaseModel]] = {}


def status_model(cls: type) -> type[BaseModel]:
    """A pydantic model of a status dataclass: same fields, the unit and meaning as the description."""
    if cls in _MODELS:
        return _MODELS[cls]
    hints = typing.get_type_hints(cls)
    fields = {}
    for f in dataclasses.fields(cls):
        unit = f.metadata.get("unit")
        doc = f.metadata.get("doc", "")
        desc = f"{doc} [{unit}]" if unit else doc
        fields[f.name] = (_annotation(hints[f.name]), Field(description=desc))
    model = create_model(cls.__name__, __base__=_Doc, __doc__=(cls.__doc__ or "").strip() or None, **fields)
    _MODELS[cls] = model
    return model


def layer_model(cls: type[Status]) -> type[BaseModel]:
    """A layer's status as it appears in /api/state: its fields plus the tick time."""
    base = status_model(cls)
    return create_model(f"{cls.__name__}InState", __base__=base,
                        tick_ms=(float, Field(description="wall time of the layer's last tick [ms]")))


def _layer_status_classes() -> dict[str, type[Status]]:
    """Layer name -> its Status class, from the layers' own `status` annotations."""
    from controller.system import layer_classes

    out = {}
    for name, cls in layer_classes().items():
        ret = typing.get_type_hints(cls.status).get("return")
        out[name] = ret if isinstance(ret, type) and issubclass(ret, Status) else Status
    return out


def state_model() -> type[BaseModel]:
    """The StateDocument model: /api/state, field by field, with units."""
    layers = create_model("Layers", __base__=_Doc, **{
        name: (layer_model(cls) | None, Field(default=None, description=f"status of the '{name}' layer"))
        for name, cls in _layer_status_classes().items()})
    joint = create_model("JointState", __base__=_Doc,
                         cmd_deg=(float, Field(description="command written to the servo [deg]")),
                         meas_deg=(float, Field(description="encoder [deg]")),
                         seq_deg=(float, Field(description="the planned stream (SequencePlayer output) [deg]")))
    base = create_model("BaseState", __base__=_Doc,
                        pos=(list[float], Field(description="BODY position, world [m] (simulator truth)")),
                        rpy_deg=(list[float], Field(description="BODY roll, pitch, yaw [deg] (simulator truth)")),
                        linvel=(list[float], Field(description="BODY velocity, world [m/s] (simulator truth)")),
                        source=(Literal["simulation"], Field(description="where these come from")))
    estimate = create_model("EstimateState", __base__=_Doc,
                            rpy_deg=(list[float], Field(description="KalmanFilter attitude [deg]")),
                            source=(Literal["kf"], Field(description="the estimating layer")))
    cp = create_model("CapturePointState", __base__=_Doc,
                      ref=(list[float], Field(description="reference capture point x, y [m]")),
                      act=(list[float], Field(description="actual capture point x, y [m]")),
                      error=(list[float], Field(description="ref - act [m]")),
                      error_norm=(float, Field(description="|ref - act| [m]")),
                      cp_threshold_m=(float, Field(description="the emergency flag's threshold on error_norm [m]")),
                      support_edge_m=(float | None, Field(description=(
                          "distance from the reference capture point to the edge of the planned support polygon: "
                          "the error at which the actual one leaves the support; null without a gait reference [m]"))),
                      threshold=(float, Field(description="deprecated name of cp_threshold_m [m]", deprecated=True)))
    opt_float = float | None
    emergency = create_model(
        "EmergencyState", __base__=_Doc,
        hard_stop=(bool, Field(description="the hard e-stop (HardEmergencyStopper) is engaged")),
        hard_stop_reason=(str | None, Field(description="'operator', 'fault' or 'fallen'")),
        hard_stop_stopping=(str | None, Field(description=(
            "engaged, the command not frozen yet: 'landing the step' (the step in progress lands first, for at most "
            "the HardEmergencyStopper's landing_max_s); null: frozen, or not engaged"))),
        fault=(str | None, Field(description="the last controller fault, until released")),
        fall=(str | None, Field(description="why the fall detector says the robot fell (until a reset)")),
        flag=(bool, Field(description="the Stabilizer's capture-point emergency flag")),
        flag_rise_time=(opt_float, Field(description="deprecated name of flag_rose_at [s]", deprecated=True)),
        flag_rose_at=(opt_float, Field(description="simulated time the flag last rose [s]")),
        motion_stop=(bool, Field(description="the EmergencyStopper holds the planned motion")),
        motion_stop_reason=(str | None, Field(description="'capture_point' or 'operator'")),
        motion_stop_time=(opt_float, Field(description="simulated time of the motion stop [s]")),
        motion_stop_cp_error_m=(opt_float, Field(description=(
            "reason 'capture_point': |CP error| of the tick the flag rose, what raised the stop (capture_point."
            "error_norm is the value now) [m]"))),
        flag_cp_error_m=(opt_float, Field(description="|CP error| of the tick the flag last rose [m]")),
        walking_stop=(bool, Field(description="the AutoBalancer's emergency walking stop is in force")),
        walk_cut=(str | None, Field(description=(
            "why the last walk ended before its plan, and when (the capture-point flag); null when it ended as "
            "planned or a new walk began"))),
        stabilizer_stop=(bool, Field(description="the Stabilizer was stopped by the operator")))
    loop = create_model("LoopState", __base__=_Doc,
                        lateness_p99_ms=(float, Field(description="tick start-lateness p99 over the last ticks [ms]")),
                        lateness_max_ms=(float, Field(description="tick start-lateness max [ms]")),
                        speed_last=(opt_float, Field(description="simulated / wall time of the last 1-s window")))
    return create_model(
        "StateDocument", __base__=_Doc,
        __doc__="The latest snapshot of the robot. Units: m, s, deg unless a field says otherwise.",
        time=(float, Field(description="simulated time [s]")),
        tick=(int, Field(description="control ticks since the (re)start")),
        fallen=(bool, Field(description="the robot has fallen (simulator truth, or the fall detector)")),
        base=(base, Field(description="BODY pose from the simulator (for display; the controller never reads it)")),
        estimate=(estimate, Field(description="what the controller estimates")),
        joints=(dict[str, joint], Field(description="per joint, JOINT_NAMES order")),
        cog=(list[float], Field(description="estimated COG, world [m]")),
        zmp=(list[float], Field(description="ZMP from the foot F/T sensors, world [m]")),
        foot_forces_n=(dict[Literal["rleg", "lleg"], float], Field(
            description="vertical force of each foot's F/T sensor (rfsensor, lfsensor: sensor frame z, after the "
                        "offset removal) [N]")),
        walking=(bool, Field(description="a walk is in progress")),
        support=(str, Field(description="'both', 'rleg' or 'lleg'")),
        capture_point=(cp, Field(description="the Stabilizer's capture points")),
        emergency=(emergency, Field(description="every stop of [MLC] II-B")),
        layers=(layers, Field(description="each layer's status, chain order")),
        chain=(str, Field(description="the layer order, 'kf -> rmfo -> ...'")),
        speed=(opt_float, Field(description="real-time factor asked for; null = as fast as possible")),
        scene=(str, Field(description="the simulated scene")),
        loop_ms=(float, Field(description="wall time of the last tick, chain + physics [ms]")),
        loop=(loop, Field(description="how the loop keeps its deadlines")),
        operation=(dict[str, Any] | None, Field(
            description="the operation layer per operational point (rhand, lhand, head, waist, walk, rfoot, lfoot): "
                        "target, achieved, limited (null, 'reach', 'joint_limit', 'velocity', 'motion_stop' or "
                        "'balancing' (a foot waits for the COM to be over the other foot)), the "
                        "operator's (motion) and the behaviours' twists, feet frame F, the dead-man's state of the "
                        "operator's stream (deadman: 'streaming', 'ramping' or 'stopped'); null without the layer")),
        runs=(list[run_model()], Field(description="the behaviour runs kept, oldest first")),
        operator_acks=(dict[str, ack_model()], Field(
            description="per operational point, the operator's newest setpoint the robot applied")),
        operator_lock=(OperatorLockState | None, Field(
            default=None, description="who holds the operator lock (the console's, beside the robot's snapshot)")),
        commands=(list[CommandRecord] | None, Field(
            default=None, description="the last control requests of every client (POST, PUT, DELETE under /api/), "
                                      "oldest first: who sent what and how it was answered (the console's)")),
    )


def run_model() -> type[BaseModel]:
    """A behaviour run (behaviors.runner.RunStatus) as the API gives it."""
    if "RunStatus" not in _NAMED:
        _NAMED["RunStatus"] = create_model(
            "RunStatus", __base__=_Doc,
            id=(int, Field(description="run id")),
            behavior=(str, Field(description="the behaviour's name")),
            params=(dict[str, Any], Field(description="its parameters (SI units, as GET /api/behaviors lists)")),
            state=(Literal["running", "succeeded", "failed", "cancelled"], Field(description="where the run is")),
            progress=(float, Field(description="0..1: elapsed vs nominal time, or distance vs tolerance")),
            message=(str, Field(description="what happened, in words")),
            result=(dict[str, Any], Field(description="what the behaviour measured at the end")),
            points=(list[str], Field(description="what it needs alone: operational points, '<hand>.gripper'")),
            started_s=(float, Field(description="control time it started [s]")),
            ended_s=(float | None, Field(description="control time it ended [s]")),
            nominal_duration_s=(float, Field(description="how long it should take; it fails at 1.5 x [s]")),
            cause=(Literal[tuple(RUN_CAUSES)] | None, Field(
                default=None, description="a failed or cancelled run: the cause its message names, from a closed "
                                          "set (behaviors.causes); null otherwise or when it names none")),
            mode=(Literal["run", "step"], Field(default="run", description="step: it holds before each phase")),
            waiting=(bool, Field(default=False, description="step mode: held before its next phase (POST "
                                                            "/api/behaviors/runs/{id}/step starts it)")))
    return _NAMED["RunStatus"]


def ack_model() -> type[BaseModel]:
    if "SetpointAckState" not in _NAMED:
        _NAMED["SetpointAckState"] = create_model(
            "SetpointAckState", __base__=_Doc,
            seq=(int, Field(description="the setpoint's sequence number (the console numbers them)")),
            tick=(int, Field(description="the control tick it was applied before")),
            time_s=(float, Field(description="that tick's control time: the dead-man's stamp [s]")),
            ignored=(str | None, Field(default=None, description="why it was not applied: 'hard_stop' (the hard "
                                                                 "e-stop was engaged), 'before_release' (sent "
                                                                 "before the e-stop's release), 'invalid' (out "
                                                                 "of the point's ranges) or 'state' (not now: a "
                                                                 "foot while walking or the other foot up, the "
                                                                 "walk with a foot up); null: applied")))
    return _NAMED["SetpointAckState"]


_NAMED: dict[str, type[BaseModel]] = {}
