"""Named places: the known places of the objects the scene has, each located object (the operator's word on
it included), aliases, and an unknown name answered with the valid ones."""

import pytest

import robot.generate as gen
from behaviors.approach_table import TABLE_NEAR_EDGE_X_M
from behaviors.places import UnknownPlace, places, resolve

EXPO_OBJECTS = ("can", "table", "trash_box", "object")


def test_the_table_and_the_trash_box_are_known_where_the_behaviours_take_them_to_be():
    found = places(EXPO_OBJECTS, {})
    assert set(found) == {"table", "trash_box"}
    table = found["table"]
    assert table.source == "known"
    assert table.position_m == pytest.approx((TABLE_NEAR_EDGE_X_M + 0.15, 0.0, gen.EXPO_TABLE_SIZE_M[2] + 0.05))
    assert found["trash_box"].position_m == pytest.approx((*gen.TRASH_BOX_CENTRE_M, gen.TRASH_BOX_OUTER_M[2]))


def test_a_scene_without_those_objects_knows_no_place():
    assert places((), {}) == {}
    with pytest.raises(UnknownPlace, match="unknown place 'table'; valid: none"):
        resolve("table", (), {})


def test_a_located_object_is_a_place_and_replaces_the_known_one_of_the_same_name():
    recognitions = {"can": {"position_m": [2.1, 0.05, 0.7325], "status": "corrected"},
                    "trash_box": {"position_m": [1.43, -1.98, 0.6]}}
    found = places(EXPO_OBJECTS, recognitions)
    assert found["can"].position_m == (2.1, 0.05, 0.7325) and found["can"].source == "corrected"
    assert found["trash_box"].position_m == (1.43, -1.98, 0.6) and found["trash_box"].source == "estimated"


def test_box_is_the_trash_box_and_an_unknown_name_lists_the_valid_ones():
    assert resolve("box", EXPO_OBJECTS, {}).name == "trash_box"
    with pytest.raises(UnknownPlace) as err:
        resolve("sofa", EXPO_OBJECTS, {"can": {"position_m": [2.1, 0.0, 0.73]}})
    assert str(err.value) == "unknown place 'sofa'; valid: table, trash_box, can, box"
