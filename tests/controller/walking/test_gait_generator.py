"""Gait generator: hrpsys testGaitGenerator checks (per-tick jumps, step times), ZMP in the support polygon, landing."""

import math

import numpy as np
import pytest

from controller.core.errors import InvalidCommand, InvalidState
from controller.walking.footsteps import Footstep
from controller.walking.gait_generator import GaitGenerator, GaitParams

DT = 0.005
SOLE_HALF_X, SOLE_HALF_Y = 0.2172 / 2, 0.138 / 2  # HRP-2 sole, taken as centred on the sole frame [m]
MAX_ZMP_JUMP_M, MAX_FOOT_JUMP_M, MAX_FOOT_ROT_JUMP_RAD = 0.020, 0.010, math.radians(1.0)  # hrpsys thresholds


def run(gg, commands=None, max_ticks=20000):
    """Tick until the walk ends; `commands` maps a tick to a callable run before it."""
    samples = []
    commands = commands or {}
    for k in range(max_ticks):
        if k in commands:
            commands[k](gg)
        if not gg.walking:
            break
        samples.append(gg.tick())
    assert not gg.walking
    return samples


def sole_corners(p, R):
    local = np.array([[SOLE_HALF_X, SOLE_HALF_Y, 0], [SOLE_HALF_X, -SOLE_HALF_Y, 0],
                      [-SOLE_HALF_X, -SOLE_HALF_Y, 0], [-SOLE_HALF_X, SOLE_HALF_Y, 0]])
    return (p + local @ R.T)[:, :2]


def cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def convex_hull(points):
    pts = sorted(map(tuple, points))
    def half(seq):
        out = []
        for q in seq:
            while len(out) >= 2 and cross2(np.subtract(out[-1], out[-2]), np.subtract(q, out[-2])) <= 0:
                out.pop()
            out.append(q)
        return out
    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])  # counter-clockwise


def inside(point, hull, tol=1e-9):
    edges = np.roll(hull, -1, axis=0) - hull
    return bool(np.all(cross2(edges, point[:2] - hull) >= -tol))


def rot_angle(Ra, Rb):
    return math.acos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0))


def check_walk(gg, samples, footsteps):
    """All the per-plan checks, returns nothing; `footsteps` is the final plan."""
    zmp = np.array([s.zmp_world for s in samples])
    assert np.max(np.linalg.norm(np.diff(zmp, axis=0), axis=1)) < MAX_ZMP_JUMP_M
    for p_key, R_key in (("p_rfoot_world", "R_rfoot_world"), ("p_lfoot_world", "R_lfoot_world")):
        p = np.array([getattr(s, p_key) for s in samples])
        assert np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)) < MAX_FOOT_JUMP_M
        R = [getattr(s, R_key) for s in samples]
        assert max(rot_angle(a, b) for a, b in zip(R[:-1], R[1:], strict=True)) < MAX_FOOT_ROT_JUMP_RAD
    # executed step times equal the input step times
    index = np.array([s.footstep_index for s in samples])
    counts = np.bincount(index, minlength=len(footsteps) + 1)
    expected = [f.step_time_s for f in footsteps] + [gg.params.final_double_support_s]
    assert np.allclose(counts * DT, expected, atol=1e-5)
    # ZMP in the convex hull of the soles on the ground
    for s in samples:
        corners = []
        if s.contact[0]:
            corners.append(sole_corners(s.p_rfoot_world, s.R_rfoot_world))
        if s.contact[1]:
            corners.append(sole_corners(s.p_lfoot_world, s.R_lfoot_world))
        assert inside(s.zmp_world, convex_hull(np.vstack(corners))), s
    # every step: swing peak at the step height, landing exactly on the footstep
    for k, f in enumerate(footsteps[1:], start=1):
        ticks = [s for s in samples if s.footstep_index == k]
        key = "rfoot" if f.leg == "rleg" else "lfoot"
        z = np.array([getattr(s, f"p_{key}_world")[2] for s in ticks])
        assert z.max() == pytest.approx(f.z + f.step_height_m, abs=1e-9)
        assert np.allclose(getattr(ticks[-1], f"p_{key}_world"), f.position, atol=1e-12)
        assert np.allclose(getattr(ticks[-1], f"R_{key}_world"), f.T_world_foot[:3, :3], atol=1e-12)
    # start and end: both feet down, ZMP at the feet mid
    for s in (samples[0], samples[-1]):
        assert s.support == "both"
        assert np.allclose(s.zmp_world, 0.5 * (s.p_rfoot_world + s.p_lfoot_world), atol=2e-3)
    assert np.allclose(samples[-1].zmp_world, 0.5 * (samples[-1].p_rfoot_world + samples[-1].p_lfoot_world))


