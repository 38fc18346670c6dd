"""App test fixtures: the operator service on a robot in this process whose loop the test steps itself
(`runtime.loop.run_for`), served through FastAPI's TestClient."""

import pytest
from fastapi.testclient import TestClient

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot


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
