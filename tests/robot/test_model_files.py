"""The robot folder is complete, its generated files are current, and every scene steps without warnings."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import robot.generate as gen
from app.lab.experiments import wall as wall_experiment
from robot.names import MODEL_DIR
from robot.plant import SCENES, MujocoPlant, available_scenes

REQUIRED_FILES = ("hrp2.xml", "scene.xml", "scene_wall.xml", "scene_valve.xml", "scene_door.xml", "scene_expo.xml",
                  "scene_fridge.xml", "scene_trash.xml", "scene_chair.xml", "hrp2.urdf", "README.md", "LICENSE",
                  "CHANGELOG.md")


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


# ------------------------------------------------------------------ emergency-stop scenes


def test_emergency_stop_scenes_are_registered():
    assert set(available_scenes()) >= {"default", "wall", "valve", "door"}
    for name in ("wall", "valve", "door"):
        assert SCENES[name] == MODEL_DIR / f"scene_{name}.xml"


def _pose(plant, deg: dict[str, float]):
    """The home keyframe with some joints overridden [deg], kinematics only."""
    m, d = plant.model, plant.data
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    for joint, value in deg.items():
        d.qpos[m.joint(joint).qposadr[0]] = math.radians(value)
    mujoco.mj_kinematics(m, d)
    mujoco.mj_collision(m, d)
    return m, d


def _arm_geoms(m, prefix: str) -> list[int]:
    return [g for g in range(m.ngeom) if m.geom(g).name.startswith(prefix) and m.geom_contype[g]]


def _min_distance(m, d, geoms, other: int) -> float:
    return min(mujoco.mj_geomDistance(m, d, g, other, 1.0, None) for g in geoms)


def _collides(m, g1: int, g2: int) -> bool:
    return bool(m.geom_contype[g1] & m.geom_conaffinity[g2] or m.geom_contype[g2] & m.geom_conaffinity[g1])


def test_wall_faces_are_where_documented():
    m = MujocoPlant("wall").model
    front, left = m.geom("front_wall"), m.geom("left_wall")
    assert front.pos[0] - front.size[0] == pytest.approx(gen.FRONT_WALL_X_M) == pytest.approx(0.40)
    assert front.pos[1] - front.size[1] == pytest.approx(-1.0) and front.pos[1] + front.size[1] == pytest.approx(1.0)
    assert front.pos[2] - front.size[2] == pytest.approx(0.0) and front.pos[2] + front.size[2] == pytest.approx(1.8)
    assert left.pos[1] - left.size[1] == pytest.approx(gen.LEFT_WALL_Y_M) == pytest.approx(0.825)
    assert front.friction[0] == pytest.approx(0.8) and left.friction[0] == pytest.approx(0.8)
    assert m.body_jntnum[front.bodyid[0]] == 0 and m.body_jntnum[left.bodyid[0]] == 0  # static


def test_forward_reach_touches_the_front_wall_early_in_a_0_25_m_push():
    plant = MujocoPlant("wall")
    m, d = _pose(plant, wall_experiment.REACH_FORWARD_DEG)
    wall = m.geom("front_wall").id
    face_x = gen.FRONT_WALL_X_M
    for side in ("rarm", "larm"):
        hand_gap = face_x - d.site(f"{side}_end").xpos[0]
        assert 0.05 < hand_gap < 0.25
        geoms = _arm_geoms(m, side)
        assert all(_collides(m, g, wall) for g in geoms)
        gap = _min_distance(m, d, geoms, wall)
        # contact after ~0.05 m of the 0.25 m push
        assert gap == pytest.approx(wall_experiment.FRONT_REACH_CLEARANCE_M, abs=0.02)
        hand_geoms = [g for g in geoms if m.body(m.geom_bodyid[g]).name.endswith(("LINK5", "LINK6"))]
        assert _min_distance(m, d, hand_geoms, wall) == pytest.approx(gap)  # the hand touches first


def test_left_reach_touches_the_left_wall_early_in_a_0_25_m_push():
    plant = MujocoPlant("wall")
    m, d = _pose(plant, wall_experiment.REACH_LEFT_DEG)
    wall = m.geom("left_wall").id
    assert 0.05 < gen.LEFT_WALL_Y_M - d.site("larm_end").xpos[1] < 0.25
    gap = _min_distance(m, d, _arm_geoms(m, "larm"), wall)
    assert gap == pytest.approx(wall_experiment.LEFT_REACH_CLEARANCE_M, abs=0.02)


@pytest.mark.parametrize("scene", ["wall", "valve", "door"])
def test_home_keyframe_does_not_touch_the_fixtures(scene):
    plant = MujocoPlant(scene)
    m, d = _pose(plant, {})
    robot = {m.body("BODY").id}
    robot |= {b for b in range(m.nbody) if m.body_rootid[b] == m.body("BODY").id}
    for c in d.contact[:d.ncon]:
        bodies = {m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]}
        names = {m.geom(c.geom1).name, m.geom(c.geom2).name}
        assert names & {"floor"} or not (bodies & robot), names
    fixtures = [g for g in range(m.ngeom) if m.geom_bodyid[g] not in robot and m.geom(g).name != "floor"]
    robot_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] in robot and m.geom_contype[g]]
    # the front wall of `wall` is 0.17 m from the half-sitting hands
    assert min(_min_distance(m, d, robot_geoms, f) for f in fixtures) > 0.15


def test_valve_is_a_torus_on_a_friction_hinge_out_of_the_wall():
    plant = MujocoPlant("valve")
    m, d = _pose(plant, {})
    hinge = m.joint("valve_hinge")
    assert hinge.type[0] == mujoco.mjtJoint.mjJNT_HINGE
    np.testing.assert_allclose(hinge.axis, [-1, 0, 0])
    assert hinge.frictionloss[0] == pytest.approx(2.0) and hinge.damping[0] == pytest.approx(1.0)
    np.testing.assert_allclose(d.body("valve").xpos, [0.6, 0.0, 0.9])
    ring = [g for g in range(m.ngeom) if m.geom(g).name.startswith("valve_ring")]
    assert len(ring) == 12
    radii = [np.linalg.norm(d.geom_xpos[g] - d.body("valve").xpos) for g in ring]
    chord_mid = 0.15 * math.cos(math.pi / 12)
    np.testing.assert_allclose(radii, chord_mid, atol=1e-9)
    wall = m.geom("valve_wall")
    assert wall.pos[0] - wall.size[0] == pytest.approx(0.75)
    assert m.sensor("valve_angle").type[0] == mujoco.mjtSensor.mjSENS_JOINTPOS
    assert m.sensor("valve_angle").objid[0] == hinge.id


def test_valve_turns_under_a_torque_above_its_friction():
    plant = MujocoPlant("valve")
    adr = plant.model.sensor("valve_angle").adr[0]
    plant.data.qfrc_applied[plant.model.joint("valve_hinge").dofadr[0]] = 5.0
    plant.step(300)
    assert plant.data.sensordata[adr] > 0.3


def test_door_is_a_pull_door_with_a_stop():
    plant = MujocoPlant("door")
    m, d = _pose(plant, {})
    hinge = m.joint("door_hinge")
    np.testing.assert_allclose(d.xanchor[hinge.id], [0.5, -0.45, 0.0])
    np.testing.assert_allclose(hinge.range, [-math.pi / 2, 0.0])
    assert hinge.damping[0] > 0 and 0 < hinge.frictionloss[0] <= 2.0
    panel = m.geom("door_panel")
    np.testing.assert_allclose(2 * panel.size, [0.04, 0.8, 1.8])
    np.testing.assert_allclose(d.geom_xpos[panel.id][:2], [0.52, -0.05])
    np.testing.assert_allclose(d.geom_xpos[m.geom("door_knob").id], [0.42, 0.2, 0.9])
    assert m.sensor("door_angle").objid[0] == hinge.id
    adr = m.sensor("door_angle").adr[0]
    plant.reset()
    plant.push("door", [200.0, 0.0, 0.0], 0.3)  # pushing away from the robot: the stop holds
    plant.step(300)
    assert abs(plant.data.sensordata[adr]) < 0.01
    plant.reset()
    plant.push("door", [-100.0, 0.0, 0.0], 0.3)  # pulling toward the robot opens it (negative angle)
    plant.step(300)
    assert plant.data.sensordata[adr] < -0.2
