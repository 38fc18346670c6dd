"""The operator lock: one client controls the robot, the others watch ([OP] V-A's single operator seat).

Taken explicitly (POST /api/operator/lock), which answers a secret lease token to the taker only; the holder
proves itself with that token (header X-Lock-Token, or ?lock_token= on a WebSocket), never with its name,
which is a display name shown to everyone. Kept while the holder has a WebSocket open with the token (the
page's telemetry or stick stream), or for `lease_s` after its last request when it has none (a script renews
it with any control request or another POST); when the holder's last such WebSocket closes, the lock goes
after `grace_s` unless it comes back. Any authenticated client may engage the e-stop whatever the lock says."""

from __future__ import annotations

import hmac
import re
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

CLIENT_ID = re.compile(r"^[A-Za-z0-9._:-]{1,64}$")
CLIENT_ID_RULE = "1 to 64 characters out of A-Z a-z 0-9 . _ : -"
LEASE_S = 5.0  # [s] the lock of a holder without a WebSocket lasts this long after its last request
GRACE_S = 2.0  # [s] after the holder's last WebSocket closed
TOKEN_HEADER = "X-Lock-Token"  # the holder's lease token on HTTP
TOKEN_PARAM = "lock_token"  # ... and on a WebSocket (?lock_token=; a browser cannot set a WebSocket's headers)


class Locked(Exception):
    """Another client holds the lock (HTTP 423)."""

    def __init__(self, holder: str, action: str) -> None:
        super().__init__(f"{action} refused: the operator lock is held by {holder!r} (its holder sends the lease "
                         f"token it was given, header {TOKEN_HEADER} or ?{TOKEN_PARAM}=); watch, or ask them to "
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
    """Thread-safe (HTTP handlers in the thread pool and WebSockets on the event loop share it). The holder is
    whoever presents the lease token `take` returned; its name is only shown."""

    def __init__(self, lease_s: float = LEASE_S, grace_s: float = GRACE_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not (lease_s > 0 and grace_s >= 0):
            raise ValueError(f"lease_s must be > 0 and grace_s >= 0 [s], got {lease_s!r}, {grace_s!r}")
        self.lease_s = float(lease_s)
        self.grace_s = float(grace_s)
        self._clock = clock
        self._mutex = threading.Lock()
        self._holder: str | None = None  # the holder's display name
        self._token: str | None = None  # the holder's lease token (secret: only `take` returns it)
        self._expires_at = 0.0  # [s] clock time the holder's lock ends unless connected
        self._connections: dict[str, int] = {}  # lease token -> open WebSockets that presented it

    def __repr__(self) -> str:
        return f"OperatorLock(holder={self.holder!r}, lease_s={self.lease_s:g}, grace_s={self.grace_s:g})"

    # ---- inside the mutex --------------------------------------------------------------------------------
    def _current(self, now: float) -> str | None:
        h = self._holder
        if h is not None and not self._connections.get(self._token or "") and now >= self._expires_at:
            self._holder = h = None
            self._token = None
        return h

    def _is_holder(self, token: str | None) -> bool:
        """Whether `token` is the current lease's (compared in constant time)."""
        if token is None or self._token is None:
            return False
        return hmac.compare_digest(token.encode("utf-8", "replace"), self._token.encode("utf-8"))

    # ---- reading -----------------------------------------------------------------------------------------
    @property
    def holder(self) -> str | None:
        """The holder's display name (None: free)."""
        with self._mutex:
            return self._current(self._clock())

    def state(self) -> LockState:
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            connected = h is not None and bool(self._connections.get(self._token or ""))
            expires = None if h is None or connected else max(0.0, self._expires_at - now)
            return LockState(h, self.lease_s, self.grace_s, expires, connected)

    def holds(self, token: str | None) -> bool:
        """Whether `token` is the lease token of the lock's current holder."""
        with self._mutex:
            return self._current(self._clock()) is not None and self._is_holder(token)

    # ---- the holder's side ---------------------------------------------------------------------------------
    def take(self, client: str, token: str | None = None) -> tuple[LockState, str]:
        """Take the lock as `client` (a display name), or renew it with the lease `token`: (the state, the lease
        token, the same on a renewal). Locked if another lease holds it, whatever name it was taken with."""
        check_client_id(client)
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            if h is not None and not self._is_holder(token):
                raise Locked(h, "taking the operator lock")
            if h is None:
                self._token = secrets.token_urlsafe(24)
            self._holder = client
            self._expires_at = now + self.lease_s
            lease = self._token
        assert lease is not None
        return self.state(), lease

    def release(self, token: str | None) -> None:
        """Give the lock back (nothing to do when free); Locked unless `token` is the lease's."""
        with self._mutex:
            h = self._current(self._clock())
            if h is None:
                return
            if not self._is_holder(token):
                raise Locked(h, "releasing the operator lock")
            self._holder = None
            self._token = None

    def check(self, token: str | None, action: str = "control") -> bool:
        """Locked unless the lock is free or `token` is its lease's (whose lease is then renewed). True when
        the caller holds the lock, False when it is free."""
        with self._mutex:
            now = self._clock()
            h = self._current(now)
            if h is None:
                return False
            if not self._is_holder(token):
                raise Locked(h, action)
            self._expires_at = max(self._expires_at, now + self.lease_s)
            return True

    # ---- WebSockets: the holder's connection keeps the lock -------------------------------------------------
    def connected(self, token: str | None) -> str | None:
        """A WebSocket opened with `token`: while it is open the lock is kept, if `token` is the current
        lease's. Returns what to hand to `disconnected` (None: nothing was counted)."""
        with self._mutex:
            if self._current(self._clock()) is None or not self._is_holder(token):
                return None
            lease = self._token
            assert lease is not None
            self._connections[lease] = self._connections.get(lease, 0) + 1
            return lease

    def disconnected(self, lease: str | None) -> None:
        """The WebSocket that `connected` counted as `lease` closed."""
        if lease is None:
            return
        with self._mutex:
            n = self._connections.get(lease, 0) - 1
            if n > 0:
                self._connections[lease] = n
                return
            self._connections.pop(lease, None)
            if self._token == lease:
                self._expires_at = self._clock() + self.grace_s
