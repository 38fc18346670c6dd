"""Issue 13.3: standing pushes on BODY (0.1 s) that the ankles cannot absorb are caught by the capture-point
emergency step; without it (AutoBalancer emergency_step off) the robot falls.

The largest impulses absorbed standing without a step (docs/measurements/walking-and-balance.md): 28 N s forward
(29 falls), 20 N s backward (21 falls), 40 N s sideways (41 falls). Tested: 1.5x and 2x the forward one rounded to
42 and 56 N s, 1.5x the backward one (30 N s) and 1.5x the sideways one (60 N s).

Measured (this machine; "e": the foot touched down before its planned time, where it was):

| push | without the step | with it | step (leg, landing x, y [m]) | worst tilt [deg] |
|---|---|---|---|---|
| 42 N s forward | falls | stands | 1: rleg (+0.356, -0.064) e | 2.4 |
| 56 N s forward | falls | stands | 1: rleg (+0.444, -0.067) e | 4.6 |
| 30 N s backward | falls | stands | 1: rleg (-0.246, -0.065) e | 1.9 |
| 60 N s sideways | falls | falls | 1: lleg (-0.01, +0.29) e, the CP 0.59 m out at touchdown | - |

With the step, forward 29-58 N s and backward 21-40 N s stand (60 and 42 fall). The step is 0.3 s long, reaches
0.55 m forward, and drives the legs at up to 4.5 rad/s (3.5 otherwise): with a 0.45 s step and 0.45 m of reach the
2x forward push fell (the CP 0.61 m ahead at touchdown, the foot 0.39 m out). Sideways nothing is gained: the
push carries the capture point past the loaded left foot's outer edge, so the left foot cannot be unloaded to step
out without the capture point running away faster (with the ZMP on the right sole it is 0.59 m out when the left
foot lands 0.29 m out), and only the right foot crossing over could catch it, which the hip's range does not
allow (the step never crosses). That case is a strict xfail below: a controller change that makes it stand shows
up.
"""

from dataclasses import dataclass

import numpy as np
import pytest

from tests.scenarios.helpers import make_system, tilt_deg

PUSH_S = 0.1  # the impulse is a constant force over 0.1 s
SETTLE_S = 2.5  # standing before the push (AutoBalancer and Stabilizer blended in)
AFTER_S = 4.5  # watched after the push: the step, its double supports and standing again
#: the measured tilt times this, and the measured landing +- LANDING_TOL_M: the simulation is deterministic on one
#: machine; the margins are for another machine's floating point and small controller changes
MARGIN = 1.3
LANDING_TOL_M = 0.03
#: [m] the CP error 1 s before the end, standing again on the feet apart (measured 0.6-1.0 mm)
SETTLED_CP_ERROR_M = 0.0035


@dataclass
class Outcome:
    fallen: bool
    worst_tilt_deg: float
    snaps: list

    @property
    def last(self):
        return self.snaps[-1]

    @property
    def steps(self):
        return self.last.layers["abc"].emergency_steps


def push(impulse_ns, step: bool = True) -> Outcome:
    """Stand SETTLE_S, push BODY with `impulse_ns` [N s] over PUSH_S, watch AFTER_S (or until the fall)."""
    system = make_system()
    loop = system.loop
    abc = system.chain["abc"]
    if not step:
        loop.call(lambda: abc.set_params(abc.params.replaced(**{"emergency_step.enabled": False})))
    loop.run_for(SETTLE_S)
    loop.call(lambda: loop.plant.push("BODY", np.asarray(impulse_ns, dtype=float) / PUSH_S, PUSH_S))
    snaps = []
    for _ in range(int(round(AFTER_S / loop.dt_control_s))):
        snaps.append(loop.step())
        if snaps[-1].fallen:
            break
    worst = max(tilt_deg(s.truth.base_quat_wxyz) for s in snaps)
    return Outcome(snaps[-1].fallen, worst, snaps)


CAUGHT = [  # impulse [N s], measured worst tilt [deg], measured landing (x, y) [m] of the one step (rleg)
    pytest.param((42.0, 0.0, 0.0), 2.4, (0.356, -0.064), id="forward-42Ns-1.5x"),
    pytest.param((56.0, 0.0, 0.0), 4.6, (0.444, -0.067), id="forward-56Ns-2x"),
    pytest.param((-30.0, 0.0, 0.0), 1.9, (-0.246, -0.065), id="backward-30Ns-1.5x"),
]


@pytest.mark.slow
@pytest.mark.parametrize("impulse, measured_tilt_deg, measured_landing", CAUGHT)
def test_one_emergency_step_catches_the_push_and_the_robot_stands_with_its_feet_apart(impulse, measured_tilt_deg,
                                                                                      measured_landing):
    r = push(impulse)
    # 1. it stands: the simulation's BODY never fell, its tilt stayed small
    assert not r.fallen
    assert r.worst_tilt_deg < MARGIN * measured_tilt_deg, f"worst tilt {r.worst_tilt_deg:.1f} deg"
    # 2. one step, with the less loaded leg, where the capture point went
    (step,) = r.steps
    assert step.leg == "rleg" and step.landed
    assert step.landing == pytest.approx(measured_landing, abs=LANDING_TOL_M), f"landed at {step.landing}"
    assert np.sign(step.landing[0]) == np.sign(impulse[0])
    # 3. standing again, the feet apart where they landed, the step over, the CP error that of standing
    last = r.last
    abc = last.layers["abc"]
    assert not abc.emergency_step and not abc.walking
    gait = last.reference.gait
    assert np.linalg.norm(gait.p_rsole_world[:2] - gait.p_lsole_world[:2]) > 0.25  # measured 0.30-0.47 m
    assert gait.p_rsole_world[:2] == pytest.approx(step.landing, abs=1e-9)
    truth_rfoot = last.truth.body_pos_world[7][:2]  # RLEG_LINK5, the ankle above the sole frame
    assert np.linalg.norm(truth_rfoot - np.asarray(step.landing)) < 0.03  # the foot is where the plan has it
    assert max(s.layers["st"].cp_error_norm for s in r.snaps[-200:]) < SETTLED_CP_ERROR_M
    # 4. the arms' motion stopped: the EmergencyStopper holds it (the CP flag rose first, in the push)
    es = last.layers["es"]
    assert es.stopped and es.reason in ("capture_point", "emergency_step")


@pytest.mark.slow
@pytest.mark.parametrize("impulse", [(42.0, 0.0, 0.0), (-30.0, 0.0, 0.0), (56.0, 0.0, 0.0), (0.0, 60.0, 0.0)],
                         ids=["forward-42Ns", "backward-30Ns", "forward-56Ns", "sideways-60Ns"])
def test_without_the_emergency_step_the_robot_falls(impulse):
    r = push(impulse, step=False)
    assert r.fallen
    assert r.steps == ()


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="not achieved: sideways the CP passes the loaded foot's outer edge, only a "
                                       "crossing step could catch it, and the step never crosses (measured: falls)")
def test_an_emergency_step_catches_one_and_a_half_times_the_largest_sideways_push_absorbed_without():
    r = push((0.0, 60.0, 0.0))
    assert len(r.steps) >= 1
    assert not r.fallen


def test_a_push_the_ankles_absorb_takes_no_step():
    # 20 N s forward (the trace's push): the CP stays 51 mm inside the toes, no step, as before issue 13.3
    r = push((20.0, 0.0, 0.0))
    assert not r.fallen
    assert r.steps == ()
