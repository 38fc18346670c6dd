"""The EXPO 2005 scene [OP VI]: table, 300 ml can, trash box with a 120 x 280 mm hole, an unknown object."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import robot.generate as gen
from robot.names import MODEL_DIR
from robot.plant import SCENES, MujocoPlant

CAN_RADIUS_M = 0.0325
CAN_HEIGHT_M = 0.107
TABLE_TOP_Z_M = 0.70
#: A can at rest on the table after 1 s, measured: 0.043 mm below its nominal height (contact penetration),
#: 0.01 mm horizontal drift, 0.011 deg tilt; allowed (margin for other placements): 1 mm, 1 mm, 0.5 deg.
REST_Z_TOLERANCE_M = 0.001
REST_DRIFT_TOLERANCE_M = 0.001
REST_TILT_TOLERANCE_DEG = 0.5
RANDOM_PLACEMENTS = 10


@pytest.fixture(scope="module")
def plant():
    return MujocoPlant("expo")


def world_aabb(plant: MujocoPlant, prefix: str) -> tuple[np.ndarray, np.ndarray]:
    """World-frame bounds of the geoms whose names start with `prefix` (boxes and cylinders, yaw only)."""
    m, d = plant.model, plant.data
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for g in range(m.ngeom):
        if not m.geom(g).name.startswith(prefix):
            continue
        R = d.geom_xmat[g].reshape(3, 3)
        half = np.abs(R) @ m.geom_aabb[g, 3:]
        lo, hi = np.minimum(lo, d.geom_xpos[g] - half), np.maximum(hi, d.geom_xpos[g] + half)
    return lo, hi


def tilt_deg(quat_wxyz) -> float:
    w, x, y, z = quat_wxyz
    return math.degrees(math.acos(min(1.0, 1.0 - 2.0 * (x * x + y * y))))


def test_expo_scene_is_registered_and_generated():
    assert SCENES["expo"] == MODEL_DIR / "scene_expo.xml"
    assert "scene_expo.xml" in gen.GENERATED_FILES


def test_scene_steps_two_seconds_standing_without_warnings():
    plant = MujocoPlant("expo")
    q_home_rad = np.array(plant.data.ctrl)
    for _ in range(400):
        plant.write(q_home_rad)
        plant.step(5)
    assert plant.warnings() == {}
    assert plant.ground_truth().base_pos_world[2] > 0.6  # still standing


def test_table_is_0_75_m_deep_1_5_m_wide_0_70_m_high_with_its_near_edge_2_m_ahead(plant):
    plant.reset()
    lo, hi = world_aabb(plant, "table_")
    np.testing.assert_allclose(hi - lo, [0.75, 1.5, 0.70], atol=1e-9)
    np.testing.assert_allclose(lo, [2.0, -0.75, 0.0], atol=1e-9)


def test_can_is_65_mm_across_107_mm_tall_330_g_and_stands_on_the_table(plant):
    plant.reset()
    m = plant.model
    can = m.geom("can")
    assert 2 * can.size[0] == pytest.approx(0.065) and 2 * can.size[1] == pytest.approx(CAN_HEIGHT_M)
    assert m.body("can").mass[0] == pytest.approx(0.33)
    assert plant.placeable_objects()["can"] == "free"
    pos, _ = plant.object_pose("can")
    np.testing.assert_allclose(pos, [2.15, 0.0, TABLE_TOP_Z_M + CAN_HEIGHT_M / 2])


def test_trash_box_has_a_280_by_120_mm_hole_in_a_lid_0_60_m_up_2_m_from_the_robot_at_the_table(plant):
    plant.reset()
    m, d = plant.model, plant.data
    lo, hi = world_aabb(plant, "trash_box_")
    np.testing.assert_allclose(hi - lo, [0.45, 0.30, 0.60], atol=1e-9)
    # the hole: the gap between the four lid plates
    ends = [world_aabb(plant, f"trash_box_lid_{s}") for s in ("px", "nx", "py", "ny")]
    hole_x = ends[0][0][0] - ends[1][1][0]
    hole_y = ends[2][0][1] - ends[3][1][1]
    assert (hole_x, hole_y) == (pytest.approx(0.28), pytest.approx(0.12))
    hole_centre = np.array([(ends[0][0][0] + ends[1][1][0]) / 2, (ends[2][0][1] + ends[3][1][1]) / 2])
    np.testing.assert_allclose(hole_centre, gen.TRASH_BOX_CENTRE_M, atol=1e-9)
    assert np.linalg.norm(hole_centre - [1.4, 0.0]) == pytest.approx(2.0)
    assert plant.placeable_objects()["trash_box"] == "fixed"  # static, moved only by placing it
    assert d.mocap_pos[m.body_mocapid[m.body("trash_box").id]][2] == 0.0  # standing on the floor


def test_unknown_object_is_a_300_g_box_on_the_floor_near_the_table(plant):
    plant.reset()
    m = plant.model
    assert 0.2 <= m.body("unknown_object").mass[0] <= 0.5
    pos, _ = plant.object_pose("unknown_object")
    assert pos[2] == pytest.approx(gen.UNKNOWN_OBJECT_SIZE_M[2] / 2)
    table_lo, table_hi = world_aabb(plant, "table_")
    gap_m = np.linalg.norm(np.maximum(np.maximum(table_lo[:2] - pos[:2], pos[:2] - table_hi[:2]), 0.0))
    assert 0.1 < gap_m < 1.0


def test_objects_are_free_or_fixed_as_documented(plant):
    assert plant.placeable_objects() == {"table": "fixed", "trash_box": "fixed", "can": "free",
                                         "unknown_object": "free"}


def test_can_placed_at_random_spots_along_the_near_edge_rests_upright_on_the_table(plant):
    rng = np.random.default_rng(2005)
    q_home_rad = None
    for _ in range(RANDOM_PLACEMENTS):
        plant.reset()
        q_home_rad = np.array(plant.data.ctrl) if q_home_rad is None else q_home_rad
        from_edge_m = rng.uniform(*gen.EXPO_CAN_FROM_EDGE_RANGE_M)
        y_m = rng.uniform(-0.75 + 0.05, 0.75 - 0.05)
        placed = plant.place_object("can", (2.0 + from_edge_m, y_m), yaw_rad=rng.uniform(-math.pi, math.pi))
        assert placed[2] == pytest.approx(TABLE_TOP_Z_M + CAN_HEIGHT_M / 2)
        for _ in range(200):
            plant.write(q_home_rad)
            plant.step(5)
        pos, quat = plant.object_pose("can")
        assert pos[2] == pytest.approx(placed[2], abs=REST_Z_TOLERANCE_M)
        assert np.linalg.norm(pos[:2] - placed[:2]) < REST_DRIFT_TOLERANCE_M
        assert tilt_deg(quat) < REST_TILT_TOLERANCE_DEG
    assert plant.warnings() == {}


def test_a_can_dropped_0_1_m_above_the_hole_centre_ends_inside_the_box(plant):
    plant.reset()
    hole = np.array(gen.TRASH_BOX_CENTRE_M)
    lid_top_m = gen.TRASH_BOX_OUTER_M[2]
    plant.place_object("can", (*hole, lid_top_m + 0.1 + CAN_HEIGHT_M / 2))
    plant.step(2000)
    pos, _ = plant.object_pose("can")
    inner_half = np.array(gen.TRASH_BOX_OUTER_M[:2]) / 2 - gen.TRASH_BOX_WALL_M
    assert np.all(np.abs(pos[:2] - hole) < inner_half)
    assert pos[2] < gen.TRASH_BOX_WALL_M + CAN_HEIGHT_M  # on the bottom, upright or lying
    assert plant.warnings() == {}


def test_placing_on_x_y_puts_a_free_object_on_what_is_below_it(plant):
    plant.reset()
    on_floor = plant.place_object("can", (1.0, 0.5))
    assert on_floor[2] == pytest.approx(CAN_HEIGHT_M / 2)
    into_box = plant.place_object("can", gen.TRASH_BOX_CENTRE_M)  # through the hole onto the bottom
    assert into_box[2] == pytest.approx(gen.TRASH_BOX_WALL_M + CAN_HEIGHT_M / 2)
    on_lid = plant.place_object("can", (gen.TRASH_BOX_CENTRE_M[0] + 0.18, gen.TRASH_BOX_CENTRE_M[1]))
    assert on_lid[2] == pytest.approx(gen.TRASH_BOX_OUTER_M[2] + CAN_HEIGHT_M / 2)


def test_placing_the_table_moves_all_of_it_until_the_next_reset(plant):
    plant.reset()
    plant.place_object("table", (1.0, 0.5), yaw_rad=math.pi / 2)
    lo, hi = world_aabb(plant, "table_")
    np.testing.assert_allclose(hi - lo, [1.5, 0.75, 0.70], atol=1e-9)
    np.testing.assert_allclose((lo + hi)[:2] / 2, [1.0, 0.5], atol=1e-9)
    assert lo[2] == pytest.approx(0.0)
    plant.reset()
    np.testing.assert_allclose(world_aabb(plant, "table_")[0], [2.0, -0.75, 0.0], atol=1e-9)


def test_placed_free_object_is_at_rest(plant):
    plant.reset()
    plant.step(10)
    plant.place_object("unknown_object", (1.5, 1.2, 0.3), yaw_rad=0.4)
    adr = plant.model.joint("unknown_object_free").dofadr[0]
    assert np.all(plant.data.qvel[adr:adr + 6] == 0.0)
    pos, quat = plant.object_pose("unknown_object")
    np.testing.assert_allclose(pos, [1.5, 1.2, 0.3])
    np.testing.assert_allclose(quat, [math.cos(0.2), 0, 0, math.sin(0.2)])


def test_unknown_object_names_list_the_valid_ones(plant):
    with pytest.raises(ValueError, match="can, unknown_object"):
        plant.place_object("cup", (2.2, 0.0))
    with pytest.raises(ValueError, match="none in this scene"):
        MujocoPlant().place_object("can", (2.2, 0.0))


@pytest.mark.parametrize("position", [(1.0,), (1.0, 2.0, 3.0, 4.0), (np.nan, 0.0), "here"])
def test_place_object_rejects_positions_that_are_not_2_or_3_finite_numbers(plant, position):
    with pytest.raises(ValueError, match="position"):
        plant.place_object("can", position)


def test_the_open_gripper_takes_the_65_mm_can_and_closes_on_it_before_its_limit():
    params = gen.load_parameters()
    face_x = gen.gripper_fixed_jaw_face_x(params, "RARM")
    px, _, _ = gen.gripper_pivot(params, "RARM")
    pad_inner_x = px + gen.FINGER_PAD_DEPTH_M * math.sin(math.radians(60.0)) - gen.FINGER_PAD_RADIUS_M
    assert pad_inner_x - face_x > gen.CAN_DIAMETER_M + 0.03  # 3 cm to spare on approach
    _, finger_rad = gen.grasp_centre(params, "RARM", gen.CAN_DIAMETER_M / 2)
    assert math.radians(-60.0) < finger_rad < math.radians(16.0) - math.radians(30.0)  # far from the stop


def test_the_grasp_contact_model_is_the_one_the_modelling_guide_advises_against_slip(plant):
    """Elliptic cones with impratio 10 (friction as stiff as the normal direction), condim 6 on the objects a
    hand takes (torsional and rolling friction against turning in a two-jaw grasp), jaws and pads primitives,
    and no noslip pass papering over creep; robot/hrp2/README.md, "Contact model for grasping"."""
    m = plant.model
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.opt.impratio >= 10.0
    assert m.opt.noslip_iterations == 0
    for name in ("can", "unknown_object"):
        assert m.geom(name).condim[0] == 6
    hand_geoms = [m.geom(g).name for g in range(m.ngeom)
                  if "finger" in m.geom(g).name or "jaw" in m.geom(g).name]
    assert hand_geoms, "no jaw or finger geoms found"
    assert all(m.geom(g).type[0] != mujoco.mjtGeom.mjGEOM_MESH for g in hand_geoms)
