"""Stabilizer: LIP feedback direction, transitions, the capture-point error and the emergency flag."""

import numpy as np
import pytest

from controller.core.errors import InvalidState
from controller.core.types import Estimate, GaitState, Reference, TickContext
from controller.interpolation.blend import sigmoid_ratio as sigmoid_transition
from controller.kinematics.model import RobotKinematics
from controller.layers.stabilizer import Stabilizer, StabilizerParams
from robot.generate import half_sitting_deg
from robot.sensors import Sensors

HALF = np.deg2rad(half_sitting_deg())
BASE = np.array([0.0, 0.0, 0.648702])
KIN = RobotKinematics()


def gait(cog_xy=(0.0095, 0.0), cog_vel_xy=(0.0, 0.0)):
    KIN.update(BASE, np.eye(3), HALF)
    (pr, Rr), (pl, Rl) = KIN.frame_pose("rleg_end"), KIN.frame_pose("lleg_end")
    return GaitState(walking=False, support="both", contact=(True, True), p_rsole_world=pr, R_rsole_world=Rr,
                     p_lsole_world=pl, R_lsole_world=Rl, zmp_world=np.array([0.0095, 0.0, 0.0]),
                     cog_world=np.array([*cog_xy, 0.81]), cog_vel_world=np.array([*cog_vel_xy, 0.0]),
                     cog_pc_world=np.array([*cog_xy, 0.81]))


def standing_ctx(t=0.0, load=1.0):
    """Sensors of the robot standing still in half-sitting: each foot carries half the weight (x load)."""
    w = np.zeros((4, 6))
    w[:2, 2] = 0.5 * (58.0 - 2 * 1.63877) * 9.80665 * load
    s = Sensors(t, HALF.copy(), np.zeros(30), w, np.zeros(3), np.array([0.0, 0.0, 9.80665]))
    return TickContext(tick=0, time_s=t, dt_s=0.005, sensors=s, estimate=Estimate())


def run_ticks(st, ref, n, load=1.0):
    from controller.layers.remove_force_offset import RemoveForceOffset
    rmfo = RemoveForceOffset(RobotKinematics())
    out = None
    for k in range(n):
        ctx = standing_ctx(0.005 * k, load)
        rmfo.tick(ctx, ref)
        out = st.tick(ctx, ref)
    return out


def test_sigmoid_transition_goes_exactly_from_0_to_1_and_is_monotone():
    assert sigmoid_transition(0.0) == 0.0 and sigmoid_transition(1.0) == pytest.approx(1.0, abs=1e-15)
    assert sigmoid_transition(0.5) == pytest.approx(0.5)
    s = [sigmoid_transition(x) for x in np.linspace(0, 1, 101)]
    assert np.all(np.diff(s) > 0)


def test_without_a_gait_reference_the_stabilizer_passes_the_reference_through():
    st = Stabilizer(0.005)
    ref = Reference.from_arrays(HALF, base_pos_world=BASE)
    assert run_ticks(st, ref, 3) is ref


def test_a_disabled_stabilizer_passes_a_gait_reference_through_and_raises_no_flag():
    st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
    st.enabled = False
    ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait(cog_xy=(0.2, 0.0)))
    assert run_ticks(st, ref, 3) is ref
    assert st.emergency is False


def test_a_reference_cog_behind_the_actual_one_moves_the_feedback_zmp_backward():
    # actual COG ~ above the ankles; reference 3 cm behind: u = zmp_ref + k1 (cog_ref - cog) with k1 < 0
    st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
    ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait(cog_xy=(-0.02, 0.0)))
    run_ticks(st, ref, 10)
    assert st.new_zmp[0] > 0.0095 + 0.02  # the feet push the COG back toward the reference


def test_capture_point_error_over_the_threshold_raises_the_flag_and_records_its_time():
    st = Stabilizer(0.005, StabilizerParams(cp_threshold_m=0.05, transition_time_s=0.01))
    calm = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait())
    run_ticks(st, calm, 5)
    assert not st.emergency and st.flag_rose_at_s is None
    fast = calm.with_(gait=gait(cog_vel_xy=(0.3, 0.0)))  # reference CP 8.6 cm ahead of the actual one
    run_ticks(st, fast, 5)
    assert st.emergency
    assert st.cp_error[0] == pytest.approx(0.3 / np.sqrt(9.80665 / 0.81), abs=0.01)
    assert st.status().flag_rose_at is not None


