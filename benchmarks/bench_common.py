"""What the benchmark scripts share: loading a sibling script as a module, the code version
a run records (read back, and kept when a run is continued), the cores, the kept-runs file,
a markdown table row, and the tools' CAD model written, read back and built into the paper's
tool models.

A script puts this folder on ``sys.path`` and imports it; tests do the same to load a
benchmark's scripts (``load_module``)."""

from __future__ import annotations

import datetime
import importlib.util
import json
import os
import platform
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "benchmarks"
#: Written next to a run's results by a benchmark's run_case_folder: its code version and
#: date, the dates it was continued on (and why a run was stopped).
CODE_FILE = "code.json"
#: What makes a run's numbers: a change elsewhere (the reports in docs/) leaves them.
#: What makes a run's numbers: the package, the core, the build, and the scripts that write
#: the benchmarks' cases and tools (git pathspecs). The report scripts (run.py) only read the
#: results back, so a change to a report leaves the code its runs recorded.
CODE_PATHS = ("ddpy", "fortran", "meson.build", "pyproject.toml", "benchmarks/bench_common.py",
              "benchmarks/*/make_case.py")


def load_module(path: Path, name: str) -> ModuleType:
    """The script at ``path`` as a module named ``name`` (unique: two benchmarks both have a
    make_case.py), registered in sys.modules, where dataclasses look their module up."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def code_version(checkout: Path = ROOT) -> str:
    """The ``git describe --always`` of the last commit that changed the code (CODE_PATHS)
    in the checkout (this repository's, or another checkout's), with "-dirty" when the code
    differs from HEAD; empty outside a git checkout. Commits that change only the reports
    leave it, so runs made on either side of them count as the same code."""
    try:
        last = subprocess.run(["git", "log", "-1", "--format=%H", "HEAD", "--", *CODE_PATHS],
                              cwd=checkout, capture_output=True, text=True,
                              check=True).stdout.strip() or "HEAD"
        described = subprocess.run(["git", "describe", "--always", last], cwd=checkout,
                                   capture_output=True, text=True, check=True).stdout.strip()
        changed = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", *CODE_PATHS],
                                 cwd=checkout).returncode != 0
    except (OSError, subprocess.CalledProcessError):
        return ""
    return described + ("-dirty" if changed else "")


def computed_at(code: str, runs: dict[str, str] | None = None) -> str:
    """The line near the top of a report that names the code it was computed at: ``code``
    (code_version() of the run that wrote it), and, for a report built from kept runs, the
    code each run recorded (``runs``: label -> its code, "" where none was recorded)."""
    line = f"Computed at code `{code or 'unknown'}`"
    if not runs:
        return line + "."
    stamps = {label: stamp or "not recorded" for label, stamp in runs.items()}
    if set(stamps.values()) == {code}:
        return line + " (this report and every run in it)."
    by_code: dict[str, list[str]] = {}
    for label, stamp in stamps.items():
        by_code.setdefault(stamp, []).append(label)
    return (line + " (this report); its runs: " + "; ".join(
        f"at code `{stamp}` ({', '.join(labels)})" if stamp != "not recorded" else
        f"code not recorded ({', '.join(labels)})" for stamp, labels in by_code.items()) + ".")


#: The commit that changed ddpy's default Newton tolerances (``newton_force`` and
#: ``newton_displacement``) from the first value to the second.
TOLERANCE_CHANGE = ("2bf9974", 1e-4, 1e-3)


def force_tolerance(recorded: Any, code: str) -> float | None:
    """The Newton tolerance on the force a run converged to: the loosest of its phases'
    as its results file records them (``recorded``, the ``newton_force`` attribute), else
    ddpy's default at the run's ``code`` (for a deck without the line, run before results
    files recorded it); None when git cannot place ``code``."""
    if recorded is not None:
        return float(max(recorded))
    commit, before, after = TOLERANCE_CHANGE
    revision = code.split(",")[0].removesuffix("-dirty")
    try:
        placed = subprocess.run(["git", "merge-base", "--is-ancestor", commit, revision],
                                cwd=ROOT, capture_output=True).returncode
    except OSError:
        return None
    return {0: after, 1: before}.get(placed)


def cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
        os.cpu_count() or 1


def cpu_model() -> str:
    """The processor's model name (Linux's /proc/cpuinfo), for reports that compare times."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or "unknown"
    found = re.search(r"model name\s*:\s*(.+)", text)
    return found[1].strip() if found else "unknown"


def recorded_code(folder: Path) -> dict[str, Any]:
    """What CODE_FILE in a run's results folder records; {} when it has none."""
    try:
        return json.loads((folder / CODE_FILE).read_text())
    except (OSError, ValueError):
        return {}


