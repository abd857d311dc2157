"""ddpy against CalculiX on the same deck: the quarter Numisheet 2002 BM-B bending blank of
60 x 6 x 2 elements (issue #53, item 5). Writes docs/benchmarks/calculix_same_deck.md (+ .png)
and keeps its runs in docs/benchmarks/calculix_same_deck_runs.json.

    python benchmarks/calculix_same_deck/run.py            # the runs, then the report
    python benchmarks/calculix_same_deck/run.py --reuse    # the report from the kept runs

deck.py writes the cases and the CalculiX decks into work/ (git-ignored). CalculiX (``ccx``,
Debian's calculix-ccx) runs its decks (the coarse facets, then the fine facets) one after the
other as child processes while ddpy runs its Nagata, coarse facet and fine facet cases one
after the other, each in a child process through the case runner: one OpenMP thread each
(OMP_NUM_THREADS=1), side by side on two cores. CPU time and peak memory:
resource.getrusage of each ccx child (os.wait4) and of each ddpy process around its run.
Without ``ccx`` on the PATH the ddpy runs are made and the report says CalculiX is missing.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import (  # noqa: E402
    DOCS,
    code_version,
    computed_at,
    cores,
    cpu_model,
    load_module,
    runs_file,
)
from bench_common import table_row as _row  # noqa: E402

deck = load_module(HERE / "deck.py", "calculix_same_deck_deck")
make_case = deck.make_case
STEM = "calculix_same_deck"
WORK = HERE / "work"
LABELS = {"nagata": "ddpy, Nagata", "facets_coarse": "ddpy, coarse facets",
          "facets_fine": "ddpy, fine facets", "ccx_facets_coarse": "CalculiX, coarse facets",
          "ccx_facets_fine": "CalculiX, fine facets"}
#: Each comparison of a ddpy run with a CalculiX run: the same facets (the same vertices),
#: and ddpy's Nagata tools against each CalculiX run.
PAIRS = (("nagata", "ccx_facets_fine"), ("nagata", "ccx_facets_coarse"),
         ("facets_fine", "ccx_facets_fine"), ("facets_coarse", "ccx_facets_coarse"))
#: The CalculiX run the goal is judged against: its tools the nearest CalculiX comes to the
#: smooth ones (deck.CCX_MODELS says why).
GOAL_REFERENCE = "ccx_facets_fine"
#: Chatter: RMS deviation from the moving quadratic over 1 mm of stroke, from 1 mm on
#: (benchmarks/cylindrical_bending/run.py's WINDOW and START), and over the last part.
WINDOW, START, LATE = 1.0, 1.0, 20.0
#: Strokes at which the report gives the force (the benchmark's Table 2 strokes).
AT = (7.0, 14.0, 21.0, 28.5)
#: The goal of issue #53: at least this many times less CPU than CalculiX with Nagata tools.
GOAL = 20.0


def ddpy_worker(case: Path, output: Path, record: Path, stop_after: int | None) -> None:
    """Run one ddpy case on one thread in this process; write its CPU time (user + system,
    getrusage of this process: the whole process, and around the run), peak memory and status
    to ``record``."""
    from ddpy.app.runner import run_case
    from ddpy.io.decks import read_case

    loaded = read_case(case)
    before = resource.getrusage(resource.RUSAGE_SELF)
    start = time.perf_counter()
    outcome = run_case(loaded, output, overwrite=True, threads=1, max_increments=stop_after)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    record.write_text(json.dumps({
        # the run; and the whole process, Python's start and reading the case included (as
        # ccx's CPU time includes reading its deck)
        "run_cpu_s": cpu, "cpu_s": after.ru_utime + after.ru_stime, "wall_s": wall,
        "peak_memory_mb": after.ru_maxrss / 1024.0,
        "status": outcome.status + (f": {outcome.message}" if outcome.message else ""),
        "results": str(outcome.results)}))


def _run_ddpy(model: str, case: Path, stop_after: int | None) -> dict[str, Any]:
    """One ddpy case in a child process (run.py --worker), read back."""
    output = WORK / "results" / model
    record = WORK / "results" / f"{model}.json"
    record.parent.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", str(case),
               str(output), str(record)]
    if stop_after is not None:
        command += ["--stop-after", str(stop_after)]
    print(f"ddpy {model}: running", file=sys.stderr, flush=True)
    subprocess.run(command, check=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    measured = json.loads(record.read_text())
    return {**read_ddpy(Path(measured["results"])), **measured, "label": LABELS[model]}


def _tip_index(nodes: np.ndarray) -> int:
    return int(np.argmin(np.linalg.norm(nodes - np.array(deck.TIP), axis=1)))


def read_ddpy(results: Path) -> dict[str, Any]:
    """Increments, iterations, force-stroke curve and the tip's z of a ddpy run."""
    from ddpy.app.post import load_run
    from ddpy.io.results import ResultsReader

    run = load_run(results)
    forming = run.phase == 0
    with ResultsReader(results) as r:
        h = r.history()
        frames = r.frames
        tip = _tip_index(r.nodes)
        formed = max((f for f in frames if f.phase == 0), key=lambda f: f.increment)
        z_formed = float(r.field("displacement", formed.index)[tip, 2])
        z_final = (float(r.field("displacement", frames[-1].index)[tip, 2])
                   if frames[-1].phase == 1 else None)
        time_total = h["time_total"]
    all_trials = h.get("newton_iterations")
    return {
        "increments": int(forming.sum()), "springback_increments": int((~forming).sum()),
        "iterations": int(run.iterations[forming].sum()),
        "springback_iterations": int(run.iterations[~forming].sum()),
        "all_iterations": int(all_trials.sum()) if all_trials is not None else None,
        "cuts": int(run.cutbacks.sum()),
        # from the flat blank (0, 0) as CalculiX's curve, then each forming increment
        "stroke": [0.0] + [round(float(s), 5) for s in run.stroke[forming]],
        "force": [0.0] + [round(float(f), 4) for f in run.force[forming]],
        # wall time of each forming increment (one thread: close to its CPU time)
        "increment_s": [0.0] + [round(float(t), 4) for t in time_total[forming]],
        "iterations_per_increment": [0] + [int(i) for i in run.iterations[forming]],
        "tip_z_formed": z_formed, "tip_z_sprung": z_final,
    }