def test_support_polygon_mode_flags_only_a_capture_point_outside_the_shrunk_feet():
    st = Stabilizer(0.005, StabilizerParams(emergency_mode="cp_support", cp_margin_m=0.03, transition_time_s=0.01))
    ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait(cog_vel_xy=(0.3, 0.0)))
    run_ticks(st, ref, 5)
    assert not st.emergency  # the reference moves, the actual CP is still over the feet


def test_stopping_twice_is_an_invalid_state():
    st = Stabilizer(0.005, active=False)
    with pytest.raises(InvalidState):
        st.stop()
    st.start()
    with pytest.raises(InvalidState):
        st.start()


def test_unknown_emergency_mode_is_rejected_listing_the_modes():
    with pytest.raises(ValueError, match="cp_error"):
        StabilizerParams(emergency_mode="tilt")


def test_no_flag_while_the_stabilizer_is_still_blending_in():
    st = Stabilizer(0.005, StabilizerParams(cp_threshold_m=0.05, transition_time_s=1.0))
    fast = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait(cog_vel_xy=(0.3, 0.0)))
    run_ticks(st, fast, 100)  # 0.5 s into a 1 s start
    assert not st.emergency and st.flag_rose_at_s is None
    run_ticks(st, fast, 120)
    assert st.emergency


def test_hand_forces_reading_more_than_the_robot_weight_fall_back_to_the_plain_cog_instead_of_raising():
    from types import SimpleNamespace

    st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
    ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait())
    run_ticks(st, ref, 3)
    cog = np.array([0.01, 0.0, 0.81])
    wrenches = np.zeros((4, 6))
    est = SimpleNamespace(wrenches_ext_world=wrenches,
                          sensor_pos_from_base=np.array([[0, -0.1, -0.65], [0, 0.1, -0.65], [0.3, -0.3, 0.2],
                                                         [0.3, 0.3, 0.2]]))
    wrenches[2, 2] = -50.0  # a 50 N pull down at the right hand moves the balance point toward it
    assert st.static_balance_point(cog, est, 0.0)[0] > cog[0] + 0.01
    wrenches[2, 2] = 700.0  # a spike: more upward force than the robot weighs (58 kg * g = 569 N)
    assert np.array_equal(st.static_balance_point(cog, est, 0.0), cog)
    wrenches[2, 2] = -700.0
    assert np.array_equal(st.static_balance_point(cog, est, 0.0), cog)


def test_the_body_tilt_port_is_the_soles_kinematics_not_the_attitude_estimate():
    """Both soles loaded and planned flat, the encoders at half-sitting (planned with BODY level): the port says
    BODY is level although the attitude estimate says 0.6 deg roll, 1.7 deg pitch; a sole lifted in the plan
    does not count, and soles planned pitched (toe-off) give None."""
    from controller.kinematics.rotations import rpy_to_matrix
    from controller.layers.remove_force_offset import RemoveForceOffset

    st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
    rmfo = RemoveForceOffset(RobotKinematics())
    ref = Reference.from_arrays(HALF, base_pos_world=BASE)
    base = gait()
    fields = {f: getattr(base, f) for f in GaitState.__slots__}
    toe_off = rpy_to_matrix(np.radians([0.0, 5.0, 0.0]))
    cases = (({}, True), ({"contact": (True, False)}, True),
             ({"R_rsole_world": toe_off @ base.R_rsole_world, "R_lsole_world": toe_off @ base.R_lsole_world}, False))
    for changes, level in cases:
        ctx = standing_ctx()
        ctx.estimate.base_rpy_rad = np.array([0.01, 0.03, 0.0])
        rmfo.tick(ctx, ref)
        st.tick(ctx, ref.with_(gait=GaitState(**{**fields, **changes})))
        if level:
            np.testing.assert_allclose(ctx.ports.body_tilt_kin_rad, (0.0, 0.0), atol=1e-9)
        else:
            assert ctx.ports.body_tilt_kin_rad is None


