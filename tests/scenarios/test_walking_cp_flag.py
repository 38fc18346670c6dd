"""The capture-point flag stays on while walking (issue 13.2): on the standard walks the CP error stays below
the threshold (the KalmanFilter takes the tilt from the flat soles, not the accelerometer, so a landing does
not move the estimated COG), and a push during a walk raises the flag, the walk stops in place, the
EmergencyStopper holds the motion and the robot stands.

Measured (this machine): CP error p99 / max while walking [mm], now with the LIP's acceleration predicting the
COG velocity while walking (in brackets: before it, with the tilt already from the flat soles; before that, when
the accelerometer gave the tilt), KalmanFilter pitch / roll error against the simulation's BODY [deg] (before the
prediction; now 0.11-0.13 at most):

| walk | CP p99 | CP max | pitch max | roll max |
|---|---|---|---|---|
| goPos 3 m forward | 14.4 (25.0; 82.3) | 18.9 (26.3; 104.9) | 0.06 (0.82) | 0.12 (0.63) |
| goPos 1 m left | 17.4 (20.7; 57.6) | 22.0 (29.0; 65.2) | 0.04 (0.52) | 0.15 (0.82) |
| goPos turn 180 deg | 16.1 (18.7; 42.5) | 18.1 (21.2; 45.9) | 0.05 (0.39) | 0.14 (0.79) |
| goVelocity 20 s, three velocities | 18.2 (23.9; 65.9) | 21.9 (26.3; 100.0) | 0.06 (0.77) | 0.14 (0.66) |
| toe 20 / heel 10 deg footsteps | 17.1 (31.4; 53.4) | 17.4 (33.4; 62.4) | 0.09 (1.22) | 0.11 (0.81) |

The issue's goal (p99 <= 25 mm, max <= 40 mm) is met by every walk; none raises the flag (40 mm), nor do 100 m
of mixed goVelocity walking (CP error max 21.7 mm; 29.3 before the prediction; the test walks two cycles of the mix,
whose maxima repeat in every cycle: 21.2 mm).

Pushes during a walk, at every phase of the gait: tests/scenarios/test_push_while_walking.py.
"""

import numpy as np
import pytest

from controller.layers.stabilizer import StabilizerParams
from controller.walking.footsteps import StepParams
from tests.scenarios.helpers import make_system

THRESHOLD_M = StabilizerParams().cp_threshold_m
#: [m] margin on the measured CP error p99 and max: the simulation is deterministic on one machine; this is
#: for another machine's floating point and small controller changes (every max + margin stays <= 40 mm)
CP_MARGIN_M = 0.005
#: [m] the CP error max over two cycles of the mixed walk (test_mixed_walking_twice_over_raises_no_flag): measured
#: 21.2 mm, the same in every cycle (each motion's max repeats to 0.1 mm); 21.7 mm over 100 m (14 cycles)
MIXED_MEASURED_MAX_M = 0.0212
#: cycles of the mix walked: the second repeats the first's maxima, so more add CI time, not cases
MIXED_CYCLES = 2
#: [deg] the KalmanFilter's roll and pitch error while walking: measured 0.13 deg at most (0.11-0.13 over the
#: walks; 0.04-0.15 before the LIP prediction; 0.39-1.22 with the accelerometer's tilt), margin 0.1 deg
MAX_ATTITUDE_ERROR_DEG = 0.23


def roll_pitch(quat_wxyz) -> tuple[float, float]:
    w, x, y, z = quat_wxyz
    return (float(np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))),
            float(np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))))


