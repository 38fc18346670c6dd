"""HTTP API contract: state fields, e-stop, sequence commands, validation, reset, push, log, docs."""

import math

import numpy as np
import pytest

from robot.generate import half_sitting_deg
from robot.names import JOINT_NAMES, joint_index

HALF_SITTING_DEG = list(half_sitting_deg())
RARM0 = joint_index("RARM_JOINT0")


def step(runtime, seconds):
    return runtime.system.loop.run_for(seconds)


def q_cmd_deg(runtime):
    return np.rad2deg(np.array(runtime.loop.snapshot.q_cmd_rad))


def q_seq_deg(runtime):
    """The planned stream: what a command could change (the AutoBalancer keeps adjusting the legs)."""
    return np.rad2deg(np.array(runtime.loop.snapshot.q_seq_rad))


def test_state_has_every_contract_field_with_the_right_types(client, runtime):
    step(runtime, 0.05)
    s = client.get("/api/state").json()
    assert isinstance(s["time"], float) and s["time"] == pytest.approx(0.05)
    assert isinstance(s["tick"], int) and s["tick"] == 10
    assert s["fallen"] is False
    assert len(s["base"]["pos"]) == 3 and len(s["base"]["rpy_deg"]) == 3
    assert s["base"]["source"] == "simulation"
    assert 0.5 < s["base"]["pos"][2] < 0.8
    assert len(s["estimate"]["rpy_deg"]) == 3
    assert list(s["joints"]) == list(JOINT_NAMES)
    for j in s["joints"].values():
        assert set(j) == {"cmd_deg", "meas_deg", "seq_deg"}
        assert all(isinstance(v, float) for v in j.values())
    assert len(s["cog"]) == 3 and len(s["zmp"]) == 3
    assert s["emergency"]["hard_stop"] is False and s["emergency"]["fault"] is None
    assert isinstance(s["emergency"]["flag"], bool)
    assert s["emergency"]["flag_rose_at"] is None or isinstance(s["emergency"]["flag_rose_at"], float)
    assert set(s["layers"]) == set(runtime.loop.chain.order())
    assert all(isinstance(v, dict) for v in s["layers"].values())
    assert s["chain"] == runtime.loop.chain.describe() and s["chain"].startswith("kf -> ")
    assert s["speed"] is None


def test_estop_freezes_the_command_and_a_motion_requested_meanwhile_is_refused_naming_it(client, runtime):
    step(runtime, 0.05)
    assert client.post("/api/estop").status_code == 200
    step(runtime, 0.01)
    frozen = q_cmd_deg(runtime)
    planned = q_seq_deg(runtime)
    assert client.get("/api/state").json()["emergency"]["hard_stop"] is True
    r = client.post("/api/sequence/joint-angles", json={"angles_deg": {"RARM_JOINT0": -40.0}, "time": 0.5})
    assert r.status_code == 409 and r.json()["reason"] == "hard_stop" and "hard e-stop" in r.json()["detail"]
    step(runtime, 0.8)
    np.testing.assert_allclose(q_cmd_deg(runtime), frozen, atol=1e-9)
    np.testing.assert_allclose(q_seq_deg(runtime), planned, atol=1e-9)  # the plan holds too


def test_release_unfreezes_and_releasing_twice_is_a_conflict(client, runtime):
    client.post("/api/estop")
    step(runtime, 0.02)
    r = client.post("/api/estop/release")
    assert r.status_code == 200
    step(runtime, 0.02)
    assert client.get("/api/state").json()["emergency"]["hard_stop"] is False
    r = client.post("/api/estop/release")
    assert r.status_code == 409
    assert "not engaged" in r.json()["detail"]


def test_joint_angles_by_dict_move_only_the_named_joint(client, runtime):
    r = client.post("/api/sequence/joint-angles", json={"angles_deg": {"RARM_JOINT0": -20.0}, "time": 0.5})
    assert r.status_code == 200, r.text
    assert client.get("/api/sequence/status").json() == {"interpolating": True}
    step(runtime, 0.7)
    q = q_cmd_deg(runtime)
    assert q[RARM0] == pytest.approx(-20.0, abs=0.1)
    assert q[joint_index("LARM_JOINT0")] == pytest.approx(15.0, abs=0.1)
    assert client.get("/api/sequence/status").json() == {"interpolating": False}


