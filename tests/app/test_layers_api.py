"""Balance state in /api/state, generic layer parameter endpoints, layer start/stop."""

import re

import pytest

from controller.layers.auto_balancer import AutoBalancerParams
from controller.layers.stabilizer import StabilizerParams

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def step(runtime, seconds):
    return runtime.system.loop.run_for(seconds)


def test_state_has_walking_support_capture_point_and_the_emergency_flag(client, runtime):
    step(runtime, 0.05)
    s = client.get("/api/state").json()
    assert s["walking"] is False
    assert s["support"] in ("rleg", "lleg", "both") and s["support"] == "both"
    cp = s["capture_point"]
    assert set(cp) == {"ref", "act", "error", "error_norm", "cp_threshold_m", "threshold",  # threshold: deprecated
                       "support_edge_m"}
    # standing still, the capture point sits inside the two soles: the support edge is positive, under a sole's size
    assert cp["support_edge_m"] is not None and 0.0 < cp["support_edge_m"] < 0.2
    for key in ("ref", "act", "error"):
        assert len(cp[key]) == 2 and all(isinstance(v, float) for v in cp[key])
    assert isinstance(cp["error_norm"], float) and cp["error_norm"] >= 0.0
    assert cp["error_norm"] == pytest.approx(abs(complex(*cp["error"])), abs=1e-5)
    assert cp["cp_threshold_m"] == pytest.approx(StabilizerParams().cp_threshold_m)
    st = runtime.loop.snapshot.layers["st"]
    assert cp["error"] == pytest.approx(st.cp_error, abs=1e-6)
    assert s["emergency"]["flag"] is bool(st.emergency)
    rise = s["emergency"]["flag_rose_at"]
    assert rise is None or isinstance(rise, float)


@pytest.mark.parametrize(("segment", "cls"), [("auto-balancer", AutoBalancerParams),
                                              ("stabilizer", StabilizerParams)])
def test_get_params_gives_values_and_the_schema_declared_by_the_controller(client, segment, cls):
    r = client.get(f"/api/{segment}/params")
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["params"] == cls().to_dict()
    assert [f["name"] for f in body["schema"]] == [f["name"] for f in cls.describe()]
    for f in body["schema"]:
        assert "default" in f


def test_put_stabilizer_params_roundtrip_and_is_applied_to_the_layer(client, runtime):
    r = client.put("/api/stabilizer/params", json={"cp_threshold_m": 0.06})
    assert r.status_code == 200, r.text
    assert r.json()["params"]["cp_threshold_m"] == 0.06
    assert client.get("/api/stabilizer/params").json()["params"]["cp_threshold_m"] == 0.06
    assert runtime.loop.chain["st"].params.cp_threshold_m == 0.06
    step(runtime, 0.01)
    assert client.get("/api/state").json()["capture_point"]["cp_threshold_m"] == pytest.approx(0.06)
    # an integer is accepted for a float field and stored as a float
    r = client.put("/api/auto-balancer/params", json={"transition_time_s": 3})
    assert r.status_code == 200, r.text
    assert runtime.loop.chain["abc"].params.transition_time_s == 3.0


PARAM_ERRORS = [
    ("stabilizer", {"cp_threshold_m": -1}, ["cp_threshold_m", "0.001", "0.5"]),
    ("stabilizer", {"bogus": 1}, ["bogus", "cp_threshold_m", "k1", "emergency_mode"]),
    ("stabilizer", {"emergency_mode": "panic"}, ["emergency_mode", "cp_error", "cp_support", "none"]),
    ("stabilizer", {"cp_threshold_m": "wide"}, ["cp_threshold_m", "number"]),
    ("stabilizer", {"estop_while_walking": 1}, ["estop_while_walking", "true or false"]),
    ("stabilizer", {}, ["cp_threshold_m", "at least one"]),
    ("auto-balancer", {"transition_time_s": 20.0}, ["transition_time_s", "[0.01, 10] s"]),
    ("auto-balancer", {"nope": 0}, ["nope", "transition_time_s", "preview_q"]),
    ("auto-balancer", {"step_time_s": 0.1}, ["step_time_s", "[0.4, 5] s"]),
    ("auto-balancer", {"step_height_m": 0.5}, ["step_height_m", "[0, 0.2] m"]),
    ("auto-balancer", {"stride_fwd_x_m": -0.1}, ["stride_fwd_x_m", "[0, 0.4] m"]),
    ("auto-balancer", {"stride_inside_th_rad": 2.0}, ["stride_inside_th_rad", "[0, 0.8] rad"]),
    ("auto-balancer", {"double_support_ratio_before": 0.5}, ["double_support_ratio_before", "[0, 0.45]"]),
    ("auto-balancer", {"toe_angle_rad": "steep"}, ["toe_angle_rad", "number"]),
    ("auto-balancer", {"foot_distance_m": 0.1}, ["foot_distance_m", "[0.14, 0.3] m"]),
    ("auto-balancer", {"emergency_step": {"step_time_s": 3.0}}, ["emergency_step.step_time_s", "[0.2, 1.5] s"]),
    ("auto-balancer", {"emergency_step.step_time_s": 3.0}, ["emergency_step.step_time_s", "[0.2, 1.5] s"]),
    ("auto-balancer", {"emergency_step": {"bogus": 1}}, ["emergency_step.bogus", "max_forward_m"]),
    ("auto-balancer", {"emergency_step": 0.3}, ["emergency_step", "EmergencyStepParams"]),
    ("auto-balancer", {"emergency_step": {"min_width_m": 0.3, "max_width_m": 0.2}},
     ["emergency_step", "min_width_m", "lateral range"]),
]


