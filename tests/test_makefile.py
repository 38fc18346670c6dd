"""`make test` keeps the browser tests' screenshots: it points HRP2_ARTIFACTS at a folder inside the tree that
git ignores (a CI run keeps it as its artifacts; nothing of it is committed)."""

import re
import shutil
import subprocess
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