def test_joint_angles_by_list_move_the_commanded_joints(client, runtime):
    target = list(HALF_SITTING_DEG)
    target[joint_index("LARM_JOINT0")] = -10.0
    r = client.post("/api/sequence/joint-angles", json={"angles_deg": target, "time": 0.5})
    assert r.status_code == 200, r.text
    step(runtime, 0.7)
    assert q_cmd_deg(runtime)[joint_index("LARM_JOINT0")] == pytest.approx(-10.0, abs=0.1)


def rarm_in_body(runtime, q_rad):
    """rarm_end position [m] and rpy [deg] in the BODY frame for joint angles q_rad."""
    from controller.kinematics.rotations import matrix_to_rpy

    kin = runtime.system.kin
    kin.update_rpy(np.zeros(3), np.zeros(3), np.asarray(q_rad))
    pos, R = kin.frame_pose("rarm_end")
    return np.array(pos), np.rad2deg(matrix_to_rpy(np.asarray(R)))


def test_target_pose_moves_the_hand_to_the_requested_position(client, runtime):
    pos0, rpy0 = rarm_in_body(runtime, runtime.loop.snapshot.q_cmd_rad)
    target = pos0 + np.array([0.05, 0.0, 0.03])
    r = client.post("/api/sequence/target-pose", json={"limb": "rarm", "frame": "BODY", "pos": target.tolist(),
                                                       "rpy_deg": rpy0.tolist(), "time": 0.5})
    assert r.status_code == 200, r.text
    step(runtime, 0.8)
    pos1, _ = rarm_in_body(runtime, runtime.loop.snapshot.q_cmd_rad)
    np.testing.assert_allclose(pos1, target, atol=0.01)


def test_clear_stops_the_motion_where_it_is(client, runtime):
    client.post("/api/sequence/joint-angles", json={"angles_deg": {"RARM_JOINT0": -60.0}, "time": 1.0})
    step(runtime, 0.3)
    assert client.post("/api/sequence/clear").status_code == 200
    step(runtime, 0.02)
    held = q_cmd_deg(runtime)[RARM0]
    assert client.get("/api/sequence/status").json() == {"interpolating": False}
    step(runtime, 0.5)
    assert q_cmd_deg(runtime)[RARM0] == pytest.approx(held, abs=0.05)
    # held where the minimum-jerk move from 15 to -60 deg was when cleared, 0.30-0.31 s into its 1 s
    done = [10 * t**3 - 15 * t**4 + 6 * t**5 for t in (0.30, 0.31)]
    assert 15.0 - 75.0 * done[1] - 0.05 < held < 15.0 - 75.0 * done[0] + 0.05


