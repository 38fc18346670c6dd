"""The experiments' declared disturbances: defaults are the experiments of docs/estop-study.md, values are checked by
name and range, the CLI's --disturb names what is allowed."""

import math

import pytest

from app.lab.experiments import EXPERIMENTS
from app.lab.experiments.common import DisturbanceParam
from tests.app.test_cli import run

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_no_values_give_every_declared_disturbance_at_its_default():
    for exp in EXPERIMENTS.values():
        assert exp.disturbance() == {name: d.default for name, d in exp.disturbances.items()}
    assert EXPERIMENTS["wall-push-forward"].disturbance()["push_speed_m_s"] == 0.25 / 4.0  # Fig. 9 (alpha)
    assert EXPERIMENTS["wall-push-left"].disturbance()["push_speed_m_s"] == 0.25 / 2.0  # Fig. 9 (beta)


def test_an_unknown_disturbance_lists_the_accepted_ones():
    with pytest.raises(ValueError, match="wall_gap_m, push_height_m, push_yaw_deg, push_speed_m_s"):
        EXPERIMENTS["wall-push-forward"].disturbance({"gap": 0.1})
    with pytest.raises(ValueError, match="accepts: none"):
        EXPERIMENTS["door"].disturbance({"offset_x_m": 0.1})


@pytest.mark.parametrize("value", [0.5, -0.2, math.nan, math.inf, True, "0.1", None])
def test_a_value_out_of_range_or_not_a_number_names_the_range(value):
    with pytest.raises(ValueError, match=r"wall_gap_m must be a number in \[-0.04, 0.1\] m"):
        EXPERIMENTS["wall-push-forward"].disturbance({"wall_gap_m": value})


def test_a_declared_default_must_lie_in_its_range():
    with pytest.raises(ValueError, match="default"):
        DisturbanceParam(1.0, 0.0, 0.5, "m", "")


def test_the_experiment_command_refuses_a_bad_disturbance_naming_the_option():
    r = run("experiment", "valve", "--disturb", "offset_x_m=0.5")
    assert r.returncode == 2
    assert "--disturb" in r.stderr and "offset_x_m must be a number in [0, 0.13] m" in r.stderr
    r = run("experiment", "valve", "--disturb", "offset_x_m")
    assert r.returncode == 2 and "NAME=VALUE" in r.stderr
