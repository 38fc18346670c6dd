"""Perception in the EXPO scene [OP VI] as the robot does it: it walks to the table, turns its head, renders
its narrow camera, and places what it sees through its own estimate of the camera pose (encoders, KalmanFilter
attitude, leg odometry). The simulator's poses only measure the error.

1. The robot stands 2.5 s, walks 1.0 m towards the table (go_pos) and stops, BODY 1.0 m from the near edge.
2. For each of five head yaws (pitch 25 deg down) it settles, takes its camera-pose estimate from the snapshot,
   and for each of 20 can placements (simulator operations, unknown to the robot) renders the plant's state
   and runs locate_can. Per placement the view with the most can pixels not cut by the border counts.
3. It walks 0.4 m on and turns 90 deg right to face the trash box about 2 m away, and locates the hole.

Errors are stated two ways: in the world (what the issue asks, and what the map and the operator's 3D view
share; it includes the leg odometry's error over the walk) and in the robot's own frame (where the can is
relative to BODY, estimated vs true: what reaching for it needs; the odometry error cancels). Before leg
odometry the world errors were the gait plan's: 17 mm for the can after 1.0 m, 38 mm for the box."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import robot.generate as gen
from app.service.local import LocalRobot
from behaviors.perception import locate_can, locate_trash_box
from behaviors.perception.head_pose import T_world_body_estimate, T_world_camera_estimate
from controller.kinematics.model import RobotKinematics
from robot.camera import CameraRig

pytestmark = pytest.mark.slow

CAMERA = "narrow_left"
WALK_TO_TABLE_M = 1.0
HEAD_PITCH_DEG = 25.0
SCAN_HEAD_YAWS_DEG = (-30.0, -15.0, 0.0, 15.0, 30.0)
HEAD_MOVE_S = 1.0
HEAD_SETTLE_S = 0.5
PLACEMENTS = 20
PLACEMENT_SEED = 2005
#: Measured over the 20 seeded placements, in the robot's frame: median 0.2 mm, max 0.2 mm (ideal depth); in the
#: world median 2.3 mm, max 3.0 mm (leg odometry after the 1.0 m walk: BODY 0.8 mm off, and its heading
#: 0.04 deg; with the gait plan's odometry it was 17.2 / 17.3 mm).
#: Required [issue 11]: < 15 mm.
CAN_ERROR_LIMIT_M = 0.015
#: What the world error may grow to before this test says so: the 3.0 mm measured plus 2 mm.
CAN_WORLD_ERROR_BOUND_M = 0.005
#: The first 5 placements again with 1 px of stereo disparity noise (9 mm of depth noise at 1.2 m): max 3.5 mm.
NOISY_PLACEMENTS = 5
DISPARITY_NOISE_PX = 1.0
#: To the trash box: walk 0.4 m on to (1.4, 0) and turn -90 deg; head pitched 20 deg down, about 2 m away.
BOX_WALK = (0.4, 0.0, -math.pi / 2)
BOX_HEAD_PITCH_DEG = 20.0
#: Measured from 1.98 m after 1.4 m and a 90 deg turn: hole centre 3.3 mm off in the world, 1.0 mm relative to
#: the estimated BODY (4.6 and 2.4 mm before the F/T weight compensation was fixed; with the gait plan's odometry:
#: 37.7 mm and 0.2 mm); required [issue 11]: < 20 mm. Yaw allowed 1 deg.
BOX_ERROR_LIMIT_M = 0.020
#: What the world error may grow to before this test says so: the 3.3 mm measured plus 3.4 mm.
BOX_WORLD_ERROR_BOUND_M = 0.0067
BOX_YAW_LIMIT_DEG = 1.0


def T_from_truth(truth) -> np.ndarray:
    T = np.eye(4)
    w, x, y, z = truth.base_quat_wxyz
    T[:3, :3] = Rotation.from_quat([x, y, z, w]).as_matrix()
    T[:3, 3] = truth.base_pos_world
    return T


def in_frame(T_world_frame: np.ndarray, p_world) -> np.ndarray:
    return np.linalg.solve(T_world_frame, np.append(p_world, 1.0))[:3]


class Robot:
    """The simulated HRP-2 with its controller in the EXPO scene, and its own estimates from the snapshot."""

    def __init__(self) -> None:
        self.sim = LocalRobot("expo")
        self.kin = RobotKinematics()  # perception's own model (the controller's belongs to the loop)
        self.sim.run_for(2.5)

    def walk(self, dx_m: float, dy_m: float, dtheta_rad: float) -> None:
        abc = self.sim.chain["abc"]
        self.sim.loop.submit(lambda: abc.go_pos(dx_m, dy_m, dtheta_rad))
        self.sim.run_for(0.1)
        for _ in range(60):
            if not abc.gait.walking:
                break
            obs = self.sim.run_for(0.5)
            assert not obs.fallen
        assert not abc.gait.walking
        self.sim.run_for(1.0)

    def look(self, yaw_deg: float, pitch_deg: float) -> None:
        seq = self.sim.chain["seq"]
        q = np.radians([yaw_deg, pitch_deg])
        self.sim.loop.submit(lambda: seq.set_joint_angles_of_group("head", q, HEAD_MOVE_S))
        obs = self.sim.run_for(HEAD_MOVE_S + HEAD_SETTLE_S)
        assert not obs.fallen

    def estimates(self) -> tuple[np.ndarray, np.ndarray]:
        """(T_world_camera, T_world_body) as the robot estimates them now: the snapshot's, no ground truth."""
        snap = self.sim.host.observation.snapshot
        args = (snap.q_meas_rad, snap.base_rpy_est_rad, snap.odometry)
        return T_world_camera_estimate(self.kin, *args, CAMERA), T_world_body_estimate(self.kin, *args)

    @property
    def T_world_body_true(self) -> np.ndarray:
        return T_from_truth(self.sim.host.observation.truth)