@pytest.mark.parametrize("orbit_type", ["cycloid", "rectangle", "trapezoid"])
def test_go_pos_0_2_0_1_20deg_passes_the_hrpsys_checks(orbit_type):
    gg = GaitGenerator(GaitParams(orbit_type=orbit_type), DT)
    steps = gg.go_pos(0.2, 0.1, math.radians(20.0))
    check_walk(gg, run(gg), steps)


def test_go_pos_x_0_3_passes_the_hrpsys_checks_and_ends_on_the_goal():
    gg = GaitGenerator(dt_s=DT)
    steps = gg.go_pos(0.3, 0.0, 0.0)
    check_walk(gg, run(gg), steps)
    assert gg.T_world_rfoot[:3, 3] == pytest.approx([0.3, -0.095, 0.0], abs=1e-12)
    assert gg.T_world_lfoot[:3, 3] == pytest.approx([0.3, 0.095, 0.0], abs=1e-12)
    assert gg.tick().walking is False


def test_set_footsteps_plan_passes_the_hrpsys_checks():
    gg = GaitGenerator(dt_s=DT)
    steps = gg.set_footsteps([("rleg", [0, -0.095, 0], [0, 0, 0]), ("lleg", [0, 0.095, 0], [0, 0, 0]),
                              ("rleg", [0.1, -0.095, 0], [0, 0, 0]), ("lleg", [0.2, 0.095, 0], [0, 0, 0]),
                              ("rleg", [0.2, -0.095, 0], [0, 0, 0])])
    check_walk(gg, run(gg), steps)


def test_go_velocity_with_updates_and_go_stop_passes_the_hrpsys_checks():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.1, 0.05, math.radians(10.0))
    commands = {700: lambda g: g.go_velocity(0.0, 0.0, math.radians(10.0)),
                1500: lambda g: g.go_velocity(0.1, 0.0, 0.0),
                2450: lambda g: g.go_stop()}
    samples = run(gg, commands)
    steps = gg.footsteps
    assert steps[-1].step_time_s == 1.0 and len(steps) <= 2450 // 200 + 3  # nothing planned after the stop
    check_walk(gg, samples, steps)
    last = {f.leg: f for f in steps}
    assert last["lleg"].yaw == pytest.approx(last["rleg"].yaw, abs=1e-12)  # aligned


def test_emergency_stop_mid_walk_ends_with_steps_in_place():
    gg = GaitGenerator(dt_s=DT)
    gg.go_pos(1.0, 0.0, 0.0)
    samples = run(gg, {450: lambda g: g.emergency_stop()})
    steps = gg.footsteps
    assert [f.step_height_m for f in steps[-3:]] == [0.0, 0.0, 0.0]
    assert len(steps) == 3 + 3  # node 0, the step in progress and the next, 3 in place
    check_walk(gg, samples, steps)


