"""Plots of what was tuned (ZMP, COG, capture point while walking and when pushed, the emergency step):
`python -m app.lab.plots`."""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from app.service import OperatorService  # noqa: E402
from app.service.local import LocalRobot  # noqa: E402
from controller.kinematics.rotations import matrix_to_rpy, quat_wxyz_to_matrix  # noqa: E402


def record_walk(seconds: float = 12.0):
    """Stand 2.5 s, goPos(0.6, 0.1, 0); per tick: time, reference/actual ZMP, COG, CP, true COM, flag."""
    robot = LocalRobot()
    service = OperatorService(robot)
    robot.run_for(2.5)
    service.go_pos(0.6, 0.1, 0.0)
    rows = []
    for _ in range(int(seconds / robot.loop.dt_control_s)):
        s = robot.step()
        g = s.reference.gait
        st = s.layers["st"]
        rows.append([s.time_s, *g.zmp_world[:2], *s.zmp_world[:2], *g.cog_world[:2], *s.cog_world[:2],
                     *st.cp_ref, *st.cp_act, *s.truth.com_world[:2], st.cp_error_norm])
    return np.array(rows)


def record_push(impulse_ns: float = 20.0, seconds: float = 4.0):
    robot = LocalRobot()
    service = OperatorService(robot)
    robot.run_for(3.0)
    service.push("BODY", (impulse_ns / 0.1, 0.0, 0.0), 0.1)
    rows = []
    for _ in range(int(seconds / robot.loop.dt_control_s)):
        s = robot.step()
        st = s.layers["st"]
        rows.append([s.time_s, *st.cp_error, st.cp_error_norm, st.cp_threshold_m, float(st.emergency),
                     *s.zmp_world[:2], *s.cog_world[:2]])
    return np.array(rows)


#: the tuning before issue 13.1 (the accelerometer trusted while BODY turns, one foot damping for roll and pitch;
#: the tilt from the accelerometer, not the flat soles, as before issue 13.2)
PUSH_TUNING_BEFORE = {"kf": {"gyro_trust_band_rad_s": 0.0, "use_sole_tilt": False},
                      "st": {"rot_damping_gain_pitch": 300.0}}


def record_push_detail(impulse_ns: float = 20.0, seconds: float = 3.0, overrides: dict | None = None):
    """Stand 3 s, push BODY forward; per tick: time, |CP error|, measured and commanded ZMP x from the ankle,
    estimated and simulated BODY pitch. `overrides`: layer name -> parameter values."""
    robot = LocalRobot()
    loop = robot.loop
    if overrides:
        OperatorService(robot).set_params(overrides)
    robot.run_for(3.0)
    loop.call(lambda: loop.plant.push("BODY", (impulse_ns / 0.1, 0.0, 0.0), 0.1))
    rows = []
    for _ in range(int(seconds / loop.dt_control_s)):
        s = robot.step()
        st = s.layers["st"]
        ankle_x = s.reference.gait.p_rsole_world[0]
        pitch_truth = matrix_to_rpy(quat_wxyz_to_matrix(np.asarray(s.truth.base_quat_wxyz, dtype=float)))[1]
        rows.append([s.time_s, st.cp_error_norm, s.zmp_world[0] - ankle_x, st.new_zmp[0] - ankle_x,
                     s.base_rpy_est_rad[1], pitch_truth])
    d = np.array(rows)
    d[:, 0] -= d[0, 0]
    return d


