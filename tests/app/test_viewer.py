"""The viser view: one frame per body, poses follow the simulation, the E-STOP button engages the stop."""

import numpy as np
import pytest

from app.runtime import Runtime
from app.viewer import Viewer


@pytest.fixture
def viewer():
    rt = Runtime(speed=None)
    v = Viewer(rt, host="127.0.0.1", port=0, rate_hz=50.0)
    yield v
    v.stop()


def test_every_body_gets_a_frame_placed_at_its_simulated_pose(viewer):
    model = viewer.runtime.loop.plant.model
    assert len(viewer._frames) == model.nbody - 1
    viewer.runtime.loop.run_for(0.1)
    viewer._apply_poses(viewer.runtime.loop.snapshot.truth)
    np.testing.assert_allclose(viewer._frames[0].position, viewer.runtime.loop.snapshot.truth.body_pos_world[1])


def test_the_estop_and_release_buttons_go_through_the_loop(viewer):
    loop = viewer.runtime.loop
    viewer._command("engaged", lambda lp: lp.chain["hes"].engage())
    loop.step()
    assert loop.snapshot.emergency["hard_stop"] is True
    viewer._command("released", lambda lp: lp.chain["hes"].release())
    viewer._command("released", lambda lp: lp.chain["hes"].release())
    assert "not engaged" in viewer._message.value


def test_the_cp_error_plot_and_the_balance_markers_are_built_and_follow_the_snapshots(viewer):
    from app.viewer import MAX_FOOTSTEPS

    loop = viewer.runtime.loop
    assert viewer._cp_plot is not None and len(viewer._cp_plot.data) == 5
    assert set(viewer._markers) == {"cog", "zmp", "cp_ref", "cp_act", "support", "soles", "footsteps"}
    for _ in range(5):
        loop.run_for(0.05)
        snap = loop.snapshot
        viewer.apply_snapshot(snap)
        viewer._update_plot(snap)
    snap = loop.snapshot
    m = viewer._markers
    np.testing.assert_allclose(m["cog"].position, snap.cog_world, atol=1e-6)
    st = snap.layers["st"]
    np.testing.assert_allclose(m["cp_act"].position[:2], st["cp_act"], atol=1e-6)
    np.testing.assert_allclose(m["cp_ref"].position[:2], st["cp_ref"], atol=1e-6)
    assert m["support"].visible and m["soles"].visible and not m["footsteps"].visible
    assert m["support"].points.shape == (8, 2, 3)
    # the support polygon (both feet down) surrounds the midpoint of the soles
    gait = snap.reference.gait
    mid = 0.5 * (np.asarray(gait.p_rsole_world[:2]) + np.asarray(gait.p_lsole_world[:2]))
    pts = m["support"].points[:, 0, :2]
    assert pts[:, 0].min() < mid[0] < pts[:, 0].max() and pts[:, 1].min() < mid[1] < pts[:, 1].max()
    t, ex, ey, hi, lo = viewer._cp_plot.data
    assert len(t) >= 5 and np.all(np.diff(t) > 0) and t[-1] == pytest.approx(snap.time_s)  # + thread samples
    assert ex[-1] == pytest.approx(1e3 * st["cp_error"][0]) and ey[-1] == pytest.approx(1e3 * st["cp_error"][1])
    np.testing.assert_allclose(hi, 1e3 * st["threshold"])
    np.testing.assert_allclose(lo, -hi)
    handles = dict(m)
    # planned footsteps from the AutoBalancer status, when it exposes them: same handles, now shown
    import dataclasses

    steps = [{"leg": "rleg", "pos": [0.1, -0.1, 0.0], "yaw": 0.0}, {"leg": "lleg", "pos": [0.2, 0.1, 0.0], "yaw": 0.1}]
    layers = dict(snap.layers)
    layers["abc"] = {**layers["abc"], "footsteps": steps}
    viewer.apply_snapshot(dataclasses.replace(snap, layers=layers))
    assert m["footsteps"].visible and m["footsteps"].points.shape == (4 * MAX_FOOTSTEPS, 2, 3)
    assert viewer._markers == handles and all(viewer._markers[k] is handles[k] for k in handles)


def test_the_cp_history_keeps_a_time_window_and_clears_on_reset():
    from types import SimpleNamespace

    from app.viewer import CpErrorHistory

    h = CpErrorHistory(window_s=1.0)
    st = {"cp_error": [0.01, -0.02], "threshold": 0.04}
    for i in range(30):
        assert h.add(SimpleNamespace(time_s=0.1 * i, layers={"st": st}))
    t, ex, ey, hi, lo = h.data()
    assert t[-1] - t[0] <= 1.0 + 1e-9 and ex[0] == pytest.approx(10.0) and ey[0] == pytest.approx(-20.0)
    assert hi[0] == pytest.approx(40.0) and lo[0] == pytest.approx(-40.0)
    assert not h.add(SimpleNamespace(time_s=5.0, layers={}))
    h.add(SimpleNamespace(time_s=0.0, layers={"st": st}))
    assert len(h) == 1