class WalkWatch:
    """A simulated HRP-2 standing 2.5 s, then commanded; every tick while the AutoBalancer walks it records the
    Stabilizer's CP error and flag and the KalmanFilter's attitude error against the simulation."""

    def __init__(self) -> None:
        self.system = make_system()
        self.loop = self.system.loop
        self.abc = self.system.chain["abc"]
        self.loop.run_for(2.5)
        self.cp_error_m: list[float] = []
        self.flag_ticks = 0
        self.attitude_error_rad: list[float] = []

    def run(self, seconds: float) -> None:
        for _ in range(int(round(seconds / self.loop.dt_control_s))):
            snap = self.loop.step()
            assert not snap.fallen, f"fell at t={snap.time_s:.2f} s"
            assert not snap.layers["abc"].emergency_steps, "a capture-point emergency step while walking"
            if snap.layers["abc"].walking:
                st = snap.layers["st"]
                self.cp_error_m.append(st.cp_error_norm)
                self.flag_ticks += st.emergency
                true_rp = roll_pitch(snap.truth.base_quat_wxyz)
                est_rp = snap.layers["kf"].rpy_rad[:2]
                self.attitude_error_rad.append(max(abs(e - t) for e, t in zip(est_rp, true_rp, strict=True)))

    def until_stopped(self, timeout_s: float) -> None:
        self.run(0.1)
        for _ in range(int(timeout_s / 0.5)):
            if not self.abc.gait.walking:
                self.run(0.5)
                return
            self.run(0.5)
        raise AssertionError(f"still walking after {timeout_s} s")


def walk(name: str) -> WalkWatch:
    w = WalkWatch()
    abc = w.abc
    if name == "toe-heel":  # as test_walking's toe-heel test
        sp = StepParams(toe_angle_rad=np.radians(20.0), heel_angle_rad=np.radians(10.0))
        steps = [("rleg", [0.0, -0.095, 0.0], [0, 0, 0]), ("lleg", [0.2, 0.095, 0.0], [0, 0, 0]),
                 ("rleg", [0.4, -0.095, 0.0], [0, 0, 0]), ("lleg", [0.4, 0.095, 0.0], [0, 0, 0])]
        w.loop.call(lambda: abc.set_footsteps(steps, [None, sp, sp, sp]))
    elif name == "go-velocity":  # 20 s at three velocities, then goStop
        for v, seconds in (((0.1, 0.05, np.radians(10.0)), 7.0), ((0.2, 0.0, 0.0), 7.0),
                           ((-0.05, -0.05, np.radians(-10.0)), 6.0)):
            w.loop.call(lambda v=v: abc.go_velocity(*v))
            w.run(seconds)
        w.loop.call(lambda: abc.go_stop())
    else:
        goal = {"3m-forward": (3.0, 0.0, 0.0), "1m-left": (0.0, 1.0, 0.0), "turn-180": (0.0, 0.0, np.pi)}[name]
        w.loop.call(lambda: abc.go_pos(*goal))
    w.until_stopped(40.0)
    return w


WALKS = [  # name, measured CP error p99, max [m]
    pytest.param("toe-heel", 0.0171, 0.0174, id="toe-heel"),
    pytest.param("3m-forward", 0.0144, 0.0189, id="3m-forward", marks=pytest.mark.slow),
    pytest.param("1m-left", 0.0174, 0.0220, id="1m-left", marks=pytest.mark.slow),
    pytest.param("turn-180", 0.0161, 0.0181, id="turn-180", marks=pytest.mark.slow),
    pytest.param("go-velocity", 0.0182, 0.0219, id="go-velocity", marks=pytest.mark.slow),
]


@pytest.mark.parametrize(("name", "measured_p99_m", "measured_max_m"), WALKS)
def test_the_standard_walks_raise_no_flag_and_keep_the_capture_point_error_small(name, measured_p99_m,
                                                                                  measured_max_m):
    w = walk(name)
    err = np.array(w.cp_error_m)
    assert len(err) > 500  # it walked (5 s at least)
    # 1. the flag is on while walking (the default) and never rose
    assert StabilizerParams().estop_while_walking
    assert w.flag_ticks == 0, f"{w.flag_ticks} ticks flagged, max CP error {err.max() * 1e3:.1f} mm"
    # 2. the CP error as measured
    p99, worst = float(np.percentile(err, 99)), float(err.max())
    print(f"{name}: CP error p99 {p99 * 1e3:.1f} mm, max {worst * 1e3:.1f} mm")
    assert p99 < measured_p99_m + CP_MARGIN_M, f"p99 {p99 * 1e3:.1f} mm"
    assert worst < measured_max_m + CP_MARGIN_M, f"max {worst * 1e3:.1f} mm"
    assert worst < THRESHOLD_M
    assert p99 <= 0.025 and worst <= 0.040  # the goal
    # 3. because the attitude estimate does not read the landings as tilt
    assert np.degrees(max(w.attitude_error_rad)) < MAX_ATTITUDE_ERROR_DEG


