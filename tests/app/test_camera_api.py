"""The operator's camera view (GET /api/camera/wide.jpg, WS /ws/camera) and the recognitions the operator confirms
or corrects (GET /api/recognitions, POST /api/recognitions/{name}/confirm and /correct)."""

from __future__ import annotations

import io
import json
import time

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image
from starlette.websockets import WebSocketDisconnect

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.camera_feed import VIEW_SIZE_PX, box_corners_world, image_box_px
from app.service.commands import HostCommands
from app.service.local import LocalRobot
from robot.images import CameraIntrinsics

#: Pixel standard deviation of the wide view of the EXPO scene from the start pose: measured 43.7 (floor, table,
#: can, sky); a blank or one-colour frame is 0-2.
MIN_PIXEL_STD = 15.0
TOKEN = "camera-token-of-the-console-0123"


@pytest.fixture(scope="module")
def expo():
    robot = LocalRobot("expo", speed=None)
    robot.run_for(0.1)
    yield robot
    robot.stop()


@pytest.fixture(scope="module")
def expo_service(expo):
    service = OperatorService(expo)
    yield service
    service.camera.close()


@pytest.fixture
def expo_client(expo_service):
    app = create_app(Settings(extra_hosts=("testserver",)), service=expo_service)
    with TestClient(app, headers={"content-type": "application/json"}) as c:
        yield c


def _image(jpeg: bytes) -> np.ndarray:
    img = Image.open(io.BytesIO(jpeg))
    assert img.format == "JPEG"
    return np.asarray(img.convert("RGB"))


def can_recognition(expo, error_m=(0.0, 0.0, 0.0)) -> dict:
    """A recognition of the can as perception publishes it (position from the scene's truth plus `error_m`: the
    test stands in for the perception worker, whose own tests measure its error)."""
    pos, _ = expo.plant.object_pose("can")
    p = [round(float(v + e), 5) for v, e in zip(pos, error_m, strict=True)]
    return {"object": "can", "position_m": p, "yaw_deg": 0.0, "sigma_m": [0.002, 0.002, 0.003],
            "covariance_m2": [[4e-6, 0, 0], [0, 4e-6, 0], [0, 0, 9e-6]], "bbox_px": [300, 200, 340, 260],
            "n_pixels": 900, "at_border": False, "time_s": 0.1}


def test_a_frame_is_a_jpeg_of_the_stated_size_and_not_blank(expo_client):
    r = expo_client.get("/api/camera/wide.jpg")
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/jpeg"
    assert r.headers["x-frame-size"] == f"{VIEW_SIZE_PX[0]}x{VIEW_SIZE_PX[1]}"
    rgb = _image(r.content)
    assert rgb.shape == (VIEW_SIZE_PX[1], VIEW_SIZE_PX[0], 3)
    assert rgb.std() > MIN_PIXEL_STD, f"pixel std {rgb.std():.1f}: a blank frame"


def test_the_view_follows_the_robot_and_only_renders_while_watched(expo, expo_service, expo_client):
    first = expo_client.get("/api/camera/wide.jpg")
    t0 = float(first.headers["x-frame-time"])
    expo.run_for(0.2)
    time.sleep(0.6)  # the first frame is older than the 0.5 s a GET may answer with
    second = expo_client.get("/api/camera/wide.jpg")
    assert float(second.headers["x-frame-time"]) >= t0 + 0.2 - 1e-9
    assert int(second.headers["x-frame-seq"]) > int(first.headers["x-frame-seq"])
    feed = expo_service.camera
    feed._until = 0.0  # the lease ran out (nobody asked for 2 s)
    time.sleep(0.2)
    n = feed.frames
    expo.run_for(0.2)  # new publications, nobody watching
    time.sleep(0.5)
    assert feed.frames == n, "frames were rendered while nobody watched"


def test_the_stream_sends_meta_then_the_jpeg_and_validates_its_rate(expo_client, expo):
    with expo_client.websocket_connect("/ws/camera?rate_hz=15") as ws:
        meta = json.loads(ws.receive_text())
        assert meta["ok"] and meta["camera"] == "wide" and (meta["width"], meta["height"]) == VIEW_SIZE_PX
        jpeg = ws.receive_bytes()
        assert len(jpeg) == meta["bytes"] and _image(jpeg).shape == (VIEW_SIZE_PX[1], VIEW_SIZE_PX[0], 3)
        ws.send_text(json.dumps({"rate_hz": 99}))
        while True:  # frames may come before the answer
            msg = ws.receive()
            if msg.get("text") and "field" in json.loads(msg["text"]):
                break
        err = json.loads(msg["text"])
        assert err["field"] == "rate_hz" and "[1, 15]" in err["detail"]
    with expo_client.websocket_connect("/ws/camera?rate_hz=0") as ws:
        err = json.loads(ws.receive_text())
        assert err["field"] == "rate_hz"
        with pytest.raises(WebSocketDisconnect):
            ws.receive_text()


