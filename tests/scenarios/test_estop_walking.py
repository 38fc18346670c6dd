"""The hard e-stop in the middle of a walk: the command freezes, the walk behind it holds (the plan does
not run on), commands sent meanwhile are refused, and after the release the robot puts its swing foot
down, brings its weight between the feet and stands, facing where it faced.

Measured (/tmp sweeps of this machine): over 11 e-stop phases of a step cycle at 0.2 m/s, and 11 at
0.1 m/s turning 10 deg/s, the robot stood every time; yaw change 0.3 deg at most. Frozen on one foot, the
robot tips onto its swing foot, away from the held plan: the capture-point error is 75-99 mm through the
2.5 s release blend (the chain still holds) and below the 40 mm threshold 0.3 s after the chain resumes;
frozen in double support it stays under 7 mm."""

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
#: after the release: the swing foot's landing (0.8 s) and the 2 s final double support, plus 0.5 s margin
SETTLED_AFTER_S = 3.3
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
], ids=["0.2m_s-single", "0.2m_s-double", "0.1m_s-turning-single", "0.1m_s-turning-double"])
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
    assert err[t >= SETTLED_AFTER_S].max() < THRESHOLD_M, f"peak {err.max() * 1e3:.0f} mm"
    assert not snap.layers["abc"].walking and not snap.safety.hard_stop
    # the robot stands where it stopped: no step of the walk it was on (the body only moves between the feet)
    assert np.linalg.norm(np.array(snap.truth.base_pos_world[:2]) - base0[:2]) < MAX_BODY_SHIFT_M
    above = np.flatnonzero(err >= THRESHOLD_M)
    settled = t[above[-1] + 1] if above.size else 0.0
    print(f"\n{vx} m/s, {vtheta_deg} deg/s, frozen in {phase}: CP error peak {err.max() * 1e3:.0f} mm, "
          f"below {THRESHOLD_M * 1e3:.0f} mm from {settled:.2f} s after the release")