def test_the_zmp_preview_is_the_future_of_the_per_tick_zmp():
    gg = GaitGenerator(dt_s=DT)
    gg.go_pos(0.2, 0.0, 0.0)
    n = 320
    previews, zmps = [], []
    while gg.walking:
        previews.append(np.array(gg.zmp_preview(n)))
        zmps.append(gg.tick().zmp_world)
    zmps = np.array(zmps)
    padded = np.vstack([zmps, np.repeat(zmps[-1:], n, axis=0)])
    for k in range(0, len(zmps), 37):
        assert np.array_equal(previews[k], padded[k:k + n])
    assert gg.zmp_preview().shape == (320, 3)


def test_standing_the_zmp_preview_is_one_view_of_the_idle_zmp_until_it_or_n_changes():
    gg = GaitGenerator(dt_s=DT)
    first = gg.zmp_preview(320)
    assert gg.zmp_preview(320) is first  # kept: no new broadcast per tick
    assert np.array_equal(first, np.broadcast_to(gg.tick().zmp_world, (320, 3)))
    assert gg.zmp_preview(100).shape == (100, 3)
    gg.go_pos(0.1, 0.0, 0.0)
    while gg.walking:
        gg.tick()
    after = gg.zmp_preview(320)  # the idle sample of the new stance: a new view of its ZMP
    assert after is not first
    assert np.array_equal(after, np.broadcast_to(gg.tick().zmp_world, (320, 3)))


def test_a_step_time_that_is_not_a_whole_number_of_ticks_is_rejected():
    gg = GaitGenerator(dt_s=0.004)
    first = Footstep("rleg", 0.0, -0.095, step_height_m=0.0, step_time_s=1.0021)
    with pytest.raises(InvalidCommand, match="whole number of ticks"):
        gg.plan([first])
    assert not gg.walking


def test_footsteps_0_must_be_the_current_support_foot():
    gg = GaitGenerator(dt_s=DT)
    with pytest.raises(InvalidCommand, match="current rleg pose"):
        gg.plan([Footstep("rleg", 0.1, -0.095, step_height_m=0.0)])


# ---- the walking point (goVelocity every tick with step parameters), goPos while walking, parameters ------

def feet_mid(gg):
    """Planar mid-coords (x, y, yaw) of the feet where they stand (idle)."""
    Tr, Tl = gg.T_world_rfoot, gg.T_world_lfoot
    yr, yl = math.atan2(Tr[1, 0], Tr[0, 0]), math.atan2(Tl[1, 0], Tl[0, 0])
    return (0.5 * (Tr[0, 3] + Tl[0, 3]), 0.5 * (Tr[1, 3] + Tl[1, 3]), math.atan2(math.sin(yr) + math.sin(yl),
                                                                                math.cos(yr) + math.cos(yl)))


def test_velocity_step_parameters_apply_to_the_steps_planned_after_the_next_check():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.2, 0.0, 0.0)  # 0.2 m per 1 s step, clamped to the 0.15 m forward stride limit
    planned = gg.footsteps
    samples = run(gg, {300: lambda g: g.set_velocity_step(0.08, 0.24), 1900: lambda g: g.go_stop()})
    steps = gg.footsteps
    check_walk(gg, samples, steps)
    # what was planned before the change kept the default stride; steps planned later took the new ones
    assert steps[:3] == planned[:3]
    strides = np.diff([f.x for f in steps[1:-2]])  # one footstep lands one mid-coords stride beyond the last
    assert strides[0] == pytest.approx(0.15, abs=1e-9)
    assert max(abs(d) for d in strides[4:]) == pytest.approx(0.08, abs=1e-9)
    assert steps[-1].y - steps[-2].y == pytest.approx(0.24 * (1 if steps[-1].leg == "lleg" else -1), abs=1e-9)


def test_go_velocity_after_go_stop_resumes_the_walk_instead_of_ending_it():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.1, 0.0, 0.0)
    stopped_at = []
    samples = run(gg, {500: lambda g: g.go_stop(), 520: lambda g: (stopped_at.append(g.velocity_mode),
                                                                   g.go_velocity(0.0, 0.05, 0.0)),
                       1500: lambda g: g.go_stop()})
    assert stopped_at == ["ending"]
    check_walk(gg, samples, gg.footsteps)
    assert len(samples) * DT > 7.0  # it walked on after the first goStop
    assert feet_mid(gg)[1] > 0.05  # and sideways at the new velocity


