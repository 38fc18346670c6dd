"""Command line: `hrp2-console` runs simulation, controller, HTTP API and 3D viewer; `bench` times the chain."""

from __future__ import annotations

import argparse
import json
import logging
import signal
import socket
import sys
import threading
import time
from collections.abc import Sequence

from app.cli_args import positive_float, positive_int, positive_seconds, speed_or_max
from app.session.files import KEEP_BYTES, KEEP_COUNT, retention_rule
from robot.plant import available_scenes

log = logging.getLogger("hrp2-console")

CONSOLE_SWITCH_INTERVAL_S = 0.0005  # [s] Python's GIL switch interval in the console process


# ---- argument types (the ones the campaign shares are in app.cli_args) ------------------------------------
def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected a TCP port in 0..65535 "
                                         "(0 picks a free one)")
    return value


def _scene(text: str) -> str:
    scenes = available_scenes()
    if text not in scenes:
        raise argparse.ArgumentTypeError(f"unknown scene {text!r}; available scenes: {', '.join(scenes)}")
    return text


def _params_file(text: str) -> dict[str, dict]:
    """A parameter document {owner: {field: value}} read from a JSON file (GET /api/params writes one)."""
    from pathlib import Path

    try:
        doc = json.loads(Path(text).read_text(encoding="utf-8"))
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"cannot read {text!r}: {exc.strerror or exc}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise argparse.ArgumentTypeError(f"{text!r} is not JSON: {exc}") from None
    if not isinstance(doc, dict) or not all(isinstance(v, dict) for v in doc.values()):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a JSON object {{owner: {{field: value}}}} as "
                                         "GET /api/params gives")
    return doc


#: where sessions go unless a path is given (`--record` without a path, POST /api/sessions/start)
SESSIONS_DIR = "out/sessions"


def _new_session_path(text: str) -> str:
    """A session file to create: `text` (".mcap" appended when it has no suffix), or, when empty, a new
    name in SESSIONS_DIR; its folder is made; an existing file is refused (a session is never overwritten)."""
    from pathlib import Path

    from app.session.files import new_session_name

    path = Path(text) if text else Path(SESSIONS_DIR) / new_session_name()
    if path.suffix == "":
        path = path.with_suffix(".mcap")
    if path.suffix != ".mcap":
        raise argparse.ArgumentTypeError(f"invalid path {text!r}: a session is an MCAP file (*.mcap)")
    if path.exists():
        raise argparse.ArgumentTypeError(f"{str(path)!r} exists: a session is never overwritten; choose another "
                                         "path")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"cannot make the folder of {str(path)!r}: {exc.strerror or exc}") from None
    return str(path)


