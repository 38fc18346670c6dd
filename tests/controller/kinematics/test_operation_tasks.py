"""The operation IK's tasks: the scale of a point's step, the joint step bounds and the limit they name."""

from types import SimpleNamespace

import numpy as np
import pytest

from controller.kinematics.operation_params import OperationIKParams
from controller.kinematics.operation_targets import JOINT_LIMIT, REACH, VELOCITY
from controller.kinematics.operation_tasks import CHAINS, LIMBS, PointTask, StepBounds

P = OperationIKParams()
STEP = P.joint_velocity_limit_rad_s * P.dt_s  # [rad] per tick
K = P.dt_s / P.joint_limit_braking_time_s


class FakeSolver:
    """What StepBounds asks of placo's solver."""

    def __init__(self) -> None:
        self.removed = []

    def add_joint_space_half_spaces_constraint(self, A, b):
        return SimpleNamespace(A=A, b=b, configure=lambda *args: None)

    def remove_constraint(self, constraint) -> None:
        self.removed.append(constraint)


def bounds(free=(0, 1)):
    b = StepBounds(np.arange(30) + 7, -np.ones(30), np.ones(30))
    solver = FakeSolver()
    b.rebuild(solver, np.array(free), 37, P)
    return b, solver


def test_the_scale_is_the_achieved_step_along_the_requested_one():
    assert PointTask.scale(0.0, 0.0, (0.001, 0.0, 0.0), (0.002, 0.0, 0.0), (0.0,) * 3, (0.0,) * 3, P) == 0.5
    assert PointTask.scale(0.0, 0.0, (0.0, 0.002, 0.0), (0.002, 0.0, 0.0), (0.0,) * 3, (0.0,) * 3, P) == 0.0
    assert PointTask.scale(0.0, 0.0, (0.003, 0.0, 0.0), (0.002, 0.0, 0.0), (0.0,) * 3, (0.0,) * 3, P) == 1.0


def test_a_request_under_the_deadband_is_nothing_asked():
    tiny = (0.5 * P.scale_deadband_m, 0.0, 0.0)
    assert PointTask.scale(0.0, 0.0, (0.0,) * 3, tiny, (0.0,) * 3, (0.0,) * 3, P) == 1.0


def test_every_hand_chain_has_the_torso_and_its_own_arm_as_its_limb():
    for hand in ("rhand", "lhand"):
        assert set(LIMBS[hand]) < set(CHAINS[hand])
    assert LIMBS["head"] == CHAINS["head"]


def test_the_step_bounds_are_the_velocity_limit_far_from_a_limit_and_brake_near_one():
    b, _ = bounds()
    q = np.zeros(37)
    q[7 + 1] = 0.99  # joint 1 near its upper limit 1 rad
    b.update(q, STEP)
    upper, lower = b.constraint.b[:2], b.constraint.b[2:]
    assert upper[0] == pytest.approx(STEP) and lower[0] == pytest.approx(STEP)  # q + dq <= q + step
    assert upper[1] == pytest.approx(0.99 + K * 0.01)  # a step covers k of the distance left
    assert np.array_equal(b.constraint.A[0, 7:9], (1.0, 0.0)) and np.array_equal(b.constraint.A[3, 7:9], (0.0, -1.0))


def test_rebuilding_the_bounds_replaces_the_constraint():
    b, solver = bounds()
    first = b.constraint
    b.rebuild(solver, np.array((0, 1, 2)), 37, P)
    assert solver.removed == [first] and b.constraint.A.shape == (6, 37)


def test_the_limit_named_is_the_limbs_joint_limit_the_chains_velocity_or_else_the_reach():
    b, _ = bounds()
    point = SimpleNamespace(bound_rows=None, chain_list=[0, 1], limb_set=frozenset({1}))
    q_prev = [0.0] * 37
    q_prev[7 + 1] = 0.99
    braked = list(q_prev)
    braked[7 + 1] += K * 0.01
    assert b.limit_reason(point, q_prev, braked, STEP) == JOINT_LIMIT
    fast = list(q_prev)
    fast[7] += STEP
    assert b.limit_reason(point, q_prev, fast, STEP) == VELOCITY
    assert b.limit_reason(point, q_prev, q_prev, STEP) == REACH
