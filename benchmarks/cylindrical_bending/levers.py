"""The speed levers change no answer: the bending benchmark's paper mesh with Nagata tools
run with ddpy's speed levers switched off, against the paper report's run with them on
(docs/benchmarks/cylindrical_bending_paper.md): Table 2's angles, the punch force and its
oscillation, and what the levers save. Writes docs/benchmarks/cylindrical_bending_levers.md.

The levers, and how a variant switches them off (docs/theory/speed.md):

- the linear solver: GMRES on older LU factors with Eisenstat-Walker tolerances between
  factorizations (``FormingTuning.reuse_from``, ddpy.model.control: from that many
  unknowns); off (the deck's ``tune reuse_from`` past any mesh): every Newton iteration
  factorizes its own Jacobian and solves exactly;
- the line search's whole-step acceptance (``FormingTuning.whole_step``); off (``tune
  whole_step 0``): the natural monotonicity test alone;
- the first touch of a new contact zone only (the deck's ``rmin_touch new``, the default);
  off: ``rmin_touch every``, every free node that touches lands the increment.

    python run.py --mesh paper --models nagata        # the run with the levers, once
    python levers.py --variant off                    # a run without them (about an hour)
    python levers.py --variant direct                 # the linear solver's lever alone
    python levers.py --reuse                          # the report from the saved runs
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from bench_common import (  # noqa: E402
    DOCS,
    code_version,
    computed_at,
    load_module,
    runs_file,
)
from bench_common import table_row as _row  # noqa: E402

bench = load_module(HERE / "run.py", "bending_run")
make_case = bench.make_case

#: What each variant switches off: the linear solver's reuse of older factors, the
#: whole-step acceptance, the first touch of new contact zones only.
VARIANTS = {
    "off": {"linear_solver": "direct", "whole_step": 0.0, "rmin_touch": "every"},
    "direct": {"linear_solver": "direct"},
}
LABELS = {"off": "levers off", "direct": "direct solves only"}
#: The issue's bound: Table 2's angles within this of the same code without the levers.
ANGLE_BOUND = 0.5
STEM = "cylindrical_bending_levers"
ANGLES = ("theta_1 (7 mm)", "theta_2 (14 mm)", "theta_3 (21 mm)", "theta_4 (28.5 mm)",
          "beta_1", "beta_2")


def case_folder(variant: str) -> Path:
    """The paper mesh's Nagata case, its deck with the variant's ``rmin_touch`` and
    ``tune`` lines (the levers it switches off)."""
    source = HERE / "cases" / "paper" / "nagata"
    if not (source / "control.dat").exists():
        make_case.main(["--mesh", "paper"])
    folder = HERE / "cases" / "paper" / f"levers_{variant}"
    folder.mkdir(parents=True, exist_ok=True)
    for path in source.iterdir():
        shutil.copy2(path, folder / path.name)
    touch = VARIANTS[variant].get("rmin_touch")
    if touch:
        control = folder / "control.dat"
        text = control.read_text()
        line = "rmin_contact         on\n"
        if line not in text:
            raise SystemExit(f"{control}: no '{line.strip()}' line to add rmin_touch after")
        control.write_text(text.replace(line, line + f"rmin_touch           {touch}\n"))
    control = folder / "control.dat"
    control.write_text("".join(f"tune {name} {value}\n" for name, value in tunes(variant).items())
                       + control.read_text())
    return folder


def tunes(variant: str) -> dict[str, Any]:
    """The deck's ``tune`` lines (ddpy.model.control.FormingTuning) that switch off the
    variant's levers."""
    settings = VARIANTS[variant]
    changes: dict[str, Any] = {}
    if settings.get("linear_solver") == "direct":
        changes["reuse_from"] = sys.maxsize  # "auto" never reuses: a factorization each time
    if "whole_step" in settings:
        changes["whole_step"] = settings["whole_step"]
    return changes


def run_variant(variant: str, restart: bool = False) -> dict[str, Any]:
    """Run one variant into results/paper/levers_<variant> and keep its numbers."""
    folder = case_folder(variant)
    output = HERE / "results" / "paper" / f"levers_{variant}"
    print(f"running {variant} ({VARIANTS[variant]}) ...", file=sys.stderr, flush=True)
    return keep(variant, bench.run_case_folder(folder, output=output, verbose=True,
                                               restart=restart))