def _blocks(text: str, what: str, node_set: str) -> list[tuple[float, list[float]]]:
    """(time, values summed over the set's nodes: a one-node set's own) of each '<what> ...
    for set <set>' block of a CalculiX .dat file."""
    head = re.compile(rf"{what} \(.*?\) for set {node_set} and time\s+(\S+)\s*\n\s*\n")
    row = re.compile(r"\s*\d+\s+(\S+)\s+(\S+)\s+(\S+)\s*\n")
    blocks = []
    for m in head.finditer(text):
        total, at = np.zeros(3), m.end()
        while (r := row.match(text, at)) is not None:
            total += [float(r[1]), float(r[2]), float(r[3])]
            at = r.end()
        blocks.append((float(m[1]), total.tolist()))
    return blocks


def read_sta(text: str) -> dict[int, dict[str, int]]:
    """Per step of a CalculiX .sta file: converged increments, their iterations, every
    attempt's iterations (unconverged ones, marked U, included), unconverged attempts."""
    steps: dict[int, dict[str, int]] = {}
    for m in re.finditer(r"^\s*(\d+)\s+(\d+)\s+(\d+)(U?)\s+(\d+)\s+\S+\s+\S+\s+\S+\s*$", text,
                         re.MULTILINE):
        s = steps.setdefault(int(m[1]), {"increments": 0, "iterations": 0,
                                         "all_iterations": 0, "cuts": 0})
        s["all_iterations"] += int(m[5])
        if m[4]:
            s["cuts"] += 1
        else:
            s["increments"] += 1
            s["iterations"] += int(m[5])
    return steps


def read_ccx(folder: Path, stem: str = "same_deck") -> dict[str, Any]:
    """Increments, iterations (.sta), the punch's force-stroke curve and the tip's z (.dat)."""
    sta = folder / f"{stem}.sta"
    steps = read_sta(sta.read_text()) if sta.is_file() else {}
    dat = folder / f"{stem}.dat"
    text = dat.read_text() if dat.is_file() else ""
    lead = "PUNCH_REF"
    u = {t: v for t, v in _blocks(text, "displacements", lead) if t <= 1.0 + 1e-9}
    f = {t: v for t, v in _blocks(text, "forces", lead) if t <= 1.0 + 1e-9}
    times = sorted(set(u) & set(f))
    ground = dict(_blocks(text, "forces", "GROUND"))
    tip = _blocks(text, "displacements", "TIP")
    formed = [v for t, v in tip if t <= 1.0 + 1e-9]
    sprung = [v for t, v in tip if t >= 2.0 - 1e-9]
    one, two = steps.get(1, {}), steps.get(2, {})
    return {
        "increments": one.get("increments", 0), "springback_increments": two.get("increments", 0),
        "iterations": one.get("iterations", 0), "springback_iterations": two.get("iterations", 0),
        "all_iterations": sum(s["all_iterations"] for s in steps.values()),
        "cuts": sum(s["cuts"] for s in steps.values()),
        # the blank pushes the punch up: the reference node's reaction is -z
        "stroke": [0.0] + [round(-u[t][2], 5) for t in times],
        "force": [0.0] + [round(-f[t][2], 4) for t in times],
        # what the springs under the centre line hold along z (deck.SPRING): part of the
        # punch's force that does not go into the tools' contact with the blank
        "spring_force": [0.0] + [round(abs(ground[t][2]), 6) if t in ground else None
                                 for t in times],
        "tip_z_formed": formed[-1][2] if formed else None,
        "tip_z_sprung": sprung[-1][2] if sprung else None,
        "sprung_complete": bool(sprung),
    }