def test_go_velocity_at_any_moment_of_the_ending_walks_on_and_go_stop_then_never_raises():
    # campaign seed 1009: a walk point pressed in the final double support raised in go_stop (a controller fault)
    ending = GaitGenerator(dt_s=DT)
    ending.go_velocity(0.1, 0.0, 0.0)
    n_end = len(run(ending, {500: lambda g: g.go_stop()}))
    for offset in range(1, n_end - 500, 23):
        gg = GaitGenerator(dt_s=DT)
        gg.go_velocity(0.1, 0.0, 0.0)
        commands = {500: lambda g: g.go_stop(), 500 + offset: lambda g: g.go_velocity(0.0, 0.05, 0.0)}
        commands.update({k: lambda g: g.go_stop() for k in range(500 + offset + 1200, 500 + offset + 1600, 37)})
        samples = []
        for k in range(20000):
            if k in commands:
                commands[k](gg)
            sample = gg.tick()
            if not sample.walking and k > 500 + offset + 1600:
                break
            samples.append(sample)
        assert not gg.walking
        assert feet_mid(gg)[1] > 0.04, offset  # the new velocity was walked, on or after the ending walk
        gg = GaitGenerator(dt_s=DT)
        gg.go_velocity(0.1, 0.0, 0.0)
        run(gg, {500: lambda g: g.go_stop(), 500 + offset: lambda g: g.go_velocity(0.0, 0.05, 0.0),
                 501 + offset: lambda g: g.go_stop()})  # the stick let go at once: no raise, the walk ends
        gg.tick()
        assert not gg.walking


def test_go_pos_while_walking_replaces_the_rest_of_the_plan_relative_to_where_the_walk_began():
    gg = GaitGenerator(dt_s=DT)
    origin = gg.walk_origin
    first = gg.go_pos(1.0, 0.0, 0.0)
    goal = (0.3, 0.2, math.radians(20.0))
    replaced = []
    samples = run(gg, {400: lambda g: replaced.append(g.go_pos(*goal))})
    steps = gg.footsteps
    check_walk(gg, samples, steps)
    # the footsteps up to the free one are kept, the rest replaced
    k = next(i for i, (a, b) in enumerate(zip(first, steps, strict=False)) if a != b)
    assert k >= 3 and replaced[0] == list(steps)
    x, y, yaw = feet_mid(gg)
    c, s = math.cos(origin[2]), math.sin(origin[2])
    assert (c * goal[0] - s * goal[1] + origin[0], s * goal[0] + c * goal[1] + origin[1]) == pytest.approx(
        (x, y), abs=1e-4)
    assert yaw - origin[2] == pytest.approx(goal[2], abs=math.radians(0.5))


@pytest.mark.parametrize("stop_tick", [50, 400, 900, 1500, 2200, 3100, 3900])
def test_go_stop_ends_a_go_pos_walk_after_its_committed_steps_feet_side_by_side(stop_tick):
    # soak seed 10139: goStop answered "stopping" and a 41-step goPos walk went on (hrpsys stops velocity mode only)
    gg = GaitGenerator(dt_s=DT)
    full = gg.go_pos(2.0, 0.0, 0.0)  # 16 footsteps of 1 s
    samples = run(gg, {stop_tick: lambda g: g.go_stop()})
    check_walk(gg, samples, gg.footsteps)
    k = next((i for i, (a, b) in enumerate(zip(full, gg.footsteps, strict=False)) if a != b), len(full))
    assert len(gg.footsteps) <= k + 2  # the committed steps, then at most the aligning step(s)
    assert len(samples) * DT <= (stop_tick * DT) + 3 * 1.0 + GaitParams().final_double_support_s + 0.01
    x, y, yaw = feet_mid(gg)
    assert x <= 2.0 + 1e-9 and yaw == pytest.approx(0.0, abs=1e-9)
    if stop_tick * DT < len(full) - 4.0:  # stopped well before the end: short of the goal
        assert x < 2.0 - 0.1
    assert gg.T_world_lfoot[:3, 3] - gg.T_world_rfoot[:3, 3] == pytest.approx([0.0, 0.19, 0.0], abs=1e-9)


