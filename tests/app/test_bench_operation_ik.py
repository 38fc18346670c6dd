"""The operation IK's benchmark (python -m app.lab.bench_operation_ik): every scenario solves and is timed."""

from app.lab.bench_operation_ik import benchmark, main


def test_every_scenario_solves_and_reports_its_times_and_placos():
    report = benchmark(ticks=3, warmup=2)
    assert set(report) == {"idle", "hands+head", "walking", "fullbody_ik (AutoBalancer, closed form)"}
    for name in ("hands+head", "walking"):
        assert report[name]["ok"] is True
        assert 0.0 < report[name]["median_ms"] <= report[name]["max_ms"]
        assert set(report[name]["placo_solve"]) == {"median_ms", "p99_ms", "max_ms"}
    assert "placo_solve" not in report["idle"]  # an idle tick does not solve


def test_the_command_prints_one_line_per_scenario(capsys):
    main(["--ticks", "2"])
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 4 and all("median" in line for line in lines)
