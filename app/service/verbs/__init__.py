"""The operator service's verbs: one frozen dataclass per operation, checked once where it is made
(console side), run inside the robot process at a tick boundary (`run(host)`); one module per hrpsys service
(walking, sequence, layers, sim, sessions, behaviors, safety) on a common base (the `Host` protocol, `RobotInfo`,
`Verb`). Every verb is importable from here.

A verb holds plain, picklable values in SI units (m, s, rad, N). `check(info)` validates what depends on
the robot (joint limits, body names, scenes); construction validates the rest. `run` may raise the
controller's InvalidState/InvalidCommand; the host turns those into the service's errors. Only these modules
and the host index the chain by layer name. A verb sees the host as the `Host` protocol.
"""

from app.service.verbs.base import MAX_MOTION_TIME_S, MIN_MOTION_TIME_S, Host, RobotInfo, Verb
from app.service.verbs.behaviors import (
    MAX_POSITION_M,
    CancelRun,
    ConfirmRecognition,
    GetRun,
    ListBehaviors,
    ListRuns,
    PreviewBehavior,
    ResetOperationTargets,
    RunBehavior,
    SetOperatorVelocity,
    StepRun,
    list_behaviors,
)
from app.service.verbs.layers import (
    STARTABLE,
    EnableLayers,
    GetParams,
    SetParams,
    StartImpedance,
    StartLayer,
    StopImpedance,
    StopLayer,
    typed_changes,
)
from app.service.verbs.safety import ReleaseEstop, ReleaseMotion, StopMotion
from app.service.verbs.sequence import (
    MAX_TARGET_POS_M,
    TARGET_LIMBS,
    ClearSequence,
    SequenceStatus,
    SetGroupSequence,
    SetJointAngles,
    SetJointAnglesSequence,
    SetSomeJointAngles,
    SetTargetPose,
)
from app.service.verbs.sessions import StartRecording, StopRecording
from app.service.verbs.sim import (
    MAX_OBJECT_XY_M,
    MAX_OBJECT_Z_M,
    MAX_PUSH_DURATION_S,
    MAX_PUSH_FORCE_N,
    Call,
    ChainTiming,
    GetInfo,
    GetLoopTiming,
    InjectFault,
    PlaceObject,
    Push,
    Reset,
    Shutdown,
)
from app.service.verbs.walking import (
    MAX_FOOTSTEP_POS_M,
    MAX_FOOTSTEPS,
    MAX_GO_POS_M,
    MAX_GO_POS_RAD,
    CloseStance,
    Footstep,
    GetFootsteps,
    GoPos,
    GoVelocity,
    SetFootsteps,
    WalkEmergencyStop,
    WalkStop,
    step_params,
)

__all__ = ["Call", "CancelRun", "ChainTiming", "ClearSequence", "ConfirmRecognition", "EnableLayers", "Footstep",
           "GetFootsteps", "GetInfo", "GetLoopTiming", "GetParams", "GetRun", "GoPos", "GoVelocity", "Host",
           "InjectFault", "ListBehaviors", "ListRuns", "MAX_FOOTSTEPS", "MAX_FOOTSTEP_POS_M", "MAX_GO_POS_M",
           "MAX_GO_POS_RAD", "MAX_MOTION_TIME_S", "MAX_OBJECT_XY_M", "MAX_OBJECT_Z_M", "MAX_POSITION_M",
           "MAX_PUSH_DURATION_S", "MAX_PUSH_FORCE_N", "MAX_TARGET_POS_M", "MIN_MOTION_TIME_S", "PlaceObject",
           "PreviewBehavior", "Push",
           "ReleaseEstop", "ReleaseMotion", "Reset", "ResetOperationTargets", "RobotInfo", "RunBehavior", "STARTABLE",
           "SequenceStatus", "SetFootsteps", "SetGroupSequence", "SetJointAngles", "SetJointAnglesSequence",
           "SetOperatorVelocity", "SetParams", "SetSomeJointAngles", "SetTargetPose", "Shutdown", "StartImpedance",
           "StartLayer", "StartRecording", "StepRun",
           "StopImpedance", "StopLayer", "StopMotion", "StopRecording", "TARGET_LIMBS",
           "Verb", "CloseStance", "WalkEmergencyStop", "WalkStop", "list_behaviors", "step_params", "typed_changes"]