def test_go_pos_during_a_velocity_walk_ends_the_velocity_mode_on_the_goal():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.1, 0.0, math.radians(5.0))
    samples = run(gg, {700: lambda g: g.go_pos(0.5, -0.1, 0.0)})
    assert gg.velocity_mode == "idle"
    check_walk(gg, samples, gg.footsteps)
    assert feet_mid(gg) == pytest.approx((0.5, -0.1, 0.0), abs=1e-4)


def test_go_pos_in_the_last_step_waits_and_walks_to_the_goal_from_where_the_walk_ends():
    gg = GaitGenerator(dt_s=DT)
    gg.go_pos(0.1, 0.0, 0.0)  # node 0, one step, the aligning step: 3 s and the final double support
    n = int(round(2.8 / DT))
    assert run(gg, {n: lambda g: g.go_pos(-0.1, 0.1, 0.0) == []})
    assert gg.tick().walking  # the waiting goPos starts on the tick after the walk's end
    run(gg)
    assert feet_mid(gg) == pytest.approx((-0.1, 0.1, 0.0), abs=1e-4)
    assert gg.walk_origin == pytest.approx((0.0, 0.0, 0.0))  # still the first walk's origin


def test_gait_parameters_changed_mid_walk_apply_to_later_steps_without_a_jump():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.1, 0.0, 0.0)
    new = GaitParams(double_support_ratio_before=0.2, double_support_ratio_after=0.2)

    def change(g):
        g.configure(params=new, footstep_params=g.footstep_params.replaced(step_height_m=0.08, step_time_s=0.8))

    samples = run(gg, {450: change, 2000: lambda g: g.go_stop()})
    steps = gg.footsteps
    check_walk(gg, samples, steps)
    assert steps[2].step_time_s == 1.0 and steps[-1].step_time_s == 0.8 and steps[-2].step_height_m == 0.08


# ---- what the capture-point emergency step asks of the gait: its own timing, landings moved mid-step, its ZMP


def emergency_steps(step_time_s=0.45):
    return [Footstep("rleg", 0.0, -0.095, step_height_m=0.0, step_time_s=0.05),
            Footstep("lleg", 0.3, 0.15, step_height_m=0.04, step_time_s=step_time_s)]


EMERGENCY_PARAMS = GaitParams(double_support_ratio_before=0.0, double_support_ratio_after=0.2,
                              final_double_support_s=1.5, orbit_type="trapezoid")


def test_a_plans_own_timing_applies_to_that_plan_only():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    support = [s.support for s in run(gg)]
    # 0.05 s initial double support, the swing at once (no double support before it), 0.2 x 0.45 s after it
    # and 1.5 s at the end
    assert support[:10] == ["both"] * 10 and support[10] == "rleg"
    assert support.count("rleg") == 71 and len(support) == 10 + 90 + 300
    steps = gg.go_pos(0.1, 0.0, 0.0)  # the next plan has the generator's own timing again
    check_walk(gg, run(gg), steps)


def test_a_landing_moved_mid_swing_bends_the_swing_without_a_jump_and_lands_there():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    samples = [gg.tick() for _ in range(40)]  # 30 ticks into the swing
    gg.move_footsteps({1: (0.38, 0.2)})
    samples += run(gg)
    p = np.array([s.p_lfoot_world for s in samples])
    assert np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)) < MAX_FOOT_JUMP_M
    assert p[-1] == pytest.approx((0.38, 0.2, 0.0), abs=1e-12)
    assert gg.footsteps[1].x == pytest.approx(0.38)
    zmp = np.array([s.zmp_world for s in samples])
    assert zmp[-1] == pytest.approx(0.5 * (p[-1] + np.array([0.0, -0.095, 0.0])))