class CcxRun:
    """``ccx`` on the deck as a child process, its resource use from os.wait4."""

    def __init__(self, ccx: str, deck_file: Path, key: str) -> None:
        self.folder, self.stem, self.key = deck_file.parent, deck_file.stem, key
        for old in self.folder.glob(f"{self.stem}.*"):
            if old.suffix != ".inp":
                old.unlink()
        self.log = (self.folder / "ccx.log").open("w")
        self.process = subprocess.Popen([ccx, self.stem], cwd=self.folder, stdout=self.log,
                                        stderr=subprocess.STDOUT,
                                        env={**os.environ, "OMP_NUM_THREADS": "1"})
        self.start = time.perf_counter()
        self.stopped = False
        self.usage: resource.struct_rusage | None = None
        self.status = 0
        self.wall = 0.0
        self.thread = threading.Thread(target=self._wait, daemon=True)
        self.thread.start()

    def _wait(self) -> None:
        _, status, self.usage = os.wait4(self.process.pid, 0)
        self.wall = time.perf_counter() - self.start
        self.status = os.waitstatus_to_exitcode(status)
        self.process.returncode = self.status  # reaped here: Popen must not wait again
        self.log.close()

    def finish(self, deadline: float | None) -> dict[str, Any]:
        """Wait until ccx ends, or stop it (SIGTERM) at ``deadline`` (time.perf_counter);
        its numbers as far as it got."""
        self.thread.join(None if deadline is None else max(0.0, deadline - time.perf_counter()))
        if self.thread.is_alive():
            self.stopped = True
            os.kill(self.process.pid, signal.SIGTERM)
            self.thread.join()
        assert self.usage is not None
        numbers = read_ccx(self.folder, self.stem)
        if self.stopped:
            reached = numbers["stroke"][-1]
            status = f"stopped at the time limit, {reached:.2f} mm of stroke"
        elif self.status == 0 and numbers["sprung_complete"]:
            status = "completed"
        else:
            status = f"exit {self.status}"
        error = ccx_error(self.folder / "ccx.log")
        # SPOOLES, CalculiX's default sparse solver where it is built in, leaves this file
        solver = "SPOOLES" if (self.folder / "spooles.out").is_file() else "not known"
        return {**numbers, "label": LABELS[self.key], "status": status, "solver": solver,
                "error": error,
                "cpu_s": self.usage.ru_utime + self.usage.ru_stime,
                "peak_memory_mb": self.usage.ru_maxrss / 1024.0, "wall_s": self.wall}


def ccx_error(log: Path) -> str | None:
    """The last '*ERROR' message of a ccx log, on one line; None without one."""
    text = log.read_text(errors="replace") if log.is_file() else ""
    found = re.findall(r"\*ERROR[^\n]*(?:\n [^\n*]+)*", text)
    return " ".join(found[-1].split()) if found else None


def ccx_version(ccx: str) -> str:
    out = subprocess.run([ccx, "-v"], capture_output=True, text=True, check=False).stdout
    found = re.search(r"Version\s+(\S+)", out)
    return found[1] if found else "unknown"


def _ccx_runs(ccx: str, paths: dict[str, Path], limit: float | None,
              into: dict[str, Any]) -> None:
    """CalculiX on each of deck.CCX_MODELS' decks, one after the other; each stopped
    ``limit`` s after it started (None: no limit)."""
    for model in deck.CCX_MODELS:
        key = f"ccx_{model}"
        print(f"ccx {model}: running", file=sys.stderr, flush=True)
        solver = CcxRun(ccx, paths[key], key)
        into[key] = solver.finish(None if limit is None else solver.start + limit)


