"""Mixed isotropic-kinematic hardening against isotropic hardening fitted to the same monotonic
curve: the springback of the built-in bending (coarse) and of examples/strip_draw.

    python benchmarks/kinematic_hardening/run.py            # four runs, minutes on one thread
    python benchmarks/kinematic_hardening/run.py --cases bending_paper --laws mixed  # and
    python benchmarks/kinematic_hardening/run.py --cases bending_paper --laws isotropic
    python benchmarks/kinematic_hardening/run.py --reuse    # report from the saved runs

The bending paper mesh's two runs (half an hour each on one thread) go side by side, a
process per law, with OMP_NUM_THREADS=1: their times per Newton iteration are then measured
alike.

Writes the cases (the decks of the built-in bending and of examples/strip_draw with their
material.dat's hardening replaced) into cases/<case>/<law>/, runs each with the case runner
(``ddpy run``) into results/<case>/<law>/ (both git-ignored), one at a time, and writes
docs/benchmarks/kinematic_hardening.md with its figure. The numbers of every run, with the
code version and date of each, are kept in docs/benchmarks/kinematic_hardening_runs.json
(merged: a run not made keeps its entry); ``--reuse`` reads a run back from results/, else
from there.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ddpy.model.control import DEFAULT_PENETRATION as PENETRATION_LIMIT
from ddpy.model.material import (
    ArmstrongFrederick,
    HardeningTable,
    Hill48,
    Material,
    Swift,
    Voce,
)

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import (  # noqa: E402
    DOCS,
    ROOT,
    code_version,
    computed_at,
    deepest_per_tool,
    load_module,
    record_code,
    recorded_code,
    runs_file,
)
from bench_common import table_row as _row  # noqa: E402

bending = load_module(ROOT / "benchmarks" / "cylindrical_bending" / "run.py", "bending_run")

STEM = "kinematic_hardening"
#: The mixed model's isotropic part and backstress: a DP600-class dual-phase steel (Voce
#: plus one Armstrong-Frederick backstress, Lemaitre and Chaboche's form; SOURCE says where
#: the values come from). Its monotonic curve Y(ep) + X_sat (1 - exp(-C_X ep)) runs from
#: 330 MPa at yield to about 660 MPa at 10 % and 750 MPa at 20 % plastic strain.
ISOTROPIC_PART = Voce(Y0=330.0, Q=357.0, b=9.2)
BACKSTRESS = ArmstrongFrederick(C=100.0, X_sat=120.0)
SOURCE = (
    "A DP600-class set in the range the DD3IMP group's studies of mixed hardening in "
    "springback report for DP600 (Voce plus one Armstrong-Frederick backstress; Oliveira, "
    "Alves, Chaparro and Menezes, *Study on the influence of work-hardening modeling in "
    "springback prediction*, Int. J. Plasticity 23 (2007) 516-543, DP600 and DC06): "
    "initial yield 330 MPa, a backstress saturating at 120 MPa at the rate C_X = 100, and "
    "the monotonic curve of a DP600 sheet (Swift K about 1000 MPa, n about 0.18). "
    "**The values are not copied from the paper's table**: its text could not be retrieved "
    "when this report was written, so they are a representative set of that range, to be "
    "replaced by the paper's own (one edit: ISOTROPIC_PART and BACKSTRESS in run.py).")

#: The fitted isotropic law: a `hardening table` holding the mixed model's monotonic curve
#: at these plastic strains (the first 0, 99 more spaced geometrically from 1e-3 to 2, dense
#: where the backstress's exp(-C_X ep) bends the curve most; the table is constant beyond).
TABLE_STRAINS = np.concatenate(([0.0], np.geomspace(1e-3, 2.0, 99)))
#: The largest difference allowed between the table and the mixed monotonic curve, MPa, up
#: to CURVE_RANGE of plastic strain (more than either case reaches).
CURVE_TOLERANCE = 0.5
CURVE_RANGE = 1.0

#: The cases: the built-in bending (coarse blank, Nagata tools), the same on the paper's
#: blank (benchmarks/cylindrical_bending's case, made by its make_case.py when missing) and
#: the strip drawn over a die radius, with their own elasticity and Hill'48 coefficients.
BENDING = ROOT / "benchmarks" / "cylindrical_bending"
CASES = {"bending": ROOT / "ddpy" / "cases" / "cylindrical_bending",
         "bending_paper": BENDING / "cases" / "paper" / "nagata",
         "strip_draw": ROOT / "examples" / "strip_draw"}
#: The cases run when --cases is not given: the paper blank takes half an hour per run.
QUICK_CASES = ("bending", "strip_draw")
LAWS = ("mixed", "isotropic")
LAW_LABELS = {"mixed": "mixed (Voce + Armstrong-Frederick)",
              "isotropic": "isotropic (table fitted to the mixed monotonic curve)"}
#: A springback is judged to differ between the two laws when the two differ by more than
#: this many degrees and this fraction of the isotropic one.
SPRINGBACK_DEGREES = 0.25
SPRINGBACK_FRACTION = 0.05


def monotonic_curve(ep: np.ndarray, hardening: Swift | Voce | HardeningTable = ISOTROPIC_PART,
                    kinematic: ArmstrongFrederick | None = BACKSTRESS) -> np.ndarray:
    """The flow stress of monotonic (proportional) loading at plastic strains ``ep``:
    Y(ep) + X_sat (1 - exp(-C_X ep)), the backstress adding its Hill norm to the isotropic
    Y(ep) (docs/theory/material.md); Y(ep) alone without ``kinematic``. Y comes from the
    core (``Material.yield_stress``)."""
    ep = np.asarray(ep, dtype=float)
    y = Material(210e3, 0.3, Hill48.von_mises(), hardening).yield_stress(ep)
    if kinematic is None:
        return y
    return y + kinematic.X_sat * (1.0 - np.exp(-kinematic.C * ep))


def fitted_table(hardening: Swift | Voce | HardeningTable = ISOTROPIC_PART,
                 kinematic: ArmstrongFrederick = BACKSTRESS,
                 strains: np.ndarray = TABLE_STRAINS) -> HardeningTable:
    """The isotropic law fitted to the mixed model's monotonic curve: a hardening table
    holding that curve at ``strains`` (exact there, linear between), both to the 8 digits
    material.dat gets."""
    stresses = monotonic_curve(strains, hardening, kinematic)
    return HardeningTable(tuple(float(f"{e:.8g}") for e in strains),
                          tuple(float(f"{s:.8g}") for s in stresses))


def curve_gap(table: HardeningTable, hardening: Swift | Voce | HardeningTable = ISOTROPIC_PART,
              kinematic: ArmstrongFrederick = BACKSTRESS, up_to: float = CURVE_RANGE,
              points: int = 20001) -> tuple[float, float]:
    """The largest |isotropic - mixed| monotonic flow stress (MPa) on ``points`` plastic
    strains from 0 to ``up_to``, and the plastic strain where it occurs."""
    ep = np.linspace(0.0, up_to, points)
    gap = np.abs(monotonic_curve(ep, table, None) - monotonic_curve(ep, hardening, kinematic))
    worst = int(np.argmax(gap))
    return float(gap[worst]), float(ep[worst])


def hardening_lines(law: str, table: HardeningTable | None = None) -> list[str]:
    """material.dat's hardening (and kinematic) lines of ``law``: the mixed model, or the
    fitted table."""
    if law == "mixed":
        h, k = ISOTROPIC_PART, BACKSTRESS
        return [f"hardening  voce  Y0 {h.Y0:g}  Q {h.Q:g}  b {h.b:g}",
                f"kinematic  armstrong-frederick  C {k.C:g}  Xsat {k.X_sat:g}"]
    table = table or fitted_table()
    return ([f"hardening  table {len(table.strains)}   # the mixed monotonic curve: ep, Y"]
            + [f"  {e:.8g} {y:.8g}" for e, y in zip(table.strains, table.stresses,
                                                                 strict=True)])


def write_case(source: Path, folder: Path, law: str) -> Path:
    """The case at ``source`` copied to ``folder`` with its material.dat's hardening line
    replaced by ``law``'s lines (its elasticity, Hill'48 and rolling direction kept), and the
    files its mesh and tools decks name relative to ``source`` named by absolute path."""
    if folder.exists():
        shutil.rmtree(folder)
    shutil.copytree(source, folder)
    for name in ("mesh.dat", "tools.dat"):  # a file named relative to the source case
        path = folder / name
        path.write_text(re.sub(
            r"^(\s*file\s+)(\S+)",
            lambda m: m.group(1) + (m.group(2) if Path(m.group(2)).is_absolute()
                                    else str((source / m.group(2)).resolve())),
            path.read_text(), flags=re.MULTILINE))
    deck = folder / "material.dat"
    lines = deck.read_text().splitlines()
    hardening = [i for i, line in enumerate(lines) if re.match(r"\s*hardening\s", line)]
    if len(hardening) != 1 or any(re.match(r"\s*kinematic\s", line) for line in lines) or \
            re.search(r"\btable\b", lines[hardening[0]]):
        raise ValueError(f"{deck}: expected one one-line hardening law and no kinematic line")
    lines[hardening[0]:hardening[0] + 1] = [
        f"# {LAW_LABELS[law]}, written by benchmarks/kinematic_hardening/run.py",
        *hardening_lines(law)]
    deck.write_text("\n".join(lines) + "\n")
    return folder


#: examples/strip_draw's measured parts, by their initial x along the half strip (mm): the
#: free end (drawn over the die radius and released by the holder, it stands straight, tilted
#: up) and the wall (between the punch corner and the die shoulder at the end of the draw).
STRIP_FLANGE_X = 35.0
STRIP_WALL_X = (20.0, 25.0)


def strip_angles(initial: np.ndarray, formed: np.ndarray, sprung: np.ndarray
                 ) -> dict[str, list[float]]:
    """The strip's angles (degrees) at the end of the draw and after springback, each a line
    fitted through every layer's nodes: the free end's to the horizontal, the wall's to the
    vertical."""
    from ddpy.studies.bending import line_angle

    flange = initial[:, 0] >= STRIP_FLANGE_X - 1e-9
    wall = (initial[:, 0] >= STRIP_WALL_X[0] - 1e-9) & (initial[:, 0] <= STRIP_WALL_X[1] + 1e-9)
    return {"end": [line_angle(x[flange], along=0, up=2) for x in (formed, sprung)],
            "wall": [line_angle(x[wall], along=2, up=0) for x in (formed, sprung)]}


def per_iteration(history: dict[str, np.ndarray]) -> dict[str, float]:
    """Wall time per Newton iteration of a whole run (springback included), s: in all, and
    in the assembly (where the return mapping runs)."""
    iterations = max(int(history["iterations"].sum()), 1)
    return {"total": float(history["time_total"].sum()) / iterations,
            "assembly": float(history["time_assembly"].sum()) / iterations}


def read_run(case: str, results: Path) -> dict[str, Any]:
    """The numbers of one run from its results file: the angles after forming and after
    springback (the bending's beta_1, beta_2 as benchmarks/cylindrical_bending reads them),
    the effort and the time per iteration."""
    from ddpy.app.runner import read_status
    from ddpy.io.results import ResultsReader

    with ResultsReader(results) as r:
        history = r.history()
        frames = r.frames
        threads = r.threads
        if case.startswith("bending"):
            angles = {"beta": list(bending.betas(bending.from_results(results)))}
        else:
            last_forming = max(f.phase for f in frames if f.phase < frames[-1].phase)
            formed = max((f for f in frames if f.phase == last_forming),
                         key=lambda f: f.increment)
            angles = strip_angles(r.nodes, r.field("coordinates", formed.index),
                                  r.field("coordinates", frames[-1].index))
        deepest = deepest_per_tool(history, slice(None), r.tools)
        thickness = float(np.ptp(np.asarray(r.nodes)[:, 2]))  # a flat blank's, at the start
    status = read_status(results.parent)
    return {"status": status.get("status", "unknown"),
            "penetration_mm": deepest, "thickness_mm": round(thickness, 6),
            "angles_deg": {k: [round(float(a), 3) for a in v] for k, v in angles.items()},
            "increments": int(history["iterations"].size),
            "iterations": int(history["iterations"].sum()),
            "wall_s": round(float(history["time_total"].sum()), 2),
            "per_iteration_s": {k: round(v, 5) for k, v in per_iteration(history).items()},
            "threads": threads, **recorded_code(results.parent)}


def run_one(case: str, law: str, verbose: bool = True) -> dict[str, Any]:
    """Write ``case``'s decks for ``law``, run them (``ddpy run``) into results/<case>/<law>
    and read the numbers back."""
    from ddpy.app.runner import run_case
    from ddpy.io.decks import read_case

    if not (CASES[case] / "control.dat").exists():  # the paper blank's case
        bending.make_case.main(["--mesh", "paper"])
    folder = write_case(CASES[case], HERE / "cases" / case / law, law)
    output = HERE / "results" / case / law
    record_code(output, code_version(), False)
    if verbose:
        print(f"running {case} with {law} hardening ...", file=sys.stderr, flush=True)
    outcome = run_case(read_case(folder), output, overwrite=True)
    if verbose:
        print(f"  {outcome.status}, {outcome.increments} increments, {outcome.wall_time:.0f} s",
              file=sys.stderr, flush=True)
    return read_run(case, outcome.results)


def springback(numbers: dict[str, Any], angle: str) -> float:
    """The change of ``angle`` at springback (after minus before), degrees."""
    formed, sprung = numbers["angles_deg"][angle]
    return sprung - formed


def verdict(mixed: float, isotropic: float) -> tuple[bool, str]:
    """Whether two angles (degrees: a springback, or an angle after springback, with mixed and
    with isotropic hardening) differ: by more than SPRINGBACK_DEGREES and SPRINGBACK_FRACTION
    of the isotropic one. With the words the report prints."""
    difference = mixed - isotropic
    differs = abs(difference) > SPRINGBACK_DEGREES and \
        abs(difference) > SPRINGBACK_FRACTION * abs(isotropic)
    relative = f", {difference / isotropic:+.1%} of the isotropic" if isotropic else ""
    return differs, (f"{'differs' if differs else 'same'} (mixed minus isotropic "
                     f"{difference:+.2f} deg{relative})")


ANGLE_LABELS = {"beta": "flange to the vertical (beta_1 formed, beta_2 sprung)",
                "end": "free end to the horizontal", "wall": "wall to the vertical"}
#: The angle each case's verdict is on: the bending's beta, the strip's free end.
MAIN_ANGLE = {"bending": "beta", "bending_paper": "beta", "strip_draw": "end"}
#: Mixed hardening may cost this much more time per Newton iteration than isotropic on the
#: bending paper mesh (issue #49).
COST_LIMIT = 1.10


def plot_curves(table: HardeningTable, path: Path) -> Path:
    """The mixed model's monotonic curve and the fitted table (left), their difference
    (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ep = np.linspace(0.0, CURVE_RANGE, 20001)
    mixed = monotonic_curve(ep)
    fitted = monotonic_curve(ep, table, None)
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    shown = ep <= 0.3
    left.plot(ep[shown], mixed[shown], "k-", lw=2, label="mixed: Y(ep) + X(ep)")
    left.plot(ep[shown], fitted[shown], "r--", lw=1.2, label="isotropic: the table")
    left.plot(ep[shown], monotonic_curve(ep[shown], ISOTROPIC_PART, None), "b:",
              label="mixed model's isotropic part Y(ep)")
    left.set_xlabel("equivalent plastic strain")
    left.set_ylabel("monotonic flow stress, MPa")
    left.legend()
    right.plot(ep, fitted - mixed, "r-")
    right.set_xscale("symlog", linthresh=1e-3)
    right.set_xlabel("equivalent plastic strain")
    right.set_ylabel("isotropic minus mixed, MPa")
    right.axhline(-CURVE_TOLERANCE, color="grey", ls=":")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def keep_runs(path: Path, numbers: dict[str, dict[str, Any]]) -> None:
    """Merge the numbers of the runs made into the runs file ``path`` (keys case/law)."""
    kept = json.loads(path.read_text()) if path.exists() else {}
    kept.update(numbers)
    path.write_text(json.dumps(kept, indent=1, sort_keys=True) + "\n")


def kept_runs(path: Path) -> dict[str, dict[str, Any]]:
    """The runs file's numbers by case/law ({} when it does not exist)."""
    return json.loads(path.read_text()) if path.exists() else {}


#: The plastic strains at which the report states the monotonic curve.
SHOWN_STRAINS = (0.0, 0.02, 0.1, 0.2)


def report(numbers: dict[str, dict[str, Any]], table: HardeningTable, gap: tuple[float, float],
           figure: Path, code: str) -> str:
    """The report's text."""
    h, k = ISOTROPIC_PART, BACKSTRESS
    lines = [
        "# Mixed isotropic-kinematic hardening: its effect on springback, measured",
        "",
        "Written by `benchmarks/kinematic_hardening/run.py` (every number here is computed by "
        "it; `--reuse` rewrites this report from the saved or kept runs). "
        + computed_at(code, {key: n.get("code", "") for key, n in numbers.items()}),
        "",
        "Two hardening laws with **the same monotonic curve** run the same cases: mixed "
        "isotropic-kinematic hardening (Lemaitre-Chaboche, as DD3IMP: an isotropic Y(ep) and "
        "an Armstrong-Frederick backstress X, docs/theory/material.md) and purely isotropic "
        "hardening fitted to the mixed model's monotonic curve. What differs is only what "
        "happens when the loading reverses (the Bauschinger effect: the mixed model yields "
        "earlier in reverse) - in a sheet bent and unbent over a radius, and at springback.",
        "",
        "## The steel",
        "",
        f"- Isotropic part: Voce, Y = {h.Y0:g} + {h.Q:g} (1 - exp(-{h.b:g} ep)) MPa.",
        f"- Backstress: Armstrong-Frederick, C_X = {k.C:g}, X_sat = {k.X_sat:g} MPa "
        f"(`kinematic armstrong-frederick C {k.C:g} Xsat {k.X_sat:g}`).",
        "- Monotonic curve Y(ep) + X_sat (1 - exp(-C_X ep)): "
        + ", ".join(f"{v:.0f} MPa at ep = {e:g}" for e, v in
                    zip(SHOWN_STRAINS, monotonic_curve(np.array(SHOWN_STRAINS)), strict=True))
        + ".",
        "- Source: " + SOURCE,
        "- Each case keeps its own elasticity and Hill'48 coefficients (the bending's Numisheet "
        "2002 B steel, the strip's r-values) and rolling direction; only the hardening "
        "changes. Both have G + H = 1, so the curves above are the rolling direction's "
        "uniaxial ones; in any proportional loading the backstress grows along the relative "
        "stress and the Hill stress of s is Y(ep) + X_sat (1 - exp(-C_X ep)) exactly, so the "
        "two laws agree on every monotonic path, not only in tension.",
        "",
        "## The fitted isotropic law",
        "",
        f"The `hardening table` law (chosen over a Swift fit: it takes the curve exactly at its "
        f"points): {len(table.strains)} points, ep = 0 and 99 spaced geometrically from "
        f"{TABLE_STRAINS[1]:g} to {TABLE_STRAINS[-1]:g} (dense where exp(-C_X ep) bends the "
        f"curve), holding the mixed monotonic curve; linear between, constant beyond the last.",
        "",
        f"**Largest difference between the two monotonic curves: {gap[0]:.3f} MPa** (at "
        f"ep = {gap[1]:.4g}), on {20001} plastic strains from 0 to {CURVE_RANGE:g}; "
        f"the tolerance is {CURVE_TOLERANCE:g} MPa (tests/test_kinematic_benchmark.py). The "
        "table lies below the curve between its points (the curve is concave).",
        "",
        f"![monotonic curves]({figure.name})",
        "",
        "## Springback",
        "",
        "The built-in bending case (`ddpy run cylindrical-bending`: coarse blank, Nagata tools; "
        "bending_paper: the same on the paper's blank of benchmarks/cylindrical_bending; "
        "beta_1 and beta_2 read as benchmarks/cylindrical_bending/run.py reads them: the free "
        "flange's angle to the vertical at full stroke and after springback) and "
        "examples/strip_draw (drawn under a holder, drawn further without it over the die's "
        f"5 mm radius, released: the free end, initially at x >= {STRIP_FLANGE_X:g} mm, and the "
        f"wall, initially at x = {STRIP_WALL_X[0]:g} to {STRIP_WALL_X[1]:g} mm, each a line "
        "through all its nodes). Each run on one thread (the two laws of a case side by "
        "side on the two cores, or one at a time).",
        "",
        _row(["case", "angle", "law", "formed, deg", "after springback, deg",
              "springback, deg", "status"]),
        _row(["---"] * 7),
    ]
    verdicts = []
    for case in CASES:
        if not all(f"{case}/{law}" in numbers for law in LAWS):
            continue
        for angle in numbers[f"{case}/mixed"]["angles_deg"]:
            for law in LAWS:
                n = numbers[f"{case}/{law}"]
                formed, sprung = n["angles_deg"][angle]
                lines.append(_row([case, ANGLE_LABELS[angle], law, f"{formed:.2f}",
                                   f"{sprung:.2f}", f"{springback(n, angle):+.2f}",
                                   n["status"]]))
            mixed, isotropic = numbers[f"{case}/mixed"], numbers[f"{case}/isotropic"]
            main = " (the case's main angle)" if angle == MAIN_ANGLE[case] else ""
            _, text = verdict(springback(mixed, angle), springback(isotropic, angle))
            verdicts.append(f"- {case}, {ANGLE_LABELS[angle]}{main}: springback {text}; "
                            "angle after springback " + verdict(
                                mixed["angles_deg"][angle][1],
                                isotropic["angles_deg"][angle][1])[1])
    lines += ["", f"Verdict (an angle differs when mixed and isotropic differ by more than "
              f"{SPRINGBACK_DEGREES:g} deg and {SPRINGBACK_FRACTION:.0%} of the isotropic "
              "one; the springback, and the angle after it, which also carries the forming's "
              "difference):", "", *verdicts, "",
              "## Time per Newton iteration", "",
              "From the results' increments/time_* columns: the whole run's wall time (and its "
              "assembly, where the return mapping runs) over its Newton iterations, "
              "springback included. **The machine was shared** with other sessions' runs "
              "(2 cores), so these times carry their noise; the iteration counts do not.", "",
              _row(["case", "law", "increments", "iterations", "s / iteration",
                    "assembly s / iteration", "mixed / isotropic", "threads"]),
              _row(["---"] * 8)]
    for case in CASES:
        for law in LAWS:
            n = numbers.get(f"{case}/{law}")
            if n is None:
                continue
            iso = numbers.get(f"{case}/isotropic")
            ratio = (f"{n['per_iteration_s']['total'] / iso['per_iteration_s']['total']:.2f}"
                     if law == "mixed" and iso else "")
            lines.append(_row([case, law, n["increments"], n["iterations"],
                               f"{n['per_iteration_s']['total']:.4f}",
                               f"{n['per_iteration_s']['assembly']:.4f}", ratio,
                               n["threads"]]))
    lines += ["", "## Penetration", "",
              "The deepest slave node of the blank in any tool at any converged increment "
              "(the solver's record, `increments/penetration` of the results), against the "
              f"limit of {100 * PENETRATION_LIMIT:g} % of the blank's thickness "
              "(docs/theory/contact.md, \"Penetration\"):", "",
              _row(["case", "law", "deepest [mm]", "tool", "/ thickness", "within"]),
              _row(["---"] * 6)]
    for case in CASES:
        for law in LAWS:
            n = numbers.get(f"{case}/{law}")
            if n is None:
                continue
            depth = n.get("penetration_mm")
            if not depth:
                lines.append(_row([case, law, "not recorded (a run kept at code "
                                   f"{n.get('code') or 'unknown'})", "", "", ""]))
                continue
            tool = max(depth, key=depth.get)
            share = depth[tool] / n["thickness_mm"]
            lines.append(_row([case, law, f"{depth[tool]:.4g}", tool, f"{100 * share:.2f} %",
                               "yes" if share <= PENETRATION_LIMIT else "**no**"]))
    mixed, iso = numbers.get("bending_paper/mixed"), numbers.get("bending_paper/isotropic")
    if mixed and iso:
        ratio = mixed["per_iteration_s"]["total"] / iso["per_iteration_s"]["total"]
        lines += ["", f"On the bending paper mesh mixed hardening takes {ratio:.2f} times the "
                  "time per Newton iteration of isotropic hardening (the limit: "
                  f"{COST_LIMIT:.2f}): **{'within' if ratio <= COST_LIMIT else 'over'}** it."
                  + (" Both runs on one thread each, started together, so that they "
                     "shared the machine alike." if mixed["threads"] == iso["threads"] == 1
                     else "")]
    else:
        lines += ["", "Not run here: the bending paper mesh (`--cases bending_paper`, half an "
                  "hour per run on one thread)."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reuse", action="store_true",
                        help="report from the runs saved in results/, else kept in the runs "
                        "file (no new run)")
    parser.add_argument("--cases", default=",".join(QUICK_CASES),
                        help="comma-separated among " + ", ".join(CASES)
                        + " (default: " + ",".join(QUICK_CASES) + ")")
    parser.add_argument("--laws", default=",".join(LAWS),
                        help="comma-separated among " + ", ".join(LAWS) + " (two processes, "
                        "a law each, run side by side)")
    args = parser.parse_args(argv)
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    laws = [law.strip() for law in args.laws.split(",") if law.strip()]
    if set(cases) - set(CASES):
        parser.error(f"--cases must be among {', '.join(CASES)}")
    if set(laws) - set(LAWS):
        parser.error(f"--laws must be among {', '.join(LAWS)}")
    table = fitted_table()
    gap = curve_gap(table)
    stored = kept_runs(runs_file(STEM))
    numbers: dict[str, dict[str, Any]] = {}
    made: dict[str, dict[str, Any]] = {}
    for case in cases:
        for law in laws:
            key, saved = f"{case}/{law}", HERE / "results" / case / law / "results.h5"
            if args.reuse and saved.exists():  # read again: kept with what is read now
                numbers[key] = made[key] = read_run(case, saved)
            elif args.reuse and key in stored:
                numbers[key] = stored[key]
            elif args.reuse:
                sys.exit(f"--reuse: no saved or kept run of {key}; run it without --reuse")
            else:
                numbers[key] = made[key] = run_one(case, law)
    for key, kept in stored.items():  # the report shows every kept run
        numbers.setdefault(key, kept)
    DOCS.mkdir(parents=True, exist_ok=True)
    keep_runs(runs_file(STEM), made)
    figure = plot_curves(table, DOCS / f"{STEM}_curves.png")
    out = DOCS / f"{STEM}.md"
    out.write_text(report(numbers, table, gap, figure, code_version()))
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