def test_a_foot_that_touched_down_early_stays_where_it_touched_down_and_the_step_is_double_support():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    for _ in range(60):
        last = gg.tick()
    assert last.support == "rleg"
    gg.move_footsteps({1: (0.25, 0.12)}, landed=True)
    rest = run(gg)
    assert {s.support for s in rest} == {"both"}
    assert np.array([s.p_lfoot_world for s in rest]) == pytest.approx(np.tile((0.25, 0.12, 0.0), (len(rest), 1)))
    assert gg.T_world_lfoot[:3, 3] == pytest.approx((0.25, 0.12, 0.0))


def test_only_the_footstep_being_stepped_on_or_a_later_one_moves():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    with pytest.raises(InvalidState, match="being stepped on"):
        gg.move_footsteps({1: (0.3, 0.2)}, landed=True)  # the swing has not started
    gg.move_footsteps({1: (0.35, 0.2)})  # before the swing: replaced
    assert gg.footsteps[1].x == pytest.approx(0.35)
    for _ in range(110):
        gg.tick()  # the final double support
    with pytest.raises(InvalidCommand, match="only the footstep being stepped on"):
        gg.move_footsteps({1: (0.4, 0.2)})


def _sampled(gg):
    return [(s.support, s.footstep_index, s.zmp_world.tolist(), s.p_rfoot_world.tolist(), s.p_lfoot_world.tolist(),
             s.R_rfoot_world.tolist(), s.R_lfoot_world.tolist(), s.r_lleg) for s in run(gg)]


@pytest.mark.parametrize("ticks", [20, 40, 60])  # before the swing, mid-swing, late in it
def test_a_landing_moved_with_its_zmp_walks_the_floats_of_the_move_then_set_zmp(ticks):
    plans = []
    for combined in (False, True):
        gg = GaitGenerator(dt_s=DT)
        gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
        for _ in range(ticks):
            gg.tick()
        for x, y in ((0.38, 0.2), (0.381, 0.205)):  # moved twice: the second from the first
            zmp = np.column_stack((np.linspace(0.1, 0.2, 400 - gg._tick), np.zeros(400 - gg._tick),
                                   np.zeros(400 - gg._tick)))
            if combined:
                gg.move_footsteps({1: (x, y)}, zmp_world=zmp)
            else:
                gg.move_footsteps({1: (x, y)})
                gg.set_zmp(zmp)
            gg.tick()
        plans.append((gg.footsteps, _sampled(gg), gg.T_world_lfoot.tolist()))
    assert plans[0] == plans[1]


def test_set_zmp_overwrites_the_next_ticks_reference_and_nothing_before():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    first = gg.tick().zmp_world.copy()
    path = np.column_stack((np.linspace(0.1, 0.2, 50), np.zeros(50), np.zeros(50)))
    gg.set_zmp(path)
    assert gg.zmp_preview(50) == pytest.approx(path)
    assert gg.tick().zmp_world == pytest.approx(path[0])
    assert not np.allclose(first, path[0])


@pytest.mark.parametrize("goal", [(0.3, 0.0, 0.0), (0.2, 0.1, math.radians(20.0))])
def test_swing_samples_left_counts_down_to_the_touchdown_of_every_swing(goal):
    gg = GaitGenerator(dt_s=DT)
    gg.go_pos(*goal)
    supports, left = [], []
    while gg.walking:
        supports.append(gg.tick().support)
        left.append(gg.swing_samples_left() if gg.walking else 0)
    supports.append("both")
    swings = 0
    for k, (support, n) in enumerate(zip(supports, left, strict=False)):
        if support == "both":
            assert n == 0
            continue
        # the samples k .. k + n - 1 are this swing's, sample k + n is the double support after it
        assert set(supports[k:k + n]) == {support} and supports[k + n] == "both"
        swings += supports[k - 1] == "both"
    assert swings >= 2


