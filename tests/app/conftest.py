"""App test fixtures: a Runtime whose loop is not started, served through FastAPI's TestClient."""

import pytest
from fastapi.testclient import TestClient

from app.deps import get_runtime
from app.main import create_app
from app.runtime import Runtime


@pytest.fixture
def runtime():
    rt = Runtime(speed=None)
    yield rt
    rt.stop()


@pytest.fixture
def client(runtime):
    app = create_app()
    app.dependency_overrides[get_runtime] = lambda: runtime
    with TestClient(app) as c:
        yield c