def record_code(output: Path, code: str, restart: bool, **settings: Any) -> dict[str, Any]:
    """Write the code version and date of the run in ``output`` next to its results, with
    the deck ``settings`` the report states. A run continued from its checkpoint
    (``restart``) keeps the date it started and adds today's to "continued"; with other
    code its code reads "<first>, continued at <code>"."""
    output.mkdir(parents=True, exist_ok=True)
    earlier = recorded_code(output) if restart else {}
    if earlier.get("code"):
        code = earlier["code"] if earlier["code"].endswith(code) else \
            f"{earlier['code']}, continued at {code}"
    today = datetime.date.today().isoformat()
    record = {"code": code, "date": earlier.get("date", today), **settings}
    if restart:
        record["continued"] = [*earlier.get("continued", []), today]
    (output / CODE_FILE).write_text(json.dumps(record))
    return record


def restart_plan(results: dict[str, Path]) -> dict[str, str]:
    """What ``--restart`` does with each model's saved results file: "read" a completed run
    back, "continue" one from its checkpoint, "run" a model with nothing saved. Refuses,
    before any run starts, a saved run that did not complete and has no checkpoint."""
    from ddpy.app.runner import CHECKPOINT, read_status

    plan = {}
    for model, path in results.items():
        if not path.exists():
            plan[model] = "run"
        elif read_status(path.parent).get("status") == "completed":
            plan[model] = "read"
        elif (path.parent / CHECKPOINT).is_file():
            plan[model] = "continue"
        else:
            sys.exit(f"{path.parent}: the saved run of {model} did not complete and has no "
                     f"checkpoint to continue from; run it again without --restart")
    return plan


def runs_file(stem: str) -> Path:
    """The kept runs of a report: docs/benchmarks/<stem>_runs.json."""
    return DOCS / f"{stem}_runs.json"


def deepest_per_tool(history: dict[str, Any], rows: Any, tools: list[str]
                     ) -> dict[str, float] | None:
    """The deepest slave node in each tool over the increments ``rows`` of a results
    file's history (its ``penetration`` column, mm); None where the file has no such
    column."""
    import numpy as np

    if "penetration" not in history:
        return None
    depth = history["penetration"][rows]
    depth = np.where(np.isfinite(depth), depth, 0.0).max(axis=0, initial=0.0)
    return {tool: float(f"{depth[i]:.4g}") for i, tool in enumerate(tools)}


def table_row(cells: list[Any]) -> str:
    """A markdown table row."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


#: Tool file of each tool model of the paper, and the description the deck gives it.
TOOL_FILES = {"bezier": ("bezier", "bezier"), "nagata": ("nagata", "nagata"),
              "facets_coarse": ("facets_coarse", "facets"),
              "facets_fine": ("facets_fine", "facets")}


def written_tool_faces(step: Path, make: Callable[[Path], dict[str, list[int]]]
                       ) -> dict[str, list[int]]:
    """Write a CAD model of tools with ``make(step)`` (which adds them to the current gmsh
    model and returns their face tags by tool) and read it back as ``ddpy tools build``
    does (``load_cad``): the face tags of each tool in the file read back, matched to
    those made by the point at the middle of each face. Runs in its own gmsh session."""
    import math

    import gmsh

    from ddpy.cad import gmsh_session, load_cad

    with gmsh_session():
        gmsh.clear()
        made = make(step)
        marks = {t: _inner_point(t) for faces in made.values() for t in faces}
        gmsh.clear()
        loaded = load_cad(step)
        back = {f: _inner_point(f) for f in loaded}
        found = {t: min(loaded, key=lambda f: math.dist(back[f], x)) for t, x in marks.items()}
        if sorted(found.values()) != sorted(loaded) or any(
                math.dist(back[found[t]], x) > 1e-6 for t, x in marks.items()):
            raise RuntimeError(f"{step}: the faces read back differ from those written")
        gmsh.clear()
    return {tool: [found[t] for t in faces] for tool, faces in made.items()}


def _inner_point(face: int) -> list[float]:
    """A point of a gmsh face, at the middle of its parameter range."""
    import gmsh

    lo, hi = gmsh.model.getParametrizationBounds(2, face)
    return list(gmsh.model.getValue(2, face, [0.5 * (a + b) for a, b in zip(lo, hi, strict=True)]))


def build_tool_model(step: Path, folder: Path, tool: str, model: str, faces: list[int],
                     blank_side: tuple[float, float, float], per_arc: int = 0,
                     size: float | None = None, arc_size: float | None = None) -> Path:
    """Write ``<tool>.<model>.tool`` in ``folder`` from the faces of ``step``: ``model`` one
    of TOOL_FILES (Bezier patches, or a mesh of ``per_arc`` patches or facets per 90 degrees
    of arc, straight edges at most ``size`` and arcs ``arc_size`` mm long)."""
    from ddpy.cad import build_tool_models

    if model == "bezier":
        return build_tool_models(step, folder, tool, models=("bezier",),
                                 blank_side=blank_side, faces=faces)["bezier"]
    kind = "nagata" if model == "nagata" else "facets"
    written = build_tool_models(step, folder, tool, patches_per_arc=per_arc,
                                facets_per_arc=per_arc, size=size, arc_size=arc_size,
                                blank_side=blank_side, faces=faces, models=(kind,))
    target = folder / f"{tool}.{model}.tool"
    written[kind].replace(target)
    return target
