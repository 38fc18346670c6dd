"""The robot folder is complete, its generated files are current, and every scene steps without warnings."""

from __future__ import annotations

import pytest

import robot.generate as gen
from robot.names import MODEL_DIR
from robot.plant import SCENES, MujocoPlant, available_scenes

REQUIRED_FILES = ("hrp2.xml", "scene.xml", "hrp2.urdf", "README.md", "LICENSE", "CHANGELOG.md")


@pytest.mark.parametrize("name", REQUIRED_FILES)
def test_robot_folder_has(name):
    assert (MODEL_DIR / name).is_file()


def test_generated_files_are_byte_identical_to_a_fresh_generation(tmp_path):
    written = gen.generate(tmp_path)
    assert sorted(p.name for p in written) == sorted(gen.GENERATED_FILES)
    for path in written:
        stale = f"{path.name} is stale: run python -m robot.generate"
        assert path.read_bytes() == (MODEL_DIR / path.name).read_bytes(), stale


def test_generation_is_deterministic(tmp_path):
    first = gen.render()
    gen.generate(tmp_path)
    assert {name: (tmp_path / name).read_text() for name in gen.GENERATED_FILES} == first


def test_generated_files_hold_no_absolute_paths():
    for name in gen.GENERATED_FILES:
        text = (MODEL_DIR / name).read_text()
        assert str(MODEL_DIR) not in text and "file=\"/" not in text


@pytest.mark.parametrize("scene", available_scenes())
def test_scene_steps_one_second_without_warnings(scene):
    plant = MujocoPlant(scene)
    plant.step(round(1.0 / plant.dt_physics))
    assert plant.warnings() == {}
    assert plant.time_s == pytest.approx(1.0)


def test_unknown_scene_lists_the_valid_names():
    with pytest.raises(ValueError, match="default"):
        MujocoPlant("no_such_scene")


def test_scenes_point_at_existing_files():
    assert all(path.is_file() for path in SCENES.values())
