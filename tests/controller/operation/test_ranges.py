"""The points' ranges, defined once: each point's component bounds follow the components it uses, and the walking
point's ranges are exactly what the AutoBalancer takes (unit)."""

import math

import pytest

from controller.core.errors import InvalidCommand
from controller.core.types import WalkCommand
from controller.operation import ranges
from controller.operation.points import POINTS, USED_COMPONENTS
from controller.operation.ranges import WALK_FOOT_DISTANCE_RANGE_M, WALK_MAX_STRIDE_RANGE_M
from controller.walking.auto_balancer_params import check_walk_command


def test_every_point_has_bounds_and_a_component_it_does_not_use_is_bounded_at_zero():
    assert tuple(ranges.SPEED_BOUNDS) == POINTS
    for point in POINTS:
        for bounds, mask, limit in zip(ranges.component_bounds(point), USED_COMPONENTS[point],
                                       ranges.SPEED_BOUNDS[point], strict=True):
            assert bounds == tuple(limit if used else 0.0 for used in mask)
    assert ranges.component_bounds("head") == ((0.0, 0.0, 0.0), (0.0, math.radians(90.0), math.radians(90.0)))


def test_the_auto_balancer_takes_a_walk_command_at_the_edges_of_the_ranges():
    v, w = ranges.WALK_MAX_LINEAR_M_S, ranges.WALK_MAX_ANGULAR_RAD_S
    for stride, distance in ((WALK_MAX_STRIDE_RANGE_M[0], WALK_FOOT_DISTANCE_RANGE_M[1]),
                             (WALK_MAX_STRIDE_RANGE_M[1], WALK_FOOT_DISTANCE_RANGE_M[0])):
        check_walk_command(WalkCommand(v, -v, w, stride, distance))
        check_walk_command(WalkCommand(-v, v, -w, stride, distance))


@pytest.mark.parametrize(("command", "words"), [
    (WalkCommand(0.1, 0.0, 0.0, max_stride_m=WALK_MAX_STRIDE_RANGE_M[1] + 0.01), "max_stride_m=0.31"),
    (WalkCommand(0.1, 0.0, 0.0, foot_distance_m=WALK_FOOT_DISTANCE_RANGE_M[0] - 0.01), "foot_distance_m=0.13"),
    (WalkCommand(ranges.WALK_MAX_LINEAR_M_S + 0.01, 0.0, 0.0), "vx_m_s=0.51"),
    (WalkCommand(0.0, 0.0, ranges.WALK_MAX_ANGULAR_RAD_S * 1.01), "vtheta_rad_s"),
])
def test_the_auto_balancer_refuses_a_walk_command_just_beyond_the_ranges(command, words):
    with pytest.raises(InvalidCommand, match=words):
        check_walk_command(command)
