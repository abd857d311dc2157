"""The benchmarks' shared module: the code version a run records."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_common import code_version  # noqa: E402


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
