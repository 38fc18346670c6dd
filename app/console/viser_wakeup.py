"""A repair for a lost wake-up in viser 1.1.1's message buffers (pinned in pyproject.toml).

`AsyncMessageBuffer.push`, called from the thread that updates the scene and the GUI, sets the buffer's
`asyncio.Event` directly from that thread before it also schedules a set on the event loop. asyncio's Event is
not thread-safe: if the loop's sending task has just found the event clear and is appending its waiter when the
other thread sets it, the waiter is never woken, and every later set finds the event already set and wakes no
one. The task then waits for good: the page's viser panel (time, capture-point plot, legend) stops updating
while every thread of the console is idle (seen in about one browser-test run in three, and in CI).

A set event with a waiter still pending cannot happen otherwise on the loop's own thread (a set there wakes its
waiters at once), so `wake_if_stuck`, run on the loop, looks for exactly that and wakes the waiters by clearing
and setting the event again. `wake_stuck_buffers` schedules it for the broadcast buffer and each client's."""

from __future__ import annotations

import asyncio
import logging

log = logging.getLogger(__name__)


def wake_if_stuck(event: asyncio.Event) -> bool:
    """On the event's loop: wake waiters a cross-thread set left waiting on a set event; whether there were."""
    stuck = event.is_set() and any(not fut.done() for fut in getattr(event, "_waiters", ()) or ())
    if stuck:
        event.clear()
        event.set()
    return stuck


def _wake_on_loop(buffer) -> None:
    if wake_if_stuck(buffer.message_event):
        log.warning("viser: a message buffer's sender had missed its wake-up; woken")


def wake_stuck_buffers(server) -> int:
    """Schedule `wake_if_stuck` on viser's loop for the broadcast buffer and each connected client's; how many
    buffers. `server`, a viser.ViserServer (1.1.1's internals: its websocket server and client connections)."""
    buffers = [server._websock_server.get_message_buffer()]
    buffers += [client._websock_connection.get_message_buffer() for client in server.get_clients().values()]
    for buffer in buffers:
        try:
            buffer.event_loop.call_soon_threadsafe(_wake_on_loop, buffer)
        except RuntimeError:  # the loop has closed (the server is stopping)
            pass
    return len(buffers)
