"""The hrp2-console command: a headless timed run, the bench subcommand, argument errors."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def console() -> list[str]:
    script = Path(sys.executable).with_name("hrp2-console")
    if script.exists():
        return [str(script)]
    found = shutil.which("hrp2-console")
    return [found] if found else [sys.executable, "-m", "app.cli"]


def run(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    return subprocess.run([*console(), *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT)


def test_a_headless_timed_run_exits_zero_and_prints_the_summary():
    r = run("--headless", "--duration", "5", "--speed", "max", "--port", "0")
    # no fault, no fall: exit status 0 is the run's own counters' verdict (1 when they hold either); the
    # lines below check the summary printed from the same counters
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout
    assert "summary:" in out
    assert "fallen: false" in out
    assert "faults: none" in out
    sim_line = next(line for line in out.splitlines() if "sim time:" in line)
    assert float(sim_line.split(":")[1].split()[0]) >= 5.0
    for key in ("ticks:", "real-time factor:", "max loop ms:"):
        assert key in out


def test_the_help_states_the_sessions_retention_rule():
    from app.cli import run_parser

    text = " ".join(run_parser().format_help().split())
    assert "at most 20 session files and 4096 MB together" in text and "never the one being recorded" in text
    assert "--sessions-keep N" in text and "--sessions-max-mb MB" in text


def test_bench_prints_json_with_every_chain_layer_timed():
    r = run("bench", "--duration", "1")
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads(r.stdout)
    assert report["scenario"] == "stand"
    assert report["sim_time_s"] == pytest.approx(1.0)
    assert report["real_time_factor"] > 0
    for key in ("tick_ms", "physics_ms"):
        assert report[key]["p99_ms"] >= report[key]["p50_ms"] > 0
    layers = report["chain"].split(" -> ")
    assert list(report["layers"]) == layers and "seq" in layers
    for name in layers:
        assert set(report["layers"][name]) == {"p50_ms", "p99_ms"}


def test_an_unknown_speed_fails_naming_the_option_and_what_is_allowed():
    r = run("--speed", "fast")
    assert r.returncode == 2
    assert "--speed" in r.stderr and "max" in r.stderr


def test_an_unknown_bench_scenario_lists_the_valid_ones():
    r = run("bench", "--scenario", "moonwalk")
    assert r.returncode == 2
    assert "--scenario" in r.stderr and "stand" in r.stderr and "arms" in r.stderr and "walk" in r.stderr


def test_bench_walk_scenario_reports_the_walking_part():
    r = run("bench", "--scenario", "walk", "--duration", "2", timeout=120.0)
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads(r.stdout)
    assert report["scenario"] == "walk"
    assert report["sim_time_s"] == pytest.approx(2.0)  # the warm-up is not timed
    assert report["real_time_factor"] > 0
    assert set(report) == {"scenario", "scene", "chain", "ticks", "sim_time_s", "wall_time_s", "real_time_factor",
                           "tick_ms", "physics_ms", "layers", "fallen", "fault", "read_to_write_ms", "after_write_ms",
                           "after_write_layers"}
    assert report["fallen"] is False and report["fault"] is None
    assert list(report["layers"]) == report["chain"].split(" -> ")


def test_bench_foundation_chain_reports_its_layers_and_the_loop_overhead():
    r = run("bench", "--chain", "foundation", "--duration", "1")
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads(r.stdout)
    assert report["chain"] == "kf -> rmfo -> seq -> co -> hes -> el"
    assert list(report["layers"]) == report["chain"].split(" -> ")
    assert list(report["passthrough"]) == ["op", "es", "ic", "abc", "st"]  # disabled: their input passes through
    assert report["disabled_but_ran"] == []
    for key in ("tick_ms", "physics_ms", "step_ms", "layers_sum_ms", "loop_overhead_ms"):
        assert set(report[key]) == {"p50_ms", "p99_ms"}
        assert report[key]["p99_ms"] >= report[key]["p50_ms"]
    assert report["step_ms"]["p50_ms"] > 0 and report["real_time_factor"] > 0
    assert report["fallen"] is False and report["fault"] is None


def test_bench_layers_option_takes_a_list_and_rejects_unknown_names():
    r = run("bench", "--layers", "kf,rmfo,seq", "--duration", "0.2")
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads(r.stdout)
    # the HardEmergencyStopper works disabled too: it ran, and is labelled so
    assert report["chain"] == "kf -> rmfo -> seq -> hes" and report["disabled_but_ran"] == ["hes"]
    assert list(report["passthrough"]) == ["op", "es", "ic", "abc", "st", "co", "el"]
    r = run("bench", "--layers", "kf,warp")
    assert r.returncode == 2
    assert "--layers" in r.stderr and "warp" in r.stderr and "rmfo" in r.stderr


def test_bench_scenario_needing_a_left_out_layer_fails_naming_it():
    r = run("bench", "--scenario", "walk", "--chain", "foundation")
    assert r.returncode == 2
    assert "abc" in r.stderr


def test_the_console_starts_with_a_parameter_file_and_refuses_a_bad_one(tmp_path):
    good, bad, broken = tmp_path / "good.json", tmp_path / "bad.json", tmp_path / "broken.json"
    good.write_text(json.dumps({"st": {"cp_threshold_m": 0.05}}))
    bad.write_text(json.dumps({"st": {"k1": "a"}}))
    broken.write_text("{not json")
    r = run("--headless", "--duration", "0.2", "--speed", "max", "--port", "0", "--params", str(good))
    assert r.returncode == 0, r.stdout + r.stderr
    r = run("--headless", "--duration", "0.2", "--speed", "max", "--port", "0", "--params", str(bad))
    assert r.returncode == 2 and "st.k1: must be a number" in r.stderr
    r = run("--headless", "--params", str(broken))
    assert r.returncode == 2 and "--params" in r.stderr and "is not JSON" in r.stderr


def test_an_operator_session_over_http_on_the_real_console_replays_identical(tmp_path):
    """`hrp2-console --record` (the robot in its own process, paced at real time): goVelocity, a hand streamed as
    the page streams it, an e-stop and its release, all over HTTP; then `hrp2-console replay` finds every tick
    identical at --speed max."""
    import time

    from app.lab.console_process import Console

    path = tmp_path / "http-session.mcap"
    with Console("--speed", "1.0", "--record", str(path)) as c:
        conn = c.connection()
        deadline = time.monotonic() + 60.0
        while c.request("GET", "/api/state", conn=conn)[1]["time"] < 2.2:  # the AutoBalancer has blended in
            assert time.monotonic() < deadline
            time.sleep(0.05)
        walk = {"vx": 0.1, "vy": 0.0, "vtheta_deg": 0.0}
        assert c.request("POST", "/api/walk/go-velocity", walk, conn=conn)[0] == 200
        for _ in range(40):  # 0.8 s of a stick at 50 Hz
            status, _ = c.request("PUT", "/api/operator/velocity", {"point": "rhand", "linear": [0, 0, 0.03],
                                                                    "angular": [0, 0, 0]}, conn=conn)
            assert status == 200
            time.sleep(0.02)
        assert c.request("POST", "/api/estop", conn=conn)[0] == 200
        time.sleep(0.3)
        assert c.request("POST", "/api/estop/release", {}, conn=conn)[0] == 200
        time.sleep(0.5)
        code, out = c.stop()
    assert code == 0 and f"session: {path}" in out, out
    r = run("replay", str(path), timeout=120.0)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "identical:" in r.stdout
    report = json.loads(r.stdout[r.stdout.index("{"):r.stdout.rindex("}") + 1])
    assert report["identical"] and report["inputs"] >= 40 and report["ticks"] > 700


def test_replay_refuses_a_file_that_is_not_a_session(tmp_path):
    bogus = tmp_path / "x.mcap"
    bogus.write_bytes(b"not an mcap file")
    r = run("replay", str(bogus))
    assert r.returncode == 2 and "not a session" in r.stderr


def test_record_refuses_to_overwrite_a_session(tmp_path):
    existing = tmp_path / "s.mcap"
    existing.write_bytes(b"")
    r = run("--headless", "--record", str(existing))
    assert r.returncode == 2 and "--record" in r.stderr and "never overwritten" in r.stderr
