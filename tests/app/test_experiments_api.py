"""The experiments over HTTP: the list, errors for unknown names and variants, one real run in a fresh
simulation while the live control loop keeps running."""

import csv
import io
import math
import time

import pytest

from app.console.routers import experiments as experiments_router
from app.lab import experiments

RESULT_FIELDS = {"verdict", "flag_time_s", "peak_cp_error_m", "cp_error_at_flag_m", "edge_margin_at_flag_m",
                 "min_edge_margin_m", "below_threshold_after_revert_s", "duration_s", "outcome"}


def test_the_list_gives_every_registered_experiment_with_description_and_variants(client):
    r = client.get("/api/experiments")
    assert r.status_code == 200, r.text
    listed = {e["name"]: e for e in r.json()["experiments"]}
    assert list(listed) == list(experiments.EXPERIMENTS)
    for name, exp in experiments.EXPERIMENTS.items():
        e = listed[name]
        assert e["variants"] == list(exp.variants) and e["scene"] == exp.scene
        assert e["description"] and e["duration_s"] == exp.duration_s


def test_the_list_follows_the_registry(client, monkeypatch):
    name, exp = next(iter(experiments.EXPERIMENTS.items()))
    monkeypatch.setitem(experiments.EXPERIMENTS, "api-test-extra", exp)
    names = [e["name"] for e in client.get("/api/experiments").json()["experiments"]]
    assert "api-test-extra" in names and name in names


def test_an_unknown_experiment_is_a_404_listing_the_valid_names(client):
    r = client.post("/api/experiments/no-such-experiment")
    assert r.status_code == 404
    detail = r.json()["detail"]
    assert "no-such-experiment" in detail and all(n in detail for n in experiments.EXPERIMENTS)


def test_an_unknown_variant_is_a_422_listing_the_valid_ones(client):
    name, exp = next(iter(experiments.EXPERIMENTS.items()))
    r = client.post(f"/api/experiments/{name}", json={"variant": "no-such-variant"})
    assert r.status_code == 422
    body = r.json()
    assert body["field"] == "variant"
    assert "no-such-variant" in body["detail"] and all(v in body["detail"] for v in exp.variants)


@pytest.mark.parametrize(("body", "word"), [({"es": "maybe"}, "es"), ({"bogus": 1}, "bogus"),
                                            ({"variant": 3}, "variant")])
def test_a_bad_body_is_a_422_naming_the_field(client, body, word):
    name = next(iter(experiments.EXPERIMENTS))
    r = client.post(f"/api/experiments/{name}", json=body)
    assert r.status_code == 422 and word in r.json()["detail"], r.text


@pytest.mark.parametrize(("params", "words"), [
    ({"cp_threshold_m": 0.9}, ["params.cp_threshold_m", "[0.001, 0.5] m"]),
    ({"t1": -1}, ["params.t1", "[0, 10] s"]),
    ({"mode": "panic"}, ["params.mode", "cp_error", "cp_support", "none"]),
    ({"t1_s": 1.0}, ["params.t1_s", "t1", "t2", "recover_time", "cp_threshold_m", "mode"]),
    ({"t2": "later"}, ["params.t2", "number"]),
    ({}, ["params", "at least one", "t1", "cp_threshold_m"]),
])
def test_bad_run_params_are_a_422_naming_the_field_and_range(client, params, words):
    name = next(iter(experiments.EXPERIMENTS))
    r = client.post(f"/api/experiments/{name}", json={"params": params})
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    for w in words:
        assert w in detail, f"{w!r} not in {detail!r}"


def test_a_second_run_while_one_runs_is_a_conflict(client):
    name = next(iter(experiments.EXPERIMENTS))
    runner = client.app.fastapi.state.experiments = experiments_router.ExperimentRunner()
    assert runner._lock.acquire(blocking=False)  # as a run in progress holds it
    try:
        r = client.post(f"/api/experiments/{name}")
        assert r.status_code == 409 and "running" in r.json()["detail"]
    finally:
        runner._lock.release()


def test_the_experiment_endpoints_are_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert "get" in paths["/api/experiments"] and "post" in paths["/api/experiments/{name}"]


