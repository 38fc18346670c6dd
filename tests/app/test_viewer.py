"""The viser view: one frame per body, poses follow the simulation, the E-STOP button goes through the
operator service, the markers follow the controller (planned footsteps with their yaw), and the websocket
refuses pages of other origins."""

import dataclasses
import math

import numpy as np
import pytest

from app.console.viewer import PLOT_RANGE_MM, Viewer
from app.service import OperatorService
from app.service.local import LocalRobot


@pytest.fixture
def robot():
    return LocalRobot(speed=None)


@pytest.fixture
def viewer(robot):
    v = Viewer(OperatorService(robot), host="127.0.0.1", port=0, rate_hz=50.0)
    yield v
    v.stop()


def test_every_body_gets_a_frame_placed_at_its_simulated_pose(viewer, robot):
    model = robot.host.plant.model
    assert len(viewer._frames) == model.nbody - 1
    obs = robot.run_for(0.1)
    viewer._apply_poses(obs.truth)
    np.testing.assert_allclose(viewer._frames[0].position, obs.truth.body_pos_world[1])


def test_a_snapshot_of_another_scene_is_not_drawn_on_the_bodies_of_this_one(viewer, robot):
    """Around a reset to another scene, the scene's name and the snapshots change at different moments: a snapshot
    with more bodies than drawn (the EXPO scene's can, table, box) once raised IndexError in the viewer's thread."""
    obs = robot.run_for(0.05)
    before = np.array(viewer._frames[0].position)
    extra = dataclasses.replace(obs.truth, body_pos_world=np.vstack([obs.truth.body_pos_world, np.ones((3, 3))]),
                                body_quat_wxyz=np.vstack([obs.truth.body_quat_wxyz, np.ones((3, 4))]))
    assert viewer._set_body_poses(extra) is False
    viewer.apply_snapshot(dataclasses.replace(obs, truth=extra))
    np.testing.assert_array_equal(viewer._frames[0].position, before)
    assert viewer._set_body_poses(obs.truth) is True


def test_the_estop_and_release_buttons_are_verbs_of_the_service(viewer, robot):
    viewer._command("engaged", viewer.service.estop)
    robot.step()
    assert robot.loop.snapshot.safety.hard_stop is True
    viewer._command("released", viewer.service.release_estop)
    assert viewer._message.value == "released"
    viewer._command("released", viewer.service.release_estop)
    assert "not engaged" in viewer._message.value


def test_the_cp_error_plot_and_the_balance_markers_are_built_and_follow_the_snapshots(viewer, robot):
    # the viewer's own update thread off: it writes the plot too, and under load its older data landed after this
    # test's (a CI run: the last sample not the last snapshot's)
    viewer._stop.set()
    viewer._thread.join(timeout=2.0)
    assert viewer._cp_plot is not None and len(viewer._cp_plot.data) == 8
    assert set(viewer._markers) == {"cog", "zmp", "cp_ref", "cp_act", "support", "soles", "footsteps",
                                     "target_rhand", "target_lhand"}
    for _ in range(5):
        snap = robot.run_for(0.05)
        viewer.apply_snapshot(snap)
        viewer._update_plot(snap)
    m = viewer._markers
    np.testing.assert_allclose(m["cog"].position, snap.cog_world, atol=1e-6)
    st = snap.layers["st"]
    np.testing.assert_allclose(m["cp_act"].position[:2], st.cp_act, atol=1e-6)
    np.testing.assert_allclose(m["cp_ref"].position[:2], st.cp_ref, atol=1e-6)
    assert m["support"].visible and m["soles"].visible and not m["footsteps"].visible
    assert m["support"].points.shape == (8, 2, 3)
    # the support polygon (both feet down) surrounds the midpoint of the soles
    gait = snap.reference.gait
    mid = 0.5 * (np.asarray(gait.p_rsole_world[:2]) + np.asarray(gait.p_lsole_world[:2]))
    pts = m["support"].points[:, 0, :2]
    assert pts[:, 0].min() < mid[0] < pts[:, 0].max() and pts[:, 1].min() < mid[1] < pts[:, 1].max()
    t, ex, ey, hi, lo, edge_hi, edge_lo, _band = viewer._cp_plot.data
    assert len(t) >= 5 and np.all(np.diff(t) > 0) and t[-1] == pytest.approx(snap.time_s)
    assert ex[-1] == pytest.approx(1e3 * st.cp_error[0]) and ey[-1] == pytest.approx(1e3 * st.cp_error[1])
    np.testing.assert_allclose(hi, 1e3 * st.cp_threshold_m)
    np.testing.assert_allclose(lo, -hi)
    # standing on both feet, the reference capture point is mid-support: 80-100 mm (the plot's range) from its
    # nearest edge (measured 93.6 mm), the dotted lines well outside the 40 mm threshold
    assert 80.0 <= edge_hi[-1] <= PLOT_RANGE_MM and edge_lo[-1] == -edge_hi[-1]