def run_all(stop_after: int | None, ccx_limit: float | None) -> dict[str, Any]:
    """Write the decks, run the ccx decks beside the ddpy runs; the session's numbers."""
    paths = deck.prepare(WORK)
    ccx = shutil.which("ccx")
    # the deck as the coarse facet case states it, with each facet model's faces
    described = {model: deck.describe(paths[model]) for model in deck.CCX_MODELS}
    described = {**described["facets_coarse"],
                 "faces": {model: d["faces"] for model, d in described.items()}}
    session = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
               "code": code_version(), "cores": cores(), "cpu": cpu_model(),
               "load_before": round(os.getloadavg()[0], 2),
               "ccx": ccx_version(ccx) if ccx else None, "ddpy_stop_after": stop_after,
               "ccx_limit_s": ccx_limit, "deck": described}
    ccx_results: dict[str, Any] = {}
    calculix = (threading.Thread(target=_ccx_runs, args=(ccx, paths, ccx_limit, ccx_results))
                if ccx else None)
    if calculix is not None:
        calculix.start()
    runs = {model: _run_ddpy(model, paths[model], stop_after) for model in deck.MODELS}
    if calculix is not None:
        print("ccx: waiting", file=sys.stderr, flush=True)
        calculix.join()
    runs.update(ccx_results)
    session["load_after"] = round(os.getloadavg()[0], 2)
    return {"session": session, "runs": runs}


def summary(run: dict[str, Any]) -> dict[str, Any]:
    """Force at AT, the largest, and the chatter of one run's curve."""
    from ddpy.studies.bending import force_oscillation

    s, f = np.asarray(run["stroke"], float), np.asarray(run["force"], float)
    reached = float(s[-1]) if s.size else 0.0
    at = [float(np.interp(a, s, f)) if reached >= a - 1e-6 else None for a in AT]
    chatter = (force_oscillation(s, f, WINDOW, start=START)
               if reached >= START + WINDOW else None)
    late = force_oscillation(s, f, WINDOW, start=LATE) if reached >= LATE + WINDOW else None
    mean = float(np.mean(f[s >= START])) if reached >= START + WINDOW else None
    return {"reached": reached, "at": at, "largest": float(f.max()) if f.size else 0.0,
            "chatter": chatter, "chatter_late": late, "mean": mean}


def _fmt(value: float | None, spec: str = ".1f") -> str:
    return "-" if value is None else format(value, spec)


def figure(runs: dict[str, dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.4), sharey=True)
    for ax, facets in zip(axes, ("facets_coarse", "facets_fine"), strict=True):
        for key, style, width in ((f"ccx_{facets}", "-", 1.0), (facets, "--", 1.4),
                                  ("nagata", "-", 1.4)):
            if key in runs:
                r = runs[key]
                ax.plot(r["stroke"], r["force"], style, lw=width, label=r["label"])
        ax.set_xlabel("punch stroke (mm)")
        ax.grid(alpha=0.3)
        ax.legend()
    axes[0].set_ylabel("punch force (N), quarter model")
    fig.suptitle("Numisheet 2002 BM-B bending, 60 x 6 x 2 blank, the same deck")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _cpu_to(run: dict[str, Any], stroke: float) -> float | None:
    """A ddpy run's CPU time to ``stroke`` of forming: its increments' wall times to there
    (one thread) scaled by the run's CPU / wall."""
    s, t = np.asarray(run["stroke"], float), np.cumsum(run.get("increment_s", []))
    if stroke <= 0.0 or not s.size or t.size != s.size or s[-1] < stroke:
        return None
    return float(np.interp(stroke, s, t)) * run["cpu_s"] / max(run["wall_s"], 1e-9)


def curve_gap(run: dict[str, Any], reference: dict[str, Any]) -> tuple[float, float, float]:
    """How far ``run``'s force-stroke curve lies from ``reference``'s, at the reference's
    increments from START mm to WINDOW mm short of where either stopped (a run that fails is
    cut back and forced through in its last increments): the largest and the RMS difference
    as shares of the reference's force, and the stroke compared to (0: none shared)."""
    s, f = np.asarray(run["stroke"], float), np.asarray(run["force"], float)
    rs, rf = np.asarray(reference["stroke"], float), np.asarray(reference["force"], float)
    end = min(s[-1], rs[-1]) - WINDOW
    at = (rs >= START) & (rs <= end)
    if not at.any():
        return float("nan"), float("nan"), 0.0
    gap = (np.interp(rs[at], s, f) - rf[at]) / rf[at]
    return float(np.abs(gap).max()), float(np.sqrt(np.mean(gap ** 2))), float(end)


