"""The operator lock: one client controls the robot, the others watch ([OP] V-A's single operator seat).

Taken explicitly (POST /api/operator/lock); kept while the holder has a WebSocket open (the page's telemetry
or stick stream), or for `lease_s` after its last request when it has none (a script renews it with any
control request or another POST); when the holder's last WebSocket closes, the lock goes after `grace_s`
unless it comes back. Any authenticated client may engage the e-stop whatever the lock says."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

CLIENT_ID = re.compile(r"^[A-Za-z0-9._:-]{1,64}$")
CLIENT_ID_RULE = "1 to 64 characters out of A-Z a-z 0-9 . _ : -"
LEASE_S = 5.0  # [s] the lock of a holder without a WebSocket lasts this long after its last request
GRACE_S = 2.0  # [s] after the holder's last WebSocket closed


class Locked(Exception):
    """Another client holds the lock (HTTP 423)."""

    def __init__(self, holder: str, action: str) -> None:
        super().__init__(f"{action} refused: the operator lock is held by {holder!r}; watch, or ask them to "
                         "release it (DELETE /api/operator/lock)")
        self.holder = holder


def check_client_id(value: object, field: str = "client") -> str:
    """The client id as given, or ValueError naming `field` and what is allowed."""
    if not isinstance(value, str) or not CLIENT_ID.match(value):
        raise ValueError(f"{field}: {value!r} is not a client id ({CLIENT_ID_RULE})")
    return value


@dataclass(frozen=True)
class LockState:
    holder: str | None  # None: nobody holds it, every authenticated client may control
    lease_s: float  # [s] how long a holder without a WebSocket keeps it after its last request
    grace_s: float  # [s] how long it is kept after the holder's last WebSocket closed
    expires_in_s: float | None  # [s] None while the holder has a WebSocket open (or nobody holds it)
    connected: bool  # the holder has a WebSocket open

    def to_dict(self) -> dict:
        return {"holder": self.holder, "lease_s": self.lease_s, "grace_s": self.grace_s,
                "expires_in_s": None if self.expires_in_s is None else round(self.expires_in_s, 3),
                "connected": self.connected}


class OperatorLock:
    """Thread-safe (HTTP handlers in the thread pool and WebSockets on the event loop share it)."""

    def __init__(self, lease_s: float = LEASE_S, grace_s: float = GRACE_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not (lease_s > 0 and grace_s >= 0):
            raise ValueError(f"lease_s must be > 0 and grace_s >= 0 [s], got {lease_s!r}, {grace_s!r}")
        self.lease_s = float(lease_s)
        self.grace_s = float(grace_s)
        self._clock = clock
        self._mutex = threading.Lock()
        self._holder: str | None = None
        self._expires_at = 0.0  # [s] clock time the holder's lock ends unless connected
        self._connections: dict[str, int] = {}  # client -> open WebSockets

    def __repr__(self) -> str:
        return f"OperatorLock(holder={self.holder!r}, lease_s={self.lease_s:g}, grace_s={self.grace_s:g})"

    # ---- inside the mutex --------------------------------------------------------------------------------
    def _current(self, now: float) -> str | None:
        h = self._holder
        if h is not None and not self._connections.get(h) and now >= self._expires_at:
            self._holder = h = None
        return h

    # ---- reading -----------------------------------------------------------------------------------------
    @property
    def holder(self) -> str | None:
        with self._mutex:
            return self._current(self._clock())

    def state(self) -> LockState:
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            connected = h is not None and bool(self._connections.get(h))
            expires = None if h is None or connected else max(0.0, self._expires_at - now)
            return LockState(h, self.lease_s, self.grace_s, expires, connected)

    # ---- the holder's side ---------------------------------------------------------------------------------
    def take(self, client: str) -> LockState:
        """Take the lock (or renew it, for its holder); Locked if another client holds it."""
        check_client_id(client)
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            if h is not None and h != client:
                raise Locked(h, "taking the operator lock")
            self._holder = client
            self._expires_at = now + self.lease_s
        return self.state()

    def release(self, client: str | None) -> None:
        """Give the lock back (nothing to do when free); Locked if another client holds it."""
        with self._mutex:
            h = self._current(self._clock())
            if h is None:
                return
            if h != client:
                raise Locked(h, "releasing the operator lock")
            self._holder = None

    def check(self, client: str | None, action: str = "control") -> None:
        """Locked unless the lock is free or `client` holds it (then its lease is renewed)."""
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            if h is None:
                return
            if h != client:
                raise Locked(h, action)
            self._expires_at = max(self._expires_at, now + self.lease_s)

    # ---- WebSockets: the holder's connection keeps the lock -------------------------------------------------
    def connected(self, client: str) -> None:
        with self._mutex:
            self._connections[client] = self._connections.get(client, 0) + 1

    def disconnected(self, client: str) -> None:
        with self._mutex:
            n = self._connections.get(client, 0) - 1
            if n > 0:
                self._connections[client] = n
                return
            self._connections.pop(client, None)
            if self._holder == client:
                self._expires_at = self._clock() + self.grace_s
