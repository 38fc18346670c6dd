"""A session survives a crash: the recording process SIGKILLed (the writer finishes the file with what it got),
or the recording process and its writer SIGKILLed together (the file is read up to its last flushed batch);
either way whole batches of ticks are there, and they replay bit for bit."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from app.service.session_recorder import BATCH_TICKS
from app.session.reader import read_session
from app.session.replay import replay

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = """
import sys
from app.service.local import LocalRobot
from app.service.verbs import GoVelocity

def main():
    robot = LocalRobot(speed=None, record=sys.argv[1])
    robot.run_for(2.2)
    robot.submit(GoVelocity(0.1, 0.0, 0.0)).result()
    print("walking", flush=True)
    while True:
        robot.step()

if __name__ == "__main__":
    main()
"""


def _record_then_kill(tmp_path: Path, whole_group: bool) -> Path:
    script = tmp_path / "record.py"
    script.write_text(SCRIPT)
    path = tmp_path / "crash.mcap"
    proc = subprocess.Popen([sys.executable, str(script), str(path)], cwd=ROOT, stdout=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        assert proc.stdout.readline().strip() == "walking"
        deadline = time.monotonic() + 60.0
        while not path.exists() or path.stat().st_size < 700_000:  # about 2.7 s of ticks written
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
    finally:
        if whole_group:
            os.killpg(proc.pid, signal.SIGKILL)
        else:
            proc.kill()
        proc.wait(10)
    if not whole_group:  # the writer notices its parent is gone and finishes the file
        deadline = time.monotonic() + 10.0
        while read_session(path).complete is False and time.monotonic() < deadline:
            time.sleep(0.2)
    return path


@pytest.mark.parametrize("whole_group", [False, True], ids=["recorder-killed", "recorder-and-writer-killed"])
def test_a_killed_recording_keeps_whole_batches_that_replay_bit_for_bit(tmp_path, whole_group):
    session = read_session(_record_then_kill(tmp_path, whole_group))
    assert session.complete is (not whole_group), session.problem
    assert session.ticks >= 500 and session.ticks % BATCH_TICKS == 0
    assert [d["name"] for d in session.inputs] == ["go_velocity"]
    result = replay(session)
    assert result.identical, result.summary()