def at_border(r, k) -> bool:
    u0, v0, u1, v1 = r.bbox_px
    return u0 <= 0 or v0 <= 0 or u1 >= k.width - 1 or v1 >= k.height - 1


def can_placements(n: int, seed: int) -> list[tuple[float, float, float]]:
    """(x, y, yaw) along the near edge, 0.10-0.30 m in, anywhere the narrow camera's scan covers."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        from_edge_m = rng.uniform(*gen.EXPO_CAN_FROM_EDGE_RANGE_M)
        out.append((gen.EXPO_TABLE_NEAR_EDGE_X_M + from_edge_m, rng.uniform(-0.65, 0.65),
                    rng.uniform(-math.pi, math.pi)))
    return out


@pytest.fixture(scope="module")
def expo_run():
    robot = Robot()
    robot.walk(WALK_TO_TABLE_M, 0.0, 0.0)
    plant = robot.sim.plant
    placements = can_placements(PLACEMENTS, PLACEMENT_SEED)
    best: list[dict | None] = [None] * PLACEMENTS
    noisy_best: list[dict | None] = [None] * NOISY_PLACEMENTS
    with CameraRig("expo", cameras=(CAMERA,)) as rig, \
            CameraRig("expo", cameras=(CAMERA,), disparity_noise_px=DISPARITY_NOISE_PX, seed=7) as noisy_rig:
        for yaw_deg in SCAN_HEAD_YAWS_DEG:
            robot.look(yaw_deg, HEAD_PITCH_DEG)
            T_world_camera, T_world_body = robot.estimates()
            T_world_body_true = robot.T_world_body_true
            for i, (x, y, yaw) in enumerate(placements):
                true_m = plant.place_object("can", (x, y), yaw_rad=yaw)  # the robot is not told
                views = [(best, rig.request_state_of(plant.data))]
                if i < NOISY_PLACEMENTS:
                    views.append((noisy_best, noisy_rig.request_state_of(plant.data)))
                for table, future in views:
                    image = future.result()[CAMERA]
                    r = locate_can(image.rgb, image.depth_m, image.intrinsics, T_world_camera)
                    if r is None or at_border(r, image.intrinsics):
                        continue
                    if table[i] is None or r.n_pixels > table[i]["r"].n_pixels:
                        table[i] = {"r": r, "true_m": true_m, "image": image, "T_world_camera": T_world_camera,
                                    "T_world_body": T_world_body, "T_world_body_true": T_world_body_true}
        plant.place_object("can", placements[0][:2])  # out of the way of nothing: back on the table
        robot.walk(*BOX_WALK)
        robot.look(0.0, BOX_HEAD_PITCH_DEG)
        T_world_camera, T_world_body = robot.estimates()
        frames = rig.request_state_of(plant.data).result()
        box = {"image": frames[CAMERA], "T_world_camera": T_world_camera, "T_world_body": T_world_body,
               "T_world_body_true": robot.T_world_body_true,
               "camera_true_m": frames.T_world_camera_true[CAMERA][:3, 3]}
    return {"cans": best, "noisy": noisy_best, "box": box}


def robot_frame_error_m(run: dict, true_world_m) -> float:
    """|can relative to BODY, estimated - true| [m]: the estimate through the robot's own BODY estimate."""
    estimated = in_frame(run["T_world_body"], run["r"].position_world_m)
    true = in_frame(run["T_world_body_true"], true_world_m)
    return float(np.linalg.norm(estimated - true))


