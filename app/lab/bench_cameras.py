"""Benchmarks of the head cameras: wall time to render what a recognition consumes, and of a whole recognition."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

#: Renders timed per run (after one untimed warm-up render).
RENDERS = 20
#: [OP VI] / issue 11: a recognition takes at most this much wall time on the 2-core machine [s].
RECOGNITION_GOAL_S = 0.3
#: The view timed: BODY 1.0 m before the table's near edge, head pitched 25 deg down (the can scan's view).
VIEW_BASE_X_M = 1.0
VIEW_HEAD_PITCH_DEG = 25.0

CAMERA_SCENARIOS = {
    "camera": f"the EXPO scene's narrow stereo pair with depth (640 x 480, EGL) rendered {RENDERS} times from "
              f"a copy of the plant state: wall time per rendering against the {RECOGNITION_GOAL_S} s "
              "recognition goal",
    "recognition": f"the standing robot recognises the can {RENDERS} times (render narrow_left colour + depth, "
                   "camera pose from its snapshot, locate_can): wall time per recognition against the "
                   f"{RECOGNITION_GOAL_S} s goal",
    "recognition-paced": "the console at real time (`--speed 1.0`, EXPO scene): tick start-lateness while standing "
                         "without recognitions, then while locate_can runs back to back for as long (issue 11: "
                         "the tick p99 with recognition equals the p99 without, no late tick)",
}


def _wall_stats_s(samples) -> dict[str, float]:
    a = np.asarray(samples, dtype=float)
    return {"median": round(float(np.median(a)), 4), "p90": round(float(np.percentile(a, 90)), 4),
            "max": round(float(a.max()), 4)}


def table_view_qpos(plant) -> np.ndarray:
    """The plant's home state with BODY at VIEW_BASE_X_M and the head pitched down (kinematics only)."""
    m = plant.model
    q = plant.data.qpos.copy()
    q[m.joint("root").qposadr[0]] = VIEW_BASE_X_M
    q[m.joint("HEAD_JOINT1").qposadr[0]] = math.radians(VIEW_HEAD_PITCH_DEG)
    return q


def run_camera_bench(renders: int = RENDERS) -> dict[str, Any]:
    """Render the narrow pair with depth `renders` times and report the wall time per rendering."""
    from robot.camera import CameraRig
    from robot.plant import MujocoPlant

    plant = MujocoPlant("expo")
    q = table_view_qpos(plant)
    d = plant.data
    cameras = ("narrow_left", "narrow_right")
    walls, inside = [], []
    with CameraRig("expo", cameras=cameras) as rig:
        rig.render(q, d.time, d.mocap_pos, d.mocap_quat)  # warm-up: first-frame GL setup
        for _ in range(renders):
            start = time.perf_counter()
            frames = rig.render(q, d.time, d.mocap_pos, d.mocap_quat)
            walls.append(time.perf_counter() - start)
            inside.append(frames.render_wall_s)
    median = float(np.median(walls))
    return {"scenario": "camera", "scene": "expo", "cameras": list(cameras), "size_px": [640, 480],
            "renders": renders, "wall_s": _wall_stats_s(walls), "render_thread_s": _wall_stats_s(inside),
            "goal_s": RECOGNITION_GOAL_S, "within_goal": median <= RECOGNITION_GOAL_S}