BAD_INPUTS = [
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINTX": 1.0}, "time": 1.0},
     ["angles_deg", "RARM_JOINTX", "RARM_JOINT0", "LARM_JOINT6"]),
    ("/api/sequence/joint-angles", {"angles_deg": [0.0] * 29, "time": 1.0}, ["angles_deg", "30", "29"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": 200.0}, "time": 1.0},
     ["RARM_JOINT0", "200", "range", "deg"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": 500.0}, "time": 1.0},
     ["RARM_JOINT0", "360"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": -10.0}, "time": 0.0},
     ["time", "greater than or equal to 0.005"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": -10.0}, "time": 5e-324},
     ["time", "greater than or equal to 0.005"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": "-30"}, "time": 1.0}, ["RARM_JOINT0", "number"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": True}, "time": 1.0}, ["RARM_JOINT0", "number"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": -10.0}, "time": "1"}, ["time", "number"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": -10.0}, "time": 4000},
     ["time", "3600"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": -10.0}}, ["time", "required"]),
    ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": "a lot"}, "time": 1.0},
     ["angles_deg", "RARM_JOINT0"]),
    ("/api/sequence/target-pose", {"limb": "tail", "pos": [0, 0, 0], "rpy_deg": [0, 0, 0], "time": 1.0},
     ["limb", "rarm", "lleg"]),
    ("/api/sequence/target-pose", {"limb": "rarm", "pos": [0, 0], "rpy_deg": [0, 0, 0], "time": 1.0},
     ["pos", "3"]),
    ("/api/sim/reset", {"scene": "mars"}, ["scene", "mars", "default"]),
    ("/api/sim/push", {"body": "BODY", "force": [3000, 0, 0], "duration": 0.1}, ["force", "1154"]),
    ("/api/sim/push", {"body": "BODY", "force": [10, 0, 0], "duration": 6}, ["duration", "5"]),
    ("/api/sim/push", {"body": "BODY", "force": [10, 0, 0], "duration": 0}, ["duration", "greater than or equal"]),
]


@pytest.mark.parametrize(("url", "body", "words"), BAD_INPUTS, ids=[f"{u.rsplit('/', 1)[-1]}-{i}"
                                                                    for i, (u, _, _) in enumerate(BAD_INPUTS)])
def test_bad_input_gets_a_422_naming_the_field_and_changes_nothing(client, runtime, url, body, words):
    step(runtime, 0.02)
    before = q_seq_deg(runtime)
    tick = runtime.loop.snapshot.tick
    r = client.post(url, json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, str)
    for w in words:
        assert w in detail, f"{w!r} not in {detail!r}"
    step(runtime, 0.3)
    assert runtime.loop.snapshot.tick == tick + 60  # no reset happened
    np.testing.assert_allclose(q_seq_deg(runtime), before, atol=1e-6)
    assert client.get("/api/sequence/status").json() == {"interpolating": False}


#: valid requests that name something that does not exist (404) or ask for what cannot be done (409)
CANNOT_BE_DONE = [
    ("/api/sequence/target-pose", {"limb": "rarm", "frame": "NOPE", "pos": [0.3, -0.2, 0.0], "rpy_deg": [0, 0, 0],
                                   "time": 1.0}, 404, ["frame", "NOPE", "BODY"]),
    ("/api/sequence/target-pose", {"limb": "rarm", "frame": "BODY", "pos": [3.0, 0.0, 0.0], "rpy_deg": [0, 0, 0],
                                   "time": 1.0}, 409, ["rarm", "cannot reach"]),
    ("/api/sim/push", {"body": "TAIL", "force": [10, 0, 0], "duration": 0.1}, 404, ["body", "TAIL", "BODY"]),
]


@pytest.mark.parametrize(("url", "body", "status", "words"), CANNOT_BE_DONE,
                         ids=["unknown-frame", "out-of-reach", "unknown-body"])
def test_a_valid_request_for_what_does_not_exist_or_cannot_be_done_says_so_and_changes_nothing(
        client, runtime, url, body, status, words):
    step(runtime, 0.02)
    before = q_seq_deg(runtime)
    r = client.post(url, json=body)
    assert r.status_code == status, r.text
    for w in words:
        assert w in r.json()["detail"]
    if status == 409:
        assert r.json()["reason"] == "reach"
    step(runtime, 0.3)
    np.testing.assert_allclose(q_seq_deg(runtime), before, atol=1e-6)


@pytest.mark.parametrize("bad", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_numbers_are_rejected_naming_the_field(client, runtime, bad):
    for url, raw, field in [
        ("/api/sequence/joint-angles", '{"angles_deg": {"RARM_JOINT0": BAD}, "time": 1}', "RARM_JOINT0"),
        ("/api/sequence/joint-angles", '{"angles_deg": {"RARM_JOINT0": 1}, "time": BAD}', "time"),
        ("/api/sequence/joint-angles", '{"angles_deg": [BAD' + ', 0' * 29 + '], "time": 1}', "angles_deg"),
        ("/api/sim/push", '{"body": "BODY", "force": [BAD, 0, 0], "duration": 0.1}', "force"),
    ]:
        raw = raw.replace("BAD", bad)
        r = client.post(url, content=raw, headers={"Content-Type": "application/json"})
        assert r.status_code == 422, (url, raw, r.text)
        assert field in r.json()["detail"] and "finite" in r.json()["detail"]
    step(runtime, 0.2)
    assert client.get("/api/sequence/status").json() == {"interpolating": False}


def test_an_error_raised_inside_the_loop_is_a_500_and_the_loop_keeps_running(client, runtime, monkeypatch):
    from fastapi.testclient import TestClient

    loop = runtime.loop

    def broken(*_args):
        raise RuntimeError("boom")

    monkeypatch.setattr(loop.chain["seq"], "clear", broken)
    app = client.app
    with TestClient(app, raise_server_exceptions=False, headers={"content-type": "application/json"}) as c:
        r = c.post("/api/sequence/clear")
    assert r.status_code == 500 and "boom" in r.json()["detail"]
    tick = loop.snapshot.tick
    step(runtime, 0.05)
    assert loop.snapshot.tick == tick + 10 and loop.snapshot.fault is None
    assert client.get("/api/health").json()["run"]["faults"] == []  # a failed verb is no controller fault


def test_health_gives_the_runs_own_counters_and_a_controller_fault_stays_in_them(client, runtime, monkeypatch):
    step(runtime, 0.05)
    run = client.get("/api/health").json()["run"]
    assert run["ticks"] == 10 and run["fallen"] is False and run["faults"] == [] and run["max_loop_ms"] > 0.0

    def broken(*_args):
        raise RuntimeError("boom")

    monkeypatch.setattr(runtime.loop.chain["es"], "tick", broken)
    step(runtime, 0.05)
    monkeypatch.undo()
    # the release clears the loop's fault: the snapshot forgets it, the run's counters do not
    assert client.post("/api/estop/release").status_code == 200
    step(runtime, 0.05)
    assert runtime.loop.snapshot.fault is None
    run = client.get("/api/health").json()["run"]
    assert run["ticks"] == 30 and run["faults"] == ["RuntimeError: boom"]


def test_reset_restarts_the_simulation(client, runtime):
    step(runtime, 0.2)
    client.post("/api/estop")
    r = client.post("/api/sim/reset", json={"scene": "default"})
    assert r.status_code == 200, r.text
    s = client.get("/api/state").json()
    assert s["time"] == 0.0 and s["tick"] == 0 and s["emergency"]["hard_stop"] is False
    assert client.post("/api/sim/reset").status_code == 200


def test_push_changes_the_base_velocity(client, runtime):
    step(runtime, 0.1)
    v0 = np.array(runtime.truth.base_linvel_world)
    r = client.post("/api/sim/push", json={"body": "BODY", "force": [300.0, 0.0, 0.0], "duration": 0.1})
    assert r.status_code == 200, r.text
    step(runtime, 0.1)
    v1 = np.array(runtime.truth.base_linvel_world)
    assert v1[0] - v0[0] > 0.05


def test_chain_reports_order_and_per_layer_timing(client, runtime):
    step(runtime, 0.1)
    c = client.get("/api/chain").json()
    assert c["order"] == runtime.loop.chain.order()
    for name in c["order"]:
        assert c["timing"][name]["n"] == 20 and c["timing"][name]["p99_ms"] >= c["timing"][name]["p50_ms"]


def test_a_reset_then_loop_timing_gives_the_figures_of_the_new_run_only():
    """Paced at real time for 1.5 s, reset, 0.5 s more: /api/loop/timing?last_s=5 covers the new run's ticks
    only, none measured against the old run's schedule (that tick was the whole old run late)."""
    import time

    from fastapi.testclient import TestClient

    from app.console.main import create_app
    from app.console.settings import Settings
    from app.service import OperatorService
    from app.service.local import LocalRobot

    robot = LocalRobot(speed=1.0)
    robot.start()
    try:
        app = create_app(Settings(extra_hosts=("testserver",)), service=OperatorService(robot))
        with TestClient(app, headers={"content-type": "application/json"}) as client:
            time.sleep(1.5)
            reset_at = time.monotonic()  # (at the latest: the loop resets before the answer)
            assert client.post("/api/sim/reset").status_code == 200
            time.sleep(0.5)
            t = client.get("/api/loop/timing?last_s=5").json()
            since_reset_s = time.monotonic() - reset_at
    finally:
        robot.stop()
    assert 0 < t["ticks"] <= since_reset_s / 0.005 + 2, t
    assert t["lateness_max_ms"] < 1000.0, t  # the old schedule would give ~1500 ms
    assert t["speed_run"] is not None and t["speed_run"] > 0.2, t


def test_log_csv_has_a_header_and_one_row_per_tick(client, runtime):
    step(runtime, 0.05)
    r = client.get("/api/log.csv")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    lines = r.text.strip().splitlines()
    assert lines[0].startswith("time_s,joints/q_cmd_rad/RLEG_JOINT0")
    assert len(lines) == 1 + 10
    assert math.isclose(float(lines[-1].split(",")[0]), 0.05)


def test_log_mcap_holds_the_same_ticks_as_the_csv(client, runtime):
    import io
    import json

    from mcap.reader import make_reader

    step(runtime, 0.05)
    r = client.get("/api/log.mcap")
    assert r.status_code == 200 and r.headers["content-disposition"].endswith('filename="hrp2_log.mcap"')
    joints = [json.loads(m.data) for _, _, m in make_reader(io.BytesIO(r.content)).iter_messages(topics=["/joints"])]
    assert [m["tick"] for m in joints] == list(range(1, 11))
    assert joints[-1]["time_s"] == runtime.loop.snapshot.time_s


def test_docs_the_operator_page_and_config_are_served(client):
    assert client.get("/docs").status_code == 200
    assert "/api/sequence/joint-angles" in client.get("/openapi.json").json()["paths"]
    page = client.get("/")
    assert page.status_code == 200 and "E-STOP" in page.text
    cfg = client.get("/api/config").json()
    assert cfg["viewer_port"] == 8080 and cfg["joints"] == list(JOINT_NAMES)


def min_jerk(s):
    s = np.clip(s, 0.0, 1.0)
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def rarm0_per_tick(runtime, seconds):
    """RARM_JOINT0 commanded and encoder angles [deg] after each tick of `seconds`."""
    cmd, meas = [], []
    for _ in range(round(seconds / runtime.loop.dt_control_s)):
        step(runtime, runtime.loop.dt_control_s)
        cmd.append(q_cmd_deg(runtime)[RARM0])
        meas.append(np.rad2deg(runtime.loop.snapshot.q_meas_rad[RARM0]))
    return np.array(cmd), np.array(meas)


def test_motion_stop_reverts_the_planned_stream_holds_it_and_release_brings_it_back(client, runtime):
    dt = runtime.loop.dt_control_s
    step(runtime, 2.5)
    assert client.post("/api/motion/release").status_code == 409  # nothing to release
    r = client.post("/api/sequence/joint-angles", json={"angles_deg": {"RARM_JOINT0": -60.0}, "time": 2.0})
    assert r.status_code == 200
    moving, _ = rarm0_per_tick(runtime, 0.5)
    # the SequencePlayer's minimum-jerk move from 15 to -60 deg over 2 s (measured error 5e-11 deg)
    t = dt * np.arange(1, len(moving) + 1)
    np.testing.assert_allclose(moving, 15.0 - 75.0 * min_jerk(t / 2.0), atol=1e-6)
    assert client.post("/api/motion/stop").status_code == 200
    stopped, _ = rarm0_per_tick(runtime, 2.0)
    s = client.get("/api/state").json()
    assert s["emergency"]["motion_stop"] is True and s["emergency"]["motion_stop_reason"] == "operator"
    # Eq. 15: back to the plan T1 = 1 s before the stop (15 deg, the move had not begun) in T2 = 0.5 s,
    # then held there. The revert starts from the motion's velocity (first step -0.1962 deg, the last moving
    # step -0.1964), carries on down from the 7.24 deg where it was stopped to a single minimum (measured
    # 4.36 deg, bound 4.36 - 0.5) and rises monotonically to 15 deg; no step over 0.288 deg/tick (measured
    # 0.238, bound 0.238 + 0.05).
    t2_ticks = round(0.5 / dt)
    revert, hold = stopped[:t2_ticks], stopped[t2_ticks:]
    np.testing.assert_allclose(hold, 15.0, atol=1e-6)
    assert revert[0] - moving[-1] == pytest.approx(moving[-1] - moving[-2], abs=0.01)
    low = int(np.argmin(revert))
    assert np.all(np.diff(revert[:low + 1]) < 0) and np.all(np.diff(revert[low:]) > 0)
    assert 4.36 - 0.5 < revert[low] < moving[-1] - 1.0
    assert np.abs(np.diff(np.concatenate((moving[-1:], stopped)))).max() < 0.238 + 0.05
    assert client.get("/api/state").json()["joints"]["RARM_JOINT0"]["cmd_deg"] == pytest.approx(15.0, abs=1e-4)
    assert client.post("/api/motion/release").status_code == 200
    released, encoder = rarm0_per_tick(runtime, 3.0)
    # recover: a minimum-jerk blend over 2.5 s from the held 15 deg to the live plan, by now the goal -60 deg
    # (measured error 5e-11 deg): monotone, and exactly the goal at the end
    t = dt * np.arange(1, len(released) + 1)
    np.testing.assert_allclose(released, 15.0 - 75.0 * min_jerk(t / 2.5), atol=1e-6)
    assert np.all(np.diff(released) <= 0.0)
    s = client.get("/api/state").json()
    assert s["emergency"]["motion_stop"] is False
    assert s["joints"]["RARM_JOINT0"]["cmd_deg"] == pytest.approx(-60.0, abs=1e-4)
    # the joint follows: the encoder in the last 0.5 s within 0.4 deg of the goal (measured at most 0.31 deg
    # short of it, steady; bound 0.31 + 30 %)
    np.testing.assert_allclose(encoder[-round(0.5 / dt):], -60.0, atol=0.4)


def test_the_state_matches_its_published_schema_generated_from_the_layers_status(client, runtime):
    from app.console.routers.state import StateDocument

    step(runtime, 2.6)  # AutoBalancer and Stabilizer working
    doc = client.get("/api/state").json()
    StateDocument.model_validate(doc)  # extra="forbid": no field the schema does not describe
    schema = client.get("/openapi.json").json()
    ref = schema["paths"]["/api/state"]["get"]["responses"]["200"]["content"]["application/json"]["schema"]["$ref"]
    components = schema["components"]["schemas"]
    assert ref.endswith("/StateDocument")
    st = components["StabilizerStatusInState"]["properties"]
    assert "[m]" in st["cp_error"]["description"] and "[ms]" in st["tick_ms"]["description"]
    assert set(doc["layers"]["st"]) == set(st)


def test_every_422_the_api_sends_matches_the_error_schema_it_publishes(client):
    from app.console.errors import ErrorBody

    schema = client.get("/openapi.json").json()
    published = schema["components"]["schemas"]["HTTPValidationError"]
    assert published["properties"]["detail"]["type"] == "string"
    for url, body in [("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINT0": "x"}, "time": 1.0}),
                      ("/api/sequence/joint-angles", {"angles_deg": {"RARM_JOINTX": 1.0}, "time": 1.0}),
                      ("/api/walk/go-pos", {"x": 9.0, "y": 0.0, "theta_deg": 0.0})]:
        r = client.post(url, json=body)
        assert r.status_code == 422
        ErrorBody.model_validate(r.json())
        ref = schema["paths"][url]["post"]["responses"]["422"]["content"]["application/json"]["schema"]["$ref"]
        assert ref == "#/components/schemas/ErrorBody"
