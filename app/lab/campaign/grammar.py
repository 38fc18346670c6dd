"""The random operator's grammar: the actions, their stated probabilities and ranges; a seed gives one list."""

from __future__ import annotations

import dataclasses
import math
import random
from collections.abc import Mapping, Sequence
from typing import Any

#: Probability of each kind of action (they sum to 1); the report prints this table.
PROBABILITIES: Mapping[str, float] = {
    "stick": 0.14,                # a stick stream on one point (WebSocket /ws/operator), ended by a zero
    "closed_tab": 0.04,           # a stick stream that stops without a zero (the tab closed)
    "go_velocity": 0.07,          # POST /api/walk/go-velocity
    "go_pos": 0.06,               # POST /api/walk/go-pos (also during a walk)
    "walk_stop": 0.05,            # POST /api/walk/stop (goStop)
    "walk_emergency_stop": 0.03,  # POST /api/walk/emergency-stop (ends by itself once the robot stands still)
    "behavior": 0.12,             # POST /api/behaviors/{name}, random valid parameters
    "cancel": 0.05,               # POST /api/behaviors/runs/{id}/cancel (the newest run)
    "estop": 0.05,                # POST /api/estop
    "estop_release": 0.06,        # POST /api/estop/release
    "motion_stop": 0.03,          # POST /api/motion/stop
    "motion_release": 0.04,       # POST /api/motion/release
    "push": 0.06,                 # POST /api/sim/push inside the envelope (PUSH_ENVELOPE_NS)
    "push_beyond": 0.01,          # ... beyond it: a fall after it is no violation
    "params": 0.04,               # PUT a safe parameter within SAFE_PARAMS
    "reset": 0.02,                # POST /api/sim/reset
    "watch": 0.04,                # a second client reads /ws/telemetry
    "take_lock": 0.03,            # a second client holds the operator lock, then gives it back
    "compete": 0.03,              # a second client streams to a point
    "wait": 0.03,                 # nothing
}

GAP_MEAN_S = 1.5  # [s] mean simulated time between two actions (exponential)
GAP_RANGE_S = (0.05, 6.0)  # [s] the gap is clipped to this
STREAM_S = (0.3, 3.0)  # [s] a stick stream's or a second client's duration
STREAM_POINTS = ("rhand", "lhand", "head", "waist", "walk", "rfoot", "lfoot")
#: [m/s] / [deg/s] the stick's range per point and component, inside the door's limits (README, PUT
#: /api/operator/velocity; each point's unused components stay 0)
STICK_LIMITS: Mapping[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "rhand": ((0.1, 0.1, 0.1), (20.0, 20.0, 20.0)),
    "lhand": ((0.1, 0.1, 0.1), (20.0, 20.0, 20.0)),
    "head": ((0.0, 0.0, 0.0), (0.0, 30.0, 30.0)),
    "waist": ((0.0, 0.0, 0.05), (10.0, 10.0, 10.0)),
    "walk": ((0.3, 0.15, 0.0), (0.0, 0.0, 30.0)),
    "rfoot": ((0.1, 0.1, 0.1), (0.0, 0.0, 0.0)),  # the sole (standing: the weight goes over the other foot first)
    "lfoot": ((0.1, 0.1, 0.1), (0.0, 0.0, 0.0)),
}
WALK_STRIDE_M = (0.05, 0.3)  # [m] the walk point's max_stride (the AutoBalancer's range is 0-0.3)
WALK_FOOT_DISTANCE_M = (0.16, 0.24)  # [m] its foot_distance (range 0.14-0.30)
GO_VELOCITY = (0.3, 0.15, 30.0)  # |vx| [m/s], |vy| [m/s], |vtheta| [deg/s] (documented: 0.5, 0.5, 45)
GO_POS = (1.0, 0.5, 90.0)  # |x| [m], |y| [m], |theta| [deg] (documented: 5, 5, 360; kept short for 60 s)
PUSH_DURATION_S = 0.1  # [s] a push lasts this long; its force is impulse / duration
PUSH_BEYOND_FACTOR = (1.5, 3.0)  # a push beyond the envelope: this many times it

