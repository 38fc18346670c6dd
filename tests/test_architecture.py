"""Import rules of the design card: the controller never imports the app nor the simulator (plant, cameras,
object operations, ground truth); robot imports no other package; behaviours never reach the app, MuJoCo or
the simulator, nor read a ground-truth attribute; no private name crosses modules of the controller; no HTTP
router imports another; nothing outside the operator service and the controller indexes the chain by string."""

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


def names_a_module_defines(tree: ast.AST) -> set[str]:
    """Names a module makes its own: functions, classes, assigned names, attributes it sets on self/cls or
    through object.__setattr__ (frozen dataclasses), and __slots__ entries."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
            names.add(node.attr)
        elif (isinstance(node, ast.Call) and ast.unparse(node.func) == "object.__setattr__" and len(node.args) >= 2
              and isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value, str)):
            names.add(node.args[1].value)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.isidentifier():
            names.add(node.value)  # __slots__ = ("_x", ...), namedtuple field lists
    return names


def private_names_crossing(source: str, filename: str = "<module>") -> list[str]:
    """Private names (`_x`, not dunders) one module of the controller takes from another: imported (absolute
    from controller, or relative), or read as `obj._x` on an object other than self/cls when the module
    itself defines no `_x` (so `obj` is another module's object)."""
    tree = ast.parse(source, filename=filename)
    own = names_a_module_defines(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.level > 0 or (node.module or "").startswith("controller")):
            module = "." * node.level + (node.module or "")
            found += [f"{a.name} imported from {module}" for a in node.names if a.name.startswith("_")]
        elif (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
              and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))
              and node.attr not in own):
            found.append(f"{ast.unparse(node)} read at line {node.lineno}")
    return found


def test_the_private_name_check_sees_imports_relative_imports_and_attribute_reads():
    source = ("from controller.core.types import _REFERENCE_FIELDS\n"
              "from .model import _helper\n"
              "from . import _sibling\n"
              "def f(kin, other):\n"
              "    return kin._below_joint, other.public\n")
    assert private_names_crossing(source) == [
        "_REFERENCE_FIELDS imported from controller.core.types", "_helper imported from .model",
        "_sibling imported from .", "kin._below_joint read at line 5"]
    own = ("class A:\n"
           "    def __init__(self):\n"
           "        self._x = 1\n"
           "def g(a):\n"
           "    return a._x, a.__class__, a._x.__dict__\n")
    assert private_names_crossing(own) == []


def test_no_private_name_crosses_modules_of_the_controller():
    offenders = []
    for path in sorted((ROOT / "controller").rglob("*.py")):
        found = private_names_crossing(path.read_text(), str(path))
        offenders += [f"{path.relative_to(ROOT)}: {what}" for what in found]
    assert offenders == []


def test_the_controller_tree_shows_its_architecture():
    packages = sorted(p.name for p in (ROOT / "controller").iterdir() if p.is_dir() and (p / "__init__.py").exists())
    assert packages == ["balance", "core", "interpolation", "kinematics", "layers", "operation", "walking"]
    # beside the packages only the assembly of every layer (on top of them all, so not in core)
    assert sorted(p.name for p in (ROOT / "controller").glob("*.py")) == ["__init__.py", "system.py"]
    from controller.core.chain import CHAIN_ORDER
    from controller.system import layer_classes

    assert tuple(layer_classes()) == CHAIN_ORDER  # one layer per file of controller/layers, in chain order
    layer_files = {p.stem for p in (ROOT / "controller" / "layers").glob("*.py") if p.name != "__init__.py"}
    assert {cls.__module__.rsplit(".", 1)[-1] for cls in layer_classes().values()} == layer_files


def router_imports(source: str, filename: str = "<module>") -> list[str]:
    """The app.console.routers modules a router module imports: absolute (`from app.console.routers.x import y`,
    `from app.console.routers import x`, `import app.console.routers.x`) or relative (`from .x import y`)."""
    found = []
    for node in ast.walk(ast.parse(source, filename=filename)):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names
                      if a.name == "app.console.routers" or a.name.startswith("app.console.routers.")]
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level > 0:
                found.append("." * node.level + module)
            elif module == "app.console.routers":  # `from app.console.routers import x`: x is a router module
                found += [f"app.console.routers.{a.name}" for a in node.names]
            elif module.startswith("app.console.routers."):
                found.append(module)
    return found