def test_abort_ends_the_walk_where_the_plan_is_a_swing_foot_in_the_air_included():
    gg = GaitGenerator(dt_s=DT)
    gg.go_velocity(0.1, 0.0, 0.0)
    while True:  # into the first swing, half way
        last = gg.tick()
        if last.support != "both" and gg.swing_samples_left() < 60:
            break
    swing = "lfoot" if last.support == "rleg" else "rfoot"
    p_swing = getattr(last, f"p_{swing}_world").copy()
    assert p_swing[2] > 0.01  # in the air
    assert gg.abort() == last.support
    assert not gg.walking and gg.swing_samples_left() == 0
    T = gg.T_world_lfoot if swing == "lfoot" else gg.T_world_rfoot
    assert T[:3, 3] == pytest.approx(p_swing, abs=1e-12)  # the next plan starts from the foot where it is
    idle = gg.tick()
    assert not idle.walking and getattr(idle, f"p_{swing}_world") == pytest.approx(p_swing, abs=1e-12)
    assert gg.abort() == "both"  # not walking: nothing to end


# ---- a change computed ahead (the emergency step's after-write work): put in only on the plan it was computed from


def _zmp_rows(gg, x):
    n = 400 - gg._tick
    return np.column_stack((np.full(n, x), np.zeros(n), np.zeros(n)))


@pytest.mark.parametrize("ticks", [40, 60])  # mid-swing, late in it
def test_a_move_prepared_ahead_and_applied_walks_the_floats_of_the_move_itself(ticks):
    plans = []
    for ahead in (False, True):
        gg = GaitGenerator(dt_s=DT)
        gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
        for _ in range(ticks):
            gg.tick()
        for x, y in ((0.38, 0.2), (0.381, 0.205)):
            zmp = _zmp_rows(gg, 0.1 + x)
            if ahead:
                before = (gg._arrays, gg.footsteps, gg.plan_version)
                patch = gg.prepare_move_swing({1: (x, y)}, zmp)
                assert (gg._arrays, gg.footsteps, gg.plan_version) == before  # nothing changed yet
                assert gg.apply(patch)
            else:
                gg.move_footsteps({1: (x, y)}, zmp_world=zmp)
            gg.tick()
            if ahead:
                assert gg.apply(gg.prepare_set_zmp(_zmp_rows(gg, 0.2)))
            else:
                gg.set_zmp(_zmp_rows(gg, 0.2))
        plans.append((gg.footsteps, _sampled(gg), gg.T_world_lfoot.tolist()))
    assert plans[0] == plans[1]


def test_a_patch_computed_before_the_plan_changed_is_refused_and_changes_nothing():
    gg = GaitGenerator(dt_s=DT)
    gg.plan(emergency_steps(), params=EMERGENCY_PARAMS)
    for _ in range(40):
        gg.tick()
    stale = [gg.prepare_set_zmp(_zmp_rows(gg, 0.3)), gg.prepare_move_swing({1: (0.38, 0.2)}, _zmp_rows(gg, 0.3))]
    gg.tick()  # a tick later
    arrays, version = gg._arrays, gg.plan_version
    assert not any(gg.apply(p) for p in stale)
    assert gg._arrays is arrays and gg.plan_version == version
    stale = gg.prepare_set_zmp(_zmp_rows(gg, 0.3))
    gg.set_zmp(_zmp_rows(gg, 0.25))  # another ZMP set meanwhile
    assert not gg.apply(stale)
    stale = gg.prepare_set_zmp(_zmp_rows(gg, 0.3))
    gg.configure(params=gg.params.replaced(final_double_support_s=1.0))  # new parameters
    assert not gg.apply(stale)
    assert gg.prepare_move_swing({0: (0.0, 0.0)}, _zmp_rows(gg, 0.3)) is None  # move_footsteps would refuse it
