"""The benchmarks' shared module: the code version a run records, the tolerance it ran at."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_common import TOLERANCE_CHANGE, code_version, force_tolerance  # noqa: E402


def _git(folder: Path, *args: str) -> str:
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args],
                          cwd=folder, capture_output=True, text=True, check=True).stdout.strip()


def test_the_code_version_is_the_last_commit_that_changed_the_code(tmp_path: Path) -> None:
    # A report's commit leaves the version its runs recorded; a change to the code makes it
    # "-dirty" until committed, then the new commit's.
    _git(tmp_path, "init", "-q")
    (tmp_path / "ddpy").mkdir()
    (tmp_path / "docs").mkdir()
    (tmp_path / "ddpy" / "a.py").write_text("x = 1\n")
    _git(tmp_path, "add", "-A")
    _git(tmp_path, "commit", "-qm", "code")
    code = _git(tmp_path, "rev-parse", "--short", "HEAD")
    assert code_version(tmp_path) == code
    (tmp_path / "docs" / "report.md").write_text("numbers\n")
    (tmp_path / "benchmarks" / "bend").mkdir(parents=True)
    (tmp_path / "benchmarks" / "bend" / "run.py").write_text("report = 1\n")
    _git(tmp_path, "add", "-A")
    _git(tmp_path, "commit", "-qm", "report")
    assert code_version(tmp_path) == code
    (tmp_path / "benchmarks" / "bend" / "make_case.py").write_text("deck = 1\n")
    _git(tmp_path, "add", "-A")
    _git(tmp_path, "commit", "-qm", "cases")
    code = _git(tmp_path, "rev-parse", "--short", "HEAD")
    assert code_version(tmp_path) == code
    (tmp_path / "ddpy" / "a.py").write_text("x = 2\n")
    assert code_version(tmp_path) == code + "-dirty"
    _git(tmp_path, "commit", "-qam", "code again")
    assert code_version(tmp_path) == _git(tmp_path, "rev-parse", "--short", "HEAD") != code
    assert code_version(tmp_path / "nowhere") == ""


def _default_tolerance(revision: str) -> float:
    """NewtonSettings' default force tolerance in ddpy/model/control.py at ``revision``."""
    text = subprocess.run(["git", "show", f"{revision}:ddpy/model/control.py"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout
    return float(re.search(r"force_tolerance: float = (\S+)", text)[1])


def test_a_run_without_a_recorded_tolerance_ran_at_its_codes_default() -> None:
    # The change the helper names is the commit that changed NewtonSettings' default, read
    # from the source on either side of it; runs before it take the old value.
    commit, before, after = TOLERANCE_CHANGE
    if subprocess.run(["git", "cat-file", "-e", f"{commit}^"], cwd=ROOT).returncode != 0:
        pytest.skip("not a checkout with the history")
    assert _default_tolerance(f"{commit}^") == before
    assert _default_tolerance(commit) == after
    assert force_tolerance(None, f"{commit}^") == before
    assert force_tolerance(None, commit) == after
    assert force_tolerance(None, "HEAD") == after
    assert force_tolerance(None, f"{commit}^, continued at {commit}") == before
    assert force_tolerance(None, "not-a-revision") is None
    # What the results file records wins: the loosest of the phases.
    assert force_tolerance([1e-3, 5e-4, 2e-3], f"{commit}^") == 2e-3
