"""Study runs on a Ray cluster (`--ray ADDRESS`; `ray` is the optional extra `.[ray]`): the same runs as the pool,
one CPU each. Every node needs this project installed (the same version) in the Python that Ray runs."""

from __future__ import annotations

import os
import socket
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from app.lab.study.run import run_spec

#: [s] how long the cluster's address may take to accept a TCP connection before --ray gives up (Ray's own connect
#: retries an address nothing answers at for minutes)
PROBE_TIMEOUT_S = 5.0


class RayUnavailable(RuntimeError):
    """`ray` is not installed, or nothing answers at the cluster's address."""


def probe_address(address: str, timeout_s: float = PROBE_TIMEOUT_S) -> None:
    """Raise RayUnavailable unless a TCP connection to `address` ("HOST:PORT" or "ray://HOST:PORT") opens within
    `timeout_s`: an unreachable cluster fails fast, naming the address, instead of hanging in Ray's connect."""
    host_port = address.removeprefix("ray://")
    host, sep, port = host_port.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise RayUnavailable(f"--ray {address!r}: expected HOST:PORT, ray://HOST:PORT, 'auto' or 'local'")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except (OSError, UnicodeError) as exc:  # UnicodeError: a host name IDNA cannot encode (a label over 63)
        raise RayUnavailable(f"--ray {address!r}: nothing answers at {host}:{port} within {timeout_s:g} s ({exc}); "
                             "start the cluster (ray start --head) or check the address") from exc


class RayBackend:
    """`address`: a running cluster's ("HOST:PORT", "ray://HOST:10001", "auto"), or "local" to start a
    private one on this machine (loopback only, no dashboard; shut down after the runs). Without an address,
    a Ray session the caller already started is used (the tests start one). `fn` runs one spec (the e-stop
    study's `run_spec` by default, the push map's `run_push`)."""

    def __init__(self, address: str | None = None, fn: Callable[[dict[str, Any]], dict[str, Any]] = run_spec) -> None:
        self.address = address
        self.fn = fn

    def __repr__(self) -> str:
        return f"RayBackend(address={self.address!r})"

    def describe(self) -> str:
        return f"Ray ({self.address or 'the session already started'})"

    def _connect(self):
        if self.address not in (None, "local", "auto"):
            probe_address(self.address)
        try:
            import ray
        except ImportError as exc:
            raise RayUnavailable("--ray needs the ray package: pip install -e '.[ray]'") from exc
        started = False
        if not ray.is_initialized():
            if self.address in (None, "local"):
                ray.init(address="local", num_cpus=os.cpu_count(), include_dashboard=False,
                         _node_ip_address="127.0.0.1", log_to_driver=False)
            else:
                try:
                    ray.init(address=self.address, log_to_driver=False)
                except ConnectionError as exc:  # something answers, but not a Ray cluster that accepts us
                    raise RayUnavailable(f"--ray {self.address!r}: {exc}") from exc
            started = True
        return ray, started

    def run(self, specs: Sequence[dict[str, Any]]) -> Iterator[dict[str, Any]]:
        if not specs:
            return
        ray, started = self._connect()
        remote = ray.remote(num_cpus=1)(self.fn)
        pending = [remote.remote(s) for s in specs]
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    yield ray.get(ref)
        finally:
            for ref in pending:  # the caller stopped early
                ray.cancel(ref, force=True)
            if started:
                ray.shutdown()
