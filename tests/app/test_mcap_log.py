"""The DataLogger's MCAP export, opened with the MCAP reader: the channels and their JSON schemas, one message
per tick on the tick topics, the on-change topics only when they changed, and values equal to the run's."""

import json

import numpy as np
import pytest
from mcap.reader import make_reader

from app.service.data_logger import DataLogger
from app.service.local import LocalRobot
from app.service.log_row import COLUMNS, TICK_TOPICS, column
from app.service.verbs import GoVelocity
from app.session.channels import TF_TOPIC

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def _check_against_schema(value, schema, where):
    """The parts of JSON schema the channels use: object properties, nullable types, arrays, enums."""
    types = schema.get("type")
    types = [types] if isinstance(types, str) else (types or [])
    if value is None:
        assert "null" in types, where
        return
    if "object" in types:
        assert isinstance(value, dict), where
        props = schema.get("properties", {})
        assert set(value) <= set(props), f"{where}: {sorted(set(value) - set(props))} not in the schema"
        for key, v in value.items():
            _check_against_schema(v, props[key], f"{where}.{key}")
    elif "array" in types:
        assert isinstance(value, list), where
        for i, v in enumerate(value):
            _check_against_schema(v, schema["items"], f"{where}[{i}]")
    elif "boolean" in types:
        assert isinstance(value, bool), where
    elif "number" in types:
        assert isinstance(value, (int, float)) and not isinstance(value, bool), where
    elif "integer" in types:
        assert isinstance(value, int), where
    elif "string" in types:
        assert isinstance(value, str) and value in schema.get("enum", [value]), where


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """2.5 s standing (the AutoBalancer blends in), then goVelocity: a walk whose footsteps appear on their
    channel; the log keeps the last 2 s."""
    robot = LocalRobot(speed=None)
    robot.host.logger = logger = DataLogger(400)
    robot.run_for(2.5)
    robot.submit(GoVelocity(0.1, 0.0, 0.0)).result()
    robot.run_for(1.5)
    path = tmp_path_factory.mktemp("mcap") / "log.mcap"
    n = logger.to_mcap(path)
    return path, logger.rows(), n


def test_the_export_has_every_channel_with_a_json_schema_and_one_message_per_tick(written):
    path, rows, n = written
    assert n == len(rows) == 400
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        channels = {c.topic: c for c in summary.channels.values()}
        assert set(channels) == {*TICK_TOPICS, "/footsteps", "/operation/targets", TF_TOPIC}
        for c in channels.values():
            schema = summary.schemas[c.schema_id]
            assert c.message_encoding == "json" and schema.encoding == "jsonschema"
            assert json.loads(schema.data)["type"] == "object"
        counts = {channels_topic: summary.statistics.channel_message_counts[c.id]
                  for channels_topic, c in channels.items()}
        assert all(counts[t] == n for t in (*TICK_TOPICS, TF_TOPIC))
        assert 2 <= counts["/footsteps"] < n // 10  # the first row, then each time the plan moves on
        assert counts["/operation/targets"] == 1  # nothing operated: only the first row
        assert summary.schemas[channels[TF_TOPIC].schema_id].name == "foxglove.FrameTransform"
        for schema, channel, message in reader.iter_messages():
            _check_against_schema(json.loads(message.data), json.loads(schema.data), channel.topic)


def test_the_messages_hold_the_runs_values_exactly(written):
    path, rows, _ = written
    last = {}
    walking = []
    with open(path, "rb") as f:
        for _, channel, message in make_reader(f).iter_messages():
            doc = json.loads(message.data)
            last[channel.topic] = (message.log_time, doc)
            if channel.topic == "/flags":
                walking.append(doc["walking"])
    row = rows[-1]
    log_time, joints = last["/joints"]
    assert log_time == round(row[0] * 1e9) and joints["time_s"] == row[0]
    assert [joints["q_cmd_rad"][n] for n in ("RLEG_JOINT3", "LARM_JOINT6")] == [
        row[column("joints/q_cmd_rad/RLEG_JOINT3")], row[column("joints/q_cmd_rad/LARM_JOINT6")]]
    balance = last["/balance"][1]
    assert balance["cp_error_m"] == row[column("balance/cp_error_m")]
    assert balance["zmp_ref_m"]["y"] == row[column("balance/zmp_ref_m/y")]
    act = last["/wrenches"][1]["act"]
    assert act["rfsensor"]["fz"] == row[column("wrenches/act.rfsensor/fz")]
    assert act["rfsensor"]["fz"] + act["lfsensor"]["fz"] > 400.0  # the robot's weight on its soles
    tf = last[TF_TOPIC][1]
    assert [tf["translation"][k] for k in "xyz"] == row[[column(f"base/pos_sim_m/{k}") for k in "xyz"]].tolist()
    assert walking[0] is False and walking[-1] is True
    steps = last["/footsteps"][1]["footsteps"]
    assert steps and steps[0]["leg"] in ("rleg", "lleg") and steps[0]["x"] == row[column("footsteps/next.0/x")]
    assert np.isnan(row[column("operation/targets/rhand/x")]) and last["/operation/targets"][1]["rhand"] is None
    assert len(COLUMNS) == rows.shape[1]
