"""Draws docs/img/architecture.svg, the data flow of docs/architecture.md (plain SVG, no dependency):

    python docs/img/architecture.py
"""

from pathlib import Path
from xml.sax.saxutils import escape

from controller.core.chain import CHAIN_ORDER

W = 1060
LEFT, RIGHT, COL_W = 40, 550, 470  # the joystick's column and the behaviour's
LINE_H, PAD = 16, 8
out: list[str] = []


def text(x: float, y: float, s: str, cls: str = "code", anchor: str = "start") -> None:
    out.append(f'<text x="{x}" y="{y}" class="{cls}" text-anchor="{anchor}">{escape(s)}</text>')


def box(x: float, y: float, w: float, lines: list[str], cls: str = "box") -> float:
    """A box whose first line is its title; returns its bottom."""
    h = 2 * PAD + LINE_H * len(lines)
    out.append(f'<rect x="{x}" y="{y}" width="{w}" height="{h}" rx="6" class="{cls}"/>')
    for i, line in enumerate(lines):
        text(x + PAD, y + PAD + LINE_H * (i + 1) - 4, line, "title" if i == 0 else "code")
    return y + h


def arrow(x1: float, y1: float, x2: float, y2: float, label: str = "", cls: str = "arrow") -> None:
    out.append(f'<line x1="{x1}" y1="{y1}" x2="{x2}" y2="{y2}" class="{cls}" marker-end="url(#head)"/>')
    if label:
        text((x1 + x2) / 2 + 8, (y1 + y2) / 2 + 4, label, "label")


def band(y: float, h: float, title: str, cls: str) -> None:
    out.append(f'<rect x="10" y="{y}" width="{W - 20}" height="{h}" rx="10" class="{cls}"/>')
    text(24, y + 20, title, "band")