def test_planned_footsteps_are_drawn_from_the_auto_balancer_with_their_yaw(viewer, robot):
    from app.console.viewer import MAX_FOOTSTEPS
    from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
    from controller.balance.leg_odometry import control_to_world
    from controller.kinematics.rotations import rpy_to_matrix

    handles = dict(viewer._markers)
    robot.run_for(2.5)  # AutoBalancer blended in
    viewer.service.go_pos(0.3, 0.0, math.radians(40.0))
    snap = robot.run_for(0.1)
    planned = snap.layers["abc"].footsteps  # the AutoBalancer's own plan: FootstepStatus with pos and rpy
    yaws = sorted({round(math.degrees(f.rpy[2]), 3) for f in planned})
    assert len(planned) >= 4 and yaws[-1] > 10.0 and len(yaws) >= 3, yaws  # a turn: steps of several yaws
    viewer.apply_snapshot(snap)
    m, wfc = viewer._markers, snap.odometry.world_from_control
    assert m["footsteps"].visible and m["footsteps"].points.shape == (4 * MAX_FOOTSTEPS, 2, 3)
    soles = {"rleg": HRP2_RIGHT_SOLE, "lleg": HRP2_LEFT_SOLE}
    for k, f in enumerate(planned[:MAX_FOOTSTEPS]):
        outline = m["footsteps"].points[4 * k:4 * k + 4]  # the k-th sole outline: four edges, corner to corner
        sole = soles[f.leg]
        # the sole's corners (rear-right, front-right, front-left, rear-left) turned by the footstep's
        # rotation and put at its position, worked out here rather than with the viewer's helper
        local = np.array([[-sole.rear_m, -sole.right_m, 0.0], [sole.front_m, -sole.right_m, 0.0],
                          [sole.front_m, sole.left_m, 0.0], [-sole.rear_m, sole.left_m, 0.0]])
        # in the world of leg odometry (the AutoBalancer plans in its own frame)
        yaw = f.rpy[2] + wfc[3]
        pos = np.asarray(control_to_world(wfc, f.pos))
        expected = local @ rpy_to_matrix(np.array([0.0, 0.0, yaw])).T + pos
        np.testing.assert_allclose(outline[:, 0, :2], expected[:, :2], atol=1e-5, err_msg=f"footstep {k}")
        np.testing.assert_allclose(outline[:, 1, :2], np.roll(expected[:, :2], -1, axis=0), atol=1e-5)
        side = outline[0]  # rear-right -> front-right: the sole's x axis, so its direction is the yaw itself
        drawn = math.atan2(side[1, 1] - side[0, 1], side[1, 0] - side[0, 0])
        assert abs(math.remainder(drawn - yaw, 2 * math.pi)) < 1e-4, \
            f"footstep {k}: drawn at {math.degrees(drawn):.2f} deg, planned {math.degrees(yaw):.2f} deg"
        np.testing.assert_allclose(side[:, 2], pos[2] + 0.002, atol=1e-6)
    assert all(viewer._markers[k] is handles[k] for k in handles)  # handles updated, never rebuilt