def plot_push_before_after(out: Path) -> None:
    from controller.balance.capture_point import HRP2_RIGHT_SOLE

    runs = (("before", record_push_detail(overrides=PUSH_TUNING_BEFORE)), ("after", record_push_detail()))
    fig, axes = plt.subplots(3, 2, figsize=(12, 8), sharex=True, sharey="row")
    for col, (label, d) in enumerate(runs):
        t = d[:, 0]
        ax = axes[0, col]
        ax.plot(t, d[:, 1] * 1e3, color="tab:red", label="|CP error|")
        ax.axhline(40.0, color="tab:blue", ls="--", label="threshold")
        ax.axhline(10.0, color="tab:gray", ls=":", label="10 mm")
        ax.set_title(label)
        ax = axes[1, col]
        ax.plot(t, d[:, 2] * 1e3, color="tab:green", label="ZMP x measured (F/T)")
        ax.plot(t, d[:, 3] * 1e3, color="tab:orange", label="ZMP x commanded")
        ax.axhline(HRP2_RIGHT_SOLE.front_m * 1e3, color="k", ls=":", lw=0.8, label="toe / heel edge")
        ax.axhline(-HRP2_RIGHT_SOLE.rear_m * 1e3, color="k", ls=":", lw=0.8)
        ax = axes[2, col]
        ax.plot(t, np.degrees(d[:, 4]), color="tab:purple", label="BODY pitch (KalmanFilter)")
        ax.plot(t, np.degrees(d[:, 5]), color="tab:gray", ls="--", label="BODY pitch (simulation)")
        ax.set_xlabel("time after the push [s]")
    axes[0, 0].set_ylabel("CP error [mm]")
    axes[1, 0].set_ylabel("from the ankle [mm]")
    axes[2, 0].set_ylabel("[deg]")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    for ax in axes[:, 1]:
        ax.legend(fontsize=8)
    fig.suptitle("20 N s forward push on BODY, standing: before / after issue 13.1 (KF gyro trust, pitch damping) "
                 "and 13.2 (KF tilt from the flat soles)")
    fig.tight_layout()
    fig.savefig(out, dpi=100)


#: the emergency step of issue 13.3 as first delivered: a 0.45 s step reaching 0.45 m forward, the legs at the
#: everyday 3.5 rad/s (the 2x forward push fell with it)
FIRST_EMERGENCY_STEP = {"abc": {"emergency_step": {"step_time_s": 0.45, "max_forward_m": 0.45}},
                        "el": {"emergency_step_velocity_limit_rad_s": 3.5}}


def record_emergency_step(impulse_ns: float = 56.0, step: bool = True, seconds: float = 4.5,
                          overrides: dict | None = None):
    """Stand 2.5 s, push BODY forward, watch until the fall or `seconds`; per tick: time after the push, measured
    CP x, simulated COM x, measured ZMP x, the simulated ankles' x and heights (right, left), the front edge of the
    planned soles in contact, BODY tilt (simulation) [deg], an emergency step in progress. `overrides`: layer
    parameters set before the push ({layer: {name: value}})."""
    from controller.balance.capture_point import HRP2_RIGHT_SOLE

    robot = LocalRobot()
    loop = robot.loop
    if not step:
        OperatorService(robot).set_params({"abc": {"emergency_step": {"enabled": False}}})
    if overrides:
        OperatorService(robot).set_params(overrides)
    robot.run_for(2.5)
    loop.call(lambda: loop.plant.push("BODY", (impulse_ns / 0.1, 0.0, 0.0), 0.1))
    rows = []
    for _ in range(int(seconds / loop.dt_control_s)):
        s = robot.step()
        g = s.reference.gait
        front = max(p[0] for p, c in ((g.p_rsole_world, g.contact[0]), (g.p_lsole_world, g.contact[1])) if c)
        w, x, y, _ = (float(v) for v in s.truth.base_quat_wxyz)
        tilt = np.degrees(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)))
        r_ankle, l_ankle = s.truth.body_pos_world[7], s.truth.body_pos_world[13]  # RLEG_LINK5, LLEG_LINK5
        rows.append([s.time_s, s.layers["st"].cp_act[0], s.truth.com_world[0], s.zmp_world[0], r_ankle[0],
                     l_ankle[0], r_ankle[2], l_ankle[2], front + HRP2_RIGHT_SOLE.front_m, tilt,
                     float(s.layers["abc"].emergency_step)])
        if s.fallen:
            break
    d = np.array(rows)
    d[:, 0] -= d[0, 0]
    return d


