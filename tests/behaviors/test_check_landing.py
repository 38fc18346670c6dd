"""The landing verdict (behaviors/check_landing.py): in the box when the can is seen within the lid's outline
below its top or not seen around the box, out when seen anywhere else; along/across in the box's own axes."""

from __future__ import annotations

import math

import pytest

from behaviors.check_landing import landing_verdict
from behaviors.perception.models import IN_BOX, OUT_OF_BOX

HOLE_M = (1.4, -2.0, 0.6)


def test_not_seen_around_the_box_is_in_it():
    landing = landing_verdict(None, HOLE_M, 0.0)
    assert landing.verdict == IN_BOX and landing.can_world_m is None
    assert "not seen" in landing.detail()


@pytest.mark.parametrize("yaw_deg", [0.0, 90.0, -30.0])
@pytest.mark.parametrize(("along_m", "across_m", "z_m", "verdict"), [
    (0.0, 0.0, 0.3, IN_BOX),  # below the hole
    (0.2, 0.1, 0.1, IN_BOX),  # in a corner, inside the lid's 0.45 x 0.30 m outline
    (0.0, 0.0, 0.65, OUT_OF_BOX),  # on the lid
    (0.24, 0.0, 0.03, OUT_OF_BOX),  # on the floor just past the long side's end
    (0.0, 0.16, 0.03, OUT_OF_BOX),  # just past the short side
    (0.6, -0.4, 0.03, OUT_OF_BOX),
])
def test_the_verdict_follows_the_lids_outline_in_the_boxs_own_axes(yaw_deg, along_m, across_m, z_m, verdict):
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    can = (HOLE_M[0] + c * along_m - s * across_m, HOLE_M[1] + s * along_m + c * across_m, z_m)
    landing = landing_verdict(can, HOLE_M, yaw_deg)
    assert landing.verdict == verdict
    assert (landing.along_m, landing.across_m) == pytest.approx((along_m, across_m), abs=1e-9)
    assert ("outside the box" in landing.detail()) == (verdict == OUT_OF_BOX)


def test_bad_positions_name_the_fields():
    with pytest.raises(ValueError, match="can_world_m and hole_world_m"):
        landing_verdict((1.0, 2.0), HOLE_M, 0.0)