def test_the_cp_history_keeps_a_time_window_and_clears_on_reset():
    from types import SimpleNamespace

    from app.console.viewer import CpErrorHistory

    h = CpErrorHistory(window_s=1.0)
    st = SimpleNamespace(cp_error=(0.01, -0.02), cp_threshold_m=0.04, emergency=False)
    flagged = SimpleNamespace(cp_error=(0.05, 0.0), cp_threshold_m=0.04, emergency=True)
    for i in range(30):
        assert h.add(SimpleNamespace(time_s=0.1 * i, layers={"st": flagged if i == 29 else st}))
    t, ex, ey, hi, lo, edge_hi, edge_lo, band = h.data()
    assert t[-1] - t[0] <= 1.0 + 1e-9 and ex[0] == pytest.approx(10.0) and ey[0] == pytest.approx(-20.0)
    assert hi[0] == pytest.approx(40.0) and lo[0] == pytest.approx(-40.0)
    assert edge_hi[0] == PLOT_RANGE_MM and edge_lo[0] == -PLOT_RANGE_MM  # no gait reference: the range
    # the flag band fills the fixed range while the flag is raised, and nothing (its bottom) otherwise
    assert band[-1] == PLOT_RANGE_MM and set(band[:-1]) == {-PLOT_RANGE_MM}
    assert h.latest() == pytest.approx((2.9, 50.0, 0.0, 40.0, True))
    assert not h.add(SimpleNamespace(time_s=5.0, layers={}))
    h.add(SimpleNamespace(time_s=0.0, layers={"st": st}))
    assert len(h) == 1


def test_the_operator_pages_origin_is_accepted_once_allowed(viewer):
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    url, page = f"ws://127.0.0.1:{viewer.port}/", "http://127.0.0.1:8123"
    with pytest.raises(InvalidStatus):
        connect(url, origin=page, subprotocols=["viser-v1"], open_timeout=5)
    viewer.allow_page(8123)
    with connect(url, origin=page, subprotocols=["viser-v1"], open_timeout=5):
        pass


def test_the_hand_targets_of_the_operation_layer_are_drawn_in_the_world(viewer, robot):
    from app.service.setpoints import Setpoint

    snap = robot.run_for(0.05)
    viewer.apply_snapshot(snap)
    assert not viewer._markers["target_rhand"].visible
    for _ in range(10):
        viewer.service.put_setpoint(Setpoint("rhand", (0.0, 0.0, 0.1), (0.0, 0.0, 0.0)))
        snap = robot.run_for(0.02)
    viewer.apply_snapshot(snap)
    handle = viewer._markers["target_rhand"]
    target = snap.layers["op"].points["rhand"].target
    assert handle.visible and target is not None
    gait = snap.reference.gait
    origin_z = 0.5 * (gait.p_rsole_world[2] + gait.p_lsole_world[2])
    assert handle.position[2] == pytest.approx(origin_z + target[2], abs=1e-6)


@pytest.mark.parametrize("origin, accepted", [("http://127.0.0.1:{port}", True), ("http://localhost:{port}", True),
                                               ("http://evil.example", False), ("http://127.0.0.1:9", False),
                                               ("null", False)])
def test_the_websocket_accepts_only_the_viewers_own_origins(viewer, origin, accepted):
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    port = viewer.port
    url = f"ws://127.0.0.1:{port}/"
    try:
        with connect(url, origin=origin.format(port=port), subprotocols=["viser-v1"], open_timeout=5):
            ok = True
    except InvalidStatus as exc:
        assert exc.response.status_code == 403
        ok = False
    assert ok is accepted