def plot_emergency_step_before_after(out: Path, impulse_ns: float = 56.0) -> None:
    """The 2x forward push without the capture-point emergency step (falls), with the step as first delivered
    (falls) and with the faster, longer step (steps and stands)."""
    runs = (("without the emergency step", record_emergency_step(impulse_ns, step=False)),
            ("0.45 s step, 0.45 m reach, legs 3.5 rad/s",
             record_emergency_step(impulse_ns, step=True, overrides=FIRST_EMERGENCY_STEP)),
            ("0.3 s, 0.55 m, legs 4.5 rad/s (now)", record_emergency_step(impulse_ns, step=True)))
    fig, axes = plt.subplots(3, len(runs), figsize=(16, 9), sharex=True, sharey="row")
    for col, (label, d) in enumerate(runs):
        t = d[:, 0]
        ax = axes[0, col]
        ax.plot(t, d[:, 1], color="tab:red", label="CP x (measured)")
        ax.plot(t, d[:, 2], color="tab:gray", ls="--", label="COM x (simulation)")
        ax.plot(t, d[:, 3], color="tab:green", lw=0.8, label="ZMP x (F/T)")
        ax.plot(t, d[:, 8], color="k", ls=":", label="toe edge of the soles down (plan)")
        ax.set_ylim(-0.1, 1.0)
        ax.set_title(label)
        ax = axes[1, col]
        ax.plot(t, d[:, 4], color="tab:blue", label="right ankle x (simulation)")
        ax.plot(t, d[:, 5], color="tab:orange", label="left ankle x (simulation)")
        ax.plot(t, 2.0 * (d[:, 6] - 0.105), color="tab:blue", ls=":", label="right ankle height x 2")
        ax.plot(t, 2.0 * (d[:, 7] - 0.105), color="tab:orange", ls=":", label="left ankle height x 2")
        ax = axes[2, col]
        ax.plot(t, d[:, 9], color="tab:purple", label="BODY tilt (simulation)")
        ax.axhline(45.0, color="tab:red", ls="--", lw=0.8, label="fallen (45 deg)")
        ax.set_ylim(0.0, 50.0)
        ax.set_xlabel("time after the push [s]")
        for a in axes[:, col]:
            a.fill_between(t, 0, 1, where=d[:, 10] > 0.5, transform=a.get_xaxis_transform(), color="tab:pink",
                           alpha=0.25, label="emergency step" if a is axes[0, col] else None)
        if d[-1, 9] > 45.0:
            axes[2, col].annotate(f"falls at {t[-1]:.2f} s", (t[-1], 45.0), textcoords="offset points",
                                  xytext=(-60, -20), fontsize=9)
    axes[0, 0].set_ylabel("x [m]")
    axes[1, 0].set_ylabel("[m]")
    axes[2, 0].set_ylabel("[deg]")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    for ax in axes[:, -1]:
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(f"{impulse_ns:g} N s forward push on BODY (2x the largest absorbed standing), standing, "
                 "Stabilizer on")
    fig.tight_layout()
    fig.savefig(out, dpi=100)


