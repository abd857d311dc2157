"""The reverse deep drawing's tool models against the paper's Table 5.

benchmarks/reverse_deep_drawing/make_case.py meshes the five tools by the paper's rule as far
as its text and counts give it (make_case.PER_ARC, AROUND, STRAIGHT, SPLIT_FACES). The
patches of every tool and model must lie within 25 % of the paper's count, except those the
report explains (make_case.TABLE5_NOT_MET), which must really miss it: an explanation that
no longer applies fails too.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

from ddpy.io.toolfile import read_tool

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks" / "reverse_deep_drawing"
sys.path.insert(0, str(BENCH.parent))  # the benchmarks' shared module
from bench_common import load_module  # noqa: E402

#: Table 5's tolerance (issue 47): within 25 % of the paper's count.
TOLERANCE = 0.25


@pytest.fixture(scope="module")
def make_case() -> Any:
    return load_module(BENCH / "make_case.py", "drawing_make_case")


@pytest.fixture(scope="module")
def counts(make_case: Any, tmp_path_factory: pytest.TempPathFactory
           ) -> dict[str, dict[str, int]]:
    """Patches of each tool model as make_case.py writes them."""
    paths = make_case.build_tools(tmp_path_factory.mktemp("tools"))
    return {tool: {model: len(read_tool(path).face_tags) for model, path in models.items()}
            for tool, models in paths.items()}


def _deviation(count: int, paper: int) -> float:
    return abs(count / paper - 1.0)


def test_patch_counts_within_25_percent_of_table5(make_case: Any,
                                                  counts: dict[str, dict[str, int]]) -> None:
    paper = make_case.TABLE5_PATCHES
    missed = {(tool, model): (counts[tool][model], paper[tool][model])
              for tool in make_case.TOOLS for model in make_case.MODELS
              if (tool, model) not in make_case.TABLE5_NOT_MET
              and _deviation(counts[tool][model], paper[tool][model]) > TOLERANCE + 1e-12}
    assert not missed, f"(ddpy, paper) patches more than 25 % apart: {missed}"


def test_the_explained_misses_do_miss(make_case: Any,
                                      counts: dict[str, dict[str, int]]) -> None:
    paper = make_case.TABLE5_PATCHES
    for (tool, model), reason in make_case.TABLE5_NOT_MET.items():
        assert reason, (tool, model)
        assert _deviation(counts[tool][model], paper[tool][model]) > TOLERANCE, (
            f"{tool} {model}: {counts[tool][model]} patches against the paper's "
            f"{paper[tool][model]} is within 25 %: drop it from TABLE5_NOT_MET")


def test_the_report_uses_the_same_table(make_case: Any) -> None:
    run = load_module(BENCH / "run.py", "drawing_run")
    assert run.PAPER["table5_patches"] == make_case.TABLE5_PATCHES
