"""A lossy link for the browser tests: a TCP proxy on 127.0.0.1 in front of the console that delays every chunk
`one_way_s` each way (0.1 s: a 200 ms round trip) and stalls `loss` of them (5 %) by a further random
`stall_s` (0.2-0.6 s).

TCP cannot lose a packet as seen from above it: a segment lost on the wire is sent again after the
retransmission timeout (at least 200 ms on Linux, more on a 200 ms round trip), and everything behind it on that
connection waits. So a "lost" chunk here is one held back by a stall, and the chunks after it on the same
connection and direction wait behind it (head-of-line blocking), as over a real lossy TCP link. The bytes are
forwarded untouched (the Host and Origin headers too: the console sees the page's own origin, the proxy's port
in both, and its checks apply as to any page). Random with a fixed seed: a run repeats its stalls."""

from __future__ import annotations

import asyncio
import random
import socket
import threading
import time

CHUNK_BYTES = 65536


class LossyProxy:
    """`start()` listens on a free port (`port`) in a thread of its own and forwards each connection to
    127.0.0.1:`target_port`; `stop()` ends it. `chunks` and `stalled` count what it forwarded."""

    def __init__(self, target_port: int, one_way_s: float = 0.1, loss: float = 0.05,
                 stall_s: tuple[float, float] = (0.2, 0.6), seed: int = 29) -> None:
        self.target_port, self.one_way_s, self.loss, self.stall_s = target_port, one_way_s, loss, stall_s
        self.random = random.Random(seed)
        self.chunks = self.stalled = 0
        self.port: int | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._server: asyncio.Server | None = None
        self._ready = threading.Event()

    def start(self) -> LossyProxy:
        self._thread = threading.Thread(target=self._run, name="lossy-proxy", daemon=True)
        self._thread.start()
        if not self._ready.wait(10.0):
            raise RuntimeError("the lossy proxy did not start")
        return self

    def stop(self) -> None:
        if self._loop is not None and self._loop.is_running():
            asyncio.run_coroutine_threadsafe(self._shutdown(), self._loop).result(timeout=5.0)
            self._loop.call_soon_threadsafe(self._loop.stop)
        if self._thread is not None:
            self._thread.join(timeout=5.0)

    async def _shutdown(self) -> None:
        """Every connection's tasks cancelled and awaited, the listening socket closed."""
        self._server.close()
        tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    def _run(self) -> None:
        self._loop = asyncio.new_event_loop()
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.bind(("127.0.0.1", 0))
        self.port = sock.getsockname()[1]
        self._server = self._loop.run_until_complete(asyncio.start_server(self._serve, sock=sock))
        self._ready.set()
        try:
            self._loop.run_forever()
        finally:
            self._loop.close()

    async def _serve(self, client_r: asyncio.StreamReader, client_w: asyncio.StreamWriter) -> None:
        try:
            server_r, server_w = await asyncio.open_connection("127.0.0.1", self.target_port)
        except OSError:
            client_w.close()
            return
        try:
            await asyncio.gather(self._pipe(client_r, server_w), self._pipe(server_r, client_w),
                                 return_exceptions=True)
        except asyncio.CancelledError:  # stopped: ended quietly (asyncio's server logs a cancelled handler)
            client_w.close()
            server_w.close()

    def _due(self, after: float) -> float:
        """When a chunk read now is delivered: one way later, stalled at random, never before the one ahead."""
        self.chunks += 1
        delay = self.one_way_s
        if self.random.random() < self.loss:
            self.stalled += 1
            delay += self.random.uniform(*self.stall_s)
        return max(after, time.monotonic() + delay)

    async def _pipe(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        queue: asyncio.Queue[tuple[float, bytes]] = asyncio.Queue()

        async def deliver() -> None:
            while True:
                due, data = await queue.get()
                await asyncio.sleep(max(0.0, due - time.monotonic()))
                if not data:  # the sender closed: so does this side, after what was in flight
                    writer.close()
                    return
                writer.write(data)
                await writer.drain()

        delivering = asyncio.ensure_future(deliver())
        last_due = 0.0
        try:
            while True:
                data = await reader.read(CHUNK_BYTES)
                last_due = self._due(last_due)
                queue.put_nowait((last_due, data))
                if not data:
                    break
            await delivering
        except (OSError, asyncio.CancelledError):
            delivering.cancel()
            writer.close()
