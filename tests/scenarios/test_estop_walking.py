"""The hard e-stop in the middle of a walk: the command freezes, the walk behind it holds (the plan does
not run on), commands sent meanwhile are refused, and after the release the robot puts its swing foot
down, brings its weight between the feet and stands for 10 s, facing where it faced, its capture-point
error under the Stabilizer's threshold (40 mm) the whole time.

The hard e-stop freezes the joints after the Stabilizer ([MLC]'s chain order), so nothing balances during
the hold: frozen late in the right foot's support with the COG moving left, the robot tips onto its swing
foot and rests there, rolled 6-7 deg. At the release the balance layers resume at once (the blend carries
their motion) and the AutoBalancer sees its plan rotated by the measured tilt about the support sole,
levelling it as the swing foot lands (TiltAnchor), at most 0.03 rad/s so that the KalmanFilter's accelerometer
keeps the attitude right (7.6 s for 7 deg). Before, the plan still had the COG over the right sole and
the CP error peaked at 56-149 mm (the release itself 104-117 mm), though the robot stood; levelling in 2 s,
42 and 58 mm at the worst instants (the estimate lagged the turning robot by 0.5 deg and caught up in a jump).

Measured on this machine (e-stop at 11 instants of one step, 1.80-2.60 s into the walk at 0.2 m/s, and at 9
instants 2.0-3.0 s into a 0.1 m/s walk turning 10 deg/s; 3 s hold; 10 s after the release): the robot stood
every time, yaw change 0.25 deg at most; frozen in double support the CP error peaks under 6 mm, on one foot at
23-36 mm (the cases below: 30, 3, 23, 3, 32, 36 and 34 mm). With the LIP prediction of the COG velocity while
walking (issue 13.2) the cases below peak at 21.6, 3.8, 16.3, 3.5, 31.7, 35.5 and 28.6 mm (the sweep of 20
instants not redone).

Issue 25: a swing whose foot is down within the e-stop's landing_max_s (0.35 s) of the press lands first, and the
command freezes at its touchdown, in double support: the first case below (the right foot down 0.1 s after the
press) now peaks at 2 mm, and three presses 0.1, 0.2 and 0.3 s before a touchdown at 3 mm. Soak seed 10705: a
swing landing later is cut short (the AutoBalancer's catch lands it within 0.25 s where the capture point will be)
instead of frozen in the air; the single-support cases above then freeze on both feet, and peak at 3 mm where they
tipped (15-36 mm)."""

import math
import random

import numpy as np
import pytest

from app.lab.study.estop_walking import HOLDS_S, WALKS, EstopSpec, grid, run_estop
from app.service import OperatorService, Refused
from app.service.local import LocalRobot
from controller.kinematics.rotations import matrix_to_rpy, quat_wxyz_to_matrix
from controller.layers.hard_emergency_stopper import HardEmergencyStopperParams
from controller.layers.stabilizer import StabilizerParams

THRESHOLD_M = StabilizerParams().cp_threshold_m
LANDING_MAX_S = HardEmergencyStopperParams().landing_max_s
HOLD_S = 3.0
STAND_S = 10.0
MAX_YAW_CHANGE_DEG = 2.0
#: half the 0.2 m stride: the COG goes to the middle of the feet, which stay where they are
MAX_BODY_SHIFT_M = 0.12


def yaw_deg(quat_wxyz) -> float:
    return math.degrees(matrix_to_rpy(quat_wxyz_to_matrix(np.asarray(quat_wxyz, dtype=float)))[2])


@pytest.mark.slow
@pytest.mark.parametrize(("vx", "vtheta_deg", "walk_s", "phase"), [
    (0.2, 0.0, 1.8, "lleg"),  # on the left foot, the right swinging: it lands 0.1 s after the press, then freezes
    (0.2, 0.0, 2.0, "both"),  # frozen in the double support between two steps
    (0.1, 10.0, 2.2, "rleg"),  # turning, frozen on the right foot
    (0.1, 10.0, 3.0, "both"),
    (0.2, 0.0, 2.25, "rleg"),  # late on the right foot: the robot tips onto its swing foot (32 mm)
    (0.2, 0.0, 2.3, "rleg"),  # the worst instant swept (36 mm; 120 mm before the tilt anchor)
    (0.1, 10.0, 2.3, "rleg"),  # turning, tipped (34 mm; 58 mm levelling in 2 s)
    # the left foot swinging, down 0.3, 0.2 and 0.1 s after the press: it lands, then the command freezes
    (0.2, 0.0, 2.6, "rleg"),
    (0.2, 0.0, 2.7, "rleg"),
    (0.2, 0.0, 2.8, "rleg"),
], ids=["0.2m_s-single", "0.2m_s-double", "0.1m_s-turning-single", "0.1m_s-turning-double",
        "0.2m_s-single-late-tipped", "0.2m_s-single-late", "0.1m_s-turning-single-late",
        "0.2m_s-swing-lands-0.3s", "0.2m_s-swing-lands-0.2s", "0.2m_s-swing-lands-0.1s"])