def test_a_located_object_gets_a_marker_at_its_position_and_a_correction_moves_it(viewer, robot):
    service = viewer.service
    robot.host.recognitions["can"] = {"object": "can", "position_m": [1.2, 0.1, 0.75], "sigma_m": [0.003, 0.004, 0.0]}
    robot.step()
    viewer._update_recognitions(service.recognitions())
    sphere, label, _ = viewer._recognition_markers["can"]
    np.testing.assert_allclose(sphere.position, [1.2, 0.1, 0.75])
    assert sphere.color == (255, 200, 0)  # the robot's estimate, not confirmed yet
    service.confirm_recognition("can", [1.25, 0.1, 0.75])
    robot.step()
    viewer._update_recognitions(service.recognitions())
    sphere, label, _ = viewer._recognition_markers["can"]
    np.testing.assert_allclose(sphere.position, [1.25, 0.1, 0.75])
    assert sphere.color == (40, 170, 60)
    robot.host.recognitions["can"] = {**robot.host.recognitions["can"], "status": "held"}  # take_can holds it
    robot.step()
    viewer._update_recognitions(service.recognitions())
    assert "can" not in viewer._recognition_markers  # its marker on the table went
    robot.host.recognitions["can"] = {"object": "can", "position_m": [1.2, 0.1, 0.75], "sigma_m": [0.003, 0.004, 0.0]}
    robot.step()
    viewer._update_recognitions(service.recognitions())
    assert "can" in viewer._recognition_markers
    robot.reset()
    viewer._update_recognitions(service.recognitions())
    assert "can" not in viewer._recognition_markers


def test_a_click_in_3d_corrects_a_recognition_at_its_estimated_height(viewer, robot):
    from app.console.viewer import ray_at_height

    assert ray_at_height((0, 0, 2.0), (0, 0, 1.0), 0.75) is None  # away from the plane
    assert ray_at_height((0, 0, 2.0), (1.0, 0, 0), 0.75) is None  # parallel to it
    np.testing.assert_allclose(ray_at_height((0, 0, 2.0), (1.0, 0.0, -1.0), 0.75), [1.25, 0.0, 0.75])
    assert "no recognition of can" in viewer.correct_by_ray("can", (0, 0, 2), (0, 0, -1))
    robot.host.recognitions["can"] = {"object": "can", "position_m": [2.15, 0.0, 0.75], "sigma_m": [0.002] * 3}
    robot.step()
    message = viewer.correct_by_ray("can", (1.0, 0.5, 2.0), (1.0, -0.5, -1.25))  # meets z 0.75 at (2.0, 0.0)
    assert message == "can corrected to (2.000, 0.000, 0.750) m"
    assert robot.host.recognitions["can"]["position_m"] == [2.0, 0.0, 0.75]
    assert robot.host.recognitions["can"]["status"] == "corrected"


def test_the_camera_follower_puts_a_camera_on_the_body_then_moves_it_by_the_bodys_travel():
    from types import SimpleNamespace

    from app.console.viewer import CameraFollower

    class Camera(SimpleNamespace):  # as viser's: setting the position moves the look-at point with it
        def __setattr__(self, name, value):
            if name == "position" and "position" in self.__dict__:
                super().__setattr__("look_at", self.look_at + (np.asarray(value) - self.position))
            super().__setattr__(name, np.asarray(value, dtype=float))

    cam = Camera(position=np.array([3.0, 3.0, 2.0]), look_at=np.array([0.0, 0.0, 0.5]))
    follower = CameraFollower(step_m=0.002)
    assert follower.update({1: cam}, (1.0, 0.2)) == 1  # first sight: looking at the body
    np.testing.assert_allclose(cam.look_at, [1.0, 0.2, 0.5])
    np.testing.assert_allclose(cam.position, [4.0, 3.2, 2.0])  # the same orbit offset and height
    assert follower.update({1: cam}, (1.001, 0.2)) == 0  # sway: not moved
    cam.position = np.array([4.0, 1.2, 1.0])  # the operator orbits
    follower.update({1: cam}, (1.3, 0.2))
    np.testing.assert_allclose(cam.position, [4.3, 1.2, 1.0])  # their orbit kept, moved with the body
    np.testing.assert_allclose(cam.look_at, [1.3, -1.8, -0.5])
    follower.restart()
    follower.update({1: cam}, (1.3, 0.2))
    np.testing.assert_allclose(cam.look_at[:2], [1.3, 0.2])  # on the body again
    class Unreported:  # viser's camera before its client reported it
        @property
        def look_at(self):
            raise AssertionError

    assert follower.update({1: cam, 2: Unreported()}, (1.3, 0.2)) == 0  # a camera not reported yet is skipped


