"""Invariant 5's memory bound: a process tree's resident memory from /proc, and the growth checked per console."""

import os

from app.lab.campaign.memory import growth_violations, tree_rss_mb


def fake_proc(root, tree: dict[int, tuple[int, list[int]]]):
    """/proc with `pid: (VmRSS [kB], children)`."""
    for pid, (rss_kb, kids) in tree.items():
        task = root / str(pid) / "task" / str(pid)
        task.mkdir(parents=True)
        (root / str(pid) / "status").write_text(f"Name:\tx\nVmRSS:\t  {rss_kb} kB\nThreads:\t1\n")
        (task / "children").write_text(" ".join(map(str, kids)))
    return root


def test_the_tree_sums_a_process_and_all_its_descendants(tmp_path):
    proc = fake_proc(tmp_path, {10: (1024, [11, 12]), 11: (2048, [13]), 12: (512, []), 13: (1024, []),
                                99: (999999, [])})
    assert tree_rss_mb(10, proc) == (1024 + 2048 + 512 + 1024) / 1024
    assert tree_rss_mb(11, proc) == 3.0
    assert tree_rss_mb(12345, proc) is None


def test_this_process_has_a_resident_memory():
    assert tree_rss_mb(os.getpid()) > 10.0


def session(seed, worker, order, rss_mb):
    return {"seed": seed, "worker": worker, "order": order, "rss_mb": rss_mb}


def test_growth_beyond_the_bound_is_one_violation_per_console_on_its_last_session():
    results = [session(1, 0, 0, 800.0), session(2, 1, 1, 700.0), session(3, 0, 2, 900.0), session(4, 1, 3, 1000.0),
               session(5, 0, 4, 949.0)]
    found = growth_violations(results, bound_mb=150.0)
    assert [(v["seed"], v["invariant"]) for v in found] == [(4, 5)]  # console 1: +300 MB; console 0: +149 MB
    assert "300 MB" in found[0]["detail"]
    assert growth_violations([session(1, 0, 0, 800.0)], bound_mb=0.0) == []  # one session: nothing to compare