def plot_walk(out: Path) -> None:
    d = record_walk()
    t = d[:, 0]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for ax, k, name in ((axes[0], 0, "x"), (axes[1], 1, "y")):
        ax.plot(t, d[:, 1 + k] * 1e3, "k--", lw=1, label="ZMP ref (Eq. 4)")
        ax.plot(t, d[:, 3 + k] * 1e3, color="tab:green", lw=0.8, label="ZMP act (F/T)")
        ax.plot(t, d[:, 5 + k] * 1e3, color="tab:orange", label="COG ref (preview)")
        ax.plot(t, d[:, 7 + k] * 1e3, color="tab:red", lw=0.8, label="COG act (estimated)")
        ax.plot(t, d[:, 13 + k] * 1e3, color="tab:gray", lw=0.8, ls=":", label="COM (simulation)")
        ax.set_ylabel(f"{name} [mm]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[2].plot(t, d[:, 15] * 1e3, color="tab:purple", label="|CP ref - CP act|")
    axes[2].set_ylabel("CP error [mm]")
    axes[2].set_xlabel("time [s]")
    axes[2].grid(alpha=0.3)
    axes[2].legend(fontsize=8)
    fig.suptitle("goPos(0.6, 0.1, 0) in MuJoCo, AutoBalancer + Stabilizer on")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_push(out: Path) -> None:
    d = record_push()
    t = d[:, 0]
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    axes[0].plot(t, d[:, 3] * 1e3, color="tab:red", label="|CP error|")
    axes[0].plot(t, d[:, 4] * 1e3, color="tab:blue", ls="--", label="threshold")
    axes[0].fill_between(t, 0, d[:, 5] * d[:, 3].max() * 1e3, color="tab:pink", alpha=0.3, label="flag")
    axes[0].set_ylabel("[mm]")
    axes[0].legend(fontsize=8)
    axes[0].grid(alpha=0.3)
    axes[1].plot(t, d[:, 6] * 1e3, color="tab:green", label="ZMP x (F/T)")
    axes[1].plot(t, d[:, 8] * 1e3, color="tab:red", label="COG x (estimated)")
    axes[1].set_ylabel("x [mm]")
    axes[1].set_xlabel("time [s]")
    axes[1].legend(fontsize=8)
    axes[1].grid(alpha=0.3)
    fig.suptitle("20 N s forward push on BODY at t = 3 s, standing, Stabilizer on")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


#: the COG velocity filter before the LIP prediction (issue 13.2, toe-heel walk): the 4 Hz low-pass alone
COGVEL_BEFORE = {"st": {"cogvel_lip_prediction": False}}


def record_toe_heel_walk(overrides: dict | None = None, seconds: float = 8.0):
    """Stand 2.5 s, then the toe 20 / heel 10 deg footsteps of the walking tests; per tick while walking: time,
    the Stabilizer's |CP error| (estimated) and the simulation's own |CP ref - CP| (its COM and the COM's
    finite-difference velocity, the LIP's omega from the COM height over the reference ZMP)."""
    from app.service.verbs import Footstep
    from controller.core.constants import GRAVITY_M_S2
    from controller.walking.footsteps import StepParams

    robot = LocalRobot()
    loop = robot.loop
    service = OperatorService(robot)
    if overrides:
        service.set_params(overrides)
    robot.run_for(2.5)
    sp = StepParams(toe_angle_rad=np.radians(20.0), heel_angle_rad=np.radians(10.0))
    # relative to the first (the right foot where it stands): 0.2 m steps, the feet 0.19 m apart
    service.set_footsteps([Footstep("rleg", (0.0, 0.0, 0.0)), Footstep("lleg", (0.2, 0.19, 0.0)),
                           Footstep("rleg", (0.4, 0.0, 0.0)), Footstep("lleg", (0.4, 0.19, 0.0))], sp)
    rows, com_prev = [], None
    for _ in range(int(seconds / loop.dt_control_s)):
        s = robot.step()
        com = np.asarray(s.truth.com_world, dtype=float)
        vel = (com - com_prev) / loop.dt_control_s if com_prev is not None else np.zeros(3)
        com_prev = com
        if not s.layers["abc"].walking:
            continue
        st = s.layers["st"]
        omega = np.sqrt(GRAVITY_M_S2 / (com[2] - s.reference.gait.zmp_world[2]))
        true_err = np.hypot(*(np.asarray(st.cp_ref) - (com[:2] + vel[:2] / omega)))
        rows.append([s.time_s, st.cp_error_norm, true_err])
    return np.array(rows)


def plot_walk_cp_before_after(out: Path) -> None:
    runs = (("before: the COG velocity low-passed at 4 Hz (the anchor's switches already taken out)",
             record_toe_heel_walk(COGVEL_BEFORE)),
            ("after: the LIP's acceleration predicts, the 4 Hz low-pass corrects", record_toe_heel_walk()))
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True, sharey=True)
    for ax, (label, d) in zip(axes, runs, strict=True):
        p99 = np.percentile(d[:, 1], 99)
        ax.plot(d[:, 0], d[:, 1] * 1e3, color="tab:red", label=f"|CP error| estimated (p99 {p99 * 1e3:.1f} mm)")
        ax.plot(d[:, 0], d[:, 2] * 1e3, color="tab:gray", ls=":", label="|CP ref - CP| of the simulation")
        ax.axhline(25.0, color="tab:gray", ls="--", lw=0.8, label="goal p99 25 mm")
        ax.axhline(40.0, color="tab:blue", ls="--", label="threshold")
        ax.set_title(label, fontsize=10)
        ax.set_ylabel("[mm]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[1].set_xlabel("time [s]")
    fig.suptitle("Toe 20 / heel 10 deg footsteps: the capture-point error while walking (issue 13.2)")
    fig.tight_layout()
    fig.savefig(out, dpi=100)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out-dir", type=Path, default=Path("docs/img"))
    args = ap.parse_args(argv)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    plot_walk(args.out_dir / "walk_zmp_cog_cp.png")
    plot_push(args.out_dir / "push_cp_error.png")
    plot_push_before_after(args.out_dir / "push_before_after.png")
    plot_emergency_step_before_after(args.out_dir / "emergency_step_before_after.png")
    plot_walk_cp_before_after(args.out_dir / "walk_cp_error_before_after.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
