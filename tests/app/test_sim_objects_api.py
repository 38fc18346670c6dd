"""PUT /api/sim/objects/{name}: a simulator operation places the EXPO scene's objects; errors name the field."""

import math

import numpy as np
import pytest
from fastapi.testclient import TestClient

import robot.generate as gen
from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def client_for(scene: str):
    robot = LocalRobot(scene, speed=None)
    app = create_app(Settings(extra_hosts=("testserver",)), service=OperatorService(robot))
    return robot, TestClient(app, headers={"content-type": "application/json"})


@pytest.fixture(scope="module")
def expo():
    robot, client = client_for("expo")
    with client:
        yield robot, client
    robot.stop()


def test_the_objects_of_the_scene_are_listed(expo):
    _, client = expo
    r = client.get("/api/sim/objects")
    assert r.status_code == 200
    assert r.json() == {"objects": ["table", "trash_box", "can", "unknown_object"], "scene": "expo"}


def test_a_can_placed_by_x_y_stands_on_the_table_where_asked(expo):
    robot, client = expo
    r = client.put("/api/sim/objects/can", json={"position": [2.2, 0.3], "yaw_deg": 30})
    assert r.status_code == 200, r.text
    expected = [2.2, 0.3, gen.EXPO_TABLE_SIZE_M[2] + gen.CAN_HEIGHT_M / 2]
    np.testing.assert_allclose(r.json()["position"], expected, atol=1e-9)
    assert r.json()["name"] == "can" and "can placed" in r.json()["message"]
    pos, quat = robot.plant.object_pose("can")
    np.testing.assert_allclose(pos, expected, atol=1e-9)
    np.testing.assert_allclose(quat, [math.cos(math.radians(15)), 0, 0, math.sin(math.radians(15))], atol=1e-9)
    robot.run_for(0.5)  # and it stays there, standing on the table
    np.testing.assert_allclose(robot.plant.object_pose("can")[0], expected, atol=0.001)


def test_the_table_and_the_trash_box_move_whole(expo):
    robot, client = expo
    r = client.put("/api/sim/objects/trash_box", json={"position": [1.0, -1.5, 0.0], "yaw_deg": 90})
    assert r.status_code == 200, r.text
    pos, quat = robot.plant.object_pose("trash_box")
    np.testing.assert_allclose(pos, [1.0, -1.5, 0.0], atol=1e-9)
    np.testing.assert_allclose(quat, [math.sqrt(0.5), 0, 0, math.sqrt(0.5)], atol=1e-9)


def test_an_unknown_object_is_404_listing_the_valid_names(expo):
    _, client = expo
    r = client.put("/api/sim/objects/cup", json={"position": [2.2, 0.0]})
    assert r.status_code == 404
    for word in ("cup", "table", "trash_box", "can", "unknown_object"):
        assert word in r.text


@pytest.mark.parametrize(("body", "field"), [
    ({"position": [2.2]}, "position"),
    ({"position": [2.2, 0.0, 0.5, 1.0]}, "position"),
    ({"position": [11.0, 0.0]}, "position"),
    ({"position": [2.2, 0.0, 3.5]}, "position.z"),
    ({"position": [2.2, 0.0, -0.1]}, "position.z"),
    ({"position": [2.2, 0.0], "yaw_deg": 400}, "yaw_deg"),
    ({"position": ["here", 0.0]}, "position"),
    ({}, "position"),
], ids=["one-number", "four-numbers", "x-too-far", "z-too-high", "z-below-floor", "yaw-too-large", "not-a-number",
        "missing"])
def test_an_invalid_placement_is_422_naming_the_field_and_moves_nothing(expo, body, field):
    robot, client = expo
    before = robot.plant.object_pose("can")[0]
    r = client.put("/api/sim/objects/can", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["field"].split(".")[0] == field.split(".")[0] and field in r.json()["field"], r.text
    np.testing.assert_array_equal(robot.plant.object_pose("can")[0], before)


def test_a_scene_without_objects_says_so():
    robot, client = client_for("default")
    with client:
        r = client.put("/api/sim/objects/can", json={"position": [2.2, 0.0]})
    robot.stop()
    assert r.status_code == 404 and "none in scene 'default'" in r.text
