"""GET /api/places and /api/places/{name}: what the robot knows by name in the current scene, a located object
added, an unknown name a 404 listing the valid ones; look_at's x_m, y_m, z_m say a place may give them."""

import pytest

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_the_default_scene_has_no_named_place_and_says_so(client):
    assert client.get("/api/places").json() == {"places": {}, "aliases": {}}
    r = client.get("/api/places/table")
    assert r.status_code == 404 and r.json()["detail"].startswith("unknown place 'table'; valid: none")


def test_the_expo_scene_knows_the_table_and_the_box_and_a_located_can_joins_them(client, runtime):
    assert client.post("/api/sim/reset", json={"scene": "expo"}).status_code == 200
    doc = client.get("/api/places").json()
    assert set(doc["places"]) == {"table", "trash_box"} and doc["aliases"] == {"box": "trash_box"}
    assert client.get("/api/places/table").json() == {"name": "table", "position_m": pytest.approx([2.15, 0.0, 0.75]),
                                                      "source": "known"}
    assert client.get("/api/places/box").json()["name"] == "trash_box"
    runtime.host.recognitions["can"] = {"object": "can", "position_m": [2.2, 0.1, 0.7325], "sigma_m": [0.0, 0.0, 0.0]}
    runtime.step()
    can = client.get("/api/places/can").json()
    assert can["position_m"] == pytest.approx([2.2, 0.1, 0.7325]) and can["source"] == "estimated"
    r = client.get("/api/places/sofa")
    assert r.status_code == 404 and r.json()["detail"] == "unknown place 'sofa'; valid: table, trash_box, can, box"


def test_look_at_says_which_parameters_a_place_gives(client):
    look_at = next(b for b in client.get("/api/behaviors").json() if b["name"] == "look_at")
    assert {p["name"]: p.get("place") for p in look_at["params"]} == {
        "x_m": "x", "y_m": "y", "z_m": "z", "rate_deg_s": None, "tolerance_deg": None}
