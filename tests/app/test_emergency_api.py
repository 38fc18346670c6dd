"""EmergencyStopper parameters (one view over the EmergencyStopper's and the Stabilizer's params) and the
emergency block of /api/state: motion stop, walking stop, Stabilizer stop, when the flag rose."""

import math

import pytest

from controller.layers.emergency_stopper import EmergencyStopperParams
from controller.layers.stabilizer import EMERGENCY_MODES, StabilizerParams

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

URL = "/api/emergency-stopper/params"
WARM_UP_S = 2.5  # AutoBalancer and Stabilizer blended in
OWNERS = {"t1": ("es", "t1_s"), "t2": ("es", "t2_s"), "recover_time": ("es", "recover_time_s"),
          "cp_threshold_m": ("st", "cp_threshold_m"), "mode": ("st", "emergency_mode")}


def step(runtime, seconds):
    return runtime.system.loop.run_for(seconds)


def layer_params(runtime):
    chain = runtime.loop.chain
    return chain["es"].params, chain["st"].params


def test_get_presents_the_timing_and_the_flag_with_units_and_ranges(client, runtime):
    r = client.get(URL)
    assert r.status_code == 200, r.text
    body = r.json()
    es, st = EmergencyStopperParams(), StabilizerParams()
    assert body["params"] == {"t1": es.t1_s, "t2": es.t2_s, "recover_time": es.recover_time_s,
                              "cp_threshold_m": st.cp_threshold_m, "mode": st.emergency_mode,
                              "threshold": st.cp_threshold_m}  # the deprecated name, for one release
    schema = {f["name"]: f for f in body["schema"]}
    assert list(schema) == list(OWNERS)
    for name in ("t1", "t2", "recover_time"):
        assert schema[name]["unit"] == "s" and schema[name]["layer"] == "es"
        assert isinstance(schema[name]["min"], float) and isinstance(schema[name]["max"], float)
    assert schema["cp_threshold_m"]["unit"] == "m" and schema["cp_threshold_m"]["layer"] == "st"
    assert (schema["cp_threshold_m"]["min"], schema["cp_threshold_m"]["max"]) == (0.001, 0.5)
    assert schema["mode"]["choices"] == list(EMERGENCY_MODES)
    assert schema["t1"]["param"] == "EmergencyStopperParams.t1_s"
    assert schema["cp_threshold_m"]["default"] == st.cp_threshold_m


def test_put_reaches_both_layers_replacing_their_params_whole(client, runtime):
    es_before, st_before = layer_params(runtime)
    r = client.put(URL, json={"t1": 0.8, "t2": 1, "recover_time": 3.0, "cp_threshold_m": 0.06, "mode": "cp_support"})
    assert r.status_code == 200, r.text
    expected = {"t1": 0.8, "t2": 1.0, "recover_time": 3.0, "cp_threshold_m": 0.06, "mode": "cp_support",
                "threshold": 0.06}
    assert r.json()["params"] == expected
    assert client.get(URL).json()["params"] == expected
    es, st = layer_params(runtime)
    assert es is not es_before and st is not st_before  # new objects, not edited in place
    assert es == EmergencyStopperParams(t1_s=0.8, t2_s=1.0, recover_time_s=3.0)
    assert isinstance(es.t2_s, float)
    assert runtime.loop.chain["es"].reverter.params is es  # the revert uses the new timing
    assert (st.cp_threshold_m, st.emergency_mode) == (0.06, "cp_support")
    assert st.replaced(cp_threshold_m=st_before.cp_threshold_m, emergency_mode=st_before.emergency_mode) == st_before
    step(runtime, 0.01)
    s = client.get("/api/state").json()
    assert s["capture_point"]["cp_threshold_m"] == pytest.approx(0.06)
    assert s["layers"]["es"]["t1_s"] == pytest.approx(0.8)
    # a PUT of one layer's fields leaves the other layer's params object alone
    r = client.put(URL, json={"t1": 0.5})
    assert r.status_code == 200, r.text
    assert layer_params(runtime)[1] is st


