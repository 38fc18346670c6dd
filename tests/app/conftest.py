"""App test fixtures: the operator service on a robot in this process whose loop the test steps itself
(`runtime.loop.run_for`), served through FastAPI's TestClient."""

import fastapi.dependencies.models as fastapi_dependency_models
import pytest
from fastapi.testclient import TestClient

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot


@pytest.fixture(autouse=True)
def _forget_the_apps():
    """After each test, FastAPI's caches of how it classified each endpoint (lru_caches of 4096 entries, keyed by the
    endpoint itself) are emptied: they held every app a test built, and its robot, alive (the suite's process grew
    to 13 GB)."""
    yield
    for cached in vars(fastapi_dependency_models).values():
        if callable(getattr(cached, "cache_clear", None)):
            cached.cache_clear()


@pytest.fixture
def runtime():
    """The robot (a LocalRobot: same host and verbs as the robot process, stepped by the test)."""
    robot = LocalRobot(speed=None)
    yield robot
    robot.stop()


@pytest.fixture
def service(runtime):
    return OperatorService(runtime)


@pytest.fixture
def client(service):
    app = create_app(Settings(extra_hosts=("testserver",)), service=service)
    with TestClient(app, headers={"content-type": "application/json"}) as c:
        yield c
