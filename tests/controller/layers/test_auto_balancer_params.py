"""AutoBalancer parameters at run time: new preview weights (preview_q / preview_r) are solved off the control
thread and swapped in at a standstill after PREVIEW_GAINS_DELAY_S, the COG plan continuous across the swap."""

import numpy as np

from controller.core.types import WalkCommand
from controller.layers.auto_balancer import PREVIEW_GAINS_DELAY_S
from tests.controller.layers.test_auto_balancer_walk_point import DT, Ticker


def _cog_xy(t: Ticker) -> np.ndarray:
    return t.abc.last_gait.cog_pc_world[:2].copy()


def test_new_preview_weights_apply_at_a_standstill_after_the_stated_delay_without_a_cog_jump():
    t = Ticker()
    old_gains = t.abc.preview.gains
    t.abc.set_params(t.abc.params.replaced(preview_q=10.0))
    assert t.run(PREVIEW_GAINS_DELAY_S - 2 * DT, None).preview_gains == "pending"
    assert t.abc.preview.params.q == 1.0
    before = _cog_xy(t)
    assert t.run(3 * DT, None).preview_gains == "current"
    assert t.abc.preview.params.q == 10.0
    assert not np.allclose(t.abc.preview.gains.ks, old_gains.ks)  # other weights: other gains
    # standing still: the planned COG moves by less than 0.01 mm across the swap (it is at rest)
    assert np.linalg.norm(_cog_xy(t) - before) < 1e-5


def test_a_walk_keeps_the_gains_it_started_with_and_the_new_ones_come_when_it_has_stopped():
    t = Ticker()
    t.run(0.1, WalkCommand(0.1, 0.0, 0.0))
    t.abc.set_params(t.abc.params.replaced(preview_r=1e-5))
    assert t.run(1.0, WalkCommand(0.1, 0.0, 0.0)).preview_gains == "pending"
    assert t.abc.preview.params.r == 1e-6 and t.abc.gait.walking
    for _ in range(40):  # stop the walk: pending until the feet are together and the gait has ended
        t.run(0.25, None)
        if not t.abc.gait.walking:
            break
    t.run(2 * DT, None)
    assert t.abc.status().preview_gains == "current" and t.abc.preview.params.r == 1e-5