def _send_camera(ws, position, look_at) -> None:
    import msgspec.msgpack
    from viser._messages import ViewerCameraMessage

    d = np.asarray(look_at, dtype=float) - np.asarray(position, dtype=float)
    yaw = math.atan2(d[1], d[0])
    # OpenCV camera (+z forward, -y up) looking horizontally along yaw: columns x = right, y = down, z = forward
    fwd = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    rot = np.column_stack([right, [0.0, 0.0, -1.0], fwd])
    w = math.sqrt(max(0.0, 1.0 + np.trace(rot))) / 2.0
    wxyz = (w, (rot[2, 1] - rot[1, 2]) / (4 * w), (rot[0, 2] - rot[2, 0]) / (4 * w), (rot[1, 0] - rot[0, 1]) / (4 * w))
    msg = ViewerCameraMessage(wxyz=wxyz, position=tuple(position), fov=1.0, near=0.01, far=100.0, image_height=480,
                              image_width=640, look_at=tuple(look_at), up_direction=(0.0, 0.0, 1.0))
    ws.send(msgspec.msgpack.encode(msg.as_serializable_dict()))


def test_the_3d_view_follows_the_robot_by_default_and_the_toggle_stops_it(viewer, robot):
    """A client (a websocket speaking viser's protocol) reports its camera; the robot walks 0.3 m: the server's
    camera of that client moved with BODY, and the message went out to the client; with the toggle off it stays."""
    import time

    import viser
    from websockets.sync.client import connect

    viewer._stop.set()  # the test follows itself, at the instants it chooses (no background updates)
    viewer._thread.join()
    assert viewer._follow.value is True  # on by default
    with connect(f"ws://127.0.0.1:{viewer.port}/", subprotocols=[f"viser-v{viser.__version__}"], open_timeout=5,
                 max_size=None) as ws:
        _send_camera(ws, (2.0, -2.0, 1.5), (0.0, 0.0, 0.6))
        deadline = time.monotonic() + 5.0
        while not viewer.server.get_clients() or _camera_unset(viewer):
            assert time.monotonic() < deadline, "the viewer never got the client's camera"
            time.sleep(0.02)
        cam = next(iter(viewer.server.get_clients().values())).camera
        truth = robot.run_for(2.5).truth  # the AutoBalancer blended in: it can walk
        body = np.asarray(truth.body_pos_world[viewer._followed])
        viewer.follow(truth)
        np.testing.assert_allclose(cam.look_at[:2], body[:2], atol=1e-9)  # on the robot
        start = np.array(cam.position)
        viewer.service.go_pos(0.3, 0.0, 0.0)
        snap = robot.run_for(6.0)
        moved = np.asarray(snap.truth.body_pos_world[viewer._followed])[:2] - body[:2]
        assert moved[0] > 0.25, moved
        _received(ws, 0.3)  # what went out so far (the scene, the first move)
        viewer.follow(snap.truth)
        np.testing.assert_allclose(np.array(cam.position)[:2] - start[:2], moved, atol=1e-9)
        assert cam.position[2] == pytest.approx(start[2])  # height kept
        sent = [m for m in _received(ws, 2.0) if m["type"] == "SetCameraPositionMessage"]
        assert sent and np.allclose(sent[-1]["position"], cam.position), sent  # the client was told
        viewer._follow.value = False
        held = np.array(cam.position)
        viewer.service.go_pos(-0.3, 0.0, 0.0)
        snap = robot.run_for(6.0)
        assert viewer.follow(snap.truth) == 0
        np.testing.assert_allclose(cam.position, held)