def draw() -> str:
    mid_l, mid_r = LEFT + COL_W / 2, RIGHT + COL_W / 2
    # ---- the browser
    band(10, 128, "browser: the operator page (static/console.js)", "b1")
    b1 = box(LEFT, 38, COL_W, ["a joystick setpoint", "streamTick(): the selected point's twist, 50 Hz",
                                  "WS /ws/operator  {point, linear, angular}"])
    box(RIGHT, 38, COL_W, ["a behaviour", "POST /api/behaviors/squat  {\"depth_m\": 0.15}",
                           "(or any client: curl, scripts, the viser buttons)"])
    # ---- the console process
    band(150, 320, "console process: FastAPI (app/console/main.py: create_app; the door in app.state.service)", "b2")
    l1 = box(LEFT, 180, COL_W, ["app/console/routers/operator.py: operator_stream",
                                "pydantic OperatorVelocityRequest, the operator lock",
                                "setpoint_of(req) -> Setpoint (app/service/setpoints.py)"])
    box(RIGHT, 180, COL_W, ["app/console/routers/behaviors.py: start",
                            "body checked against the schema made from squat's Params",
                            "-> service.run_behavior(name, values)"])
    arrow(mid_l, b1, mid_l, 180)
    arrow(mid_r, b1, mid_r, 180)
    l2 = box(LEFT, l1 + 26, COL_W, ["OperatorService.put_setpoint (app/service/operator.py)",
                                    "PointClaims: one client streams to a point at a time",
                                    "RobotProcess.put_setpoint -> SetpointTable.put (numbered)"])
    r2 = box(RIGHT, l1 + 26, COL_W, ["OperatorService.run(RunBehavior(...))",
                                     "verb.check(info): invalid input is a 422 here",
                                     "RobotProcess.submit(verb) -> a Future (app/service/process.py)"])
    arrow(mid_l, l1, mid_l, l1 + 26)
    arrow(mid_r, l1, mid_r, l1 + 26)
    t = l2 + 24
    tl = box(LEFT, t, COL_W, ["shared-memory setpoint board (app/service/board.py)",
                              "every point's newest setpoint: latest wins, no queue",
                              "(PUT /api/operator/velocity takes the same way)"], "pipe")
    tr = box(RIGHT, t, COL_W, ["command pipe (multiprocessing Pipe)",
                               "(request id, verb) -> (request id, result or error)",
                               "(the e-stop has a pipe of its own: docs/safety-path.md)"], "pipe")
    arrow(mid_l, l2, mid_l, t)
    arrow(mid_r, r2, mid_r, t)
    # ---- the robot process
    top = 490
    band_at = len(out)  # the band and the loop's frame go under what is drawn next, once its height is known
    r3 = box(RIGHT, top + 30, COL_W, ["between ticks: handle_commands()",
                                      "RobotHost.apply_input -> apply (app/service/host.py)",
                                      "refused (409): fallen, hard_stop, a latched stop",
                                      "RunBehavior.run -> BehaviorRunner.run (behaviors/runner.py)"])
    arrow(mid_r, tr, mid_r, top + 30)
    loop_top = r3 + 14
    loop_at = len(out)
    bt = loop_top + 28
    arrow(mid_l, tl, mid_l, bt, "read at each tick boundary")
    l4 = box(LEFT, bt, COL_W, ["before_tick = RobotHost._before_tick",
                               "setpoints.poll() (BoardSource) -> apply_setpoints",
                               "OperationLayer.set_motion(point, twist, time_s)",
                               "acknowledged in host.setpoint_acks (tick, time)"])
    r4 = box(RIGHT, bt, COL_W, ["before_tick: BehaviorRunner.step(time_s)",
                                "behavior.step(ctx) (a composite: its plan() generator)",
                                "OperationLayer.set_behavior(twists, walk)",
                                "discrete commands: HostCommands -> RobotHost.apply"])
    arrow(mid_r, r3, mid_r, bt)
    rd = max(l4, r4) + 22
    rd_b = box(W / 2 - 150, rd, 300, ["plant.read() -> Sensors", "IMU, encoders, F/T, clock (no ground truth)"])
    arrow(mid_l, l4, W / 2 - 60, rd)
    arrow(mid_r, r4, W / 2 + 60, rd)
    # the chain
    ch = rd_b + 30
    text(W / 2, ch, "Chain.tick (controller/core/chain.py), the layers in CHAIN_ORDER, built by "
                    "ControllerSystem.build_chain (controller/system.py)", "title", "middle")
    n = len(CHAIN_ORDER)
    cw, gap = 72, 18
    x0 = (W - (n * cw + (n - 1) * gap)) / 2
    y = ch + 16
    xs = {}
    for i, name in enumerate(CHAIN_ORDER):
        x = x0 + i * (cw + gap)
        xs[name] = x
        out.append(f'<rect x="{x}" y="{y}" width="{cw}" height="34" rx="5" '
                   f'class="{"layer hot" if name in ("op", "abc") else "layer"}"/>')
        text(x + cw / 2, y + 22, name, "title", "middle")
        if i:
            arrow(x - gap, y + 17, x - 1, y + 17)
    arrow(W / 2, rd_b, W / 2, ch - 14)
    # op -> abc through the ports
    xo, xa = xs["op"] + cw / 2, xs["abc"] + cw / 2
    out.append(f'<path d="M {xo} {y + 34} C {xo} {y + 80}, {xa} {y + 80}, {xa} {y + 36}" class="port" '
               'marker-end="url(#head)"/>')
    text((xo + xa) / 2, y + 84, "Ports.walk_command (and later ports)", "label", "middle")
    notes = y + 112
    lines = ["op (controller/layers/operation.py): [OP] Eq. 5, the operator's twist + the behaviours' per point,",
             "limited, integrated in the feet frame F, upper-body IK on placo; abc walks at op's walk command;",
             "each layer returns the reference the next one takes; st balances, hes holds on the e-stop, el limits"]
    for i, line in enumerate(lines):
        text(W / 2 - 30, notes + i * LINE_H, line, "code", "middle")
    wr = notes + len(lines) * LINE_H + 10
    wr_b = box(W / 2 - 230, wr, 460, ["plant.write(q_cmd): MujocoPlant.write (robot/plant.py)",
                                      "servo targets; then plant.step: 5 x 1 ms of MuJoCo physics"], "plant")
    # el's command to the plant: down the right-hand side, into plant.write's box
    xe, ye = xs["el"] + cw / 2, (wr + wr_b) / 2
    out.append(f'<path d="M {xe} {y + 34} L {xe} {ye} L {W / 2 + 232} {ye}" class="arrow" fill="none" '
               'marker-end="url(#head)"/>')
    # the way back
    back = wr_b + 24
    back_b = box(LEFT, back, W - 2 * LEFT, [
        "back to the console: the snapshot board (app/service/board.py), 50 Hz, latest wins",
        "RobotHost._on_snapshot each tick; between ticks robot_main's publish() puts host.publish() there;",
        "the WS answers a setpoint once setpoint_acks shows it applied (OperatorService.wait_setpoint);",
        "GET /api/state, WS /ws/telemetry and GET /api/behaviors/runs/{id} read the same board"], "back")
    arrow(W / 2, wr_b, W / 2, back)
    band(top, back_b + 14 - top, "robot process: robot_main (app/service/process.py), a tick every 5 ms", "b3")
    loop_frame = out[-2:]
    del out[-2:]
    out.append(f'<rect x="24" y="{loop_top}" width="{W - 48}" height="{wr_b + 8 - loop_top}" rx="8" '
               'class="loop"/>')
    text(36, loop_top + 18, "ControlLoop.step (controller/core/loop.py): one tick", "band")
    frame = out[-2:]
    del out[-2:]
    out[loop_at:loop_at] = frame
    out[band_at:band_at] = loop_frame
    height = back_b + 14 + 10
    style = """
    .b1 { fill: #eef5ff; stroke: #8fb3e0; } .b2 { fill: #f3f9ee; stroke: #9fc98a; }
    .b3 { fill: #fff7ec; stroke: #e0b36f; } .loop { fill: #fffdf8; stroke: #d9a55b; stroke-dasharray: 5 3; }
    .box { fill: #ffffff; stroke: #555; } .pipe { fill: #f0f0f0; stroke: #777; stroke-dasharray: 4 2; }
    .plant { fill: #fbe9e9; stroke: #b55; } .back { fill: #f4f0fa; stroke: #86a; }
    .layer { fill: #ffffff; stroke: #555; } .hot { fill: #ffe9c4; stroke: #b77b12; }
    .arrow { stroke: #333; stroke-width: 1.4; } .port { fill: none; stroke: #b77b12; stroke-width: 1.4;
      stroke-dasharray: 5 3; }
    text { font-family: DejaVu Sans, Helvetica, Arial, sans-serif; fill: #222; }
    .title { font-size: 13px; font-weight: bold; } .code { font-size: 12px; font-family: DejaVu Sans Mono,
      Menlo, Consolas, monospace; } .band { font-size: 14px; font-weight: bold; fill: #444; }
    .label { font-size: 12px; font-style: italic; fill: #7a5208; }"""
    return "\n".join([
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" viewBox="0 0 {W} {height}" '
        'font-size="12">',
        "<title>hrp2-console: a joystick setpoint and a behaviour from the browser to plant.write</title>",
        f"<style>{style}\n</style>",
        '<defs><marker id="head" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
        'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#333"/></marker></defs>',
        f'<rect width="{W}" height="{height}" fill="#ffffff"/>',
        *out, "</svg>", ""])


if __name__ == "__main__":
    path = Path(__file__).with_suffix(".svg")
    path.write_text(draw())
    print(path)