def run_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="hrp2-console",
        description="Operator console for the simulated HRP-2 No.10: simulation + controller loop, "
                    "HTTP API (OpenAPI at /docs, operator page at /) and a viser 3D view.",
        epilog="Subcommands: `hrp2-console bench --help` times the controller chain; `hrp2-console replay --help` "
               "replays a recorded session; `hrp2-console campaign --help` runs random-operator sessions.")
    p.add_argument("--scene", type=_scene, default="default", help=f"scene: {', '.join(available_scenes())}")
    p.add_argument("--speed", type=speed_or_max, default=1.0,
                   help="real-time factor (1.0 = real time) or 'max' (as fast as possible)")
    p.add_argument("--headless", action="store_true", help="no 3D viewer")
    p.add_argument("--duration", type=positive_seconds, default=None,
                   help="run this many seconds of simulated time, print a summary and exit")
    p.add_argument("--host", default="127.0.0.1",
                   help="address of the HTTP API and the viewer (default 127.0.0.1, this machine only; any other "
                        "needs a token)")
    p.add_argument("--token", default=None,
                   help="the access token every /api/ request (Authorization: Bearer <token>) and WebSocket "
                        "(?token=) must carry; default: the environment variable HRP2_CONSOLE_TOKEN. Required for a "
                        "--host other than loopback. Open the page as http://HOST:PORT/?token=<token>")
    p.add_argument("--port", type=_port, default=8000, help="HTTP API port")
    p.add_argument("--viewer-port", type=_port, default=8080, help="viser viewer port")
    p.add_argument("--estop-port", type=_port, default=0,
                   help="port of the e-stop's own WebSocket door, served by the robot process (default 0: a free "
                        "one; the page reads it from GET /api/config)")
    p.add_argument("--params", type=_params_file, default=None, metavar="FILE",
                   help="start with these layer parameters: a JSON document {owner: {field: value}} as "
                        "GET /api/params gives (some owners and fields suffice; checked as PUT /api/params "
                        "checks them; kept across resets)")
    p.add_argument("--record", nargs="?", const="", default=None, type=_new_session_path, metavar="PATH",
                   help="record the session (inputs with the tick they took effect, behaviour runs, parameter "
                        f"changes, telemetry) to an MCAP file from the first tick; default path {SESSIONS_DIR}/"
                        "session-<time>.mcap; `hrp2-console replay PATH` replays it")
    p.add_argument("--sessions-dir", default=SESSIONS_DIR, metavar="DIR",
                   help=f"where POST /api/sessions/start records and GET /api/sessions lists (default {SESSIONS_DIR}); "
                        "it keeps " + retention_rule(KEEP_COUNT, KEEP_BYTES)
                        + " (--sessions-keep, --sessions-max-mb)")
    p.add_argument("--sessions-keep", type=positive_int, default=KEEP_COUNT, metavar="N",
                   help=f"session files --sessions-dir keeps at most (default {KEEP_COUNT})")
    p.add_argument("--sessions-max-mb", type=positive_float, default=KEEP_BYTES / 1024**2, metavar="MB",
                   help=f"their size together at most [MB] (default {KEEP_BYTES / 1024**2:g})")
    p.add_argument("--log-level", default="warning", choices=("debug", "info", "warning", "error"))
    return p


def bench_parser() -> argparse.ArgumentParser:
    from app.lab.bench import CHAINS, CONSOLE_SCENARIOS
    from app.lab.bench_cameras import CAMERA_SCENARIOS
    from app.lab.bench_recording import RECORDING_SCENARIOS
    from app.lab.bench_scenarios import SCENARIOS

    p = argparse.ArgumentParser(prog="hrp2-console bench",
                                description="Run the chain synchronously as fast as possible (no servers) "
                                            "and print its timing as JSON.")
    others = {**CONSOLE_SCENARIOS, **CAMERA_SCENARIOS, **RECORDING_SCENARIOS}
    p.add_argument("--scenario", choices=(*SCENARIOS, *others), default="stand",
                   help="; ".join([f"{k}: {v.description}" for k, v in SCENARIOS.items()]
                                  + [f"{k}: {v}" for k, v in others.items()]))
    p.add_argument("--duration", type=positive_seconds, default=5.0, help="simulated seconds (default 5)")
    p.add_argument("--scene", type=_scene, default="default", help=f"scene: {', '.join(available_scenes())}")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--layers", type=_layers, default=None,
                       help="only these layers work, comma-separated (e.g. kf,rmfo,seq,co,hes,el); the others "
                            "are disabled. The report adds step_ms, loop_overhead_ms, passthrough (the disabled "
                            "layers that passed their input through) and disabled_but_ran (kf, rmfo and hes "
                            "keep working when disabled)")
    which.add_argument("--chain", choices=tuple(CHAINS), default=None,
                       help="a named layer selection: " + "; ".join(f"{k}: {','.join(v)}" for k, v in CHAINS.items()))
    return p


