"""The robot process: simulation, controller and (later) behaviours in their own interpreter, as the Whole
Body Motion Generator of [OP] Fig. 6 ran on its own real-time CPU. The console talks to it through three
channels: a command pipe (verbs in, results out, applied at tick boundaries), a dedicated e-stop pipe that
no other traffic shares, and a shared-memory board the robot publishes its snapshots to (latest wins)."""

from __future__ import annotations

import dataclasses
import gc
import itertools
import logging
import multiprocessing
import os
import select
import signal
import threading
import time
import traceback
from concurrent.futures import Future
from dataclasses import dataclass
from multiprocessing import connection
from typing import Any

import numpy as np

from app.service.board import Board, attach
from app.service.data_logger import DataLogger
from app.service.errors import ServiceError, Unavailable
from app.service.estop import EstopAck, press_error
from app.service.estop_door import EstopDoor, EstopDoorConfig
from app.service.host import Published, RobotHost
from app.service.setpoints import BOARD_BYTES, BoardSource, Setpoint, SetpointTable
from app.service.verbs import GetInfo, Reset, RobotInfo, Shutdown, Verb

log = logging.getLogger(__name__)

_SINGLE_THREADED = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
START_TIMEOUT_S = 90.0  # importing MuJoCo and pinocchio and building the chain, on a slow machine
LOG_LENGTH = 12000  # DataLogger rows (60 s at 5 ms)


@dataclass(frozen=True)
class RobotConfig:
    scene: str = "default"
    speed: float | None = 1.0  # real-time factor; None = as fast as possible
    dt_control_s: float = 0.005
    # [s] of wall time between two snapshots on the board, at most: 50 Hz is more than any reader shows
    # (state polls, the 30 Hz view, 20 Hz telemetry), and publishing costs ~0.3 ms of the robot's time
    publish_period_s: float = 0.02
    log_length: int = LOG_LENGTH
    realtime_priority: bool = True  # ask the OS for a real-time (or at least a higher) priority
    # [s] the wait between ticks is taken in naps this long. Measured on this 2-core VM: a robot process that
    # slept the whole wait ran its ticks twice as slow and started them up to 28-40 ms late (p99 10-13 ms,
    # idle machine), the virtual CPU being descheduled; in 0.1 ms naps, p99 0.02 ms idle and 0.7 ms under
    # 20 pollers + 100 commands/s (polling without naps is worse: the kernel throttles a real-time task
    # that never sleeps)
    nap_s: float = 1e-4
    # a parameter document {owner: {field: value}} the chain starts with (and again after each reset)
    params: dict[str, dict[str, Any]] | None = None
    record: str | None = None  # record a session to this MCAP file from the first tick
    # the hard e-stop's own WebSocket door, served by the loop's thread (app.service.estop_door); None: none
    estop_door: EstopDoorConfig | None = None


class UnexpectedError(ServiceError):
    """An error the robot process did not mean to raise (a bug); the loop keeps running."""


# ---- inside the robot process -------------------------------------------------------------------------------
#: [s] the e-stop door is served in the wait between ticks only while this much is left before the next tick:
#: a serve (4 socket operations, a hostile handshake's parse and refusal the dearest) took up to 1.4 ms under the
#: socket fuzz, and one just before the deadline made that tick late by as much
DOOR_RESERVE_S = 2e-3