def test_the_can_is_located_within_15_mm_at_20_random_places_on_the_table(expo_run):
    runs = expo_run["cans"]
    missing = [i for i, run in enumerate(runs) if run is None]
    assert not missing, f"placements {missing} not seen whole from any head yaw"
    errors_m = np.array([robot_frame_error_m(run, run["true_m"]) for run in runs])
    world_m = np.array([np.linalg.norm(run["r"].position_world_m - run["true_m"]) for run in runs])
    odometry_m = np.array([np.linalg.norm(run["T_world_body"][:3, 3] - run["T_world_body_true"][:3, 3])
                           for run in runs])
    figures = (f"robot frame: median {1e3 * np.median(errors_m):.1f} mm, max {1e3 * errors_m.max():.1f} mm; "
               f"world: median {1e3 * np.median(world_m):.1f} mm, max {1e3 * world_m.max():.1f} mm; "
               f"BODY odometry error {1e3 * odometry_m.max():.1f} mm")
    print(figures)
    assert float(errors_m.max()) < CAN_ERROR_LIMIT_M, figures
    assert float(world_m.max()) < CAN_ERROR_LIMIT_M, figures
    assert float(world_m.max()) < CAN_WORLD_ERROR_BOUND_M, figures


def test_the_can_is_located_within_15_mm_with_stereo_depth_noise(expo_run):
    runs = expo_run["noisy"]
    assert all(run is not None for run in runs)
    errors_m = [robot_frame_error_m(run, run["true_m"]) for run in runs]
    print(f"1 px disparity noise: max {1e3 * max(errors_m):.1f} mm")
    assert max(errors_m) < CAN_ERROR_LIMIT_M


def test_a_can_recognition_carries_its_image_region_pixels_and_uncertainty(expo_run):
    run = expo_run["cans"][0]
    r, k = run["r"], run["image"].intrinsics
    u0, v0, u1, v1 = r.bbox_px
    assert 0 <= u0 < u1 < k.width and 0 <= v0 < v1 < k.height
    assert r.object_name == "can" and r.yaw_rad == 0.0
    assert 1000 < r.n_pixels <= (u1 - u0 + 1) * (v1 - v0 + 1)
    np.testing.assert_allclose(r.covariance_m2, r.covariance_m2.T)
    assert np.all(np.linalg.eigvalsh(r.covariance_m2) > 0)
    assert not r.position_world_m.flags.writeable


def rotation_x(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def test_an_error_in_the_estimated_camera_pose_moves_the_can_as_the_pose_error_predicts(expo_run):
    run = expo_run["cans"][0]
    image, T_est = run["image"], run["T_world_camera"]
    delta = np.eye(4)  # 1 deg of pitch and a few mm more error, in the camera frame
    delta[:3, :3] = rotation_x(math.radians(1.0))
    delta[:3, 3] = [0.003, -0.002, 0.004]
    T_worse = T_est @ delta
    r = locate_can(image.rgb, image.depth_m, image.intrinsics, T_worse)
    predicted_m = (T_worse @ np.linalg.inv(T_est) @ np.append(run["r"].position_world_m, 1.0))[:3]
    assert np.linalg.norm(predicted_m - run["r"].position_world_m) > 0.010  # 1 deg at ~1 m: over a centimetre
    np.testing.assert_allclose(r.position_world_m, predicted_m, atol=0.001)


def test_the_trash_box_hole_is_located_within_20_mm_from_about_2_m(expo_run):
    box = expo_run["box"]
    image = box["image"]
    r = locate_trash_box(image.rgb, image.depth_m, image.intrinsics, box["T_world_camera"], time_s=3.5)
    hole_m = np.array([*gen.TRASH_BOX_CENTRE_M, gen.TRASH_BOX_OUTER_M[2]])
    distance_m = float(np.linalg.norm(box["camera_true_m"] - hole_m))
    assert distance_m == pytest.approx(2.0, abs=0.25)
    assert r is not None and r.object_name == "trash_box" and r.time_s == 3.5
    error_m = np.linalg.norm(in_frame(box["T_world_body"], r.position_world_m)
                             - in_frame(box["T_world_body_true"], hole_m))
    print(f"trash box from {distance_m:.2f} m: hole centre {1e3 * error_m:.1f} mm off in the robot's frame, "
          f"{1e3 * np.linalg.norm(r.position_world_m - hole_m):.1f} mm in the world")
    assert error_m < BOX_ERROR_LIMIT_M
    assert np.linalg.norm(r.position_world_m - hole_m) < min(BOX_ERROR_LIMIT_M, BOX_WORLD_ERROR_BOUND_M)
    body_yaw_est = math.atan2(box["T_world_body"][1, 0], box["T_world_body"][0, 0])
    body_yaw_true = math.atan2(box["T_world_body_true"][1, 0], box["T_world_body_true"][0, 0])
    yaw_error = (r.yaw_rad - body_yaw_est) - (0.0 - body_yaw_true)  # the hole's long side relative to BODY
    yaw_error = (yaw_error + math.pi / 2) % math.pi - math.pi / 2  # a rectangle's yaw is modulo 180 deg
    assert abs(math.degrees(yaw_error)) < BOX_YAW_LIMIT_DEG