def _layers(text: str) -> tuple[str, ...]:
    from app.lab.bench import layer_selection

    try:
        return layer_selection(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


# ---- commands -------------------------------------------------------------------------------------
def bench(argv: Sequence[str]) -> int:
    from app.lab.bench import run_bench

    p = bench_parser()
    args = p.parse_args(argv)
    layers = args.layers if args.layers is not None else args.chain
    try:
        report = run_bench(args.scenario, args.duration, args.scene, layers=layers)
    except ValueError as exc:  # a scenario that needs a layer left out
        p.error(str(exc))
    print(json.dumps(report, indent=2))
    return 0


def _bind_http(host: str, port: int) -> socket.socket:
    """The HTTP server's listening socket, bound before the robot starts: its e-stop door lets in pages of this
    port only (app.console.security.origin_allowed), so the port must be known first (--port 0 picks a free one)."""
    try:
        return socket.create_server((host, port), family=socket.AF_INET6 if ":" in host else socket.AF_INET,
                                    backlog=2048)
    except OSError as exc:
        raise RuntimeError(f"the HTTP server could not listen on {host}:{port}: {exc}") from None


def _start_http(app, sock: socket.socket, log_level: str):
    import uvicorn

    from app.console.ws import MAX_MESSAGE_BYTES

    # ws_max_size: a WebSocket message over the limit is refused by the server (close 1009) from its frame's
    # length, before it is read into memory (uvicorn's default is 16 MB)
    server = uvicorn.Server(uvicorn.Config(app, log_level=log_level, lifespan="on", timeout_keep_alive=30,
                                           ws_max_size=MAX_MESSAGE_BYTES))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, name="http", daemon=True)
    thread.start()
    deadline = time.monotonic() + 15.0
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            raise RuntimeError(f"the HTTP server could not start on {sock.getsockname()}")
        time.sleep(0.02)
    return server, thread, sock.getsockname()[1]