@pytest.mark.parametrize(("segment", "body", "words"), PARAM_ERRORS)
def test_bad_params_get_a_422_naming_the_field_and_change_nothing(client, runtime, segment, body, words):
    before = client.get(f"/api/{segment}/params").json()["params"]
    r = client.put(f"/api/{segment}/params", json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    for w in words:
        assert w in detail, f"{w!r} not in {detail!r}"
    assert client.get(f"/api/{segment}/params").json()["params"] == before


def test_non_finite_param_values_are_rejected(client):
    r = client.put("/api/stabilizer/params", content='{"cp_threshold_m": NaN}',
                   headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and "cp_threshold_m" in r.json()["detail"]


def test_stabilizer_stop_then_start_and_double_stop_is_a_conflict(client, runtime):
    st = runtime.loop.chain["st"]
    assert st.active
    r = client.post("/api/stabilizer/stop")
    assert r.status_code == 200, r.text
    assert not st.active
    r = client.post("/api/stabilizer/stop")
    assert r.status_code == 409 and "not running" in r.json()["detail"]
    step(runtime, 0.05)
    assert client.post("/api/stabilizer/start").status_code == 200
    assert st.active
    r = client.post("/api/stabilizer/start")
    assert r.status_code == 409 and "already" in r.json()["detail"]
    step(runtime, 0.05)
    assert runtime.loop.snapshot.fault is None


def test_auto_balancer_stop_then_start_and_double_stop_is_a_conflict(client, runtime):
    abc = runtime.loop.chain["abc"]
    assert client.post("/api/auto-balancer/stop").status_code == 200 and not abc.active
    r = client.post("/api/auto-balancer/stop")
    assert r.status_code == 409 and "not active" in r.json()["detail"]
    assert client.post("/api/auto-balancer/start").status_code == 200 and abc.active
    assert client.post("/api/auto-balancer/start").status_code == 409


def test_the_auto_balancer_does_not_stop_while_walking_nor_away_from_its_references_place(client, runtime):
    """Stopped, the AutoBalancer hands on its input reference, whose BODY stands where the robot started: after a
    0.3 m walk the Stabilizer then balanced the robot toward that place and it fell (found from the page). So the
    stop is refused while walking and away from that place, saying why; back there it is allowed."""
    runtime.loop.run_for(2.5)  # blended in
    assert client.post("/api/walk/go-pos", json={"x": 0.3, "y": 0.0, "theta_deg": 0.0}).status_code == 200
    runtime.loop.run_for(0.5)
    r = client.post("/api/auto-balancer/stop")
    assert r.status_code == 409 and "while walking" in r.json()["detail"]
    runtime.loop.run_for(5.0)
    assert not runtime.loop.chain["abc"].gait.walking
    r = client.post("/api/auto-balancer/stop")
    assert r.status_code == 409, r.text
    assert re.match(r"AutoBalancer cannot stop 0\.(29|30)\d m and 0\.0 deg away", r.json()["detail"]), r.text
    assert "reset" in r.json()["detail"]
    assert runtime.loop.chain["abc"].active
    assert client.post("/api/walk/go-pos", json={"x": -0.3, "y": 0.0, "theta_deg": 0.0}).status_code == 200
    runtime.loop.run_for(1.0)
    while runtime.loop.chain["abc"].gait.walking:  # backward strides are shorter
        runtime.loop.run_for(0.5)
    runtime.loop.run_for(1.0)
    r = client.post("/api/auto-balancer/stop")
    assert r.status_code == 200, r.text
    runtime.loop.run_for(3.0)
    assert not client.get("/api/state").json()["fallen"]


def test_the_emergency_step_is_one_nested_object_in_the_values_the_schema_and_a_change(client, runtime):
    body = client.get("/api/auto-balancer/params").json()
    assert body["params"]["emergency_step"]["step_time_s"] == 0.3 and body["params"]["emergency_step"]["enabled"]
    (declared,) = [f for f in body["schema"] if f["name"] == "emergency_step"]
    inner = {f["name"]: f for f in declared["params"]}
    assert (inner["step_time_s"]["unit"], inner["step_time_s"]["min"], inner["step_time_s"]["max"]) == ("s", 0.2, 1.5)
    put = client.get("/openapi.json").json()["paths"]["/api/auto-balancer/params"]["put"]
    body_schema = put["requestBody"]["content"]["application/json"]["schema"]
    nested, switch = body_schema["properties"]["emergency_step"]["anyOf"]
    assert nested["type"] == "object" and not nested["additionalProperties"]
    assert switch["type"] == "boolean"  # the switch alone, as parameter documents of before the nesting give it
    assert (nested["properties"]["max_width_m"]["minimum"], nested["properties"]["max_width_m"]["maximum"]) == (
        0.16, 0.7)
    r = client.put("/api/auto-balancer/params", json={"emergency_step": {"step_time_s": 0.4, "enabled": False}})
    assert r.status_code == 200, r.text
    es = runtime.loop.chain["abc"].params.emergency_step
    assert (es.step_time_s, es.enabled, es.max_forward_m) == (0.4, False, 0.55)  # the others kept
    r = client.put("/api/auto-balancer/params", json={"emergency_step": True})
    assert r.status_code == 200, r.text
    assert runtime.loop.chain["abc"].params.emergency_step.enabled
    assert runtime.loop.chain["abc"].params.emergency_step.step_time_s == 0.4


def test_the_layer_endpoints_are_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    for segment in ("auto-balancer", "stabilizer"):
        assert {"get", "put"} <= set(paths[f"/api/{segment}/params"])
        assert "post" in paths[f"/api/{segment}/start"] and "post" in paths[f"/api/{segment}/stop"]


GAIT_PARAMS = {"step_time_s": 0.8, "step_height_m": 0.07, "toe_angle_rad": 0.1, "heel_angle_rad": 0.05,
               "double_support_ratio_before": 0.15, "double_support_ratio_after": 0.15, "stride_fwd_x_m": 0.1,
               "stride_bwd_x_m": 0.04, "stride_outside_y_m": 0.04, "stride_inside_y_m": 0.02,
               "stride_outside_th_rad": 0.1, "stride_inside_th_rad": 0.05, "foot_distance_m": 0.21}


def test_the_gait_parameters_are_in_the_schema_with_units_and_ranges(client):
    schema = {f["name"]: f for f in client.get("/api/auto-balancer/params").json()["schema"]}
    for name in GAIT_PARAMS:
        f = schema[name]
        assert f["unit"] in ("s", "m", "rad", "-") and f["min"] < f["max"], f
    assert schema["step_time_s"]["unit"] == "s" and schema["stride_fwd_x_m"]["unit"] == "m"


def test_put_gait_parameters_applies_them_to_the_next_footsteps_planned(client, runtime):
    step(runtime, 2.5)  # the AutoBalancer blended in
    r = client.put("/api/auto-balancer/params", json=GAIT_PARAMS)
    assert r.status_code == 200, r.text
    assert {k: r.json()["params"][k] for k in GAIT_PARAMS} == GAIT_PARAMS
    gait = runtime.loop.chain["abc"].gait
    assert gait.params.double_support_ratio_before == 0.15
    assert client.post("/api/walk/go-pos", json={"x": 0.3, "y": 0.0, "theta_deg": 0.0}).status_code == 200
    steps = client.get("/api/walk/footsteps").json()["footsteps"]
    assert [round(f["pos"][0] - steps[0]["pos"][0], 6) for f in steps[1:3]] == [0.1, 0.2]  # 0.1 m strides
    for f in steps[1:]:
        assert f["step_time_s"] == pytest.approx(0.8) and f["step_height_m"] == pytest.approx(0.07)
    assert abs(steps[-1]["pos"][1] - steps[-2]["pos"][1]) == pytest.approx(0.21)
    # a step time between two control ticks is rounded to a whole number of them (5 ms)
    assert client.put("/api/auto-balancer/params", json={"step_time_s": 0.8012}).status_code == 200
    assert runtime.loop.chain["abc"].gait.footstep_params.step_time_s == pytest.approx(0.8)
