"""The hard e-stop in the middle of a walk: the command freezes, the walk behind it holds (the plan does
not run on), commands sent meanwhile are refused, and after the release the robot puts its swing foot
down, brings its weight between the feet and stands for 10 s, facing where it faced, its capture-point
error under the Stabilizer's threshold (40 mm) the whole time.

Measured on this machine (e-stop at 11 instants of one step, 1.80-2.60 s into the walk, at 0.2 m/s and at
0.1 m/s turning 10 deg/s; 3 s hold; 10 s after the release): the robot stood every time, yaw change 0.44 deg
at most. Frozen in double support the capture-point error peaks under 5 mm; frozen on one foot at 30-36 mm
in most instants (the cases below: 30 and 36 mm). Frozen on the right foot 2.22-2.32 s into the walk it
peaks at 56-149 mm (0.2 m/s; 96 mm at 2.28 s turning), though the robot stands: the issue's "CP error under
the threshold" does not hold there yet (the xfail case). Why: the hard e-stop freezes the joints after the
Stabilizer ([MLC]'s chain order), so nothing balances during the hold; frozen late in the right foot's support
with the COG moving left, the robot tips onto its swing foot (both soles loaded, 273 / 290 N, the COM 42 mm
left of BODY) and rests there. The error is already 104 mm at the release: the plan still has the COG over
the right sole. Releasing at once instead of over the 2.5 s blend does not help (111 mm, and the double-support
cases rise from 4 to 15 mm); seeding the COG plan at the measured COG moves the BODY 95 mm within the blend
and the robot falls. What would: re-anchoring the plan to the measured soles and BODY roll at the release, then
levelling both over the final double support."""

import math

import numpy as np
import pytest

from app.service import OperatorService, Refused
from app.service.local import LocalRobot
from controller.kinematics.rotations import matrix_to_rpy, quat_wxyz_to_matrix
from controller.layers.stabilizer import StabilizerParams

THRESHOLD_M = StabilizerParams().cp_threshold_m
HOLD_S = 3.0
STAND_S = 10.0
MAX_YAW_CHANGE_DEG = 2.0
#: half the 0.2 m stride: the COG goes to the middle of the feet, which stay where they are
MAX_BODY_SHIFT_M = 0.12


def yaw_deg(quat_wxyz) -> float:
    return math.degrees(matrix_to_rpy(quat_wxyz_to_matrix(np.asarray(quat_wxyz, dtype=float)))[2])


@pytest.mark.slow
@pytest.mark.parametrize(("vx", "vtheta_deg", "walk_s", "phase"), [
    (0.2, 0.0, 1.8, "lleg"),  # frozen on the left foot, the right swinging (the worst single-support case)
    (0.2, 0.0, 2.0, "both"),  # frozen in the double support between two steps
    (0.1, 10.0, 2.2, "rleg"),  # turning, frozen on the right foot
    (0.1, 10.0, 3.0, "both"),
    pytest.param(0.2, 0.0, 2.3, "rleg", marks=pytest.mark.xfail(
        strict=True, raises=AssertionError, reason="frozen on the right foot 2.22-2.32 s into the walk, the robot "
        "tips onto its swing foot during the hold; the CP error after the release peaks at 56-149 mm (120 mm "
        "here, 104 mm at the release itself), over the 40 mm threshold (see the module docstring)")),
], ids=["0.2m_s-single", "0.2m_s-double", "0.1m_s-turning-single", "0.1m_s-turning-double",
        "0.2m_s-single-late"])
def test_estop_mid_walk_holds_and_after_release_the_robot_stands_where_it_is(vx, vtheta_deg, walk_s, phase):
    robot = LocalRobot()
    service = OperatorService(robot)
    # 1. walk
    robot.run_for(2.5)
    service.go_velocity(vx, 0.0, math.radians(vtheta_deg))
    robot.run_for(walk_s)
    assert robot.loop.snapshot.reference.gait.support == phase
    # 2. e-stop: the command freezes, and the walk does not run on behind it
    service.estop()
    robot.run_for(0.05)
    frozen = np.array(robot.loop.snapshot.q_cmd_rad)
    abc = robot.loop.snapshot.layers["abc"]
    planned_feet = [f.pos for f in abc.footsteps]
    robot.run_for(HOLD_S - 0.05)
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
    assert not snap.layers["abc"].walking and not snap.safety.hard_stop
    # the robot stands where it stopped: no step of the walk it was on (the body only moves between the feet)
    assert np.linalg.norm(np.array(snap.truth.base_pos_world[:2]) - base0[:2]) < MAX_BODY_SHIFT_M
    print(f"\n{vx} m/s, {vtheta_deg} deg/s, frozen in {phase}: CP error peak {err.max() * 1e3:.0f} mm "
          f"{t[err.argmax()]:.2f} s after the release")
    assert err.max() < THRESHOLD_M, f"CP error peak {err.max() * 1e3:.0f} mm at {t[err.argmax()]:.2f} s"
