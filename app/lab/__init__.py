"""The lab, on top of the rest: the benchmarks (bench*.py), the experiments, the e-stop and push studies, the
campaign, the tuning plots, the replay's view and a real console in a subprocess for the benches and tests."""
