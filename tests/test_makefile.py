"""`make test` keeps the browser tests' screenshots: it points HRP2_ARTIFACTS at a folder inside the tree that
git ignores (a CI run keeps it as its artifacts; nothing of it is committed). `make test-py313` runs the unit
tests and a walk on Python 3.13 in a git-ignored environment of its own, and `.ci/run` runs it after `make test`,
failing at once, naming python3.13, on a machine without it."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_make_test_sends_the_screenshots_to_a_git_ignored_folder_in_the_tree():
    if shutil.which("make") is None:
        pytest.skip("no make")
    dry = subprocess.run(["make", "-n", "test"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    line = next(ln for ln in dry.splitlines() if "-m pytest" in ln)
    folder = Path(re.search(r"HRP2_ARTIFACTS=(\S+)", line).group(1))
    assert folder.is_absolute() and folder.is_relative_to(ROOT), folder
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: cannot ask git what it ignores")
    probe = (folder / "page.png").relative_to(ROOT)
    ignored = subprocess.run(["git", "check-ignore", "-q", str(probe)], cwd=ROOT)
    assert ignored.returncode == 0, f"{probe} is not git-ignored"


def dry_run(target: str) -> list[str]:
    if shutil.which("make") is None:
        pytest.skip("no make")
    # -B: the whole recipe, also where the environment is already installed
    return subprocess.run(["make", "-n", "-B", target], cwd=ROOT, capture_output=True, text=True, check=True
                          ).stdout.splitlines()


def test_make_test_py313_builds_its_own_environment_on_python_3_13():
    lines = dry_run("test-py313")
    assert any(ln.startswith("python3.13 -m venv .venv313") for ln in lines), lines
    assert any("sys.version_info[:2] != (3, 13)" in ln for ln in lines), "the interpreter's version is not checked"
    if shutil.which("git") is not None and (ROOT / ".git").exists():
        assert subprocess.run(["git", "check-ignore", "-q", ".venv313/bin/python"], cwd=ROOT).returncode == 0


def test_make_test_py313_runs_the_unit_tests_and_one_walk_and_fails_on_no_tests():
    lines = dry_run("test-py313")
    i = next(i for i, ln in enumerate(lines) if "-m pytest" in ln)
    words = shlex.split(lines[i].split(";")[0])
    assert words[:2] == ["MUJOCO_GL=egl", ".venv313/bin/python"]
    targets = [w for w in words[words.index("pytest") + 1:] if w.startswith("tests/")]
    assert {"tests/controller", "tests/robot", "tests/behaviors", "tests/test_architecture.py"} <= set(targets)
    walks = [t for t in targets if t.startswith("tests/scenarios/test_walking")]
    assert len(walks) == 1, targets
    path, test = walks[0].split("::")
    assert f"def {test.split('[')[0]}(" in (ROOT / path).read_text(), f"{walks[0]} names no test"
    assert "$rc -eq 5" in lines[i + 1] and "exit 1" in lines[i + 1], "pytest's 'no tests' (5) must fail"


def fake_ci(tmp_path: Path, with_python313: bool) -> subprocess.CompletedProcess:
    """.ci/run in a copy of its folder, with a PATH of only the tools it uses: a `make` that records its
    arguments, and (or not) a `python3.13` that answers as a Python 3.13 would."""
    for tool in ("bash", "dirname", "rm", "grep", "sort", "tail"):
        if shutil.which(tool) is None:
            pytest.skip(f"no {tool}")
    (tmp_path / ".ci").mkdir()
    shutil.copy(ROOT / ".ci" / "run", tmp_path / ".ci" / "run")
    bin_ = tmp_path / "bin"
    bin_.mkdir()
    for tool in ("bash", "dirname", "rm", "grep", "sort", "tail"):
        (bin_ / tool).symlink_to(shutil.which(tool))
    scripts = {"make": f'echo "$*" >> {tmp_path}/make.calls'}
    if with_python313:
        scripts["python3.13"] = "exit 0"
    for name, body in scripts.items():
        (bin_ / name).write_text(f"#!{shutil.which('bash')}\n{body}\n")
        (bin_ / name).chmod(0o755)
    return subprocess.run([str(bin_ / "bash"), str(tmp_path / ".ci" / "run")], capture_output=True, text=True,
                          env={"PATH": str(bin_), "HOME": str(tmp_path)})


def test_ci_runs_the_suite_on_3_11_then_the_unit_tests_on_3_13(tmp_path):
    done = fake_ci(tmp_path, with_python313=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "make.calls").read_text().splitlines() == ["test ARGS=--durations=40",
                                                                  "test-py313 PYTHON313=python3.13"]


def test_ci_without_python_3_13_fails_at_once_naming_it(tmp_path):
    done = fake_ci(tmp_path, with_python313=False)
    assert done.returncode != 0
    assert "python3.13 not found" in done.stderr
    assert not (tmp_path / "make.calls").exists(), "the suite ran before the missing interpreter was reported"


def collected(which: str, paths: list[str]) -> set[str]:
    env = {**os.environ, "HRP2_TEST_PASS": which}
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", *paths],
                         cwd=ROOT, capture_output=True, text=True, env=env)
    assert out.returncode in (0, 5), out.stdout + out.stderr
    return {ln.split("::")[0] for ln in out.stdout.splitlines() if "::" in ln}


def test_make_test_runs_two_passes_that_share_out_the_suite():
    """The in-process tests on two workers; a console's, a browser's or a worker pool's one at a time."""
    lines = " ".join(dry_run("test"))
    assert "HRP2_TEST_PASS=parallel" in lines and "-n 2" in lines and "HRP2_TEST_PASS=serial" in lines, lines
    paths = ["tests/scenarios/test_walking.py", "tests/scenarios/test_expo_trials.py", "tests/app/test_board.py",
             "tests/controller/core/test_chain_and_loop.py", "tests/app/test_cli.py"]
    parallel, serial = collected("parallel", paths), collected("serial", paths)
    assert parallel == {"tests/scenarios/test_walking.py", "tests/controller/core/test_chain_and_loop.py",
                        "tests/app/test_board.py"}, parallel
    assert serial == {"tests/scenarios/test_expo_trials.py", "tests/app/test_cli.py"}, serial
    # schemathesis's items share one node id, which xdist cannot tell apart: serial, even when marked in_process
    fuzz = "tests/app/test_operator_fuzz.py"
    assert not collected("parallel", [fuzz]) and collected("serial", [fuzz]) == {fuzz}
    bad = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", paths[4]], cwd=ROOT,
                         capture_output=True, text=True, env={**os.environ, "HRP2_TEST_PASS": "both"})
    assert bad.returncode != 0 and "HRP2_TEST_PASS='both'" in bad.stdout + bad.stderr
