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
