"""Faults: a layer that raises and a physics blow-up (a NaN in MuJoCo's state) both end in the hard stop,
are reported in /api/state, and POST /api/sim/reset recovers them, in the console's process and in the
robot's own process (the same process afterwards: no restart)."""

from __future__ import annotations

import time

import pytest
from fastapi.testclient import TestClient

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.process import RobotConfig, RobotProcess
from app.service.verbs import InjectFault

STANDING_Z_M = (0.55, 0.75)  # [m] BODY height of the standing robot (home pose: 0.648 m; a fallen one < 0.3)


def _emergency(client) -> dict:
    return client.get("/api/state").json()["emergency"]


def _standing(client) -> bool:
    state = client.get("/api/state").json()
    return not state["fallen"] and STANDING_Z_M[0] < state["base"]["pos"][2] < STANDING_Z_M[1]


def test_a_layer_exception_engages_the_hard_stop_is_reported_and_reset_recovers(client, runtime):
    runtime.run_for(0.2)
    runtime.host.inject_fault("layer", "st")
    runtime.run_for(0.05)
    em = _emergency(client)
    assert em["hard_stop"] and em["hard_stop_reason"] == "fault"
    assert em["fault"] == "RuntimeError: injected fault in layer 'st'"
    # still broken: a release is followed by the same fault at the next tick
    runtime.run_for(0.5)
    assert _emergency(client)["hard_stop"] and _standing(client)  # held where it was
    r = client.post("/api/sim/reset")
    assert r.status_code == 200, r.text
    runtime.run_for(1.0)
    em = _emergency(client)
    assert not em["hard_stop"] and em["fault"] is None
    assert _standing(client)


def test_a_nan_in_the_physics_engages_the_hard_stop_halts_the_plant_and_reset_recovers(client, runtime):
    runtime.run_for(0.2)
    runtime.host.inject_fault("nan")
    runtime.run_for(0.05)
    em = _emergency(client)
    assert em["hard_stop"] and em["hard_stop_reason"] == "fault"
    assert em["fault"].startswith("PhysicsDiverged: the simulation diverged (mjWARN_BADQVEL at t=0.200 s)")
    t = client.get("/api/state").json()["time"]
    runtime.run_for(0.5)
    assert client.get("/api/state").json()["time"] == pytest.approx(t + 0.5)  # the loop ticks on
    assert _standing(client)  # halted in the last good state, not MuJoCo's default pose
    r = client.post("/api/estop/release")
    assert r.status_code == 409 and r.json()["reason"] == "diverged" and "reset" in r.json()["detail"]
    assert client.post("/api/sim/reset").status_code == 200
    runtime.run_for(1.0)
    em = _emergency(client)
    assert not em["hard_stop"] and em["fault"] is None and _standing(client)


def test_the_fault_route_exists_only_with_the_test_hooks_and_its_fault_is_recovered_by_reset(service, runtime):
    assert "/api/sim/fault" not in create_app(Settings(), service=service).fastapi.openapi()["paths"]
    app = create_app(Settings(extra_hosts=("testserver",), test_hooks=True), service=service)
    with TestClient(app, headers={"content-type": "application/json"}) as hooked:
        runtime.run_for(0.2)
        r = hooked.post("/api/sim/fault", json={"kind": "gremlin"})
        assert r.status_code == 422 and "'layer'" in r.json()["detail"] and "'nan'" in r.json()["detail"]
        r = hooked.post("/api/sim/fault", json={"kind": "layer", "layer": "nope"})
        assert r.status_code == 404 and "st" in r.json()["detail"]
        assert not _emergency(hooked)["hard_stop"]
        r = hooked.post("/api/sim/fault", json={"kind": "layer", "layer": "abc"})
        assert r.status_code == 200, r.text
        runtime.run_for(0.05)
        em = _emergency(hooked)
        assert em["hard_stop"] and em["fault"] == "RuntimeError: injected fault in layer 'abc'"
        assert hooked.post("/api/sim/reset").status_code == 200
        runtime.run_for(0.5)
        em = _emergency(hooked)
        assert not em["hard_stop"] and em["fault"] is None and _standing(hooked)


def test_without_the_test_hooks_the_fault_route_is_not_there(client):
    assert client.post("/api/sim/fault", json={"kind": "nan"}).status_code in (404, 405)
    assert not _emergency(client)["hard_stop"]


def test_an_unknown_fault_kind_is_refused_naming_the_valid_ones(runtime):
    from app.service import InvalidArgument

    with pytest.raises(InvalidArgument, match="'layer', 'nan'"):
        runtime.host.inject_fault("gremlin")


def _wait(predicate, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        time.sleep(0.02)


@pytest.mark.slow
def test_both_faults_in_the_robot_process_are_recovered_by_reset_without_a_new_process():
    robot = RobotProcess(RobotConfig(speed=2.0))
    try:
        service = OperatorService(robot)
        pid = robot.process.pid
        app = create_app(Settings(extra_hosts=("testserver",)), service=service)
        with TestClient(app, headers={"content-type": "application/json"}) as client:
            for kind, words in (("layer", "RuntimeError: injected fault in layer 'st'"),
                                ("nan", "PhysicsDiverged: the simulation diverged (mjWARN_BADQVEL")):
                _wait(lambda: client.get("/api/state").json()["time"] > 0.3)
                service.run(InjectFault(kind))
                _wait(lambda: _emergency(client)["hard_stop"])
                em = _emergency(client)
                assert em["hard_stop_reason"] == "fault" and em["fault"].startswith(words), em
                assert client.post("/api/sim/reset").status_code == 200
                _wait(lambda: client.get("/api/state").json()["time"] > 1.0)
                em = _emergency(client)
                assert not em["hard_stop"] and em["fault"] is None and _standing(client)
                assert robot.process.pid == pid and robot.alive
    finally:
        robot.close()
