"""The robot's silhouette (robot/silhouette.py) is drawing only: it touches nothing, weighs nothing, stays out of
the head cameras' images and of their view; the 3D view draws it in place of the collision shapes."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from app.console.viewer_meshes import drawn_geoms
from robot.names import MODEL_DIR
from robot.silhouette import SILHOUETTE_GROUP, WINDOW_DEPTH_M


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(MODEL_DIR / "scene_expo.xml"))


def silhouette_ids(model) -> np.ndarray:
    return np.flatnonzero(model.geom_group == SILHOUETTE_GROUP)


def test_the_silhouette_collides_with_nothing_and_is_not_rendered_by_default(model):
    ids = silhouette_ids(model)
    assert len(ids) >= 20  # chest 4, head 7, two hands 3 + 2 each
    assert not model.geom_contype[ids].any() and not model.geom_conaffinity[ids].any()
    assert not mujoco.MjvOption().geomgroup[SILHOUETTE_GROUP]  # the head cameras' renderer leaves it out


def test_its_bodies_keep_their_colliding_geoms(model):
    for g in silhouette_ids(model):
        body = model.geom_bodyid[g]
        own = [h for h in range(model.ngeom) if model.geom_bodyid[h] == body and model.geom_contype[h]]
        assert own, f"{model.body(body).name} lost its collision shapes"


def test_the_camera_windows_sit_behind_the_cameras_optical_centres(model):
    for name in ("wide", "narrow_left", "narrow_right"):
        cam, window = model.camera(name), model.geom(f"window_{name}")
        assert window.bodyid[0] == cam.bodyid[0]
        front_x = window.pos[0] + WINDOW_DEPTH_M / 2
        assert front_x < cam.pos[0]
        assert window.pos[1:] == pytest.approx(cam.pos[1:])


def test_the_view_draws_the_silhouette_where_there_is_one_and_the_collision_shapes_elsewhere(model):
    drawn = set(drawn_geoms(model))
    chest, thigh = model.body("CHEST_LINK1").id, model.body("RLEG_LINK2").id
    on = {b: {g for g in drawn if model.geom_bodyid[g] == b} for b in (chest, thigh)}
    assert on[chest] and all(model.geom_group[g] == SILHOUETTE_GROUP for g in on[chest])
    assert on[thigh] and all(model.geom_group[g] == 0 for g in on[thigh])
    assert not any(model.geom_group[g] == SILHOUETTE_GROUP and model.geom_bodyid[g] not in
                   {model.geom_bodyid[h] for h in silhouette_ids(model)} for g in drawn)


def test_the_drawn_robot_stays_light_for_software_webgl(model):
    from app.console.viewer_meshes import geom_mesh

    robot = {model.body(b).id for b in range(model.nbody) if model.body(b).rootid[0] == model.body("BODY").id}
    vertices = sum(len(m.vertices) for g in drawn_geoms(model) if model.geom_bodyid[g] in robot
                   and (m := geom_mesh(model, g)) is not None)
    print(f"robot vertices drawn as meshes: {vertices}")
    assert vertices < 4000  # measured 2460 (capsules 16x8, cylinders 24 sections)