def test_the_camera_needs_the_token_beyond_loopback(expo_service):
    app = create_app(Settings(host="0.0.0.0", token=TOKEN), service=expo_service)
    with TestClient(app) as c:
        assert c.get("/api/camera/wide.jpg").status_code == 401
        r = c.get("/api/camera/wide.jpg", headers={"authorization": f"Bearer {TOKEN}"})
        assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg"
        with pytest.raises(WebSocketDisconnect), c.websocket_connect("/ws/camera") as ws:
            ws.receive_text()
        with c.websocket_connect(f"/ws/camera?token={TOKEN}") as ws:
            assert json.loads(ws.receive_text())["ok"]


def test_a_recognition_is_boxed_where_the_object_is_in_the_view(expo, expo_service, expo_client):
    expo.host.recognitions["can"] = can_recognition(expo)
    expo.run_for(0.05)
    with expo_client.websocket_connect("/ws/camera?rate_hz=15") as ws:
        while True:
            meta = json.loads(ws.receive_text())
            jpeg = ws.receive_bytes()
            if meta["recognitions"]:
                break
    (rec,) = meta["recognitions"]
    assert rec["name"] == "can" and rec["position_m"] == expo.host.recognitions["can"]["position_m"]
    u0, v0, u1, v1 = rec["box_px"]
    rgb = _image(jpeg).astype(int)
    red = (rgb[:, :, 0] > 120) & (rgb[:, :, 1] < 80) & (rgb[:, :, 2] < 80)  # the can is red
    vs, us = np.nonzero(red)
    assert len(us) > 10, "the can is not in the view"
    margin = 2  # [px] JPEG blur at the can's edge
    inside = (us >= u0 - margin) & (us <= u1 + margin) & (vs >= v0 - margin) & (vs <= v1 + margin)
    assert inside.mean() > 0.95, f"{inside.mean():.0%} of the can's pixels inside the box {rec['box_px']}"
    assert (u1 - u0) < 40 and (v1 - v0) < 50  # a can-sized box at 2 m, not the whole image


def test_confirm_and_correct_change_what_the_next_behaviour_recalls(expo, expo_client):
    expo.host.recognitions["can"] = estimated = can_recognition(expo, error_m=(0.01, 0.0, 0.0))
    recalled = HostCommands(expo.host).recalled  # what a behaviour asks (take_can, throw_can)
    r = expo_client.post("/api/recognitions/can/confirm", json={})
    assert r.status_code == 200, r.text
    assert recalled("can")["status"] == "confirmed"
    assert recalled("can")["position_m"] == estimated["position_m"]
    r = expo_client.post("/api/recognitions/can/correct", json={"position_m": [2.15, 0.02, 0.7535]})
    assert r.status_code == 200, r.text
    assert r.json()["recognition"]["status"] == "corrected"
    assert recalled("can")["position_m"] == [2.15, 0.02, 0.7535]
    assert recalled("can")["estimated_position_m"] == estimated["position_m"]
    assert expo_client.get("/api/recognitions").json()["recognitions"]["can"]["position_m"] == [2.15, 0.02, 0.7535]


@pytest.mark.parametrize(("path", "body", "status", "field"), [
    ("/api/recognitions/can/correct", {"position_m": [1.0, 0.0]}, 422, "position_m"),
    ("/api/recognitions/can/correct", {"position_m": [1.0, 0.0, "0.7"]}, 422, "position_m.2"),
    ("/api/recognitions/can/correct", {"position_m": [1.0, 25.0, 0.7]}, 422, "position_m.1"),
    ("/api/recognitions/can/correct", {"position_m": [1.0, 0.0, 0.7], "sigma": 1}, 422, "sigma"),
    ("/api/recognitions/can/correct", {}, 422, "position_m"),
    ("/api/recognitions/can/confirm", {"status": "wrong"}, 422, "status"),
    ("/api/recognitions/Can!/confirm", {}, 422, "name"),
    ("/api/recognitions/trash_box/confirm", {}, 404, None),
])
def test_bad_confirmations_are_refused_naming_the_field(expo, expo_client, path, body, status, field):
    expo.host.recognitions["can"] = can_recognition(expo)
    expo.host.recognitions.pop("trash_box", None)
    r = expo_client.post(path, json=body)
    assert r.status_code == status, r.text
    if field is not None:
        assert r.json()["field"] == field, r.json()
    else:
        assert "trash_box" in r.json()["detail"] and "can" in r.json()["detail"]


def test_image_box_of_a_point_ahead_is_at_the_centre_and_behind_is_none():
    k = CameraIntrinsics(320, 240, 100.0, 100.0, 159.5, 119.5)
    ahead = box_corners_world((0.0, 0.0, 2.0), 0.0, (0.1, 0.1, 0.1))  # camera = world (optical frame)
    u0, v0, u1, v1 = image_box_px(np.eye(4), k, ahead)
    assert (u0 + u1) / 2 == pytest.approx(159.5, abs=0.1) and (v0 + v1) / 2 == pytest.approx(119.5, abs=0.1)
    assert u1 - u0 == pytest.approx(2 * 100 * 0.1 / 1.9, abs=0.2)  # the nearest face, 1.9 m away
    assert image_box_px(np.eye(4), k, box_corners_world((0.0, 0.0, -2.0), 0.0, (0.1, 0.1, 0.1))) is None
    assert image_box_px(np.eye(4), k, box_corners_world((50.0, 0.0, 2.0), 0.0, (0.1, 0.1, 0.1))) is None
