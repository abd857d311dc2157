"""The ``ddpy`` command and the arc accuracy study it runs (paper Fig. 3 and 4)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import ddpy
from ddpy.studies.accuracy import arc_errors


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ddpy", *args], capture_output=True,
                          text=True, check=True)


def test_version_and_help() -> None:
    assert run("--version").stdout.strip() == f"ddpy {ddpy.__version__}"
    help_text = run("--help").stdout
    assert "accuracy" in help_text and "usage: ddpy" in help_text


def test_accuracy_json_matches_analytic_and_paper() -> None:
    s = json.loads(run("accuracy", "--json").stdout)
    linear, nagata = s["arc30"]["linear"], s["arc30"]["nagata"]
    # The chord of a 30 degree arc: sagitta 1 - cos 15 deg, normal error half the angle.
    assert linear["radial_pct"] == pytest.approx(100 * (1 - np.cos(np.radians(15))), rel=1e-5)
    assert linear["normal_deg"] == pytest.approx(15.0, abs=1e-9)
    # Paper: 0.06 % and about 0.2 degrees for the Nagata curve.
    assert nagata["radial_pct"] == pytest.approx(0.060, abs=0.002)
    assert nagata["normal_deg"] == pytest.approx(0.20, abs=0.01)
    expected = {"linear": (2.0, 1.0), "nagata": (4.0, 3.0)}
    for name, (radial, normal) in expected.items():
        assert s["orders"][name]["radial"] == pytest.approx(radial, abs=0.1)
        assert s["orders"][name]["normal"] == pytest.approx(normal, abs=0.1)


def test_nagata_arc_error_signs() -> None:
    _, radial_linear, normal_linear = arc_errors(30.0, 1, smooth=False)
    _, radial_nagata, normal_nagata = arc_errors(30.0, 1, smooth=True)
    assert radial_linear.min() < 0 <= radial_linear.max() + 1e-12  # chord inside the circle
    assert radial_nagata.max() > 0 and abs(radial_nagata.min()) < 1e-9  # Nagata bulges out
    assert normal_nagata[0] < 1e-9 and normal_nagata[-1] < 1e-9  # exact normals at the nodes
    assert normal_linear[0] == pytest.approx(15.0)


def test_bad_arguments() -> None:
    with pytest.raises(ValueError):
        arc_errors(30.0, 0, smooth=True)
    result = subprocess.run([sys.executable, "-m", "ddpy", "nosuchcommand"],
                            capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice" in result.stderr


def test_compare_usage_errors_exit_2(tmp_path) -> None:
    """Labels that do not match the runs are a usage error, refused before any run is read
    (the runs here do not exist); so is a missing RUN, argparse's own."""
    labels = subprocess.run([sys.executable, "-m", "ddpy", "compare", str(tmp_path / "a"),
                             str(tmp_path / "b"), "--labels", "one", "--output",
                             str(tmp_path / "out")], capture_output=True, text=True)
    assert labels.returncode == 2
    assert "--labels gives 1 labels for 2 runs: expected one per RUN" in labels.stderr
    assert not (tmp_path / "out").exists()
    bare = subprocess.run([sys.executable, "-m", "ddpy", "compare"], capture_output=True,
                          text=True)
    assert bare.returncode == 2 and "RUN" in bare.stderr
