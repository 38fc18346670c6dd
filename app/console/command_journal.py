"""What the clients asked of the robot: every control request (POST, PUT, DELETE under /api/) that reached the
API, with who sent it and how it was answered, in a short ring that the state document carries (`commands`),
so that each page shows in its history what the other clients did. A request repeated by the same client
within `coalesce_s` (a stream of setpoints) is counted on its last entry, not listed again."""

from __future__ import annotations

import json
import threading
import time
from dataclasses import asdict, dataclass

from app.console.operator_lock import CLIENT_ID
from app.console.security import CLIENT_HEADER, UNSAFE_METHODS

JOURNAL_LENGTH = 32  # entries kept (and sent with every state document)
SHOWN_BODY_CHARS = 160  # a request body is shown up to this many characters
SHOWN_ANSWER_CHARS = 160  # the answer's message or detail, the same
ANSWER_BYTES = 4096  # of the response body read for its message (the rest passes through unread)
COALESCE_S = 0.5  # [s] (wall) the same client's same request again within this is counted, not listed


@dataclass(frozen=True)
class CommandEntry:
    seq: int  # numbered in arrival order, from 1 (a restarted console starts again)
    client: str  # the X-Client-Id header; "anonymous@<address>" without one
    request: str  # "POST /api/walk/go-pos"
    body: str  # the request's JSON as sent, cut to SHOWN_BODY_CHARS ("" without a body)
    status: int  # the HTTP status it was answered with
    answer: str  # the answer's `message` (or `detail` of an error), cut to SHOWN_ANSWER_CHARS
    count: int  # 1, or how many times in a row the client sent it (each within COALESCE_S of the last)


def _cut(text: str, n: int) -> str:
    return text if len(text) <= n else text[:n - 3] + "..."


def _answer_text(payload: bytes) -> str:
    try:
        doc = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        return ""
    if not isinstance(doc, dict):
        return ""
    text = doc.get("message", doc.get("detail", ""))
    return _cut(text if isinstance(text, str) else json.dumps(text), SHOWN_ANSWER_CHARS)


def _body_text(body: bytes) -> str:
    try:
        text = json.dumps(json.loads(body.decode("utf-8")), separators=(",", ":"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        text = body.decode("utf-8", "replace").strip()
    return _cut(text, SHOWN_BODY_CHARS)


class CommandJournal:
    """The ring of the last `length` control requests; thread-safe (requests run on several threads)."""

    def __init__(self, length: int = JOURNAL_LENGTH, coalesce_s: float = COALESCE_S) -> None:
        self._length = int(length)
        self._coalesce_s = float(coalesce_s)
        self._entries: list[CommandEntry] = []
        self._last_at = 0.0  # [s] monotonic time of the newest entry's last request
        self._seq = 0
        self._lock = threading.Lock()
        self._encoded = b"[]"

    def __repr__(self) -> str:
        return f"CommandJournal(length={self._length}, coalesce_s={self._coalesce_s}, seq={self._seq})"

    def record(self, client: str, request: str, body: bytes, status: int, answer: bytes) -> None:
        now = time.monotonic()
        shown_body, shown_answer = _body_text(body) if body.strip() else "", _answer_text(answer)
        with self._lock:
            last = self._entries[-1] if self._entries else None
            if (last is not None and last.client == client and last.request == request
                    and now - self._last_at <= self._coalesce_s):
                entry = CommandEntry(last.seq, client, request, shown_body, status, shown_answer, last.count + 1)
                self._entries[-1] = entry
            else:
                self._seq += 1
                self._entries.append(CommandEntry(self._seq, client, request, shown_body, status, shown_answer, 1))
                del self._entries[:-self._length]
            self._last_at = now
            self._encoded = json.dumps([asdict(e) for e in self._entries], separators=(",", ":")).encode()

    def entries(self) -> list[CommandEntry]:
        with self._lock:
            return list(self._entries)

    def encoded(self) -> bytes:
        """The entries as a JSON array (kept encoded: every state document carries it)."""
        return self._encoded


def client_name(scope) -> str:
    """Who sent the request: its X-Client-Id (when it is a valid client id), else its address."""
    for key, value in scope.get("headers", []):
        if key.lower() == CLIENT_HEADER:
            name = value.decode("latin-1")
            if CLIENT_ID.match(name):
                return name
    peer = scope.get("client")
    return f"anonymous@{peer[0] if peer else '?'}"


class JournalingLayer:
    """ASGI layer that records each control request under /api/ in `journal` once answered. It passes the
    wrapped app's `allowed_methods` on (the front door asks it)."""

    def __init__(self, app, journal: CommandJournal) -> None:
        self.app = app
        self.journal = journal
        if hasattr(app, "allowed_methods"):
            self.allowed_methods = app.allowed_methods

    async def __call__(self, scope, receive, send) -> None:
        if (scope["type"] != "http" or scope["method"] not in UNSAFE_METHODS
                or not scope["path"].startswith("/api/")):
            await self.app(scope, receive, send)
            return
        body = bytearray()
        answer = bytearray()
        status = 0

        async def receive_recorded():
            message = await receive()
            if message["type"] == "http.request":
                body.extend(message.get("body", b""))
            return message

        async def send_recorded(message):
            nonlocal status
            if message["type"] == "http.response.start":
                status = int(message["status"])
            elif message["type"] == "http.response.body" and len(answer) < ANSWER_BYTES:
                answer.extend(message.get("body", b"")[:ANSWER_BYTES - len(answer)])
            await send(message)

        try:
            await self.app(scope, receive_recorded, send_recorded)
        finally:
            if status:
                self.journal.record(client_name(scope), f"{scope['method']} {scope['path']}", bytes(body), status,
                                    bytes(answer))