def test_estop_mid_walk_holds_and_after_release_the_robot_stands_where_it_is(vx, vtheta_deg, walk_s, phase):
    robot = LocalRobot()
    service = OperatorService(robot)
    # 1. walk
    robot.run_for(2.5)
    service.go_velocity(vx, 0.0, math.radians(vtheta_deg))
    robot.run_for(walk_s)
    assert robot.loop.snapshot.reference.gait.support == phase
    # 2. e-stop: a swing whose foot is down within LANDING_MAX_S lands first, then the command freezes (at once
    # otherwise), and the walk does not run on behind it
    service.estop()
    t_press = robot.loop.snapshot.time_s
    snap = robot.run_until(lambda s: s.layers["hes"].stopping is None, timeout_s=LANDING_MAX_S + 0.01)
    freeze_s = snap.time_s - t_press
    if freeze_s > 1.5 * robot.loop.dt_control_s:  # it let the swing land: the freeze comes in the double support
        assert snap.reference.gait.support == "both" and freeze_s <= LANDING_MAX_S + 1e-9
    robot.run_for(0.05)
    frozen = np.array(robot.loop.snapshot.q_cmd_rad)
    abc = robot.loop.snapshot.layers["abc"]
    planned_feet = [f.pos for f in abc.footsteps]
    robot.run_for(HOLD_S - 0.05 - freeze_s)
    snap = robot.host.observation
    assert np.max(np.abs(snap.q_cmd_rad - frozen)) < 1e-9
    assert [f.pos for f in snap.layers["abc"].footsteps] == planned_feet  # nothing consumed while held
    assert snap.layers["abc"].walking_stop and len(planned_feet) <= 1  # cut to a stop: at most the landing
    # 3. commands sent during the e-stop are refused and none runs after the release
    for verb in (lambda: service.go_pos(0.5, 0.0, 0.0), lambda: service.go_velocity(0.2, 0.0, 0.0)):
        with pytest.raises(Refused):
            verb()
    yaw0 = yaw_deg(snap.truth.base_quat_wxyz)
    base0 = np.array(snap.truth.base_pos_world)
    # 4. release, then stand for 10 s
    service.release_estop()
    errors, t_release = [], snap.time_s
    for _ in range(int(round(STAND_S / robot.loop.dt_control_s))):
        snap = robot.step()
        assert not snap.fallen, f"fell {snap.time_s - t_release:.2f} s after the release"
        errors.append((snap.time_s - t_release, snap.layers["st"].cp_error_norm))
    t, err = np.array(errors).T
    assert abs(yaw_deg(snap.truth.base_quat_wxyz) - yaw0) < MAX_YAW_CHANGE_DEG
    assert not snap.safety.hard_stop
    # the cut walk's stop ends in place (a tipped robot levels slowly: up to 7.6 s and the 2 s double support)
    snap = robot.run_until(lambda s: not s.layers["abc"].walking, timeout_s=3.0)
    # the robot stands where it stopped: no step of the walk it was on (the body only moves between the feet)
    assert np.linalg.norm(np.array(snap.truth.base_pos_world[:2]) - base0[:2]) < MAX_BODY_SHIFT_M
    print(f"\n{vx} m/s, {vtheta_deg} deg/s, pressed in {phase}, frozen {freeze_s:.3f} s later: CP error peak "
          f"{err.max() * 1e3:.0f} mm "
          f"{t[err.argmax()]:.2f} s after the release")
    assert err.max() < THRESHOLD_M, f"CP error peak {err.max() * 1e3:.0f} mm at {t[err.argmax()]:.2f} s"


#: a seeded sample of `hrp2-console study estop-walking`'s grid (4 walks x 16 phases of the gait cycle x holds of
#: 0.3, 1.25 and 3 s; the whole grid and its figures: docs/safety-path.md), and the grid's one fall before (soak
#: seed 10705's kind: a sideways walk e-stopped on the left foot, its swing frozen in the air, fell after the release)
SAMPLE = [*random.Random(10705).sample(grid(WALKS, 16, HOLDS_S), 10), EstopSpec("side", 0.6875, 0.3)]
#: [s] a hold after which the frozen robot has settled: released then, the CP error peaks at 22 mm at most in the
#: grid (1.25 and 3 s holds), under the Stabilizer's threshold (the flag does not rise)
SETTLED_HOLD_S = 1.0


@pytest.mark.slow
@pytest.mark.parametrize("spec", SAMPLE, ids=[f"{s.walk}-phase{s.phase:g}-hold{s.hold_s:g}s" for s in SAMPLE])
def test_an_estop_at_any_moment_of_a_walk_freezes_the_robot_on_both_feet_and_it_stands_after_the_release(spec):
    """A swing that would land later than landing_max_s is cut short (the AutoBalancer's catch lands it where the
    capture point will be), so the command freezes with both feet down, never with one in the air."""
    r = run_estop(spec.to_dict())["result"]
    assert r["outcome"] == "stood", r
    if spec.hold_s > LANDING_MAX_S:  # (a shorter hold releases it while it lands)
        assert r["support_frozen"] == "both" and r["frozen_after_s"] <= LANDING_MAX_S + 1e-9, r
    if spec.hold_s >= SETTLED_HOLD_S:
        assert r["peak_cp_error_m"] < THRESHOLD_M and not r["flag"], r