def _camera_unset(viewer) -> bool:
    try:
        next(iter(viewer.server.get_clients().values())).camera.look_at  # noqa: B018 - raises until reported
    except AssertionError:
        return True
    return False


def _received(ws, quiet_s: float) -> list[dict]:
    """The viser messages the server sent to `ws` until it has been quiet for `quiet_s` [s] (its wire format:
    uncompressed and compressed sizes, zstd-compressed msgpack {"messages": [...]}, binary buffers)."""
    import msgspec.msgpack
    import zstandard

    out = []
    while True:
        try:
            raw = ws.recv(timeout=quiet_s)
        except TimeoutError:
            return out
        size, packed = int.from_bytes(raw[:8], "little"), int.from_bytes(raw[8:16], "little")
        inner = zstandard.ZstdDecompressor().decompress(raw[16:16 + packed], max_output_size=size)
        out += msgspec.msgpack.decode(inner)["messages"]


def test_the_cp_plot_is_pushed_at_least_20_times_a_second_with_the_robot_in_real_time():
    """The issue asks the plot updated at >= 20 Hz: the viewer's thread samples and pushes it at PLOT_RATE_HZ
    (25) with the robot running at real time in this process; measured 24.9-25.0 per s."""
    import time

    from app.console.viewer import PLOT_RATE_HZ

    robot = LocalRobot(speed=1.0)
    viewer = Viewer(OperatorService(robot), host="127.0.0.1", port=0)
    try:
        robot.start()
        time.sleep(0.5)
        n0, t0 = viewer._plot_updates, time.monotonic()
        time.sleep(2.0)
        rate = (viewer._plot_updates - n0) / (time.monotonic() - t0)
    finally:
        robot.stop()
        viewer.stop()
    assert 20.0 <= rate <= PLOT_RATE_HZ + 1.0, f"{rate:.1f} plot updates per s"


#: [mm] the drawn soles from the simulated feet after the 1 m walk (measured 0.9 mm; the controller's frame, drawn
#: unplaced, is 17 mm off): the odometry's error, the stance foot's compliance and 1.5 mm of margin
SOLES_FROM_FEET_MM = 2.5


def test_after_a_walk_the_markers_are_drawn_in_the_world_of_leg_odometry_on_the_simulated_feet(viewer, robot):
    from app.console.viewer import footstep_rectangles
    from controller.balance.leg_odometry import control_to_world

    robot.run_for(2.5)
    viewer.service.go_pos(1.0, 0.0, 0.0)
    snap = robot.run_for(12.0)
    assert not snap.reference.gait.walking
    viewer.apply_snapshot(snap)
    m, wfc = viewer._markers, snap.odometry.world_from_control
    np.testing.assert_allclose(m["cog"].position, control_to_world(wfc, snap.cog_world), atol=1e-6)
    model = robot.host.plant.model
    gait = snap.reference.gait
    for k, (body, p_plan) in enumerate((("RLEG_LINK5", gait.p_rsole_world), ("LLEG_LINK5", gait.p_lsole_world))):
        b = model.body(body).id
        w, x, y, z = snap.truth.body_quat_wxyz[b]
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        leg = ("rleg", "lleg")[k]
        true = footstep_rectangles([{"leg": leg, "pos": snap.truth.body_pos_world[b], "yaw": yaw}], 0.0)[:, 0, :2]
        drawn = m["soles"].points[4 * k:4 * k + 4, 0, :2]
        off_mm = 1e3 * np.abs(drawn - true).max()
        unplaced_mm = 1e3 * np.abs(np.asarray(p_plan[:2]) - snap.truth.body_pos_world[b][:2]).max()
        print(f"{leg}: drawn {off_mm:.1f} mm from the simulated foot, the plan's frame {unplaced_mm:.1f} mm")
        assert off_mm < SOLES_FROM_FEET_MM
        assert unplaced_mm > 4 * SOLES_FROM_FEET_MM  # what the placing corrects (the test can tell)