def compare(run: dict[str, Any], calculix: dict[str, Any]) -> tuple[float, float, float]:
    """CPU of CalculiX over ddpy's, Newton iterations of ddpy over CalculiX's (forming and
    springback), and all iterations (cut attempts too) the same way: of the whole runs when
    CalculiX completed, else of ddpy to the stroke CalculiX reached (no all-iterations
    ratio then). nan where there is nothing to compare."""
    nan = float("nan")
    reached = calculix["stroke"][-1] if calculix["stroke"] else 0.0
    if calculix["status"] == "completed":
        cpu = calculix["cpu_s"] / run["cpu_s"]
        its = (run["iterations"] + run["springback_iterations"]) / max(
            calculix["iterations"] + calculix["springback_iterations"], 1)
        every = (nan if run.get("all_iterations") is None else
                 run["all_iterations"] / max(calculix["all_iterations"], 1))
        return cpu, its, every
    if reached <= 0.0:
        return nan, nan, nan
    to = _cpu_to(run, reached)
    cpu = calculix["cpu_s"] / to if to else nan
    its = nan
    if run.get("iterations_per_increment"):
        s = np.asarray(run["stroke"])
        done = np.asarray(run["iterations_per_increment"])[s <= reached]
        its = float(done.sum()) / max(calculix["iterations"], 1)
    return cpu, (its if np.isfinite(cpu) else nan), nan


def spring_note(run: dict[str, Any]) -> str:
    """What the springs under the centre line (deck.SPRING) carried of a CalculiX run's punch
    force: its punch pushes them down with the blank, ddpy has none."""
    springs = [(s, g, f) for s, g, f in zip(run["stroke"], run.get("spring_force", []),
                                            run["force"], strict=False)
               if g is not None and s > 0.0]
    label = run.get("label", "CalculiX")
    if not springs:
        return (f"\n\n{label}: the springs' reactions were not recorded; its punch force "
                "includes what they hold.")
    stroke, largest, force = max(springs, key=lambda x: x[1])
    return (f"\n\n{label}: the springs under the centre line ({deck.SPRING:g} N/mm "
            "each, to fixed ground) are pushed down with the blank, so its punch force "
            f"includes what they hold: at most {largest:.3g} N (at {stroke:.2f} mm of stroke, "
            f"{100 * largest / max(abs(force), 1e-30):.2g} % of the punch force there), "
            "from the ground nodes' reactions (deck.SPRING says why they are this soft).")


