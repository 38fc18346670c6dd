"""Per-hand ImpedanceController endpoints: start / stop and their conflicts, parameters per limb, unknown limbs."""

import pytest

from controller.layers.impedance_controller import LIMBS, ImpedanceParams

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def step(runtime, seconds):
    return runtime.system.loop.run_for(seconds)


def ic(runtime):
    return runtime.loop.chain["ic"]


@pytest.mark.parametrize("limb", list(LIMBS))
def test_get_params_gives_values_and_the_declared_schema(client, limb):
    r = client.get(f"/api/impedance/{limb}/params")
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["params"] == ImpedanceParams().to_dict()
    assert [f["name"] for f in body["schema"]] == [f["name"] for f in ImpedanceParams.describe()]
    k_p = next(f for f in body["schema"] if f["name"] == "k_p")
    assert k_p["unit"] == "N/m" and k_p["min"] == 1.0 and k_p["max"] == 1e6


def test_put_params_reaches_only_that_limb(client, runtime):
    larm_before = ic(runtime).params["larm"]
    r = client.put("/api/impedance/rarm/params", json={"k_p": 800, "d_p": 150.0})
    assert r.status_code == 200, r.text
    assert r.json()["params"]["k_p"] == 800.0 and r.json()["params"]["d_p"] == 150.0
    assert client.get("/api/impedance/rarm/params").json()["params"]["k_p"] == 800.0
    new = ic(runtime).params["rarm"]
    assert new == ImpedanceParams(k_p=800.0, d_p=150.0) and isinstance(new.k_p, float)
    assert ic(runtime).params["larm"] is larm_before
    assert client.get("/api/impedance/larm/params").json()["params"] == ImpedanceParams().to_dict()


BAD = [
    ({"k_p": 0.5}, ["k_p", "[1, 1e+06] N/m"]),
    ({"m_p": 0.0}, ["m_p", "0.01"]),
    ({"transition_time_s": 11}, ["transition_time_s", "[0.01, 10] s"]),
    ({"k_p": "stiff"}, ["k_p", "number"]),
    ({"stiffness": 1.0}, ["stiffness", "k_p", "d_p", "m_p"]),
    ({}, ["at least one", "k_p"]),
]


@pytest.mark.parametrize(("body", "words"), BAD)
def test_bad_params_get_a_422_naming_the_field_and_range_and_change_nothing(client, runtime, body, words):
    before = dict(ic(runtime).params)
    r = client.put("/api/impedance/larm/params", json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    for w in words:
        assert w in detail, f"{w!r} not in {detail!r}"
    assert all(ic(runtime).params[limb] is before[limb] for limb in LIMBS)


def test_start_stop_and_their_conflicts(client, runtime):
    step(runtime, 0.05)
    r = client.post("/api/impedance/rarm/stop")
    assert r.status_code == 409 and r.json()["detail"] == "impedance control of rarm is not active"
    r = client.post("/api/impedance/rarm/start")
    assert r.status_code == 200, r.text
    assert ic(runtime).limbs["rarm"].active and not ic(runtime).limbs["larm"].active
    r = client.post("/api/impedance/rarm/start")
    assert r.status_code == 409 and r.json()["detail"] == "impedance control of rarm is already active"
    step(runtime, 0.1)
    layers = client.get("/api/state").json()["layers"]["ic"]
    assert layers["rarm"]["active"] is True and 0.0 < layers["rarm"]["weight"] < 1.0
    assert layers["larm"]["active"] is False
    assert client.post("/api/impedance/rarm/stop").status_code == 200
    assert not ic(runtime).limbs["rarm"].active
    step(runtime, 0.1)
    assert runtime.loop.snapshot.fault is None


@pytest.mark.parametrize(("method", "path"), [("get", "params"), ("put", "params"), ("post", "start"),
                                              ("post", "stop")])
def test_an_unknown_limb_is_a_404_listing_the_valid_ones(client, runtime, method, path):
    kwargs = {"json": {"k_p": 500.0}} if method == "put" else {}
    r = getattr(client, method)(f"/api/impedance/rleg/{path}", **kwargs)
    assert r.status_code == 404, r.text
    detail = r.json()["detail"]
    assert "rleg" in detail and all(limb in detail for limb in LIMBS)
    assert all(not lb.active for lb in ic(runtime).limbs.values())


def test_the_impedance_endpoints_are_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert {"get", "put"} <= set(paths["/api/impedance/{limb}/params"])
    assert "post" in paths["/api/impedance/{limb}/start"] and "post" in paths["/api/impedance/{limb}/stop"]
    limb = next(p for p in paths["/api/impedance/{limb}/start"]["post"]["parameters"] if p["name"] == "limb")
    assert limb["schema"]["enum"] == list(LIMBS)