def test_the_router_import_check_sees_absolute_and_relative_imports():
    source = ("from app.console.routers.params import params_document\n"
              "from app.console.routers import rate_stream\n"
              "import app.console.routers.operator\n"
              "from .layers import ChangesBody\n"
              "from app.console.params_http import ChangesBody\n"
              "from app.console.ws import RateStream\n")
    assert router_imports(source) == ["app.console.routers.params", "app.console.routers.rate_stream",
                                      "app.console.routers.operator", ".layers"]


def test_no_router_imports_another():
    """Each router is one door's HTTP face: what routers share (params documents, WebSocket helpers, schemas)
    lives in non-router modules of the console (app.console.params_http, app.console.ws, app.console.schemas)."""
    offenders = {}
    for path in sorted((ROOT / "app" / "console" / "routers").glob("*.py")):
        found = router_imports(path.read_text(), str(path))
        if found:
            offenders[str(path.relative_to(ROOT))] = found
    assert offenders == {}


#: where a layer may be looked up in the chain by its name: the operator service (the one door) and the
#: controller that builds the chain
CHAIN_LOOKUP_ALLOWED = ("app/service/", "controller/")


def _is_chain(node: ast.AST) -> bool:
    named = lambda n: (isinstance(n, ast.Name) and n.id == "chain") or (  # noqa: E731
        isinstance(n, ast.Attribute) and n.attr == "chain")
    return named(node) or (isinstance(node, ast.Attribute) and node.attr == "layers" and named(node.value))


def chain_lookups(source: str, filename: str = "<module>") -> list[str]:
    """Where a module looks a layer up in the chain by name: `chain[...]`, `x.chain[...]`, `x.chain.layers[...]`
    or `x.chain.layers.get(...)` (iterating over the whole chain is not a lookup)."""
    found = []
    for node in ast.walk(ast.parse(source, filename=filename)):
        if isinstance(node, ast.Subscript) and _is_chain(node.value):
            found.append(f"{ast.unparse(node)} at line {node.lineno}")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get"
              and _is_chain(node.func.value)):
            found.append(f"{ast.unparse(node)} at line {node.lineno}")
    return sorted(found, key=lambda s: int(s.rsplit(" ", 1)[1]))


def test_the_chain_lookup_check_sees_subscripts_and_gets():
    source = ("op = loop.chain['op']\n"
              "layer = robot.chain[name]\n"
              "seq = chain['seq']\n"
              "es = loop.chain.layers.get('es')\n"
              "st = system.chain.layers['st']\n"
              "names = loop.chain.order(); timer = loop.chain.timers['st']\n"
              "for name, layer in loop.chain.layers.items(): pass\n")
    assert chain_lookups(source) == ["loop.chain['op'] at line 1", "robot.chain[name] at line 2",
                                     "chain['seq'] at line 3", "loop.chain.layers.get('es') at line 4",
                                     "system.chain.layers['st'] at line 5"]


def test_nothing_outside_the_service_looks_a_layer_up_in_the_chain():
    """The bench, the plots, the experiments, the routers and the behaviours reach a layer through the operator
    service's verbs (or its robot host), never by its name in the chain."""
    offenders = []
    for package in ("app", "behaviors", "robot"):
        for path in sorted((ROOT / package).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel.startswith(CHAIN_LOOKUP_ALLOWED):
                continue
            offenders += [f"{rel}: {where}" for where in chain_lookups(path.read_text(), rel)]
    assert offenders == []


# ---- no import circle, and a core that rests on nothing above it ----------------------------------------------
PACKAGES = ("app", "behaviors", "controller", "robot")


def module_name(path: Path) -> str:
    """The dotted module a source file under ROOT is (a package's __init__.py is the package)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def module_imports(source: str, module: str, is_package: bool, known: set[str]) -> set[str]:
    """The modules of `known` that `module` imports, wherever the import sits (top level, under `if
    TYPE_CHECKING:`, inside a function: each ties the two modules). `from a import b` counts as a.b when a.b is a
    module, else as a; a relative import is resolved against `module`. Parent packages that Python runs on the way
    are not counted (a package's __init__ would otherwise tie every module to its siblings)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name in known}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[:len(parts) - (node.level - 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            for a in node.names:
                if f"{base}.{a.name}" in known:
                    found.add(f"{base}.{a.name}")
                elif base in known:
                    found.add(base)
    found.discard(module)
    return found


def import_graph(packages=PACKAGES) -> dict[str, set[str]]:
    """Module -> the modules of the project it imports."""
    paths = {module_name(p): p for package in packages for p in sorted((ROOT / package).rglob("*.py"))}
    known = set(paths)
    return {m: module_imports(p.read_text(), m, p.name == "__init__.py", known) for m, p in paths.items()}


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of `graph` with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(circles)


def test_the_import_graph_sees_absolute_relative_and_hidden_imports():
    known = {"pkg", "pkg.a", "pkg.b", "pkg.sub", "pkg.sub.c", "other"}
    source = ("import other\n"
              "from pkg import b\n"
              "from . import a\n"
              "from .sub.c import thing\n"
              "from typing import TYPE_CHECKING\n"
              "if TYPE_CHECKING:\n"
              "    from pkg.sub import Name\n"
              "def f():\n"
              "    import numpy\n"
              "    from pkg.a import g\n")
    assert module_imports(source, "pkg.b", False, known) == {"other", "pkg.a", "pkg.sub", "pkg.sub.c"}
    assert module_imports("from .c import x\nfrom .. import a\n", "pkg.sub", True, known) == {"pkg.sub.c", "pkg.a"}
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"f"}, "f": {"e"}, "g": {"g"}}
    assert import_circles(graph) == [["a", "b", "c"], ["e", "f"]]


