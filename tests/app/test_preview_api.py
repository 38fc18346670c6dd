"""The preview API (in process): a walk_to preview from the AutoBalancer's own planner, what it answers to bad
input, a run in step mode and its step route's errors, and the 3D view's ghost built from a preview."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.console.viewer_preview import MAX_GHOST_SEGMENTS, PreviewGhost, ghost_segments

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

WARM_UP_S = 2.5  # [s] the AutoBalancer blends in


def test_a_walk_to_preview_plans_side_by_side_feet_at_the_goal_and_moves_nothing(client, runtime):
    runtime.run_for(WARM_UP_S)
    r = client.post("/api/behaviors/walk_to/preview", json={"x_m": 0.4, "y_m": -0.1, "theta_deg": 20.0})
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["complete"] and d["phases"] == [{"phase": "walk_to", "behavior": "walk_to"}]
    right = next(s for s in reversed(d["footsteps"]) if s["side"] == "right")
    left = next(s for s in reversed(d["footsteps"]) if s["side"] == "left")
    mid = ((right["x_m"] + left["x_m"]) / 2, (right["y_m"] + left["y_m"]) / 2)
    assert math.dist(mid, (0.4, -0.1)) < 0.02  # from where the robot stands (about the origin)
    assert abs(right["yaw_rad"] - math.radians(20.0)) < 1e-3 and abs(left["yaw_rad"] - math.radians(20.0)) < 1e-3
    assert math.dist((right["x_m"], right["y_m"]), (left["x_m"], left["y_m"])) > 0.15  # side by side, not stacked
    assert client.get("/api/state").json()["runs"] == []  # nothing started
    assert not runtime.host.layer("abc").gait.walking
    assert client.delete("/api/behaviors/preview").status_code == 200


def test_bad_preview_and_step_requests_say_what_is_wrong(client, runtime):
    r = client.post("/api/behaviors/walk_to/preview", json={"x_m": 30.0})
    assert r.status_code == 422 and r.json()["field"] == "x_m"
    r = client.post("/api/behaviors/dance/preview", json={})
    assert r.status_code == 404 and "unknown behaviour 'dance'" in r.json()["detail"]
    r = client.post("/api/behaviors/squat?mode=jump", json={})
    assert r.status_code == 422 and r.json()["field"] == "mode"
    r = client.post("/api/behaviors/runs/77/step")
    assert r.status_code == 404
    runtime.run_for(WARM_UP_S)
    run_id = client.post("/api/behaviors/squat", json={"depth_m": 0.02}).json()["id"]
    r = client.post(f"/api/behaviors/runs/{run_id}/step")
    assert r.status_code == 409 and "mode 'run'" in r.json()["detail"]


def test_a_reach_in_step_mode_is_one_phase_and_runs_at_once(client, runtime):
    runtime.run_for(WARM_UP_S)
    r = client.post("/api/behaviors/reach?mode=step", json={"x_m": 0.3, "y_m": -0.3, "z_m": 0.75})
    assert r.status_code == 200, r.text
    runtime.run_for(0.5)
    run = client.get(f"/api/behaviors/runs/{r.json()['id']}").json()
    assert run["mode"] == "step" and not run["waiting"] and run["progress"] > 0.0


class _Handle:
    def __init__(self, points):
        self.points, self.visible = points, False


class _Scene:
    def add_line_segments(self, name, points, color, thickness, visible):
        return _Handle(points)


def test_the_ghost_draws_each_footstep_and_hand_path_and_hides_when_cleared():
    preview = {"footsteps": [{"side": "right", "x_m": 0.0, "y_m": -0.1, "yaw_rad": 0.0},
                             {"side": "left", "x_m": 0.2, "y_m": 0.1, "yaw_rad": 0.3}],
               "hand_paths": [{"hand": "rhand", "points_m": [[0.1, -0.3, 0.6], [0.2, -0.3, 0.7], [0.3, -0.3, 0.8]]}]}
    feet, paths = ghost_segments(preview)
    assert feet.shape == (8, 2, 3) and paths.shape == (2, 2, 3)
    np.testing.assert_allclose(paths[-1, 1], (0.3, -0.3, 0.8))
    ghost = PreviewGhost(_Scene())
    ghost.update(1, preview)
    assert ghost.shown and ghost.feet.visible and ghost.paths.visible
    assert ghost.paths.points.shape == (MAX_GHOST_SEGMENTS, 2, 3)
    ghost.update(2, None)
    assert not ghost.shown and not ghost.feet.visible and not ghost.paths.visible
