"""The foot-can task of [OP] VI, Fig. 8 ("manipulating a can on the floor using its right foot"):
`hrp2-console experiment foot-can [--seed N] [--trials K]`.

The EXPO scene's 300 ml can stands on the floor ahead of the right foot, a mark a few centimetres further on
(seeded: the can's place and the mark's distance vary). A scripted operator streams the `rfoot` point every tick
through `OperatorService.put_setpoint` (the path of WS /ws/operator): up 2 cm (the robot first puts its COM over
the left foot, controller/walking/foot_lift.py), across to behind the can, forward until the sole's front edge is a
can's radius short of the mark, back off, back over its rest place, and lets go (the foot is put down, the weight
shared again). The operator knows where it placed the can and the mark relative to the right sole (as a human sees
them) and its own foot from the operation layer's status; the can is not tracked while pushed. The simulator's
pose of the can is read only for the verdict: its centre within MARK_TOL_M of the mark, upright, the robot standing
on both feet again, no fall."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

import robot.generate as gen
from app.service import OperatorService
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from controller.balance.capture_point import HRP2_RIGHT_SOLE
from controller.walking.foot_lift import sole_centre_offset_m

SETTLE_S = 2.5  # [s] standing before the first command (the AutoBalancer starts in 2 s)
PUSH_HEIGHT_M = 0.02  # [m] the sole this far above the floor while it moves and pushes
MOVE_M_S = 0.05  # [m/s] the stick's speed to get there; pushing, PUSH_M_S
PUSH_M_S = 0.03
GAIN_1_S = 2.0  # [1/s] stick speed per metre of error: the operator slows near the goal
AT_M = 0.001  # [m] the foot counts as there
BACK_OFF_M = 0.05  # [m] after the push the sole backs off this far before it goes home
#: the can's centre relative to the right sole's rest frame [m]: x (forward) and y (across, from the sole's
#: centre line) drawn per trial; its rear starts >= 3.5 cm ahead of the sole's front edge (0.1236 m)
CAN_X_RANGE_M = (0.19, 0.23)
CAN_Y_RANGE_M = (-0.02, 0.02)
MARK_AHEAD_RANGE_M = (0.06, 0.10)  # [m] the mark this far ahead of the can's start
MARK_TOL_M = 0.02  # [m] the verdict: the can's centre within this of the mark
UPRIGHT_TOL_DEG = 10.0  # [deg] ... its axis within this of the vertical
CAN_R_M = gen.CAN_DIAMETER_M / 2


@dataclass
class FootCanResult:
    seed: int
    verdict: str  # "succeeded" or "failed: why"
    can_start_m: tuple[float, float]  # world x, y [m]
    mark_m: tuple[float, float]
    can_end_m: tuple[float, float]
    error_m: float  # the can's centre from the mark at the end
    tilt_deg: float
    fallen: bool
    cp_error_peak_mm: float
    sim_time_s: float
    wall_time_s: float

    @property
    def succeeded(self) -> bool:
        return self.verdict == "succeeded"


def draw(seed: int) -> tuple[float, float, float]:
    """The trial's can (x, y relative to the right sole's rest frame [m]) and the mark's distance ahead [m]."""
    rng = np.random.default_rng(seed)
    return (float(rng.uniform(*CAN_X_RANGE_M)), float(rng.uniform(*CAN_Y_RANGE_M)),
            float(rng.uniform(*MARK_AHEAD_RANGE_M)))


def push_offset_m(mark_x_m: float, can_y_m: float) -> tuple[float, float]:
    """The right sole's offset (x, y [m], from its rest place) that leaves a pushed can's centre on the mark: the
    sole's front edge a can's radius short of it, the sole's centre line on the can's (positions relative to the
    rest sole's frame)."""
    _, centre_y = sole_centre_offset_m(HRP2_RIGHT_SOLE)
    return mark_x_m - CAN_R_M - HRP2_RIGHT_SOLE.front_m, can_y_m - centre_y


class FootOperator:
    """A scripted operator streaming the rfoot stick every tick toward a goal offset."""

    def __init__(self, robot: LocalRobot, service: OperatorService) -> None:
        self.robot, self.service = robot, service
        self.cp_error_peak_m = 0.0

    def step(self) -> None:
        obs = self.robot.step()
        st = obs.snapshot.layers.get("st")
        if st is not None:
            self.cp_error_peak_m = max(self.cp_error_peak_m, st.cp_error_norm)
        if obs.fallen or obs.snapshot.fault is not None:
            raise RuntimeError("the robot fell" if obs.fallen else f"fault: {obs.snapshot.fault}")
        if obs.snapshot.layers["op"].motion_stopped:
            raise RuntimeError("the EmergencyStopper stopped the motion (capture-point flag)")

    def foot(self):
        """The rfoot point's status (the controller's own target and achieved offset) and the lift's phase."""
        snap = self.robot.loop.snapshot
        return snap.layers["op"].points["rfoot"], snap.layers["abc"].foot_lift

    def drive(self, goal_m, speed_m_s: float = MOVE_M_S, timeout_s: float = 15.0) -> None:
        goal = np.array(goal_m, dtype=float)
        for _ in range(round(timeout_s / self.robot.loop.dt_control_s)):
            point, phase = self.foot()
            target = np.zeros(3) if point.target is None else np.array(point.target)
            achieved = None if point.achieved is None else np.array(point.achieved)
            err = goal - target
            n = float(np.linalg.norm(err))
            v = err / n * min(speed_m_s, GAIN_1_S * n) if n > 1e-4 else np.zeros(3)
            self.service.put_setpoint(Setpoint("rfoot", tuple(v.tolist()), (0.0, 0.0, 0.0)))
            self.step()
            if phase == "lifted" and achieved is not None and np.linalg.norm(goal - achieved) < AT_M:
                return
        raise RuntimeError(f"the foot did not reach {goal.round(3).tolist()} m in {timeout_s:g} s")

    def wait(self, seconds: float) -> None:
        for _ in range(round(seconds / self.robot.loop.dt_control_s)):
            self.step()