def test_the_balance_port_carries_the_actual_cog_its_velocity_the_zmp_and_the_capture_point():
    """What the AutoBalancer's emergency step reads next tick: the Stabilizer's own estimate, the CP x + v / omega."""
    from controller.layers.remove_force_offset import RemoveForceOffset

    st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
    rmfo = RemoveForceOffset(RobotKinematics())
    ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait())
    for k in range(3):
        ctx = standing_ctx(0.005 * k)
        rmfo.tick(ctx, ref)
        st.tick(ctx, ref)
    bal = ctx.ports.balance
    assert bal.cog_world is ctx.estimate.cog_world and bal.zmp_world is ctx.estimate.zmp_world
    assert bal.cog_vel_world == pytest.approx(st.act_cogvel)
    assert bal.omega_1_s == pytest.approx(np.sqrt(9.80665 / (bal.cog_world[2] - 0.0)), rel=1e-9)
    assert bal.cp_world_xy == pytest.approx(bal.cog_world[:2] + bal.cog_vel_world[:2] / bal.omega_1_s)


def test_the_feet_are_softer_during_an_emergency_step_than_walking():
    """With Ports.emergency_step the foot damping uses rot_damping_gain_emergency_step: the same moment error
    turns the soles 3000 / 1000 times as fast as with the walking gain (the landed foot follows the ZMP)."""
    from controller.layers.remove_force_offset import RemoveForceOffset

    rates = []
    for emergency in (False, True):
        st = Stabilizer(0.005, StabilizerParams(transition_time_s=0.01))
        rmfo = RemoveForceOffset(RobotKinematics())
        walking = gait()
        ref = Reference.from_arrays(HALF, base_pos_world=BASE).with_(
            gait=GaitState(**{**{f: getattr(walking, f) for f in GaitState.__slots__}, "walking": True}))
        for k in range(4):
            ctx = standing_ctx(0.005 * k)
            ctx.sensors.wrenches[0, 4] = 20.0  # a pitch moment on the right sole the reference does not ask for
            ctx.ports.emergency_step = emergency
            rmfo.tick(ctx, ref)
            st.tick(ctx, ref)
        rates.append(abs(st.d_foot_rpy[0, 1]))
    assert rates[1] == pytest.approx(3.0 * rates[0], rel=0.05)


def test_the_flag_falls_only_after_the_error_has_stayed_below_half_the_threshold_for_the_release_time():
    """One rise per disturbance: an error hovering about the threshold keeps the flag up (the old flag rose and
    fell at each crossing); it falls cp_release_s after the error went below cp_release_ratio x threshold."""
    p = StabilizerParams(cp_threshold_m=0.05, transition_time_s=0.01)
    st = Stabilizer(0.005, p)
    calm = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait())
    run_ticks(st, calm, 5)
    over = calm.with_(gait=gait(cog_vel_xy=(0.3, 0.0)))  # CP error ~86 mm
    near = calm.with_(gait=gait(cog_vel_xy=(0.14, 0.0)))  # ~40 mm: below the threshold, above half of it
    run_ticks(st, over, 5)
    rose = st.flag_rose_at_s
    assert st.emergency and rose is not None
    for _ in range(3):  # crossing the threshold down and up again: still the first rise
        run_ticks(st, near, 40)
        assert st.emergency
        run_ticks(st, over, 5)
        assert st.emergency and st.flag_rose_at_s == rose
    release_ticks = round(p.cp_release_s / 0.005)
    run_ticks(st, calm, release_ticks - 5)
    assert st.emergency  # low, but not for long enough yet
    run_ticks(st, calm, 10)
    assert not st.emergency
    st.set_params(StabilizerParams(cp_threshold_m=0.05, transition_time_s=0.01, cp_release_s=0.0,
                                   cp_release_ratio=1.0))
    run_ticks(st, over, 5)
    run_ticks(st, near, 2)
    assert not st.emergency  # without hysteresis: down at the first tick under the threshold


def test_in_the_air_no_flag_rises_and_one_up_stays_up():
    """Both feet unloaded (a robot lifted, or both soles light for a moment during a catch step): a flag does not
    rise there, and one that is up is not dropped by it (it fell mid-catch, then rose again: two rises for a push)."""
    st = Stabilizer(0.005, StabilizerParams(cp_threshold_m=0.05, transition_time_s=0.01))
    calm = Reference.from_arrays(HALF, base_pos_world=BASE).with_(gait=gait())
    over = calm.with_(gait=gait(cog_vel_xy=(0.3, 0.0)))
    run_ticks(st, calm, 5)
    run_ticks(st, over, 5, load=0.0)
    assert not st.emergency  # in the air: no flag
    run_ticks(st, over, 5)
    assert st.emergency
    run_ticks(st, calm, 20, load=0.0)
    assert st.emergency  # unloaded a moment: still up
