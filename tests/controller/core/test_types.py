"""Tests of controller.core.types: the Reference's one list of fields."""

import dataclasses

import numpy as np
import pytest

from controller.core.types import Reference
from robot.names import FORCE_SENSOR_NAMES, NUM_JOINTS

FIELDS = tuple(f.name for f in dataclasses.fields(Reference))


def sentinel_reference() -> tuple[Reference, dict]:
    """A Reference whose every field holds its own object, so a field reset to a default shows."""
    values = {name: object() for name in FIELDS}
    return Reference(**values), values


def test_with_keeps_every_field_it_is_not_asked_to_change():
    ref, values = sentinel_reference()
    kept = ref.with_()
    assert {name: getattr(kept, name) for name in FIELDS} == values


@pytest.mark.parametrize("name", FIELDS)
def test_with_changes_only_the_named_field(name):
    ref, values = sentinel_reference()
    new = object()
    changed = ref._replace({name: new})
    assert {n: getattr(changed, n) for n in FIELDS} == {**values, name: new}


def test_with_copies_checks_and_freezes_each_array_field_to_its_shape():
    ref = Reference.from_arrays(np.zeros(NUM_JOINTS))
    shapes = {f.name: f.metadata["shape"] for f in dataclasses.fields(Reference) if "shape" in f.metadata}
    assert set(shapes) == {"q_rad", "base_pos_world", "base_rpy_rad", "zmp_base", "wrenches"}
    for name, shape in shapes.items():
        value = np.ones(shape)
        out = getattr(ref.with_(**{name: value}), name)
        assert out is not value and not out.flags.writeable and out.shape == shape
        with pytest.raises(ValueError, match="expected shape"):
            ref.with_(**{name: np.ones(shape[0] + 1)})


def test_with_rejects_an_unknown_field():
    with pytest.raises(TypeError):
        Reference.from_arrays(np.zeros(NUM_JOINTS)).with_(q=np.zeros(NUM_JOINTS))


def test_from_arrays_freezes_every_array_and_fills_the_defaults():
    ref = Reference.from_arrays(np.zeros(NUM_JOINTS))
    assert ref.wrenches.shape == (len(FORCE_SENSOR_NAMES), 6) and ref.gait is None
    assert all(not getattr(ref, n).flags.writeable for n in FIELDS if n != "gait")