def run_recognition_bench(recognitions: int = RENDERS) -> dict[str, Any]:
    """The robot (controller running, standing at the start, head 25 deg down) recognises the can `recognitions`
    times: copy of the plant state -> narrow_left colour + depth -> camera pose from its snapshot -> locate_can.
    Reports the wall time per recognition and its parts."""
    from app.service import OperatorService
    from app.service.local import LocalRobot
    from behaviors.perception import locate_can
    from behaviors.perception.head_pose import T_world_camera_from_snapshot
    from controller.kinematics.model import RobotKinematics
    from robot.camera import CameraRig

    robot = LocalRobot("expo")
    robot.run_for(1.0)
    OperatorService(robot).set_group_sequence("head", [np.radians([0.0, VIEW_HEAD_PITCH_DEG])], [1.0])
    robot.run_for(1.5)
    kin = RobotKinematics()
    camera = "narrow_left"
    walls, renders, locates, found = [], [], [], 0
    with CameraRig("expo", cameras=(camera,)) as rig:
        rig.render(robot.plant.data.qpos, 0.0)  # warm-up
        for _ in range(recognitions):
            start = time.perf_counter()
            frames = rig.request_state_of(robot.plant.data).result()
            t_render = time.perf_counter()
            T_world_camera = T_world_camera_from_snapshot(kin, robot.host.observation.snapshot, camera)
            image = frames[camera]
            r = locate_can(image.rgb, image.depth_m, image.intrinsics, T_world_camera)
            end = time.perf_counter()
            walls.append(end - start)
            renders.append(t_render - start)
            locates.append(end - t_render)
            found += r is not None
    median = float(np.median(walls))
    return {"scenario": "recognition", "scene": "expo", "camera": camera, "recognitions": recognitions,
            "found": found, "wall_s": _wall_stats_s(walls), "render_s": _wall_stats_s(renders),
            "pose_and_locate_s": _wall_stats_s(locates), "goal_s": RECOGNITION_GOAL_S,
            "within_goal": median <= RECOGNITION_GOAL_S}


#: The can scan's view point for the paced bench: on the table's near half, at the table top's height (world) [m].
_LOOK_AT_TABLE_M = {"x_m": 2.15, "y_m": 0.0, "z_m": 0.75}


def _lateness(report: dict[str, Any]) -> dict[str, Any]:
    keys = ("ticks", "lateness_p50_ms", "lateness_p99_ms", "lateness_max_ms", "late_ticks_over_1ms", "speed_min")
    return {k: report[k] for k in keys}


def run_recognition_paced_bench(duration_s: float = 20.0) -> dict[str, Any]:
    """A real console at real time in the EXPO scene, the head on the table: the loop's tick start-lateness over
    `duration_s` of standing, then over `duration_s` of back-to-back locate_can runs (each renders the narrow
    pair on the render thread and fits on the perception thread), read from GET /api/loop/timing."""
    from app.lab.console_process import Console

    with Console("--speed", "1.0", "--scene", "expo") as console:
        conn = console.connection()

        def run(name: str, body: dict) -> dict:
            status, reply = console.request("POST", f"/api/behaviors/{name}", body=body, conn=conn)
            if status != 200:
                raise RuntimeError(f"{name}: {status} {reply}")
            while True:
                time.sleep(0.05)
                _, run_doc = console.request("GET", f"/api/behaviors/runs/{reply['id']}", conn=conn)
                if run_doc["state"] != "running":
                    return run_doc

        time.sleep(3.0)  # the AutoBalancer's start blend
        run("look_at", _LOOK_AT_TABLE_M)
        time.sleep(duration_s)
        _, without = console.request("GET", f"/api/loop/timing?last_s={duration_s:g}", conn=conn)
        start = time.monotonic()
        runs, found, per_run_max_ms = 0, 0, []
        while time.monotonic() - start < duration_s:
            run_start = time.monotonic()
            doc = run("locate_can", {**_LOOK_AT_TABLE_M, "views": 1})
            runs += 1
            found += doc["state"] == "succeeded"
            _, timing = console.request("GET", f"/api/loop/timing?last_s={time.monotonic() - run_start:.3f}",
                                        conn=conn)
            per_run_max_ms.append(timing["lateness_max_ms"])
        took_s = time.monotonic() - start
        _, with_ = console.request("GET", f"/api/loop/timing?last_s={took_s:.3f}", conn=conn)
        conn.close()
    return {"scenario": "recognition-paced", "scene": "expo", "duration_s": duration_s,
            "without_recognition": _lateness(without), "with_recognition": _lateness(with_),
            "locate_can_runs": runs, "found": found, "runs_per_s": round(runs / took_s, 2),
            "lateness_max_ms_per_run": per_run_max_ms}
