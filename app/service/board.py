"""Latest-value boards in shared memory between the robot process and the console: one writer, any number
of readers, newest wins, never blocking the writer (a sequence lock: the reader retries a torn copy)."""

from __future__ import annotations

import pickle
import struct
import time
from multiprocessing import shared_memory
from typing import Any

_HEADER = struct.Struct("<qq")  # (generation counter: odd while writing, payload length [bytes])


def attach(name: str) -> shared_memory.SharedMemory:
    """Open an existing segment. (A spawned child shares its parent's resource tracker, where Python 3.11
    registers every opener: the creator's unlink is the one that counts.)"""
    return shared_memory.SharedMemory(name=name)


class Board:
    """A shared-memory slot holding the last value written (pickled).

    The writer (`put`) bumps the counter to odd, copies the bytes, bumps it to even; a reader (`get`)
    copies the payload between two reads of the counter and retries when they differ or are odd. Values
    larger than the slot are refused with ValueError (the writer is never blocked or delayed by readers).
    """

    def __init__(self, size: int = 1 << 20, name: str | None = None) -> None:
        if name is None:
            self._shm = shared_memory.SharedMemory(create=True, size=size)
            self._owner = True
            _HEADER.pack_into(self._shm.buf, 0, 0, 0)
        else:
            self._shm = attach(name)
            self._owner = False
        self.name = self._shm.name
        self.capacity = self._shm.size - _HEADER.size
        self._counter = 0
        self._last: tuple[int, Any] | None = None  # reader cache: (counter, value)

    def __getstate__(self):
        return {"name": self.name}

    def __setstate__(self, state):
        self.__init__(name=state["name"])

    # ---- writer ----------------------------------------------------------------------------------------
    def put(self, value: Any) -> int:
        """Publish `value`; returns the payload size [bytes]."""
        data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
        n = len(data)
        if n > self.capacity:
            raise ValueError(f"{n} bytes do not fit the board's {self.capacity}")
        buf = self._shm.buf
        counter = _HEADER.unpack_from(buf, 0)[0] + 1  # odd: writing
        _HEADER.pack_into(buf, 0, counter, n)
        buf[_HEADER.size:_HEADER.size + n] = data
        _HEADER.pack_into(buf, 0, counter + 1, n)  # even: consistent
        return n

    # ---- readers ---------------------------------------------------------------------------------------
    def version(self) -> int:
        """The counter: it changes with every put (a cheap "is there something new")."""
        return _HEADER.unpack_from(self._shm.buf, 0)[0]

    def get(self, retries: int = 100) -> Any:
        """The last value put, or None before the first; cached while nothing new was put."""
        buf = self._shm.buf
        for _ in range(retries):
            c1, n = _HEADER.unpack_from(buf, 0)
            if c1 == 0:
                return None
            if self._last is not None and self._last[0] == c1:
                return self._last[1]
            if c1 % 2 == 0:
                data = bytes(buf[_HEADER.size:_HEADER.size + n])
                c2 = _HEADER.unpack_from(buf, 0)[0]
                if c1 == c2:
                    try:
                        value = pickle.loads(data)
                    except Exception:  # noqa: BLE001 - torn beyond what the counter saw: read again
                        continue
                    self._last = (c1, value)
                    return value
            time.sleep(20e-6)
        raise TimeoutError("the board kept changing while being read")

    def close(self) -> None:
        self._last = None
        try:
            self._shm.close()
        finally:
            if self._owner:
                try:
                    self._shm.unlink()
                except FileNotFoundError:
                    pass