@pytest.mark.slow
def test_a_real_run_in_a_fresh_simulation_while_the_live_loop_keeps_ticking(client, runtime, tmp_path):
    # the shortest registered experiment, whichever that is now
    name, exp = min(experiments.EXPERIMENTS.items(), key=lambda kv: kv[1].duration_s)
    runtime.loop.start(1.0)  # the live simulation, in real time
    time.sleep(0.3)
    scene, tick0, wall0 = runtime.scene, runtime.loop.snapshot.tick, time.perf_counter()
    live_params = client.get("/api/emergency-stopper/params").json()["params"]
    r = client.post(f"/api/experiments/{name}", json={"save": True, "params": {"cp_threshold_m": 0.05}})
    wall = time.perf_counter() - wall0
    assert r.status_code == 200, r.text
    body = r.json()
    assert RESULT_FIELDS <= set(body)
    assert body["name"] == name and body["variant"] == exp.variants[0] and body["es"] is True
    assert body["verdict"] in ("stood", "fell")
    assert 0.0 < body["duration_s"] <= exp.duration_s + 0.01
    if body["verdict"] == "stood":
        assert body["duration_s"] == pytest.approx(exp.duration_s, abs=0.02)
    assert body["peak_cp_error_m"] > 0.0 and math.isfinite(body["min_edge_margin_m"])
    if body["flag_time_s"] is not None:
        assert 0.0 <= body["flag_time_s"] <= body["duration_s"]
        assert body["cp_error_at_flag_m"] > 0.0 and isinstance(body["edge_margin_at_flag_m"], float)
    else:
        assert body["cp_error_at_flag_m"] is None and body["edge_margin_at_flag_m"] is None
    assert isinstance(body["outcome"], dict)
    assert body["faults"] == []  # the run's own fault counter
    # the files are the console's, downloadable; no path of the server is given away
    assert "csv_path" not in body and "png_path" not in body
    png = client.get(body["png_url"])
    assert png.status_code == 200 and png.headers["content-type"] == "image/png" and png.content[:4] == b"\x89PNG"
    csv_text = client.get(body["csv_url"])
    assert csv_text.status_code == 200 and csv_text.headers["content-type"].startswith("text/csv")
    # the run used the threshold asked for; the live robot kept its parameters
    assert body["params"] == {**live_params, "cp_threshold_m": 0.05, "threshold": 0.05}  # (threshold: deprecated alias)
    rows = list(csv.DictReader(io.StringIO(csv_text.text)))
    assert rows and {float(row["threshold_m"]) for row in rows} == {0.05}
    assert client.get("/api/emergency-stopper/params").json()["params"] == live_params
    # the live simulation was neither used nor stalled: same scene, still ticking, still standing
    ticks = runtime.loop.snapshot.tick - tick0
    assert runtime.scene == scene and runtime.running
    assert ticks > 0.2 * wall / runtime.loop.dt_control_s, f"{ticks} live ticks in {wall:.1f} s"
    assert not runtime.host.observation.fallen
    print(f"\n{name}: {body['verdict']}, {body['wall_time_s']:.1f} s for the run; "
          f"live loop {ticks} ticks in {wall:.1f} s ({ticks * runtime.loop.dt_control_s / wall:.2f} x real time)")
    assert client.get(f"/api/experiments/runs/{body['run_id'] + 1}/csv").status_code == 404


@pytest.mark.slow
@pytest.mark.in_process  # a TestClient on a robot stepped by the test: on make test's parallel pass (67 s of CPU)
def test_thirty_runs_leave_the_console_no_bigger_and_no_folder_behind(client, tmp_path, monkeypatch):
    import glob
    import tempfile

    # the runs' temp folders in a directory of this test's own (other programs' runs may share /tmp)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(tempfile, "tempdir", None)

    def rss_mb() -> float:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * 4096 / 2**20

    pattern = f"{tempfile.gettempdir()}/hrp2-*"
    assert pattern.startswith(str(tmp_path))
    folders = set(glob.glob(pattern))
    body = {"save": True, "duration_s": 0.5}
    first = client.post("/api/experiments/wall-push-left", json=body)
    assert first.status_code == 200, first.text
    after_first = rss_mb()
    for _ in range(29):
        r = client.post("/api/experiments/wall-push-left", json=body)
        assert r.status_code == 200, r.text
        assert client.get(r.json()["png_url"]).status_code == 200
    growth = rss_mb() - after_first
    print(f"\nconsole memory after the first of 30 runs: {after_first:.0f} MB, growth over 29 more: {growth:.1f} MB")
    assert growth < 20.0
    assert set(glob.glob(pattern)) == folders  # every run's folder went with its worker
    kept = client.app.fastapi.state.experiments.results
    assert len(kept) == experiments_router.KEEP_RESULTS


def test_the_run_params_schema_is_the_emergency_stopper_changes_schema(client):
    """Not a free object: names, types and ranges as PUT /api/emergency-stopper/params declares them."""
    doc = client.get("/openapi.json").json()
    op = doc["paths"]["/api/experiments/{name}"]["post"]
    ref = op["requestBody"]["content"]["application/json"]["schema"]
    name = (ref.get("$ref") or next(s["$ref"] for s in ref["anyOf"] if "$ref" in s)).rsplit("/", 1)[1]
    params = doc["components"]["schemas"][name]["properties"]["params"]
    es = next(s for s in params["anyOf"] if s.get("type") == "object")
    put = doc["paths"]["/api/emergency-stopper/params"]["put"]["requestBody"]["content"]["application/json"]
    assert es == {k: v for k, v in put["schema"].items() if k != "description"}
    assert es["additionalProperties"] is False and es["properties"]["cp_threshold_m"]["maximum"] == 0.5