PUSH_S = 0.1  # [s] the push's duration


def test_the_walking_stop_on_the_flag_can_be_switched_off():
    """walking_stop_on_cp_flag off: a flag while walking stops the motion (es) but the walk goes on."""
    import dataclasses

    system = make_system()
    loop = system.loop
    abc = system.chain["abc"]
    loop.call(lambda: abc.set_params(dataclasses.replace(abc.params, walking_stop_on_cp_flag=False)))
    loop.run_for(2.5)
    loop.call(lambda: abc.go_velocity(0.1, 0.0, 0.0))
    loop.run_for(3.0)
    loop.call(lambda: loop.plant.push("BODY", np.array([-20.0, 0.0, 0.0]) / PUSH_S, PUSH_S))
    snaps = [loop.step() for _ in range(int(1.0 / loop.dt_control_s))]
    assert any(s.layers["st"].emergency for s in snaps)
    assert not any(s.layers["abc"].walking_stop for s in snaps)
    assert snaps[-1].layers["abc"].walking


#: the mixed walk's velocity cycle [m/s, m/s, rad/s], seconds; a goStop and 3 s standing after each cycle
MIXED_CYCLE = (((0.15, 0.0, 0.0), 20.0), ((0.1, 0.03, np.radians(10.0)), 15.0), ((0.15, 0.0, np.radians(-10.0)), 15.0),
               ((-0.05, -0.03, 0.0), 6.0), ((0.0, 0.05, 0.0), 6.0))


@pytest.mark.slow
def test_mixed_walking_twice_over_raises_no_flag():
    """goVelocity forward, turning both ways, backward and sideways, stopping after each cycle, for MIXED_CYCLES
    cycles (about 15 m of BODY's path, its position every 2 s, a step pair, so the sway does not count). Measured:
    CP error max 21.2 mm, no flag, no fall; 100 m of it (14 cycles) measured 21.7 mm (29.3 before the
    LIP prediction)."""
    system = make_system()
    loop = system.loop
    abc = system.chain["abc"]
    loop.run_for(2.5)
    dt = loop.dt_control_s
    every = int(round(2.0 / dt))
    path, prev, tick, flags, worst = 0.0, np.array(loop.snapshot.truth.base_pos_world[:2]), 0, 0, 0.0
    for _ in range(MIXED_CYCLES):
        for v, seconds in MIXED_CYCLE:
            loop.call(lambda v=v: abc.go_velocity(*v))
            for _ in range(int(round(seconds / dt))):
                snap = loop.step()
                assert not snap.fallen, f"fell at t={snap.time_s:.1f} s after {path:.1f} m"
                st = snap.layers["st"]
                flags += st.emergency
                worst = max(worst, st.cp_error_norm)
                tick += 1
                if tick % every == 0:
                    p = np.array(snap.truth.base_pos_world[:2])
                    path += float(np.linalg.norm(p - prev))
                    prev = p
        loop.call(lambda: abc.go_stop())
        loop.run_for(3.0)
    print(f"{path:.1f} m mixed walking: CP error max {worst * 1e3:.1f} mm, {flags} ticks flagged")
    assert path > 14.0, f"walked {path:.1f} m"  # measured 14.7 m: the mix went on walking
    assert flags == 0, f"{flags} ticks flagged, CP error max {worst * 1e3:.1f} mm"
    assert worst < MIXED_MEASURED_MAX_M + CP_MARGIN_M, f"CP error max {worst * 1e3:.1f} mm"