#: [N s] the documented push envelope (docs/push-map.md): standing, the ankles absorb >= 20 N s in every
#: direction; walking it is the walking issue's (in progress elsewhere): 10 N s. A foot operated (the weight going
#: over the other foot, or on it; no step catches a push there): 10 N s (8 directions stand, lifted and shifting;
#: 15 N s fell 2 of 8: docs/foot-can.md). Frozen by the hard e-stop the robot balances nothing
#: (docs/safety-path.md): a push then is beyond any envelope, drawn as standing or walking
PUSH_ENVELOPE_NS: Mapping[str, float] = {"standing": 20.0, "walking": 10.0, "foot": 10.0, "frozen": 0.0}

#: A few parameters safe to change, with the range the grammar draws from (inside each one's schema):
#: (PUT path, field, low, high)
SAFE_PARAMS: tuple[tuple[str, str, float, float], ...] = (
    ("/api/auto-balancer/params", "step_time_s", 0.8, 1.2),
    ("/api/auto-balancer/params", "step_height_m", 0.03, 0.07),
    ("/api/emergency-stopper/params", "recover_time", 1.0, 4.0),
    ("/api/emergency-stopper/params", "t1", 0.5, 2.0),
    ("/api/operator/params", "walk_speed_m_s", 0.1, 0.3),
    ("/api/operator/params", "hand_speed_m_s", 0.1, 0.5),
)

#: Behaviours that apply in the default scene (no table, can nor trash box), with the ranges the grammar narrows
#: their schema to (the schema's own range where not given); `sequence` chains 2-3 of the others.
SCENE_BEHAVIORS: Mapping[str, Mapping[str, tuple[float, float]]] = {
    "stand": {"time_s": (0.5, 3.0)},
    "squat": {"depth_m": (0.02, 0.15)},
    "look_at": {"x_m": (0.3, 3.0), "y_m": (-2.0, 2.0), "z_m": (0.0, 2.0)},
    "reach": {"x_m": (0.1, 0.45), "y_m": (-0.45, 0.45), "z_m": (0.5, 1.1), "roll_deg": (-30.0, 30.0),
              "pitch_deg": (-30.0, 30.0), "yaw_deg": (-30.0, 30.0)},
    "walk_to": {"x_m": (-0.5, 1.0), "y_m": (-0.5, 0.5), "theta_deg": (-60.0, 60.0)},
    "grasp": {},
    "release": {},
    "sequence": {},
}
SEQUENCE_STEPS = (2, 3)
#: parameters the grammar leaves at their default (a grasp on nothing must be allowed to succeed)
FIXED_PARAMS: Mapping[str, Mapping[str, Any]] = {"grasp": {"require_object": False}}


@dataclasses.dataclass(frozen=True)
class Action:
    """One operator action at `at_s` [s] of simulated time after the session began."""

    at_s: float
    kind: str
    params: Mapping[str, Any]

    def to_dict(self) -> dict[str, Any]:
        return {"at_s": self.at_s, "kind": self.kind, "params": dict(self.params)}

    @staticmethod
    def from_dict(d: Mapping[str, Any]) -> Action:
        return Action(float(d["at_s"]), str(d["kind"]), dict(d["params"]))


def _r(rng: random.Random, low: float, high: float, digits: int = 4) -> float:
    return round(rng.uniform(low, high), digits)


def _signed(rng: random.Random, limit: float, digits: int = 4) -> float:
    return _r(rng, -limit, limit, digits) if limit > 0 else 0.0


def stick_body(rng: random.Random, point: str) -> dict[str, Any]:
    lin, ang = STICK_LIMITS[point]
    body: dict[str, Any] = {"point": point, "linear": [_signed(rng, v) for v in lin],
                            "angular": [_signed(rng, v, 2) for v in ang]}
    if point == "walk":
        body["max_stride"] = _r(rng, *WALK_STRIDE_M, 3)
        body["foot_distance"] = _r(rng, *WALK_FOOT_DISTANCE_M, 3)
    return body


def behavior_params(rng: random.Random, name: str, schema: Sequence[Mapping[str, Any]],
                    catalogue: Mapping[str, Sequence[Mapping[str, Any]]]) -> dict[str, Any]:
    """Random valid parameters of `name`: each drawn inside its schema (narrowed by SCENE_BEHAVIORS)."""
    if name == "sequence":
        names = sorted(n for n in SCENE_BEHAVIORS if n != "sequence" and n in catalogue)
        steps = []
        for _ in range(rng.randint(*SEQUENCE_STEPS)):
            step = rng.choice(names)
            steps.append({"behavior": step, "params": behavior_params(rng, step, catalogue[step], catalogue)})
        return {"steps": steps}
    narrow = SCENE_BEHAVIORS.get(name, {})
    params: dict[str, Any] = {}
    for p in schema:
        key = p["name"]
        if key in FIXED_PARAMS.get(name, {}):
            params[key] = FIXED_PARAMS[name][key]
        elif p.get("choices"):
            params[key] = rng.choice(list(p["choices"]))
        elif p["type"] == "boolean":
            params[key] = rng.random() < 0.5
        elif p["type"] in ("number", "integer") and p.get("min") is not None and p.get("max") is not None:
            low, high = narrow.get(key, (p["min"], p["max"]))
            low, high = max(low, p["min"]), min(high, p["max"])
            params[key] = rng.randint(math.ceil(low), math.floor(high)) if p["type"] == "integer" \
                else _r(rng, low, high)
    return params