def run(seed: int) -> FootCanResult:
    """One seeded trial."""
    wall0 = time.perf_counter()
    robot = LocalRobot("expo", speed=None)
    service = OperatorService(robot)
    can_x, can_y, ahead = draw(seed)
    robot.loop.run_for(SETTLE_S)
    rsole = robot.loop.snapshot.reference.gait.p_rsole_world  # (the plan's frame is the world's at the start)
    _, centre_y = sole_centre_offset_m(HRP2_RIGHT_SOLE)
    start = (float(rsole[0] + can_x), float(rsole[1] + centre_y + can_y))
    mark = (start[0] + ahead, start[1])
    robot.plant.place_object("can", start)  # a simulator operation, as the experimenter would
    op = FootOperator(robot, service)
    fallen, why = False, None
    try:
        push_x, push_y = push_offset_m(can_x + ahead, centre_y + can_y)
        op.drive((0.0, 0.0, PUSH_HEIGHT_M))
        op.drive((0.0, push_y, PUSH_HEIGHT_M))
        op.drive((push_x, push_y, PUSH_HEIGHT_M), PUSH_M_S)
        op.drive((push_x - BACK_OFF_M, push_y, PUSH_HEIGHT_M))
        op.drive((0.0, 0.0, PUSH_HEIGHT_M))
        op.wait(4.0)  # the stick let go: the foot is put down and the weight shared again
    except RuntimeError as exc:
        why = str(exc)
        fallen = robot.loop.snapshot.safety.fall is not None
    p, q = robot.plant.object_pose("can")
    w, x, y, _ = q.tolist()
    tilt = math.degrees(2.0 * math.asin(min(1.0, math.hypot(x, y))))  # the can's axis from the vertical
    error = math.hypot(p[0] - mark[0], p[1] - mark[1])
    phase = robot.loop.snapshot.layers["abc"].foot_lift
    if why is None and phase != "idle":
        why = f"the foot is not down (phase {phase})"
    if why is None and error > MARK_TOL_M:
        why = f"the can is {1e3 * error:.0f} mm from the mark (tolerance {1e3 * MARK_TOL_M:.0f} mm)"
    if why is None and tilt > UPRIGHT_TOL_DEG:
        why = f"the can tipped ({tilt:.0f} deg)"
    return FootCanResult(seed=seed, verdict="succeeded" if why is None else f"failed: {why}", can_start_m=start,
                         mark_m=mark, can_end_m=(float(p[0]), float(p[1])), error_m=error, tilt_deg=tilt,
                         fallen=fallen, cp_error_peak_mm=1e3 * op.cp_error_peak_m,
                         sim_time_s=robot.loop.snapshot.time_s, wall_time_s=time.perf_counter() - wall0)


def plot_trials(results: list[FootCanResult], out) -> None:
    """Top view of the trials: each can's start, end and mark with the tolerance circle [m, world]."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 5))
    for k, r in enumerate(results):
        ax.plot(*r.can_start_m, "o", color="0.6", label="can start" if k == 0 else None)
        ax.plot(*r.mark_m, "+", color="g", ms=10, label="mark" if k == 0 else None)
        ax.add_patch(plt.Circle(r.mark_m, MARK_TOL_M, fill=False, color="g", lw=0.5))
        ax.plot(*r.can_end_m, "x", color="r" if not r.succeeded else "b", label="can end" if k == 0 else None)
        ax.annotate("", r.can_end_m, r.can_start_m, arrowprops={"arrowstyle": "->", "color": "0.7", "lw": 0.6})
    ax.set_aspect("equal")
    ax.set_xlabel("x (forward) [m]")
    ax.set_ylabel("y (left) [m]")
    ok = sum(r.succeeded for r in results)
    ax.set_title(f"foot-can: {ok}/{len(results)} within {1e3 * MARK_TOL_M:.0f} mm of the mark")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def main(argv) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="hrp2-console experiment foot-can",
                                description="[OP] Fig. 8: a can on the floor pushed to a mark by the right foot, "
                                            "the foot streamed as an operational point by a scripted operator.")
    p.add_argument("--seed", type=int, default=0, help="the first trial's seed (the can's place, the mark)")
    p.add_argument("--trials", type=int, default=1, help="seeded trials: seed, seed + 1, ...")
    p.add_argument("--plot", default=None, help="write a top view of the trials to this PNG")
    args = p.parse_args(list(argv))
    if args.trials < 1:
        p.error(f"--trials: {args.trials} must be >= 1")
    ok, results = 0, []
    for seed in range(args.seed, args.seed + args.trials):
        r = run(seed)
        ok += r.succeeded
        results.append(r)
        print(f"seed {seed}: can from ({r.can_start_m[0]:.3f}, {r.can_start_m[1]:.3f}) to ({r.can_end_m[0]:.3f}, "
              f"{r.can_end_m[1]:.3f}) m, mark ({r.mark_m[0]:.3f}, {r.mark_m[1]:.3f}): {1e3 * r.error_m:.1f} mm off, "
              f"tilted {r.tilt_deg:.1f} deg; cp error peak {r.cp_error_peak_mm:.0f} mm; {r.sim_time_s:.1f} s "
              f"simulated in {r.wall_time_s:.1f} s; {r.verdict}", flush=True)
    print(f"foot-can: {ok}/{args.trials} succeeded")
    if args.plot:
        plot_trials(results, args.plot)
    return 0 if ok == args.trials else 1


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