def test_no_module_imports_one_that_imports_it_back():
    """No import circle anywhere (however long, wherever the import sits): each module rests on the ones below."""
    assert import_circles(import_graph()) == []


def test_the_controller_core_imports_nothing_of_the_controller_above_it():
    """controller.core (the loop, the chain, the layer base, the data that flows) is what the layers, the
    estimators and the kinematics stand on; it imports nothing of them (robot, numpy and the stdlib are fine)."""
    core = lambda m: m == "controller.core" or m.startswith("controller.core.")  # noqa: E731
    offenders = {m: sorted(i for i in imports if not core(i)) for m, imports in import_graph(("controller",)).items()
                 if core(m)}
    assert {m: found for m, found in offenders.items() if found} == {}


# ---- app/ in rooms: the console, the service, the sessions, and the lab on top -----------------------------------
#: app/'s top level: the command line (the composition root, `hrp2-console`) over its four rooms
APP_TOP_LEVEL = {"__init__.py", "cli.py", "cli_args.py", "console", "service", "session", "lab"}
ROOMS = ("console", "service", "session", "lab")
#: the only imports of the lab from the other rooms (module, imported module)
LAB_IMPORTS_ALLOWED = {
    # POST /api/experiments is the lab's experiments over HTTP: the router lists them and runs one in a worker
    ("app.console.routers.experiments", "app.lab.experiments"),
    ("app.console.routers.experiments", "app.lab.experiments.worker"),
}


def in_room(module: str, room: str) -> bool:
    return module == f"app.{room}" or module.startswith(f"app.{room}.")


def test_app_is_the_command_line_over_its_rooms():
    assert {p.name for p in (ROOT / "app").iterdir() if p.name != "__pycache__"} == APP_TOP_LEVEL
    assert all((ROOT / "app" / room / "__init__.py").exists() for room in ROOMS)


def test_the_lab_sits_on_top_of_the_console_the_service_and_the_sessions():
    """The benches, experiments, studies and the campaign use the other rooms; none of them needs the lab (only
    app.cli, above every room, starts what the lab has), but for LAB_IMPORTS_ALLOWED."""
    graph = import_graph(("app",))
    edges = {(m, i) for m, imports in graph.items() for i in imports
             if any(in_room(m, room) for room in ROOMS if room != "lab") and in_room(i, "lab")}
    assert edges == LAB_IMPORTS_ALLOWED


#: [lines] a module longer than this is several things (issue 28): split it by concern
MAX_MODULE_LINES = 600


def test_the_robot_process_and_the_sessions_do_not_need_the_console():
    """The service (the robot process and its doors) and the sessions sit under the web console: the console
    imports them, never the reverse (the e-stop door and the state document once reached up into it)."""
    graph = import_graph(("app",))
    up = {(m, i) for m, imports in graph.items() for i in imports
          if (in_room(m, "service") or in_room(m, "session")) and in_room(i, "console")}
    assert up == set()


def test_no_module_outside_the_tests_is_longer_than_the_limit():
    long = {str(p.relative_to(ROOT)): n for package in ("app", "controller", "robot", "behaviors", "static")
            for p in sorted((ROOT / package).rglob("*")) if p.suffix in (".py", ".js", ".html", ".css")
            and (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES}
    assert long == {}