class _StopRequested:
    """Set by SIGINT / SIGTERM: the main loop ends and the console shuts down cleanly."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self.signal_name: str | None = None

    def __call__(self, signum, _frame) -> None:
        self.signal_name = signal.Signals(signum).name
        self.event.set()


def test_hooks_from_env() -> bool:
    """HRP2_TEST_HOOKS=1 (the browser tests set it) adds the fault-injection route POST /api/sim/fault."""
    import os

    return os.environ.get("HRP2_TEST_HOOKS") == "1"


def run(argv: Sequence[str]) -> int:
    args = run_parser().parse_args(argv)
    logging.basicConfig(level=args.log_level.upper(), format="%(levelname)s %(name)s: %(message)s")
    from app.console.security import TokenRequired, allowed_hosts_for, check_token_config, is_loopback, token_from_env

    token = token_from_env(args.token)
    try:  # before anything starts: nothing answers other machines without a token
        check_token_config(args.host, token)
    except TokenRequired as exc:
        print(f"hrp2-console: error: {exc}", file=sys.stderr)
        return 2

    from app.console.main import create_app
    from app.console.settings import Settings
    from app.service import OperatorService, ServiceError
    from app.service.estop_door import EstopDoorConfig
    from app.service.process import RobotConfig, RobotProcess
    from app.session.files import prune_sessions
    from robot.sensors import is_fallen

    # many request threads share this interpreter: hand the GIL over every 0.5 ms rather than 5 ms, so the
    # event loop answers (an e-stop, a state poll) without waiting behind a busy request thread
    sys.setswitchinterval(CONSOLE_SWITCH_INTERVAL_S)
    stop = _StopRequested()
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    wall0 = time.perf_counter()
    try:
        http_sock = _bind_http(args.host, args.port)
        door = EstopDoorConfig(host=args.host, port=args.estop_port, allowed_hosts=allowed_hosts_for(args.host),
                               page_ports=(http_sock.getsockname()[1],), token=token)
        robot = RobotProcess(RobotConfig(scene=args.scene, speed=args.speed, params=args.params, record=args.record,
                                         estop_door=door))
    except (ServiceError, RuntimeError) as exc:
        print(f"hrp2-console: error: {exc}", file=sys.stderr)
        return 2
    service = OperatorService(robot)
    viewer = None
    viewer_port = None
    viewer_host = args.host
    server = http_thread = None
    try:
        if not args.headless:
            from app.console.viewer import Viewer

            # viser's own server checks no token and its panel can release the e-stop: it stays on this
            # machine whatever --host says
            viewer_host = args.host if is_loopback(args.host) else "127.0.0.1"
            viewer = Viewer(service, host=viewer_host, port=args.viewer_port)
            viewer_port = viewer.port
        settings = Settings(scene=args.scene, speed=args.speed, host=args.host, port=args.port,
                            viewer_port=viewer_port, token=token, sessions_dir=args.sessions_dir,
                            sessions_keep=args.sessions_keep,
                            sessions_max_bytes=int(args.sessions_max_mb * 1024**2), test_hooks=test_hooks_from_env())
        prune_sessions(settings.sessions_dir, settings.sessions_keep, settings.sessions_max_bytes,
                       keep=[args.record] if args.record else [])
        app = create_app(settings, service=service)
        try:
            server, http_thread, http_port = _start_http(app, http_sock, args.log_level)
        except RuntimeError as exc:
            print(f"hrp2-console: error: {exc}", file=sys.stderr)
            return 2
        if viewer is not None:
            viewer.allow_page(http_port)  # the page's /viewer/ iframe opens the viewer's websocket
        speed = "max" if args.speed is None else f"{args.speed:g}x real time"
        pub = service.published()
        print(f"hrp2-console: scene {args.scene!r}, {speed}; chain {pub.chain}")
        print(f"  robot process  pid {robot.process.pid}, scheduling {robot.priority}")
        query = "?token=<the token>" if token is not None else ""
        print(f"  operator page  http://{args.host}:{http_port}/{query}   (API docs /docs)")
        if viewer_port is not None:
            note = "" if viewer_host == args.host else "   (this machine only: viser checks no token)"
            print(f"  3D viewer      http://{viewer_host}:{viewer_port}/{note}")
        if args.record is not None:
            print(f"  recording      {args.record}   (hrp2-console replay {args.record})")
        sys.stdout.flush()
        dt = robot.info().dt_control_s
        while not stop.event.is_set():
            if args.duration is not None:
                latest = robot.latest()
                # simulated time of this run, counted in ticks so that a reset does not restart it
                if latest is not None and latest.stats["ticks"] * dt >= args.duration - 1e-9:
                    break
            stop.event.wait(0.005 if args.duration is not None else 0.2)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if server is not None:
            server.should_exit = True
            http_thread.join(timeout=5.0)
        if viewer is not None:
            viewer.stop()
        last = robot.latest()
        summary = robot.close() or (last.stats if last is not None else None)
        wall_s = time.perf_counter() - wall0
    if stop.signal_name is not None:
        print(f"hrp2-console: {stop.signal_name} received, shut down")
    if summary is None:
        print("hrp2-console: error: the robot process left no summary "
              f"({robot.exit_reason or 'unknown reason'})", file=sys.stderr)
        return 1
    snap = last.snapshot if last is not None else None
    dt = robot.config.dt_control_s
    sim_s = summary["ticks"] * dt
    fallen = summary["fallen"] or bool(last is not None and is_fallen(last.truth))
    faults = summary["faults"]
    print("summary:")
    print(f"  scene: {last.scene if last is not None else args.scene}")
    print(f"  sim time: {sim_s:.3f} s")
    print(f"  ticks: {summary['ticks']}")
    print(f"  wall time: {wall_s:.3f} s")
    # the loop's own figure: simulated / wall time since the run began or was last reset (the ticks go on
    # over a reset, and the wall time counts the start-up)
    speed = last.timing.speed_run if last is not None else None
    if speed is None:
        speed = sim_s / wall_s if wall_s > 0 else float("inf")
    print(f"  real-time factor: {speed:.2f}")
    print(f"  fallen: {str(fallen).lower()}")
    print(f"  max loop ms: {summary['max_loop_ms']:.3f}")
    if last is not None:
        t = last.timing
        print(f"  tick start-lateness p50/p99/max ms: {t.lateness_p50_ms:.3f} / {t.lateness_p99_ms:.3f} / "
              f"{t.lateness_max_ms:.3f}")
    print(f"  hard stop: {str(bool(snap is not None and snap.safety.hard_stop)).lower()}")
    print(f"  faults: {'; '.join(faults) if faults else 'none'}")
    if args.record is not None:
        print(f"  session: {args.record}")
    return 1 if (fallen or faults) else 0


def replay(argv: Sequence[str]) -> int:
    """`hrp2-console replay SESSION [--view]`: re-run a session and compare it bit for bit, or play it back."""
    from app.session.reader import NotASession, read_session

    p = argparse.ArgumentParser(
        prog="hrp2-console replay",
        description="Replay a recorded session: its inputs fed again, each at its tick, into a fresh simulation run "
                    "as fast as possible (--speed max), every tick compared with the recording bit for bit "
                    "(exit 0: identical; 1: the first difference is printed). --view plays the recorded "
                    "trajectory in the browser instead (time slider, pause, speed).")
    p.add_argument("session", help="the session file (.mcap)")
    p.add_argument("--view", action="store_true", help="play it in the browser (viser) instead of re-running it")
    p.add_argument("--host", default="127.0.0.1", help="--view: address of the viewer (default this machine only)")
    p.add_argument("--port", type=_port, default=8080, help="--view: viewer port (0: a free one)")
    p.add_argument("--speed", type=speed_or_max, default=1.0,
                   help="--view: the playback speed it starts with (1.0 = real time); the replay itself always runs "
                        "at max")
    args = p.parse_args(argv)
    try:
        session = read_session(args.session)
    except (OSError, NotASession) as exc:
        print(f"hrp2-console replay: error: {exc}", file=sys.stderr)
        return 2
    print(f"session: {args.session}: {session.ticks} ticks ({session.ticks * session.dt_s:.3f} s), "
          f"{len(session.inputs)} inputs, scene {session.header.get('scene')!r}"
          + ("" if session.complete else f"; not finished ({session.problem}): read up to its last whole tick"))
    if args.view:
        return _view(session, args)
    from app.session.replay import NotReplayable
    from app.session.replay import replay as run_replay

    try:
        result = run_replay(session)
    except NotReplayable as exc:
        print(f"hrp2-console replay: error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(result.summary(), indent=2))
    if result.identical:
        print(f"identical: {result.ticks} ticks bit for bit (log row and the simulator's qpos digest)")
        return 0
    print(f"differs: {result.difference}")
    return 1


def _view(session, args) -> int:
    from app.lab.replay_viewer import ReplayViewer

    stop = _StopRequested()
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    viewer = ReplayViewer(session, host=args.host, port=args.port, speed=args.speed or 1.0)
    try:
        print(f"  replay viewer  http://{args.host}:{viewer.port}/   (Ctrl-C ends it)")
        sys.stdout.flush()
        stop.event.wait()
    finally:
        viewer.stop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return 0


def experiment(argv: Sequence[str]) -> int:
    """`hrp2-console experiment NAME [--no-es] [--out DIR]`: one [MLC] IV-C experiment, verdict last."""
    from pathlib import Path

    from app.lab.experiments import EXPERIMENTS, run_experiment

    p = argparse.ArgumentParser(prog="hrp2-console experiment",
                                description="Run an emergency-stop experiment of [MLC] IV-C in simulation.")
    p.add_argument("name", choices=sorted(EXPERIMENTS), help="the experiment")
    p.add_argument("--no-es", action="store_true", help="without the EmergencyStopper (the paper's case a)")
    p.add_argument("--variant", default=None,
                   help="the experiment's variant (e.g. the disturbance); default: its first: "
                        + "; ".join(f"{n}: {', '.join(e.variants)}" for n, e in sorted(EXPERIMENTS.items())))
    p.add_argument("--out", type=Path, default=Path("out/experiments"),
                   help="where the CSV and the Fig. 10-like PNG go (default: out/experiments)")
    accepted = {n: ", ".join(f"{k} [{d.low:g}, {d.high:g}] {d.unit}" for k, d in e.disturbances.items())
                for n, e in sorted(EXPERIMENTS.items()) if e.disturbances}
    p.add_argument("--disturb", action="append", default=[], metavar="NAME=VALUE",
                   help="set one of the experiment's disturbances (repeatable): "
                        + "; ".join(f"{n}: {names}" for n, names in accepted.items()))
    args = p.parse_args(argv)
    exp = EXPERIMENTS[args.name]
    variants = exp.variants
    if args.variant is not None and args.variant not in variants:
        p.error(f"argument --variant: {args.variant!r} is not a variant of {args.name}; "
                f"choose from {', '.join(variants)}")
    disturbance = {}
    for item in args.disturb:
        name, sep, text = item.partition("=")
        if not sep:
            p.error(f"argument --disturb: expected NAME=VALUE, got {item!r}")
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        disturbance[name.strip()] = value
    try:
        exp.disturbance(disturbance)
    except ValueError as exc:
        p.error(f"argument --disturb: {exc}")
    r = run_experiment(args.name, es=not args.no_es, out_dir=args.out, variant=args.variant,
                       disturbance=disturbance)
    print(f"experiment: {r.name} [{r.variant}] ({'with' if r.es else 'without'} EmergencyStopper), "
          f"{r.duration_s:.2f} s simulated")
    print(f"csv: {r.csv_path}\npng: {r.png_path}")
    if r.cp_error_at_flag_m is not None:
        print(f"CP error at the flag: {r.cp_error_at_flag_m * 1e3:.1f} mm, "
              f"CP {r.edge_margin_at_flag_m * 1e3:.1f} mm inside the support polygon")
    if r.below_threshold_after_revert_s is not None:
        print(f"error below the threshold {r.below_threshold_after_revert_s:.2f} s after the revert ended")
    print(f"simulated at {r.real_time_factor:.1f}x real time")
    for key, value in r.outcome.items():
        print(f"{key}: {value:.4g}")
    print(f"faults: {'; '.join(r.faults) if r.faults else 'none'}")
    print(r.verdict_line())
    return 1 if r.faults else 0  # a fall can be the experiment's result; a controller fault never is


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "bench":
        code = bench(argv[1:])
    elif argv[:2] == ["experiment", "expo"]:
        from app.lab.experiments.expo import main as expo_main

        code = expo_main(argv[2:])
    elif argv[:2] == ["study", "estop"]:
        from app.lab.study.cli import main as study_main

        code = study_main(argv[2:])
    elif argv[:2] == ["study", "push-walking"]:
        from app.lab.study.push_cli import main as push_main

        code = push_main(argv[2:])
    elif argv[:2] == ["study", "estop-walking"]:
        from app.lab.study.estop_walking_cli import main as estop_walking_main

        code = estop_walking_main(argv[2:])
    elif argv and argv[0] == "study":
        print("hrp2-console study: error: expected a study name: estop, estop-walking, push-walking (hrp2-console "
              "study estop --help)", file=sys.stderr)
        code = 2
    elif argv[:2] == ["experiment", "foot-can"]:
        from app.lab.experiments.foot_can import main as foot_can_main

        code = foot_can_main(argv[2:])
    elif argv[:2] == ["experiment", "fridge"]:
        from app.lab.experiments.fridge import main as fridge_main

        code = fridge_main(argv[2:])
    elif argv[:2] == ["experiment", "trash"]:
        from app.lab.experiments.trash import main as trash_main

        code = trash_main(argv[2:])
    elif argv[:2] == ["experiment", "chair"]:
        from app.lab.experiments.chair import main as chair_main

        code = chair_main(argv[2:])
    elif argv[:2] == ["experiment", "floor"]:
        from app.lab.experiments.floor_object import main as floor_main

        code = floor_main(argv[2:])
    elif argv and argv[0] == "experiment":
        code = experiment(argv[1:])
    elif argv and argv[0] == "campaign":
        from app.lab.campaign.cli import main as campaign_main

        code = campaign_main(argv[1:])
    elif argv and argv[0] == "replay":
        code = replay(argv[1:])
    else:
        code = run(argv)
    return code


if __name__ == "__main__":
    sys.exit(main())