def _raise_priority() -> str:
    """SCHED_FIFO if allowed, else a lower nice value, else nothing; says which. For the calling thread only:
    threads and processes it starts later (the camera process, the session writer) are not real-time
    (SCHED_RESET_ON_FORK): a camera rendering at the loop's FIFO priority took its core for 3-4 ms."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(10))
        return "SCHED_FIFO 10"
    except (AttributeError, PermissionError, OSError):
        pass
    try:
        os.nice(-10)
        return "nice -10"
    except (AttributeError, PermissionError, OSError):
        return "default"


def settle_heap() -> None:
    """Collect now, then keep everything alive so far out of later collections (gc.freeze): a full collection of
    the robot's heap (MuJoCo, pinocchio, placo and the chain, ~76,000 objects) takes 28-38 ms, and the automatic
    ones, triggered by whatever a tick or a client allocates, made ticks that late."""
    gc.unfreeze()
    gc.collect()
    gc.freeze()


def robot_main(cfg: RobotConfig, cmd: connection.Connection, estop: connection.Connection, board_name: str,
               log_name: str, setpoints_name: str | None = None) -> None:
    """The robot process's main: build, announce, tick until Shutdown, publish the last snapshot."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the console decides
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s robot %(name)s: %(message)s")
    board = Board(name=board_name)
    log_shm = attach(log_name)
    storage = np.ndarray(DataLogger.storage_shape(cfg.log_length), dtype=np.float64, buffer=log_shm.buf)
    setpoints = None if setpoints_name is None else BoardSource(Board(name=setpoints_name))
    try:
        host = RobotHost(cfg.scene, cfg.dt_control_s, cfg.speed, logger=DataLogger(cfg.log_length, storage),
                         params=cfg.params, setpoints=setpoints)
    except ServiceError as exc:  # e.g. a bad parameter document: the console says which field
        cmd.send(("failed", str(exc)))
        return
    except Exception as exc:  # noqa: BLE001 - tell the console why, then give up
        cmd.send(("failed", f"{type(exc).__name__}: {exc}"))
        return
    if cfg.record is not None:
        try:
            host.start_recording(cfg.record)
        except (ServiceError, OSError) as exc:
            cmd.send(("failed", f"cannot record to {cfg.record}: {exc}"))
            return
    # a paced loop sleeps most of each tick and deserves the CPU when it wakes; one running as fast as it can
    # never sleeps, and with SCHED_FIFO it would starve the HTTP process (and everything else) of a core
    priority = _raise_priority() if cfg.realtime_priority and cfg.speed is not None else "default"
    if priority.startswith("SCHED_FIFO"):
        # the loop preempts the camera process whatever its nice; lowered, a busy machine (a software-GL browser
        # beside the console) starved its start and its recognitions for over 10 s
        host.camera_nice = 0
    try:
        host.start_cameras()  # before the loop runs at real time (robot.camera.CameraProcess)
    except Exception as exc:  # noqa: BLE001 - no cameras (no GL here): perception fails, the robot runs
        log.error("no head cameras: %s", exc)
    door = None
    if cfg.estop_door is not None:
        try:
            door = EstopDoor(cfg.estop_door, host.engage_estop)
        except OSError as exc:  # e.g. the port is taken: the console's e-stop paths remain
            log.error("no e-stop door on %s:%s: %s", cfg.estop_door.host, cfg.estop_door.port, exc)
    board.put(host.publish())
    settle_heap()
    cmd.send(("ready", host.info(), priority, None if door is None else door.port))
    loop = host.loop
    loop.nap_s = cfg.nap_s
    last_publish = [0.0]
    pipes = (estop, cmd)

    def handle_estop() -> None:
        while estop.poll():
            request, press = estop.recv()
            # the console checked the id; should one slip through, the stop engages without it
            estop.send((request, host.engage_estop(press if press_error(press) is None else None)))

    def handle_commands() -> None:
        while cmd.poll():
            handle_estop()  # an e-stop sent before a command takes effect before it
            request, verb = cmd.recv()
            try:
                reply = ("ok", host.apply_input(verb))
                if isinstance(verb, Reset):
                    settle_heap()  # the new chain's objects out of the collector's way, the old ones freed
            except ServiceError as exc:
                reply = ("err", exc)
            except Exception as exc:  # noqa: BLE001 - a verb never kills the loop
                log.error("verb %s failed:\n%s", getattr(verb, "name", verb), traceback.format_exc())
                reply = ("err", UnexpectedError(f"internal error in {getattr(verb, 'name', verb)}: "
                                                f"{type(exc).__name__}: {exc}"))
            try:
                cmd.send((request, *reply))
            except Exception as exc:  # noqa: BLE001 - e.g. a result that cannot be pickled
                cmd.send((request, "err", UnexpectedError(f"the result could not be sent: {exc}")))

    def publish(force: bool = False) -> None:
        now = time.perf_counter()
        if force or now - last_publish[0] >= cfg.publish_period_s:
            last_publish[0] = now
            try:
                board.put(host.publish())
            except ValueError as exc:  # larger than the board: say so once in a while, keep ticking
                log.error("snapshot not published: %s", exc)

    door_watched = [False]  # a wait since the last tick boundary had the door's sockets watched

    def wait(delay_s: float) -> None:
        # the door is served while a serve cannot make the tick late; what comes later waits for after the tick
        watch_door = door is not None and loop.due_s - time.perf_counter() >= DOOR_RESERVE_S
        door_watched[0] = door_watched[0] or watch_door
        # select() sleeps to the microsecond (connection.wait's poll() rounds up to whole milliseconds)
        ready, _, _ = select.select((*pipes, *door.sockets) if watch_door else pipes, (), (), delay_s)
        if ready:
            handle_estop()
            if watch_door:
                door.serve(ready)
            # commands are not held for after the tick as the door is: a release so held would be applied after an
            # e-stop pressed after it was sent (the e-stop pipe is read first)
            handle_commands()

    def between_ticks() -> None:
        handle_estop()
        if door is not None:
            # unpaced there are no waits; paced, ticks that leave no time to spare still serve it once per tick
            if not door_watched[0]:
                door.poll()
            door.new_tick()
            door_watched[0] = False
        handle_commands()
        publish()

    try:
        loop.run_paced(wait, between_ticks)
    except (EOFError, OSError):  # the console went away
        _finish_recording(host)
        return
    finally:
        if door is not None:
            door.close()
    _finish_recording(host)
    publish(force=True)
    host.close_cameras()
    try:
        cmd.send(("bye", host.stats.summary()))
    except (EOFError, OSError):
        pass


