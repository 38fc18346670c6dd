"""The e-stop parameter study (`hrp2-console study estop`): the [MLC] IV-C experiments over (threshold, T1, T2)
and disturbance sets, on a local process pool or a Ray cluster, resumable, with a held-out validation.

space.py (what is varied), spec.py (one run and its key), run.py (one run in a worker), pool.py and
ray_backend.py (where runs go), store.py (finished runs), progress.py (the bar), wilson.py (confidence),
analysis.py (per parameter set, the recommendation), heatmap.py (figures), study.py (the phases), report.py
(tables), cli.py (the command)."""