def keep(variant: str, run: Any) -> dict[str, Any]:
    """The numbers of a variant's run (``run.Run``), merged into the kept runs."""
    numbers = bench.summary("nagata", run)
    numbers["switched_off"] = VARIANTS[variant]
    folder = HERE / "cases" / "paper" / f"levers_{variant}"
    if (folder / "control.dat").exists():
        numbers.update(bench.deck_numbers(folder))
    bench.keep_runs(runs_file(STEM), {variant: numbers}, {variant: run})
    return numbers


def _angles(n: dict[str, Any]) -> list[float]:
    return [*n["theta_deg"], n["beta1_deg"], n["beta2_deg"]]


#: The bending decks' ``newton_force`` before 2026-12-06, which the runs kept before then
#: do not record.
EARLIER_TOLERANCE = 1e-4


def resolution(on: dict[str, Any], off: dict[str, Any]) -> float:
    """The punch force's resolution of two runs converged to their decks' Newton tolerances
    on the force (``newton_force``, relative, the looser of the two) times the largest
    force: two runs that differ by less are the same."""
    tolerance = max(n.get("newton_force", EARLIER_TOLERANCE) for n in (on, off))
    return tolerance * on["max_force_N"]


def verdicts(on: dict[str, Any], off: dict[str, Any]) -> dict[str, Any]:
    """The issue's two checks of a run with the levers (``on``) against one without
    (``off``): the angles of Table 2 within ANGLE_BOUND, the oscillation no larger than
    without the levers by more than the force's resolution."""
    diffs = [a - b for a, b in zip(_angles(on), _angles(off), strict=True)]
    largest = max(abs(d) for d in diffs)
    return {"angle_diffs": diffs, "largest_angle_diff": largest,
            "angles_hold": bool(largest <= ANGLE_BOUND),
            "oscillation_holds": bool(on["oscillation_N"]
                                      <= off["oscillation_N"] + resolution(on, off))}


