"""``ddpy check CASE``: a summary and exit code 0, or every error as file:line and exit code 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from deckutil import EXAMPLES, copy_example, edit


def check(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ddpy", "check", *args], capture_output=True,
                          text=True)


def test_check_valid_case() -> None:
    result = check(str(EXAMPLES / "bending"))
    assert result.returncode == 0, result.stderr
    assert "216 hexahedra" in result.stdout and "tool punch: nagata" in result.stdout
    assert result.stdout.rstrip().endswith(": ok")


def test_check_errors(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "tools.dat", "friction     0.148", "friction -0.1")
    edit(case, "bc.dat", "fix        centre  z  phase springback", "fix centre")
    result = check(str(case), "--no-geometry")
    assert result.returncode == 2 and result.stdout == ""
    lines = result.stderr.splitlines()
    assert lines[0].startswith(f"{case / 'bc.dat'}:") and "expected 'fix NODESET" in lines[0]
    assert lines[1] == f"{case / 'tools.dat'}:7: friction must be >= 0, got -0.1"
    assert lines[2] == f"{case}: 2 errors"
    assert "not a case folder" in check(str(tmp_path / "none")).stderr