def draw_action(rng: random.Random, at_s: float, catalogue: Mapping[str, Sequence[Mapping[str, Any]]]) -> Action:
    kinds = list(PROBABILITIES)
    kind = rng.choices(kinds, weights=[PROBABILITIES[k] for k in kinds])[0]
    p: dict[str, Any] = {}
    if kind in ("stick", "closed_tab", "compete"):
        point = rng.choice(STREAM_POINTS)
        p = {"body": stick_body(rng, point), "duration_s": _r(rng, *STREAM_S, 2)}
    elif kind == "go_velocity":
        vx, vy, vth = GO_VELOCITY
        p = {"vx": _signed(rng, vx), "vy": _signed(rng, vy), "vtheta_deg": _signed(rng, vth, 2)}
    elif kind == "go_pos":
        x, y, th = GO_POS
        p = {"x": _signed(rng, x), "y": _signed(rng, y), "theta_deg": _signed(rng, th, 2)}
    elif kind == "behavior":
        names = sorted(n for n in SCENE_BEHAVIORS if n in catalogue)
        name = rng.choice(names)
        p = {"name": name, "params": behavior_params(rng, name, catalogue[name], catalogue)}
    elif kind in ("push", "push_beyond"):
        # a fraction of the envelope the robot is in when the push is sent (standing or walking), a direction
        factor = _r(rng, 0.2, 1.0, 3) if kind == "push" else _r(rng, *PUSH_BEYOND_FACTOR, 3)
        p = {"envelope_fraction": factor, "direction_deg": _r(rng, -180.0, 180.0, 1)}
    elif kind == "params":
        path, field, low, high = rng.choice(SAFE_PARAMS)
        p = {"path": path, "field": field, "value": _r(rng, low, high, 3)}
    elif kind in ("watch", "take_lock"):
        p = {"duration_s": _r(rng, *STREAM_S, 2)}
    return Action(round(at_s, 3), kind, p)


def actions_for(seed: int, seconds: float, catalogue: Mapping[str, Sequence[Mapping[str, Any]]]) -> list[Action]:
    """The action list of session `seed` lasting `seconds` [s] simulated; the same arguments, the same list.
    `catalogue`: {behaviour: its params schema} as GET /api/behaviors gives them."""
    rng = random.Random(seed)
    actions, t = [], 0.0
    while True:
        t += min(max(rng.expovariate(1.0 / GAP_MEAN_S), GAP_RANGE_S[0]), GAP_RANGE_S[1])
        if t >= seconds:
            return actions
        actions.append(draw_action(rng, t, catalogue))


def catalogue_of(behaviors: Sequence[Mapping[str, Any]]) -> dict[str, list[Mapping[str, Any]]]:
    """{name: params schema} from GET /api/behaviors' answer."""
    return {b["name"]: list(b["params"]) for b in behaviors}


def push_request(action: Action, walking: bool, frozen: bool = False,
                 foot: bool = False) -> tuple[dict[str, Any], float, float]:
    """The POST /api/sim/push body of a push action given whether the robot walks, whether a foot is operated and
    whether the hard e-stop holds it frozen: (body, impulse [N s], envelope [N s] the fall invariant holds it to)."""
    drawn = PUSH_ENVELOPE_NS["walking" if walking else "foot" if foot else "standing"]
    impulse = drawn * float(action.params["envelope_fraction"])
    envelope = PUSH_ENVELOPE_NS["frozen"] if frozen else drawn
    force = impulse / PUSH_DURATION_S
    a = math.radians(float(action.params["direction_deg"]))
    body = {"body": "BODY", "force": [round(force * math.cos(a), 3), round(force * math.sin(a), 3), 0.0],
            "duration": PUSH_DURATION_S}
    return body, impulse, envelope