def report(on: dict[str, Any], variants: dict[str, dict[str, Any]], code: str) -> str:
    """The report: the run with the levers against each variant without some."""
    names = list(variants)
    columns = ["levers on (the paper report's run)", *(LABELS[v] for v in names)]
    runs = [on, *(variants[v] for v in names)]
    lines = [
        "# The speed levers change no answer (bending, paper mesh, Nagata)", "",
        computed_at(code, {"levers on": on.get("code", ""),
                           **{LABELS[v]: variants[v].get("code", "") for v in names}}), "",
        "Written by `benchmarks/cylindrical_bending/levers.py` (its docstring says how each "
        "variant switches the levers off; docs/theory/speed.md says what each lever does). "
        "The deck is the paper report's Nagata deck (docs/benchmarks/"
        "cylindrical_bending_paper.md); the run with the levers is that report's. A wall "
        "time is of a run as it was made, on its threads.", "",
        _row(["", *columns]), _row(["---"] * (len(columns) + 1)),
        _row(["switched off", "-", *(", ".join(f"{k} {v}" for k, v in
                                               variants[n]["switched_off"].items())
                                      for n in names)]),
        _row(["code, threads", *(f"{n.get('code', '')}, {n.get('threads', '')}"
                                 for n in runs)]),
        _row(["run", *(n["status"] for n in runs)]),
        _row(["increments (at the maximum size)",
              *(f"{n['increments']} ({n['full_size_increments']})" for n in runs)]),
        _row(["forming iterations", *(n["iterations"] for n in runs)]),
        _row(["springback iterations", *(n["springback_iterations"] for n in runs)]),
        _row(["LU factorizations", *(n["factorizations"] for n in runs)]),
        _row(["GMRES iterations (older factors)", *(n["krylov_iterations"] for n in runs)]),
        _row(["wall time [min]", *(f"{n['wall_s'] / 60:.1f}" for n in runs)]),
        _row(["per iteration [s]", *(f"{bench._per_iteration(n)[1]:.3f}" for n in runs)]),
        _row(["largest punch force, quarter [N]", *(f"{n['max_force_N']:.2f}" for n in runs)]),
        _row(["oscillation [N]", *(f"{n['oscillation_N']:.4g}" for n in runs)]),
        _row(["oscillation after 20 mm [N]",
              *(f"{n['oscillation_after_20mm_N']:.4g}" for n in runs)]),
        *(_row([name, *(f"{_angles(n)[k]:.2f}" for n in runs)])
          for k, name in enumerate(ANGLES)),
        "", "## The checks", ""]
    for name in names:
        off = variants[name]
        v = verdicts(on, off)
        diffs = ", ".join(f"{a.split(' ')[0]} {d:+.2f}"
                          for a, d in zip(ANGLES, v["angle_diffs"], strict=True))
        lines.append(
            f"- Against {LABELS[name]}: the angles of Table 2 within {ANGLE_BOUND:g} degrees: "
            f"**{'holds' if v['angles_hold'] else 'does not hold'}** (levers on minus off: "
            f"{diffs}; largest {v['largest_angle_diff']:.2f}); the punch force's oscillation "
            f"no worse: **{'holds' if v['oscillation_holds'] else 'does not hold'}** "
            f"({on['oscillation_N']:.4g} N with the levers, {off['oscillation_N']:.4g} N "
            f"without; the force's resolution, newton_force times the largest force: "
            f"{resolution(on, off):.2g} N). With the levers the run takes {on['iterations']} "
            f"forming iterations against {off['iterations']} "
            f"({on['iterations'] / max(off['iterations'], 1) - 1:+.0%}) and "
            f"{on['factorizations']} LU factorizations against {off['factorizations']} "
            f"({on['factorizations'] / max(off['factorizations'], 1) - 1:+.0%})" + (
                f", {on['wall_s'] / 60:.1f} min against {off['wall_s'] / 60:.1f} "
                f"({on['wall_s'] / max(off['wall_s'], 1) - 1:+.0%}) on {on['threads']} "
                "thread(s)." if on["threads"] == off["threads"] else
                "; their wall times are on different threads (the table)."))
    force_diff = {name: _force_difference(on, variants[name]) for name in names}
    lines.append("- The punch force of the two along the stroke (at each stroke of the run "
                 "with the levers, the other run's force interpolated): largest difference "
                 + ", ".join(f"{LABELS[n]} {d:.3g} N ({d / on['max_force_N']:.2%} of the "
                             f"largest force)" for n, d in force_diff.items()) + ".")
    return "\n".join(lines) + "\n"


def _force_difference(on: dict[str, Any], off: dict[str, Any]) -> float:
    a, b = on["curves"], off["curves"]
    other = np.interp(a["stroke"], b["stroke"], b["force"])
    return float(np.max(np.abs(np.asarray(a["force"]) - other)))


def _with_curves(path: Path) -> dict[str, dict[str, Any]]:
    if not path.exists():
        return {}
    return {k: {**e["numbers"], "curves": e["curves"]}
            for k, e in json.loads(path.read_text()).items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--variant", choices=VARIANTS, help="run this variant")
    parser.add_argument("--restart", action="store_true",
                        help="continue the variant's saved run from its checkpoint")
    parser.add_argument("--reuse", action="store_true",
                        help="write the report from the saved runs (no new run)")
    args = parser.parse_args(argv)
    if args.variant and not args.reuse:
        run_variant(args.variant, restart=args.restart)
    saved = {v: HERE / "results" / "paper" / f"levers_{v}" / "results.h5" for v in VARIANTS}
    if args.reuse:  # read the saved runs back into the kept runs
        for variant, path in saved.items():
            if path.exists():
                keep(variant, bench.from_results(path))
    variants = _with_curves(runs_file(STEM))
    on = _with_curves(runs_file("cylindrical_bending_paper")).get("nagata")
    if not variants or on is None:
        print("no kept runs to report: run a variant, and the paper report's Nagata run",
              file=sys.stderr)
        return 1
    out = DOCS / f"{STEM}.md"
    out.write_text(report(on, {v: variants[v] for v in VARIANTS if v in variants},
                          code_version()))
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