def _finish_recording(host: RobotHost) -> None:
    """At the end of the robot process: stop the session being recorded, wait until its file is finished."""
    if host.recorder is not None:
        host.stop_recording()
    if host.last_recorder is not None:
        host.last_recorder.wait()


# ---- in the console ------------------------------------------------------------------------------------------
class RobotProcess:
    """Starts and supervises the robot process; the console's end of its channels.

    `submit(verb)` returns a Future resolved with the verb's result or its ServiceError; `estop()` engages
    the hard e-stop through the dedicated pipe and returns when the loop has engaged it; `latest()` reads
    the newest snapshot from shared memory. If the process dies, every call raises Unavailable (the reason
    in `exit_reason`) until `restart()`.
    """

    def __init__(self, config: RobotConfig | None = None) -> None:
        self.config = config or RobotConfig()
        self._ids = itertools.count(1)
        self._pending: dict[int, Future] = {}
        self._pending_lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._estop_lock = threading.Lock()
        self.board: Board | None = None
        self._log_shm = None
        self.process: multiprocessing.Process | None = None
        self.exit_reason: str | None = None
        self.summary: dict[str, Any] | None = None
        self.priority = "default"
        self.estop_door_port: int | None = None  # the e-stop's own door (RobotConfig.estop_door), once started
        self._info: RobotInfo | None = None
        self._start()

    # ---- lifecycle -------------------------------------------------------------------------------------
    def _start(self) -> None:
        cfg = self.config
        ctx = multiprocessing.get_context("spawn")
        self.board = Board()
        # the operator's streamed setpoints: this side writes the newest table, the robot reads it each tick
        self.setpoints_board = Board(size=BOARD_BYTES)
        self._setpoints = SetpointTable(self.setpoints_board.put)
        from multiprocessing import shared_memory

        shape = DataLogger.storage_shape(cfg.log_length)
        self._log_shm = shared_memory.SharedMemory(create=True, size=int(np.prod(shape)) * 8)
        self._log_storage = np.ndarray(shape, dtype=np.float64, buffer=self._log_shm.buf)
        self._log_storage[0] = 0.0
        cmd_here, cmd_there = ctx.Pipe(duplex=True)
        estop_here, estop_there = ctx.Pipe(duplex=True)
        self._cmd, self._estop_conn = cmd_here, estop_here
        self.process = ctx.Process(target=robot_main, name="hrp2-robot",
                                   args=(cfg, cmd_there, estop_there, self.board.name, self._log_shm.name,
                                         self.setpoints_board.name))
        # one BLAS/OpenMP thread in the robot: its matrices are tiny, and idle worker threads spin on the
        # other core (measured 3-6 % of it) where the console answers requests
        saved = {k: os.environ.get(k) for k in _SINGLE_THREADED}
        os.environ.update(_SINGLE_THREADED)
        try:
            self.process.start()
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        cmd_there.close()
        estop_there.close()
        self.exit_reason = None
        self.summary = None
        try:
            if not cmd_here.poll(START_TIMEOUT_S):
                raise Unavailable(f"the robot process did not start within {START_TIMEOUT_S:g} s")
            first = cmd_here.recv()
        except (EOFError, OSError):
            first = ("failed", f"it exited during start-up (exit code {self.process.exitcode})")
        except Unavailable:
            self.close()
            raise
        if first[0] != "ready":
            self.close()
            raise Unavailable(f"the robot process could not start: {first[1]}")
        _, self._info, self.priority, self.estop_door_port = first
        self._reader = threading.Thread(target=self._read_replies, name="robot-replies", daemon=True)
        self._reader.start()

    def _read_replies(self) -> None:
        conn = self._cmd
        while True:
            try:
                message = conn.recv()
            except (EOFError, OSError):
                break
            except Exception:  # noqa: BLE001 - a reply that cannot be read: its caller times out, others go on
                log.exception("a reply of the robot process could not be read")
                continue
            if message[0] == "bye":
                self.summary = message[1]
                continue
            request, kind, value = message
            with self._pending_lock:
                fut = self._pending.pop(request, None)
            if fut is None:
                continue
            if kind == "ok":
                fut.set_result(value)
            else:
                fut.set_exception(value)
        self._died()

    def _died(self) -> None:
        proc = self.process
        if proc is not None:
            proc.join(timeout=2.0)
        code = None if proc is None else proc.exitcode
        if self.exit_reason is None:
            self.exit_reason = ("the robot process stopped" if self.summary is not None
                                else f"the robot process exited (exit code {code})")
        with self._pending_lock:
            pending, self._pending = self._pending, {}
        for fut in pending.values():
            if not fut.done():
                fut.set_exception(Unavailable(f"{self.exit_reason}; reset starts a new one"))

    @property
    def alive(self) -> bool:
        # the reply reader sees the pipe close when the process ends and sets exit_reason (no waitpid per call)
        return self.process is not None and self.exit_reason is None

    def _require_alive(self) -> None:
        if not self.alive:
            raise Unavailable(f"{self.exit_reason or 'the robot process is not running'}; reset starts a new one")

    # ---- channels ----------------------------------------------------------------------------------------
    def submit(self, verb: Verb) -> Future:
        fut: Future = Future()
        if not self.alive:
            fut.set_exception(Unavailable(f"{self.exit_reason or 'the robot process is not running'}; "
                                          "reset starts a new one"))
            return fut
        request = next(self._ids)
        with self._pending_lock:
            self._pending[request] = fut
        try:
            with self._send_lock:
                self._cmd.send((request, verb))
        except (OSError, ValueError) as exc:
            with self._pending_lock:
                self._pending.pop(request, None)
            fut.set_exception(Unavailable(f"the robot process cannot be reached: {exc}"))
        return fut

    def estop(self, press: str | None = None, timeout_s: float = 1.0) -> EstopAck:
        """Engage the hard e-stop through its own pipe; returns when the loop has engaged it. `press`: the
        press's id (checked by the caller)."""
        self._require_alive()
        with self._estop_lock:
            request = next(self._ids)
            conn = self._estop_conn
            try:
                conn.send((request, press))
                deadline = time.monotonic() + timeout_s
                while True:
                    remaining = deadline - time.monotonic()
                    if remaining <= 0 or not conn.poll(remaining):
                        raise Unavailable(f"the robot process did not confirm the e-stop within {timeout_s:g} s")
                    got, ack = conn.recv()
                    if got == request:
                        return ack
            except (EOFError, OSError) as exc:
                raise Unavailable(f"the robot process cannot be reached: {exc}") from None

    def latest(self) -> Published | None:
        return None if self.board is None else self.board.get()

    def put_setpoint(self, setpoint: Setpoint) -> Setpoint:
        """The operator's newest setpoint for a point, on the latest-value board (no queue, no reply: the
        robot's acknowledgement comes back in the published snapshot's setpoint_acks)."""
        self._require_alive()
        return self._setpoints.put(setpoint)

    def setpoint_seq(self) -> int:
        return self._setpoints.last_seq

    def info(self) -> RobotInfo:
        return self._info

    def refresh_info(self, timeout_s: float = 10.0) -> RobotInfo:
        self._info = self.submit(GetInfo()).result(timeout=timeout_s)
        return self._info

    def log_rows(self) -> np.ndarray:
        return DataLogger.reader(self._log_storage).rows()

    def reset(self, scene: str | None = None, timeout_s: float = 30.0) -> RobotInfo:
        """Reset the simulation in the running process, or start a new process when it has died."""
        if not self.alive:
            if scene is not None:
                self.config = dataclasses.replace(self.config, scene=scene)
            self.close()
            self._start()
            return self._info
        self.submit(Reset(scene)).result(timeout=timeout_s)
        return self.refresh_info()

    def close(self, timeout_s: float = 10.0) -> dict[str, Any] | None:
        """Stop the robot process (its summary is returned) and free the shared memory."""
        proc = self.process
        if proc is not None and proc.is_alive() and self.exit_reason is None:
            try:
                self.submit(Shutdown()).result(timeout=timeout_s)
            except Exception:  # noqa: BLE001 - stopping anyway
                pass
            proc.join(timeout=timeout_s)
        self._kill()
        if self.board is not None:
            self.board.close()
            self.board = None
        if getattr(self, "setpoints_board", None) is not None:
            self.setpoints_board.close()
            self.setpoints_board = None
        if self._log_shm is not None:
            self._log_storage = None
            try:
                self._log_shm.close()
                self._log_shm.unlink()
            except (FileNotFoundError, BufferError):
                pass
            self._log_shm = None
        return self.summary

    def _kill(self) -> None:
        proc = self.process
        if proc is not None and proc.is_alive():
            proc.terminate()
            proc.join(timeout=5.0)
            if proc.is_alive():
                proc.kill()
                proc.join(timeout=5.0)
        for conn in (getattr(self, "_cmd", None), getattr(self, "_estop_conn", None)):
            if conn is not None:
                try:
                    conn.close()
                except OSError:
                    pass

    def kill_for_test(self) -> None:
        """SIGKILL the robot process (what a crash looks like to the console)."""
        if self.process is not None and self.process.pid:
            os.kill(self.process.pid, signal.SIGKILL)
