"""The README's Python example of a forming run runs as it is written."""

from __future__ import annotations

import re
import runpy
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_forming_example_of_the_readme_runs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Its increments report number, phase and travel; it ends at the punch travel and
    writes the last frame for ParaView."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## A forming run from Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    (tmp_path / "examples").symlink_to(ROOT / "examples")  # its paths are the repository's
    (tmp_path / "example.py").write_text(code)
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(tmp_path / "example.py"), run_name="__main__")
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("increment 1 of bend: ")
    assert lines[-2].endswith(": 4.00 mm")
    assert (tmp_path / "bent.vtu").stat().st_size > 0