BAD = [
    ({"t1": -0.1}, ["t1", "[0, 10] s"]),
    ({"t2": 11}, ["t2", "[0, 10] s"]),
    ({"recover_time": 31.0}, ["recover_time", "[0, 30] s"]),
    ({"cp_threshold_m": 0.0001}, ["cp_threshold_m", "[0.001, 0.5] m"]),
    ({"cp_threshold_m": 0.6}, ["cp_threshold_m", "[0.001, 0.5] m"]),
    ({"mode": "panic"}, ["mode", "cp_error", "cp_support", "none"]),
    ({"t1": "soon"}, ["t1", "number"]),
    ({"mode": 1}, ["mode", "string"]),
    ({"t1": True}, ["t1", "number"]),
    ({"bogus": 1}, ["bogus", "t1", "t2", "recover_time", "cp_threshold_m", "mode"]),
    ({"t1_s": 1.0}, ["t1_s", "t1"]),  # the layer's own name is not the API's
    ({}, ["at least one", "t1", "cp_threshold_m"]),
    ({"t1": 0.5, "cp_threshold_m": 5.0}, ["cp_threshold_m", "0.5"]),  # one bad field: nothing applied
]


@pytest.mark.parametrize(("body", "words"), BAD)
def test_bad_inputs_get_a_422_naming_the_field_and_range_and_change_nothing(client, runtime, body, words):
    before_view = client.get(URL).json()["params"]
    before = layer_params(runtime)
    r = client.put(URL, json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    for w in words:
        assert w in detail, f"{w!r} not in {detail!r}"
    after = layer_params(runtime)
    assert after[0] is before[0] and after[1] is before[1]
    assert client.get(URL).json()["params"] == before_view


def test_non_finite_values_and_non_object_bodies_are_rejected(client, runtime):
    before = layer_params(runtime)
    r = client.put(URL, content='{"t2": Infinity}', headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and "t2" in r.json()["detail"]
    r = client.put(URL, json=[1.0])
    assert r.status_code == 422
    assert layer_params(runtime) == before


def test_the_endpoint_is_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert {"get", "put"} <= set(paths[URL])


# ---- /api/state emergency block ----------------------------------------------------------------------------

def emergency(client):
    return client.get("/api/state").json()["emergency"]


def test_state_emergency_has_the_new_fields_with_their_types(client, runtime):
    step(runtime, 0.05)
    e = emergency(client)
    for key in ("hard_stop", "fault", "flag"):  # kept
        assert key in e
    for key in ("motion_stop", "walking_stop", "stabilizer_stop", "flag"):
        assert isinstance(e[key], bool), key
    assert e["flag_rose_at"] is None or isinstance(e["flag_rose_at"], float)
    assert e == {**e, "motion_stop": False, "walking_stop": False, "stabilizer_stop": False, "hard_stop": False}


def test_motion_stop_shows_in_the_state_and_release_clears_it(client, runtime):
    step(runtime, 0.05)
    assert client.post("/api/motion/stop").status_code == 200
    step(runtime, 0.02)
    e = emergency(client)
    assert e["motion_stop"] is True and e["motion_stop_reason"] == "operator"
    assert e["walking_stop"] is False and e["stabilizer_stop"] is False
    assert client.post("/api/motion/release").status_code == 200
    step(runtime, 0.02)
    assert emergency(client)["motion_stop"] is False


def test_stabilizer_stop_shows_in_the_state_and_start_clears_it(client, runtime):
    step(runtime, 0.05)
    assert client.post("/api/stabilizer/stop").status_code == 200
    step(runtime, 0.02)
    e = emergency(client)
    assert e["stabilizer_stop"] is True and e["motion_stop"] is False
    assert client.post("/api/stabilizer/start").status_code == 200
    step(runtime, 0.02)
    assert emergency(client)["stabilizer_stop"] is False


@pytest.mark.parametrize(("url", "body"), [("/api/walk/go-velocity", {"vx": 0.1, "vy": 0.0, "vtheta_deg": 0.0}),
                                         ("/api/walk/go-pos", {"x": 0.6, "y": 0.0, "theta_deg": 0.0})])
def test_emergency_walking_stop_shows_while_stopping_and_clears_when_stood_still(client, runtime, url, body):
    step(runtime, WARM_UP_S)
    assert client.post(url, json=body).status_code == 200
    step(runtime, 1.0)
    assert emergency(client)["walking_stop"] is False  # walking, not stopping
    assert client.post("/api/walk/emergency-stop").status_code == 200
    step(runtime, 0.02)
    s = client.get("/api/state").json()
    assert s["walking"] is True and s["emergency"]["walking_stop"] is True
    snap = runtime.run_until(lambda sn: not sn.layers["abc"].walking, timeout_s=8.0)
    assert not snap.fallen
    assert emergency(client)["walking_stop"] is False
    # a new walk afterwards is not shown as stopping
    assert client.post("/api/walk/go-pos", json={"x": 0.1, "y": 0.0, "theta_deg": 0.0}).status_code == 200
    step(runtime, 0.05)
    s = client.get("/api/state").json()
    assert s["walking"] is True and s["emergency"]["walking_stop"] is False


def test_flag_rose_at_is_the_simulated_time_the_flag_rose(client, runtime):
    step(runtime, WARM_UP_S)
    assert emergency(client)["flag_rose_at"] is None
    t_before = runtime.loop.snapshot.time_s
    # the smallest threshold: the flag rises on the CP error of a push (if not on the standing error already)
    assert client.put(URL, json={"cp_threshold_m": 0.001}).status_code == 200
    assert client.post("/api/sim/push", json={"body": "BODY", "force": [150.0, 0.0, 0.0],
                                              "duration": 0.1}).status_code == 200
    snap = runtime.run_until(lambda sn: sn.layers["st"].emergency, timeout_s=2.0)
    e = emergency(client)
    assert e["flag"] is True
    assert isinstance(e["flag_rose_at"], float)
    assert t_before - 1e-6 <= e["flag_rose_at"] <= snap.time_s + 1e-6
    assert math.isclose(e["flag_rose_at"], e["flag_rise_time"])
    # the flag stops the motion (the EmergencyStopper reads it one tick later)
    step(runtime, 0.02)
    e = emergency(client)
    assert e["motion_stop"] is True and e["motion_stop_reason"] == "capture_point"


def test_the_deprecated_threshold_name_still_sets_the_flag_threshold(client):
    r = client.put(URL, json={"threshold": 0.05})
    assert r.status_code == 200, r.text
    assert r.json()["params"]["cp_threshold_m"] == pytest.approx(0.05)
    r = client.put(URL, json={"threshold": 0.05, "cp_threshold_m": 0.06})
    assert r.status_code == 422 and "deprecated name of 'cp_threshold_m'" in r.text


@pytest.mark.slow
def test_after_a_fall_motion_and_the_release_answer_409_fallen_until_a_reset(client, runtime):
    # a shove no ankle and no step holds: 300 N forward on BODY for 1 s
    step(runtime, WARM_UP_S)
    r = client.post("/api/sim/push", json={"body": "BODY", "force": [300.0, 0.0, 0.0], "duration": 1.0})
    assert r.status_code == 200, r.text
    runtime.system.loop.run_until(lambda s: s.safety.fall is not None, timeout_s=3.0)
    step(runtime, 0.5)
    state = client.get("/api/state").json()
    assert state["fallen"] and state["emergency"]["hard_stop_reason"] == "fallen" and state["emergency"]["fall"]
    for method, url, body in (("POST", "/api/walk/go-pos", {"x": 0.2, "y": 0.0, "theta_deg": 0.0}),
                              ("POST", "/api/estop/release", {}),
                              ("PUT", "/api/operator/velocity", {"point": "rhand", "linear": [0.05, 0, 0]})):
        r = client.request(method, url, json=body)
        assert r.status_code == 409 and r.json()["reason"] == "fallen", (url, r.text)
    assert client.post("/api/sim/reset", json={}).status_code == 200
    step(runtime, WARM_UP_S)
    state = client.get("/api/state").json()
    assert not state["fallen"] and not state["emergency"]["hard_stop"]
    assert client.post("/api/walk/go-pos", json={"x": 0.1, "y": 0.0, "theta_deg": 0.0}).status_code == 200