def report(data: dict[str, Any]) -> str:
    """The markdown report of one session's runs (and its figure)."""
    session, runs = data["session"], data["runs"]
    d = session["deck"]
    faces = {model: ", ".join(f"{tool} {count}" for tool, count in per_tool.items())
             for model, per_tool in d["faces"].items()}
    friction = " and ".join(sorted({f"{f:g}" for f in d["friction"]}))
    per_arc = make_case.PATCHES_PER_ARC

    def sag(radius: float, per_arc: int) -> str:
        return f"{1e3 * deck.sagitta(radius, per_arc):.2g} um"
    calculix = [runs[k] for k in runs if k.startswith("ccx_")]
    solver_line = (f"its default linear solver, {calculix[0].get('solver', 'not known')} in "
                   "this build" if calculix else "not run")
    DOCS.mkdir(parents=True, exist_ok=True)
    figure(runs, DOCS / f"{STEM}.png")
    numbers = {key: summary(run) for key, run in runs.items()}
    order = [k for k in (*deck.MODELS, *(f"ccx_{m}" for m in deck.CCX_MODELS)) if k in runs]
    columns = ("run", "status", "forming increments", "Newton iterations (forming)",
               "springback increments / iterations", "all iterations (cut attempts too)",
               "cut attempts", "CPU (s)", "CPU of the run alone (s)", "wall (s)",
               "peak memory (MB)")
    rows = [_row(columns), "|---" * len(columns) + "|"]
    for k in order:
        r = runs[k]
        rows.append(_row([
            r["label"], r["status"], r["increments"], r["iterations"],
            f"{r['springback_increments']} / {r['springback_iterations']}",
            "-" if r.get("all_iterations") is None else r["all_iterations"], r["cuts"],
            f"{r['cpu_s']:.1f}", _fmt(r.get("run_cpu_s")), f"{r['wall_s']:.1f}",
            f"{r['peak_memory_mb']:.0f}"]))
    force_cols = ("run", *(f"force at {a:g} mm (N)" for a in AT), "largest (N)",
                  f"chatter from {START:g} mm (N)", f"chatter from {LATE:g} mm (N)",
                  "chatter / mean force", "tip z formed (mm)", "tip z after springback (mm)")
    force_rows = [_row(force_cols), "|---" * len(force_cols) + "|"]
    for k in order:
        n, r = numbers[k], runs[k]
        share = (f"{100 * n['chatter'] / n['mean']:.2f} %" if n["chatter"] is not None
                 and n["mean"] else "-")
        force_rows.append(_row([r["label"], *(_fmt(v) for v in n["at"]), f"{n['largest']:.1f}",
                                _fmt(n["chatter"], ".2f"), _fmt(n["chatter_late"], ".2f"),
                                share, _fmt(r["tip_z_formed"], ".3f"),
                                _fmt(r["tip_z_sprung"], ".3f")]))
    ratio_cols = ("ddpy run", "CalculiX run", "CPU: CalculiX / ddpy",
                  "Newton iterations: ddpy / CalculiX", "all iterations: ddpy / CalculiX",
                  "peak memory: ddpy / CalculiX", "chatter: ddpy / CalculiX",
                  f"force: ddpy / CalculiX at {', '.join(f'{a:g}' for a in AT)} mm",
                  f"force: largest / RMS difference from CalculiX's, {START:g} mm to "
                  f"{WINDOW:g} mm short of the end")
    lines = [_row(ratio_cols), "|---" * len(ratio_cols) + "|"]
    ratios: dict[tuple[str, str], float] = {}
    for k, c_key in PAIRS:
        if k not in runs or c_key not in runs:
            continue
        r, c = runs[k], runs[c_key]
        cpu, its, every = compare(r, c)
        ratios[(k, c_key)] = cpu
        chat = (f"{numbers[k]['chatter'] / numbers[c_key]['chatter']:.3f}"
                if numbers[k]["chatter"] and numbers[c_key]["chatter"] else "-")
        force = ", ".join(f"{a / b:.3f}" if a is not None and b else "-" for a, b in
                          zip(numbers[k]["at"], numbers[c_key]["at"], strict=True))
        largest, rms, end = curve_gap(r, c)
        gap = (f"{100 * largest:.1f} % / {100 * rms:.1f} % (to {end:.2f} mm)" if end > 0
               else "-")
        lines.append(_row([r["label"], c["label"], _fmt(cpu if np.isfinite(cpu) else None),
                           _fmt(its if np.isfinite(its) else None, ".2f"),
                           _fmt(every if np.isfinite(every) else None, ".2f"),
                           f"{r['peak_memory_mb'] / c['peak_memory_mb']:.2f}", chat,
                           force, gap]))
    verdict = "CalculiX did not run in this session: no ratios."
    if ("nagata", GOAL_REFERENCE) in ratios:
        c = runs[GOAL_REFERENCE]
        cpu = ratios[("nagata", GOAL_REFERENCE)]
        complete = c["status"] == "completed"
        # judged where CalculiX answered the forming at least: a run stopped short of the
        # stroke has not answered the problem
        formed = bool(c["stroke"]) and c["stroke"][-1] >= session["deck"]["stroke"] - 1e-6
        met = "met" if cpu >= GOAL else "not met"
        if not complete and not formed:
            met = "not judged (CalculiX did not complete its forming)"
        if complete:
            scope = "the whole runs, forming and springback"
        elif formed:
            scope = ("the forming, the whole stroke: CalculiX's springback failed "
                     f"({c['status']}), its CPU includes the failed attempts "
                     f"({c['all_iterations'] - c['iterations']} iterations of "
                     f"{c['all_iterations']} were attempts that were cut back); ddpy's CPU to "
                     "the end of its forming from its increments' times")
        else:
            scope = (f"to the {c['stroke'][-1]:.2f} mm of stroke CalculiX reached "
                     f"({c['status']}; ddpy's CPU to there from its increments' times)")
        verdict = (f"**Goal {met}**: with Nagata tools ddpy used {cpu:.1f} times less CPU "
                   f"than CalculiX with {c['label'].split(', ')[1]} ({scope}); the goal is at "
                   f"least {GOAL:g} times. The reference is CalculiX's run on the fine "
                   "facets, the tools nearest the smooth ones it can take (their sagitta lies "
                   "below ddpy's penetration limit, the coarse facets' far above it: the "
                   "deck's tools above), so that both codes answer the same problem."
                   if np.isfinite(cpu) else "**The goal cannot be judged**: the runs of "
                   "this session share no stroke to compare.")
    codes = {LABELS[k]: session["code"] for k in order}
    partial = ""
    if session.get("ddpy_stop_after") is not None:
        partial = (f"\n**A check run, not the benchmark**: ddpy stopped after "
                   f"{session['ddpy_stop_after']} increments.\n")
    ccx_note = ""
    for c_key in (k for k in order if k.startswith("ccx_")):
        c = runs[c_key]
        if c["status"] != "completed":
            error = c.get("error")
            partial += (f"\n**{c['label']} did not complete** ({c['status']}"
                        + (f", at {c['stroke'][-1]:.2f} mm of stroke: \"{error}\""
                           if error else "")
                        + "): its numbers are to where it got; the CPU and iteration ratios "
                        "compare ddpy to the same stroke.\n")
            ccx_note += (f"\n\n{c['label']}: its curve and chatter stop where it failed; "
                         "its last increments before the failure, cut back and forced "
                         "through, may carry its largest force, which also weighs in its "
                         "chatter.")
        ccx_note += spring_note(c)
    ccx_line = (f"CalculiX {session['ccx']} (Debian's calculix-ccx)" if session.get("ccx")
                else "CalculiX (not installed in this session)")
    text = f"""# ddpy and CalculiX on the same deck: Numisheet 2002 BM-B bending, 60 x 6 x 2

Written by `python benchmarks/calculix_same_deck/run.py` (issue #53, item 5); `--reuse`
writes it again from [calculix_same_deck_runs.json](calculix_same_deck_runs.json).
{computed_at(session['code'], codes)} One session: {session['date']}, {session['cores']}
cores ({session['cpu']}), load average {session['load_before']} when it started and
{session.get('load_after', '-')} when it ended (this session's runs count in it); one thread
each (OMP_NUM_THREADS=1), {ccx_line} on one core (its two decks one after the other) while
ddpy's three runs, one after the other, use the other.
{partial}
## The deck

`benchmarks/calculix_same_deck/deck.py` writes both from ddpy's case of
benchmarks/cylindrical_bending (make_case.py): the quarter 60 x 15 x 1 mm blank as
`coarse_mesh(nx={deck.NX}, ny={deck.NY}, layers={deck.LAYERS})` ({d['elements']} elements,
{d['nodes']} nodes), the punch (radius {make_case.PUNCH_RADIUS:g} mm) and the open die
(shoulder radius {make_case.SHOULDER_RADIUS:g} mm at x = {deck.SHOULDER_X:g} mm), friction
{friction}, {d['stroke']:g} mm of punch stroke at most {d['max_increment']:g} mm an increment,
symmetry on x = 0 and y = 0, then springback with the centre line held along z.

- **Tools.** ddpy runs its Nagata tools, its coarse facets (the same mesh of {per_arc}
  patches per 90 degrees of arc made flat: make_case's `facets_coarse`, the Nagata file read
  with `description facets`; the paper's coarse facets "keeping the same discretization")
  and its fine facets ({make_case.FACETS_PER_ARC} per 90 degrees of arc, the `*.facets.tool`
  files). A CalculiX deck is written from each facet case: each tool is a `*RIGID BODY` of
  one C3D8 brick behind each facet, whose S2 face is the facet, its four vertices those of
  the tool file (coarse: {faces.get('facets_coarse', '-')} faces; fine:
  {faces.get('facets_fine', '-')} faces; written to the 20 characters CalculiX reads a number
  from: the same doubles to 1e-17 mm, a longer number's last digits dropped). So each
  CalculiX run has the tools of ddpy's facet run of its name, and ddpy's Nagata tools are
  the coarse vertices smoothed.
  CalculiX cannot take Nagata patches; the fine facets are the nearest it comes to the
  smooth tools (a facet's sagitta {sag(make_case.PUNCH_RADIUS, make_case.FACETS_PER_ARC)}
  on the punch, {sag(make_case.SHOULDER_RADIUS, make_case.FACETS_PER_ARC)} on the die's
  shoulder, against {sag(make_case.PUNCH_RADIUS, per_arc)} and
  {sag(make_case.SHOULDER_RADIUS, per_arc)} for the coarse facets and ddpy's penetration
  limit of 0.01 mm, 1 % of the thickness).
- **Blank.** C3D8I in CalculiX, ddpy's defaults otherwise: its solid-shell (what `ddpy
  convert` makes of C3D8I) and Gauss-point contact with the barrier.
- **Material.** The benchmark's steel, E {d['E'] / 1000:g} GPa, nu {d['nu']:g}, Swift K
  {deck.SWIFT[0]:g} MPa, eps0 {deck.SWIFT[1]:g}, n {deck.SWIFT[2]:g}, as von Mises with the
  Swift curve sampled at {len(deck.TABLE_STRAINS)} plastic strains (2e-4 to 1): the same table
  in CalculiX's `*PLASTIC` and ddpy's material.dat. ddpy's bending case has Hill'48;
  CalculiX's `*PLASTIC` is von Mises, and Hill'48 there needs a user material, so both codes
  read the isotropic table here.
- **Contact.** CalculiX's face-to-face penalty contact, `*CONTACT PAIR, TYPE=SURFACE TO
  SURFACE` (the manual's "face-to-face penalty contact"), linear pressure-overclosure of
  {deck.PENALTY:g} MPa/mm ({deck.PENALTY * 1e-2:g} MPa of pressure at 0.01 mm of
  overclosure, ddpy's penetration limit, 1 % of the thickness; with
  {deck.STIFFER_PENALTY:g} MPa/mm, before 2026-12-06, CalculiX stopped at
  {deck.STIFFER_PENALTY_STOP:g} mm of stroke in every session, "increment size smaller than
  minimum", and frictionless too), Coulomb friction {friction} with a stick slope of
  {deck.STICK_SLOPE:g} MPa/mm (examples/calculix_bending's). Not the mortar
  (`TYPE=MORTAR`): face-to-face means the contact integrated over the blank's faces, which
  the penalty form does, at integration points of
  the slave faces as ddpy's Gauss-point contact does; the mortar form adds Lagrange
  multipliers on top of that, and `ddpy convert` (docs/abaqus-import.md) reads `SURFACE TO
  SURFACE` and `NODE TO SURFACE` only, so with the mortar the deck would not be one deck for
  both codes. {d['springs']} SPRING2 elements of {deck.SPRING:g} N/mm under the centre line
  hold CalculiX's blank along z before the tools grip it (ddpy's convert skips them; ddpy's
  contact holds the blank).
- **Process.** CalculiX ({solver_line}): one `*STATIC` step of the {d['stroke']:g} mm
  (initial and largest increment {d['max_increment'] / d['stroke']:.3g} of it,
  {d['max_increment']:g} mm; CalculiX's own increment control), then a step without the
  contact pairs (`*MODEL CHANGE, REMOVE`) for the springback, its initial increment
  {1.0 / d['springback_increments']:.3g} of it; ddpy: its forming phase (largest increment
  {d['max_increment']:g} mm, its increment limits of the coarse blank) and its springback
  released in {d['springback_increments']} step{'' if d['springback_increments'] == 1 else 's'}
  (a step that fails halved).

`tests/test_calculix_same_deck.py` checks the deck writer: the counts, the tool faces'
vertices against the tool files, and that `ddpy convert` reads the deck back to the same
blank.

## Effort

{chr(10).join(rows)}

CalculiX's increments and iterations are from its .sta file: a converged increment's
iterations, and every attempt's (those marked U, cut back, too). ddpy's: accepted iterations
of its increments, and the Newton corrections of all its trials. CPU: user + system time from
getrusage, of the ccx child (reading its deck included) and of the ddpy process at its end
(Python's start and reading the case included; the ratios take these); "of the run alone":
ddpy's around its case runner only. Peak memory: ru_maxrss (ddpy's includes the Python
interpreter and its libraries).

{chr(10).join(lines)}

{verdict}

## Force

![force-stroke](calculix_same_deck.png)

{chr(10).join(force_rows)}

Quarter model, force on the punch along its stroke (CalculiX: the reaction of the punch's
reference node, `*NODE PRINT`, at each converged increment; ddpy: the tool force of its
results). Chatter: the RMS deviation of the force from its moving quadratic over
{WINDOW:g} mm of stroke (`ddpy.studies.bending.force_oscillation`, as
benchmarks/cylindrical_bending/run.py), from {START:g} mm on and from {LATE:g} mm on. The
tip: the blank's end node (x = 60, y = 0, z = 0).{ccx_note}
"""
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reuse", action="store_true",
                        help="write the report from the kept runs, without running")
    parser.add_argument("--stop-after", type=int, default=None, metavar="N",
                        help="stop each ddpy run after N increments (a check, not the benchmark)")
    parser.add_argument("--ccx-limit", type=float, default=None, metavar="SECONDS",
                        help="stop CalculiX this long after it started and report it as far "
                        "as it got")
    parser.add_argument("--worker", nargs=3, metavar=("CASE", "OUTPUT", "RECORD"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        case, output, record = (Path(p) for p in args.worker)
        ddpy_worker(case, output, record, args.stop_after)
        return 0
    kept = runs_file(STEM)
    if args.reuse:
        data = json.loads(kept.read_text())
    else:
        data = run_all(args.stop_after, args.ccx_limit)
        kept.parent.mkdir(parents=True, exist_ok=True)
        kept.write_text(json.dumps(data, indent=1) + "\n")
    text = report(data)
    (DOCS / f"{STEM}.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
