"""The latest-value board's readers when the writer holds the slot (mid-copy: preempted on a loaded machine, or
writing as fast as it can). A CI campaign's GET /api/state once answered 500 after 100 tries met the writer."""

from __future__ import annotations

import pytest

from app.service.board import Board
from app.service.setpoints import BoardSource

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


@pytest.fixture
def board():
    b = Board(size=1 << 12)
    yield b
    b.close()


def hold_mid_write(board: Board) -> None:
    """The writer's first store done, its copy not: the counter odd, as a preempted writer leaves it."""
    board._header[0] = int(board._header[0]) + 1


def test_a_reader_gets_the_last_value_it_read_whole_while_the_writer_holds_the_slot(board):
    board.put({"tick": 1})
    reader = Board(name=board.name)
    try:
        assert reader.get() == {"tick": 1}
        board.put({"tick": 2})
        hold_mid_write(board)  # a third put stuck halfway
        assert reader.get(retries=3) == {"tick": 1}  # the last whole read, not an error
        with pytest.raises(TimeoutError, match="kept changing"):
            reader.get(retries=3, stale_ok=False)
    finally:
        reader.close()


def test_a_reader_that_never_read_whole_is_told_so(board):
    board.put({"tick": 1})
    hold_mid_write(board)
    reader = Board(name=board.name)
    try:
        with pytest.raises(TimeoutError):
            reader.get(retries=2)
    finally:
        reader.close()


def test_the_robots_setpoint_source_never_waits_for_the_consoles_writer(board):
    source = BoardSource(Board(name=board.name))
    try:
        board.put({"rhand": "a"})
        assert source.poll() == {"rhand": "a"}
        assert source.poll() is None  # nothing new
        board.put({"rhand": "b"})
        hold_mid_write(board)  # odd: being written
        assert source.poll() is None
        board._header[0] = int(board._header[0]) + 1  # the copy done (even): "b" is whole in the slot
        assert source.poll() == {"rhand": "b"}
    finally:
        source.board.close()
