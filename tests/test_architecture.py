"""Import rules of the design card: the controller never imports the app nor the simulator (plant, cameras,
object operations, ground truth); robot imports no other package; behaviours never reach the app, MuJoCo or
the simulator, nor read a ground-truth attribute; no private name crosses modules of the controller."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {
    "controller": {"app", "behaviors", "fastapi", "viser", "pydantic", "uvicorn", "starlette"},
    "robot": {"app", "behaviors", "controller", "fastapi", "viser", "pydantic"},
    "behaviors": {"app", "fastapi", "viser", "pydantic", "uvicorn", "mujoco"},
}
#: The simulator, whose state is ground truth and not the robot's knowledge: its plant, cameras and object
#: operations, and the ground-truth half of robot.sensors.
SIMULATOR_MODULES = {"robot.plant", "robot.camera", "robot.scene_objects", "robot.sensors.GroundTruth",
                     "robot.sensors.is_fallen"}
#: modules (dotted, prefix match) a package must not import, beyond FORBIDDEN's top-level packages;
#: `from robot import plant` counts as robot.plant
FORBIDDEN_MODULES = {
    "controller": SIMULATOR_MODULES,
    "behaviors": SIMULATOR_MODULES | {"mujoco"},
}
#: Attributes that carry the simulator's view (Observation.truth, MujocoPlant.ground_truth / object_pose /
#: place_object, Frames.T_world_camera_true and any *_true name, MjData's state arrays): behaviours and
#: perception never read them, even from an object handed to them.
GROUND_TRUTH_ATTRIBUTES = {"truth", "ground_truth", "object_pose", "place_object", "placeable_objects", "qpos",
                           "qvel", "xpos", "xquat", "mocap_pos", "mocap_quat", "geom_xpos", "cam_xpos", "sensordata"}
#: the only controller module allowed to import mujoco: the CollisionDetector uses it as a geometry library
MUJOCO_IN_CONTROLLER = {"controller/layers/collision_detector.py"}


def imported_modules(path: Path) -> set[str]:
    """Every dotted module name `path` imports (absolute imports)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names |= {f"{node.module}.{a.name}" for a in node.names}  # `from robot import plant`
    return names


def imported_top_levels(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_import_what_the_design_forbids(package):
    offenders = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        bad = imported_top_levels(path) & FORBIDDEN[package]
        if bad:
            offenders[str(path.relative_to(ROOT))] = sorted(bad)
    assert offenders == {}


def test_every_module_has_a_one_line_docstring():
    missing = []
    for package in ("controller", "robot", "app", "behaviors"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path.name == "__init__.py" and not path.read_text().strip():
                continue
            if ast.get_docstring(ast.parse(path.read_text())) is None:
                missing.append(str(path.relative_to(ROOT)))
    assert missing == []


@pytest.mark.parametrize("package", sorted(FORBIDDEN_MODULES))
def test_package_does_not_import_the_modules_the_design_keeps_from_it(package):
    offenders = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        bad = {m for m in imported_modules(path) for f in FORBIDDEN_MODULES[package]
               if m == f or m.startswith(f + ".")}
        if bad:
            offenders[str(path.relative_to(ROOT))] = sorted(bad)
    assert offenders == {}


def test_behaviors_read_no_ground_truth_attribute():
    offenders = {}
    for path in sorted((ROOT / "behaviors").rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        bad = sorted({node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
                      and (node.attr in GROUND_TRUTH_ATTRIBUTES or node.attr.endswith("_true"))})
        if bad:
            offenders[str(path.relative_to(ROOT))] = bad
    assert offenders == {}


def test_only_the_collision_detector_imports_mujoco_in_the_controller():
    users = {str(p.relative_to(ROOT)) for p in (ROOT / "controller").rglob("*.py")
             if "mujoco" in imported_top_levels(p)}
    assert users <= MUJOCO_IN_CONTROLLER


def test_no_private_name_is_imported_across_modules_of_the_controller():
    offenders = []
    for path in sorted((ROOT / "controller").rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("controller"):
                offenders += [f"{path.relative_to(ROOT)}: {a.name} from {node.module}" for a in node.names
                              if a.name.startswith("_")]
    assert offenders == []


def test_the_controller_tree_shows_its_architecture():
    packages = sorted(p.name for p in (ROOT / "controller").iterdir() if p.is_dir() and (p / "__init__.py").exists())
    assert packages == ["balance", "core", "interpolation", "kinematics", "layers", "operation", "walking"]
    assert not [p.name for p in (ROOT / "controller").glob("*.py") if p.name != "__init__.py"]
    from controller.core.chain import CHAIN_ORDER
    from controller.core.system import layer_classes

    assert tuple(layer_classes()) == CHAIN_ORDER  # one layer per file of controller/layers, in chain order
    layer_files = {p.stem for p in (ROOT / "controller" / "layers").glob("*.py") if p.name != "__init__.py"}
    assert {cls.__module__.rsplit(".", 1)[-1] for cls in layer_classes().values()} == layer_files
