"""Session inputs as tagged JSON: every verb rebuilds equal through its own class (floats exact, tuples, lists
and dicts kept apart), a function or an unknown class is refused, a tampered field meets the class's own check,
and the setpoints the recorder packs as numbers come back as the Setpoints they were."""

import json
import math

import numpy as np
import pytest

from app.service import verbs as v
from app.service.setpoints import Setpoint, SetpointAck
from app.session.inputs import (
    SETPOINT_POINTS,
    BadInput,
    Unencodable,
    decode,
    encode,
    setpoint_inputs,
    setpoint_row,
)
from controller.operation.points import POINTS
from controller.walking.footsteps import StepParams

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

VERBS = [
    v.GoPos(0.3, -0.1, 0.1 / 3),
    v.SetFootsteps((v.Footstep("rleg", (0.0, -0.1, 0.0)), v.Footstep("lleg", (0.2, 0.1, 0.0), (0.0, 0.0, 0.1))),
                   StepParams(step_time_s=1.2)),
    v.SetParams((("st", (("k1", -1.5), ("emergency_mode", "cp_error"))),)),
    v.RunBehavior("sequence", (("steps", [{"behavior": "squat", "params": {"depth_m": 0.1}}]),)),
    v.SetOperatorVelocity(Setpoint("rhand", (0.01, 0.0, 1e-17), (0.0, 0.0, -0.0), seq=7)),
    v.ReleaseEstop(12),
    v.Reset(None),
    v.EnableLayers((("st", False),)),
]


@pytest.mark.parametrize("verb", VERBS, ids=lambda verb: type(verb).__name__)
def test_a_verb_rebuilds_equal_from_its_json(verb):
    again = decode(json.loads(json.dumps(encode(verb))))
    assert again == verb and type(again) is type(verb)


def test_lists_dicts_and_tuples_stay_what_they_were():
    value = ([1, (2.5, "x")], {"a": [None, True]})
    assert decode(json.loads(json.dumps(encode(value)))) == value


def test_a_function_or_an_unknown_class_is_refused():
    with pytest.raises(Unencodable):
        encode(v.Call(lambda host: None))
    with pytest.raises(BadInput, match="unknown class 'os.system'"):
        decode({"$type": "os.system", "fields": {}})


def test_a_tampered_field_meets_the_classes_own_check():
    doc = encode(v.GoPos(0.3, 0.0, 0.0))
    doc["fields"]["x_m"] = 50.0
    with pytest.raises(BadInput, match="x"):
        decode(doc)


def test_setpoints_packed_as_numbers_come_back_as_they_were():
    assert SETPOINT_POINTS == POINTS
    sps = [Setpoint("walk", (0.1, 0.0, 0.0), (0.0, 0.0, math.radians(5.0)), 0.2, None, 41),
           Setpoint("head", (0.0, 0.0, 0.0), (0.0, 0.1, 0.0), None, None, 42)]
    rows = np.array([setpoint_row(7, 100, "hook", 0.505, sps[0], None),
                     setpoint_row(7, 100, "hook", 0.505, sps[1], "hard_stop"),
                     setpoint_row(9, 101, "boundary", 0.51, sps[1], None)])
    (o1, t1, m1), (o2, t2, m2) = setpoint_inputs(rows)
    assert (o1, t1, o2, t2) == (7, 100, 9, 101)
    assert m1["phase"] == "hook" and m1["time_s"] == 0.505
    assert list(decode(json.loads(json.dumps(m1["input"])))) == sps
    assert m1["outcome"]["acks"] == [["walk", 41, None], ["head", 42, "hard_stop"]]
    assert SetpointAck("head", 42, 100, 0.505, "hard_stop").ignored == m1["outcome"]["acks"][1][2]


def test_a_parameter_change_recorded_before_the_nested_emergency_step_replays_as_the_nested_fields():
    from controller.layers.auto_balancer import AutoBalancerParams

    recorded = {"$type": "SetParams", "fields": {"changes": [
        ["abc", [["emergency_step", False], ["emergency_step_time_s", 0.5], ["step_time_s", 0.8]]]]}}

    class Host:
        def __init__(self):
            self.set = {}

        def params(self, owner):
            return AutoBalancerParams()

        def set_params(self, owner, params):
            self.set[owner] = params

    host = Host()
    decode(json.loads(json.dumps(recorded))).run(host)
    p = host.set["abc"]
    assert (p.emergency_step.enabled, p.emergency_step.step_time_s, p.step_time_s) == (False, 0.5, 0.8)
