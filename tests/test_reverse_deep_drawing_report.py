"""The reverse deep drawing report (benchmarks/reverse_deep_drawing/run.py) assembled from
synthetic runs: claims, partial runs, the kept-runs file and the figures. No simulation."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "reverse_deep_drawing"
sys.path.insert(0, str(BENCH.parent))  # the benchmarks' shared module
from bench_common import load_module, restart_plan  # noqa: E402

run = load_module(BENCH / "run.py", "drawing_run")

#: Per model: oscillation per stage (N), largest plastic strain, die contact per stage,
#: increments and iterations per stage, wall time (s): facets oscillate, strain more and
#: need twice the increments and time of Nagata; Bezier touches the die with more nodes,
#: most in stage 1, and refining the facets helps the contact more in stage 2.
SYNTHETIC = {
    "bezier": ((10.0, 12.0), 0.60, (80.0, 60.0), (500, 450), (2000, 1800), 120.0),
    "nagata": ((11.0, 12.5), 0.61, (78.0, 59.0), (480, 440), (1900, 1750), 118.0),
    "facets_coarse": ((40.0, 90.0), 0.75, (50.0, 50.0), (1000, 900), (4000, 3500), 250.0),
    "facets_fine": ((20.0, 40.0), 0.68, (55.0, 58.0), (950, 880), (3800, 3400), 230.0),
}


def _end(stage: str, travel: float, ep: float) -> dict[str, Any]:
    return {"stage": stage, "travel_mm": travel, "cup_height_mm": 41.0,
            "flange_radius_mm": [62.0, 60.0, 64.0], "plastic_strain_max": ep,
            "plastic_strain_mean": ep / 3, "thickness_mm": [0.8, 1.2],
            "volume_change": 1e-3, "element_volume_change_max": 2e-3,
            "element_volume_change_at_radius_mm": 40.0, "element_volume_change_strain": 0.3,
            "balance": {"die1": {"reaction_N": 100.0, "mismatch_N": 0.0, "relative": 0.0,
                                 "nodes": 5}},
            "balance_worst": "die1",
            "penetration": {"die1": {"depth_mm": 1e-15, "inside": 0}},
            "penetration_worst": "die1", "nodes_in_contact": {"die1": 5}}


def synthetic_run(model: str, partial: bool = False) -> Any:
    """A run of ``model`` with the numbers of SYNTHETIC; ``partial``: it stopped in stage 2
    at 30 mm."""
    osc, ep, contact, increments, iterations, wall = SYNTHETIC[model]
    stages, curves = {}, {"sections": {}}
    for k, stage in enumerate(run.STAGES):
        full = 40.0 if stage == "stage1" else 42.0
        reached = 30.0 if partial and stage == "stage2" else full
        travel = np.linspace(0.1, reached, 50)
        force = 1e4 * np.sin(np.pi * travel / full) + osc[k] * np.sin(37.0 * travel)
        stages[stage] = {
            "travel_mm": full, "reached_mm": reached, "complete": reached == full,
            "increments": increments[k], "iterations": iterations[k], "cuts": 0,
            "wall_s": 60.0, "times_s": {p: 10.0 for p in run.PARTS},
            "max_force_N": float(force.max()), "oscillation_N": osc[k],
            "oscillation_rel": osc[k] / 1e4, "die": run.DIE[stage],
            "die_contact_mean": contact[k], "die_contact_max": int(contact[k]) + 5,
            "end": _end(stage, reached, ep * (k + 1) / 2)}
        curves[stage] = {"travel": travel.tolist(), "force": force.tolist(),
                         "sizes": np.full(50, 0.1).tolist(), "iterations": [3] * 50,
                         "die_contact": [int(contact[k])] * 50,
                         "penetration": np.linspace(0.0, 0.008, 50).tolist()}
        radius = np.linspace(0.0, 85.0, 20)
        curves["sections"][stage] = {"thickness": [radius.tolist(), (0.98 + 0 * radius).tolist()],
                                     "plastic_strain": [radius.tolist(),
                                                        (ep * radius / 85).tolist()]}
    x, y = np.meshgrid(np.linspace(0, 80, 6), np.linspace(0, 80, 6))
    curves["map"] = {"stage": "stage2", "travel": stages["stage2"]["reached_mm"],
                     "x": x.ravel().tolist(), "y": y.ravel().tolist(),
                     "plastic_strain": (ep * np.hypot(x, y).ravel() / 120).tolist()}
    numbers = {
        "model": model, "status": "partial" if partial else "completed",
        "run_status": "interrupted" if partial else "completed",
        "stopped": "stalled: the lead tool advanced 1e-09 mm" if partial else "",
        "reached": {"stage": "stage2", "travel_mm": stages["stage2"]["reached_mm"]},
        "code": "abc1234", "date": "2026-01-01", "threads": 1,
        "increments": sum(increments), "iterations": sum(iterations), "wall_s": wall,
        "per_iteration_s": {p: 0.01 for p in run.PARTS}, "hexahedra": 768, "stages": stages}
    return run.Run(numbers, curves)


SHAPE = {tool: {model: {"patches": 10, "cad_faces": 2, "min_signed_um": -5.0,
                        "max_signed_um": 9.0 if model == "nagata" else 18.0,
                        "max_angle_deg": 0.5} for model in run.MODELS}
         for tool in run.TOOLS}
FIGURES = {key: f"{key}.png" for key in ("force", "strain_map", "strain_section", "contact",
                                         "increments", "thickness", "penetration")}


def test_claims_hold_on_runs_made_to_hold_them() -> None:
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    verdicts = {text[:3]: verdict for text, verdict, _ in run.claims(numbers)}
    assert verdicts == {f"({c})": "holds" for c in "abcdefgh"}, verdicts


def test_claims_that_do_not_hold() -> None:
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["facets_fine"]["stages"]["stage2"]["oscillation_N"] = 200.0  # refining: worse
    numbers["facets_coarse"]["increments"] = numbers["nagata"]["increments"]
    verdicts = {text[:3]: verdict for text, verdict, _ in run.claims(numbers)}
    assert verdicts["(a)"] == "does not hold" and verdicts["(d)"] == "does not hold"
    assert verdicts["(b)"] == verdicts["(c)"] == "holds"


def test_more_oscillation_in_stage_2_only_beyond_the_smooth_models_spread() -> None:
    """Claim (a)'s "more in stage 2": the coarse facets' excess over the smooth models, as a
    share of the mean force (1e4 N here), must grow by more than the smooth models differ
    (Bezier 10 N against Nagata 11 N in stage 1: 0.01 %), not merely grow."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    coarse = numbers["facets_coarse"]["stages"]["stage2"]
    coarse["oscillation_N"] = 12.5 + 29.0 + 0.5  # excess 0.295 % against 0.290 %
    coarse["oscillation_rel"] = coarse["oscillation_N"] / 1e4
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    assert found["(a)"][0] == "does not hold"
    assert ("0.290 % in stage 1, 0.295 % in stage 2 (larger in stage 2 by more than the "
            "smooth models differ, 0.010 %: no)") in found["(a)"][1]
    coarse["oscillation_N"] = 12.5 + 29.0 + 2.0  # 0.305 %: beyond the spread
    coarse["oscillation_rel"] = coarse["oscillation_N"] / 1e4
    assert {text[:3]: v for text, v, _ in run.claims(numbers)}["(a)"] == "holds"


def test_facets_overestimate_the_strain_only_beyond_the_smooth_models_spread() -> None:
    """Claim (b): a facet model above both smooth ones by less than Bezier and Nagata differ
    from each other does not overestimate (the paper blank's fine facets: +0.0008 against a
    spread of 0.0023)."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    ends = {m: numbers[m]["stages"]["stage2"]["end"] for m in run.MODELS}
    for model, ep in (("bezier", 0.8435), ("nagata", 0.8412), ("facets_coarse", 0.8488),
                      ("facets_fine", 0.8443)):
        ends[model]["plastic_strain_max"] = ep
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    assert found["(b)"][0] == "does not hold"
    assert "(0.0023): no (Faceted-coarse +0.0053, Faceted-fine +0.0008)" in found["(b)"][1]
    # the failure's cause: an excess within the smooth models' spread is not resolved
    assert found["(b)"][1].endswith(
        "cause: Faceted-fine above both smooth models by 0.0008, less than they differ "
        "(0.0023): an excess these runs do not resolve")
    ends["facets_fine"]["plastic_strain_max"] = 0.8460  # above by 0.0025
    found = {text[:3]: verdict for text, verdict, _ in run.claims(numbers)}
    assert found["(b)"] == "holds"
    ends["facets_coarse"]["plastic_strain_max"] = 0.8400  # below both smooth models
    detail = {text[:3]: detail for text, _, detail in run.claims(numbers)}["(b)"]
    assert "cause: Faceted-coarse below the smooth models (-0.0035): not computed" in detail


def test_a_partial_run_leaves_its_claims_not_checked() -> None:
    numbers = {m: synthetic_run(m, partial=m == "facets_coarse").numbers for m in run.MODELS}
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    for claim in ("(a)", "(b)", "(c)", "(d)"):
        assert found[claim][0] == "not checked", claim
        assert "Faceted-coarse partial, stage2 30 of 42 mm" in found[claim][1]
    # the values as far as each run got, the partial one marked
    assert "stage1 oscillation: Bezier 10 N, Nagata 11 N, Faceted-coarse 40 N" in found["(a)"][1]
    assert "Faceted-coarse 90 N (to 30 mm)" in found["(a)"][1]
    assert "stage2 increments: Bezier 450, Nagata 440, Faceted-coarse 900 (to 30 mm)" \
        in found["(d)"][1]


def test_partial_runs_compare_their_effort_over_the_travel_they_all_reached() -> None:
    # The paper's blank: the facet runs stop within stage 1. Claim (d) stays not checked,
    # and compares the counts up to the last whole mm that all three runs reached (7 mm
    # here): the facets' increments and iterations there over Nagata's.
    numbers = {m: synthetic_run(m, partial=m.startswith("facets")).numbers
               for m in run.MODELS}
    mm = np.arange(1, 41)
    by_mm = {"nagata": (10 * mm, 40 * mm), "facets_coarse": (25 * mm[:7], 90 * mm[:7]),
             "facets_fine": (19 * mm[:8], 65 * mm[:8])}
    for m, (increments, iterations) in by_mm.items():
        numbers[m]["stages"]["stage1"]["by_mm"] = {"increments": increments.tolist(),
                                                   "iterations": iterations.tolist()}
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    assert found["(d)"][0] == "not checked"
    assert ("over the first 7 mm of stage1, which all three runs reached, the ratios to "
            "Nagata: Faceted-coarse increments 2.50, Faceted-coarse iterations 2.25, "
            "Faceted-fine increments 1.90, Faceted-fine iterations 1.62 (within 1.5-2.5: "
            "yes; Nagata 70 increments and 280 iterations there)") in found["(d)"][1]
    numbers["facets_fine"]["stages"]["stage1"]["by_mm"]["increments"][6] = 300
    found = {text[:3]: detail for text, _, detail in run.claims(numbers)}
    assert "Faceted-fine increments 4.29" in found["(d)"] and "2.5: no;" in found["(d)"]


def test_a_run_at_other_code_leaves_its_claims_not_checked() -> None:
    # Claims compare tool models at one code: a kept run of older code (another element,
    # another increment control) differs by more than its tool model.
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["facets_fine"]["code"] = "0ld0000"
    assert run.judged_code(numbers) == "abc1234"
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    for claim in "abcdefgh":
        assert found[f"({claim})"][0] == "not checked", claim
    assert ("not at the judged code abc1234: Faceted-fine at code 0ld0000"
            in found["(b)"][1])
    # Two against two: Nagata's code is the judged one.
    numbers["bezier"]["code"] = "0ld0000"
    assert run.judged_code(numbers) == "abc1234"
    numbers["nagata"]["code"] = "0ld0000"
    assert run.judged_code(numbers) == "0ld0000"


def test_a_partial_bezier_run_leaves_the_claims_that_need_it() -> None:
    # Nagata stands for the smooth models in (a); (b) and (c) need Bezier; (d) does not.
    numbers = {m: synthetic_run(m, partial=m == "bezier").numbers for m in run.MODELS}
    found = {text[:3]: (verdict, detail) for text, verdict, detail in run.claims(numbers)}
    assert found["(a)"][0] == found["(d)"][0] == "holds"
    assert "Bezier" not in found["(a)"][1]
    assert found["(b)"][0] == found["(c)"][0] == "not checked"
    assert "Bezier partial, stage2 30 of 42 mm" in found["(b)"][1]
    assert "Nagata" in found["(c)"][1]            # the other smooth model, for comparison


def test_report_states_every_section_and_the_partial_run(tmp_path: Path) -> None:
    runs = {m: synthetic_run(m, partial=m == "nagata") for m in run.MODELS}
    numbers = {m: r.numbers for m, r in runs.items()}
    text = run.report("coarse", numbers, SHAPE, {"nagata": "map.png"}, FIGURES, 1)
    for heading in ("## Runs", "## The tools (a reconstruction)", "## Tool models (Table 5)",
                    "## Punch force (Fig. 17-18)", "## Equivalent plastic strain (Fig. 19)",
                    "## Nodes in contact with the die (Fig. 20)",
                    "## Computational effort (Table 6)", "## The cup", "## Physical checks",
                    "## The claims of the paper", "## Findings"):
        assert heading in text, heading
    assert "**partial**" in text and "stage2 30 of 42 mm" in text
    assert "Nagata is partial" in text
    assert "| **total** |  | **50** | **50** | **50** | **50** | **42** | **386** | **1418** " \
           "| **4672** |" in text
    assert "12925" in text and "3.62 h" in text      # the paper's Table 6
    assert f"`punch2_radius` | {run.make_case.DIMENSIONS.punch2_radius:g}" in text
    assert "not checked" in text
    for name in FIGURES.values():
        assert f"({name})" in text


def test_kept_runs_round_trip_and_figures(tmp_path: Path) -> None:
    runs = {m: synthetic_run(m) for m in ("nagata", "facets_fine")}
    path = tmp_path / "runs.json"
    run.keep_runs(path, runs)
    run.keep_runs(path, {"bezier": synthetic_run("bezier")})  # merged, not replaced
    kept = run.kept_runs(path)
    assert set(kept) == {"nagata", "facets_fine", "bezier"} and all(r.kept for r in kept.values())
    assert kept["nagata"].numbers == runs["nagata"].numbers
    assert kept["nagata"].curves["stage1"]["force"] == pytest.approx(
        runs["nagata"].curves["stage1"]["force"])
    figures = run.make_figures(kept, "test", tmp_path)
    for name in figures.values():
        assert (tmp_path / name).stat().st_size > 1000


def test_a_run_is_stopped_at_its_time_limit_and_says_where() -> None:
    # A run longer than a session (the paper's blank) is stopped at --minutes and reported
    # as far as it got; without a limit the same progress does not stop it.
    class Progress:
        increment, phase, travel, phase_travel, step = 7, "stage1", 1.25, 40.0, 0.1

    watch = run.StallWatch("nagata", minutes=0.0)
    watch.progress(Progress())
    assert watch.stop() and "time limit of 0 min, at stage1 1.2500 mm" in watch.reason
    unlimited = run.StallWatch("nagata")
    unlimited.progress(Progress())
    assert not unlimited.stop()


def test_a_run_stopped_at_its_time_limit_continues_from_its_checkpoint(tmp_path: Path) -> None:
    # The paper's blank runs longer than a session: --restart continues it, and the report
    # says so. Each leg here stops after its first increment (a limit of 0 minutes).
    import datetime

    from ddpy.app.runner import BUILT_IN_CASES

    case = BUILT_IN_CASES["deep-drawing"]
    first = run.run_case_folder(case, tmp_path, minutes=0.0)
    assert first.numbers["increments"] == 1 and first.numbers["continued"] == []
    assert "time limit of 0 min" in first.numbers["stopped"]
    again = run.run_case_folder(case, tmp_path, minutes=0.0, restart=True)
    n = again.numbers
    assert n["increments"] == 2 and n["status"] == "partial"
    assert n["continued"] == [datetime.date.today().isoformat()]
    assert n["code"] == first.numbers["code"] and n["date"] == first.numbers["date"]
    # The second increment starts where the first ended: the punch went on.
    travel = again.curves["stage1"]["travel"]
    assert travel[1] > travel[0] == first.curves["stage1"]["travel"][0]
    lines = run.report("coarse", {"nagata": n}, SHAPE, {"nagata": "map.png"}, FIGURES, 1,
                       "abc").splitlines()
    assert any(line.startswith("| continued from its checkpoint on |") for line in lines)


def test_restart_refuses_a_saved_run_it_cannot_continue_before_any_run(tmp_path: Path) -> None:
    import json

    from ddpy.app.runner import CHECKPOINT, STATUS

    def saved(model: str, status: str, checkpoint: bool) -> Path:
        folder = tmp_path / model
        folder.mkdir()
        (folder / "results.h5").write_bytes(b"")
        (folder / STATUS).write_text(json.dumps({"status": status}))
        if checkpoint:
            (folder / CHECKPOINT).write_bytes(b"")
        return folder / "results.h5"

    results = {"bezier": saved("bezier", "completed", False),
               "nagata": saved("nagata", "interrupted", True),
               "facets_coarse": tmp_path / "facets_coarse" / "results.h5"}
    assert restart_plan(results) == {"bezier": "read", "nagata": "continue",
                                     "facets_coarse": "run"}
    results["facets_fine"] = saved("facets_fine", "failed", False)
    with pytest.raises(SystemExit, match="facets_fine.*no checkpoint"):
        restart_plan(results)


def test_the_soundness_check_reads_its_verdicts_off_the_forces() -> None:
    """The hand check of the reconstruction: forces set at 0.95 of Siebel's estimate pass
    it ("within", "all below" the necking force where the estimate is below it); forces
    above the necking force are said to be so; the stage whose estimate exceeds the
    necking force is named as not shown to be sound."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    estimates = run.stage_estimates({})
    for n in numbers.values():
        for stage in run.STAGES:
            n["stages"][stage]["max_force_N"] = 0.95 * estimates[stage]["siebel_N"]
    lines = [line for line in run.soundness_section(numbers, list(run.MODELS))
             if line.startswith("- stage")]
    assert len(lines) == 2
    for line, stage in zip(lines, run.STAGES, strict=True):
        e = estimates[stage]
        assert "within its 20 %" in line
        assert ("all below it" in line) == (0.95 * e["siebel_N"] < e["neck_N"])
        assert ("not show it to be a sound drawing" in line) == (e["siebel_N"] > e["neck_N"])
    for n in numbers.values():
        n["stages"]["stage1"]["max_force_N"] = 1.5 * estimates["stage1"]["neck_N"]
    first = [line for line in run.soundness_section(numbers, list(run.MODELS))
             if line.startswith("- stage1")][0]
    assert "some above it" in first and "outside its 20 %" in first


def test_the_soundness_check_leaves_out_a_stage_a_run_did_not_complete() -> None:
    """A run stopped in stage 2 has no stage-2 force in the hand check: its largest force
    so far, here far above the necking force, is not the stage's."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["nagata"] = synthetic_run("nagata", partial=True).numbers
    estimates = run.stage_estimates({})
    for n in numbers.values():
        for stage in run.STAGES:
            n["stages"][stage]["max_force_N"] = 0.95 * estimates[stage]["siebel_N"]
    numbers["nagata"]["stages"]["stage2"]["max_force_N"] = 10.0 * estimates["stage2"]["neck_N"]
    lines = run.soundness_section(numbers, list(run.MODELS))
    row = [line for line in lines if line.startswith("| computed, Nagata")][0]
    assert row.rstrip(" |").endswith("-"), row
    second = [line for line in lines if line.startswith("- stage2")][0]
    assert "0.95 to 0.95 of Siebel's estimate (within its 20 %)" in second, second


def test_the_effort_claims_fail_where_the_runs_say_so() -> None:
    """(e)-(h) each turned by one number: the facets as fast as the smooth models; the
    fine facets' contact gain largest in stage 1; the facets' increments within the smooth
    models' spread; the fine facets needing more increments. And (c) on a difference
    within the smooth models' spread: Bezier above the facets by less than Bezier and
    Nagata differ does not count as more."""
    base = {m: synthetic_run(m).numbers for m in run.MODELS}
    verdict = lambda numbers, c: {t[:3]: v for t, v, _ in run.claims(numbers)}[c]  # noqa: E731
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    for m in ("facets_coarse", "facets_fine"):
        numbers[m]["wall_s"] = 119.0
    assert verdict(numbers, "(e)") == "does not hold"
    # the wall time's ratio split into the iterations' and the time per iteration's
    numbers["facets_fine"]["iterations"] = 2 * numbers["nagata"]["iterations"]
    smooth = 0.5 * (numbers["bezier"]["wall_s"] + numbers["nagata"]["wall_s"])
    iterations = 0.5 * (numbers["bezier"]["iterations"] + numbers["nagata"]["iterations"])
    detail = {t[:3]: d for t, _, d in run.claims(numbers)}["(e)"]
    fine = numbers["facets_fine"]["iterations"] / iterations
    assert f"Faceted-fine {fine:.2f} x {119.0 / smooth / fine:.2f}" in detail, detail
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["facets_fine"]["stages"]["stage1"]["die_contact_mean"] = 70.0
    assert verdict(numbers, "(f)") == "does not hold"
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    for m in ("facets_coarse", "facets_fine"):
        for k, stage in enumerate(run.STAGES):
            numbers[m]["stages"][stage]["increments"] = (500, 450)[k]
    assert verdict(numbers, "(g)") == "does not hold"
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["facets_fine"]["increments"] = numbers["facets_coarse"]["increments"] + 1
    assert verdict(numbers, "(h)") == "does not hold"
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["nagata"]["stages"]["stage2"]["die_contact_mean"] = 50.0  # spread 10
    assert verdict(numbers, "(c)") == "does not hold"
    assert all(verdict(base, f"({c})") == "holds" for c in "cefgh")
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["bezier"]["threads"] = 2
    assert verdict(numbers, "(e)") == "not checked"


def test_claim_d_explains_itself_from_what_set_the_increments() -> None:
    """The explanation of (d) is read off the runs' limits: at the largest size for at
    least AT_MAX_SHARE of every run it says the size fixed the count; otherwise it names
    the run and its share below the largest size."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    for m in ("nagata", "facets_coarse", "facets_fine"):
        n = numbers[m]
        for stage in run.STAGES:
            s = n["stages"][stage]
            s["limits"] = {"max_increment": int(0.9 * s["increments"]),
                           "contact_touch": s["increments"] - int(0.9 * s["increments"])}
    text = run.increment_cause(numbers, ("nagata", "facets_coarse", "facets_fine"))
    assert "the increment size, not the contact, fixed their count" in text
    s = numbers["facets_coarse"]["stages"]["stage1"]
    s["limits"] = {"max_increment": 100, "contact_touch": s["increments"] - 100}
    text = run.increment_cause(numbers, ("nagata", "facets_coarse", "facets_fine"))
    assert "fixed their count" not in text and "Faceted-coarse ran" in text
    assert "contact_touch +" in text


def test_failing_effort_claims_name_the_increment_control_only_where_the_limits_show_it(
) -> None:
    """(d), (e), (g) failing: when the contact limits ended under CONTACT_SHARE of each
    facet model's increments, the cause given is the increment control; when they ended
    more, the cause is not computed. (e) splits its cause between the iterations and the
    time per iteration by the runs' own numbers, and names the part of the split that grew."""
    def limited(numbers: dict[str, Any], contact_share: float) -> None:
        for n in numbers.values():
            for s in n["stages"].values():
                touch = int(contact_share * s["increments"])
                s["limits"] = {"rotation": s["increments"] - touch, "contact_touch": touch}

    claims = lambda numbers: {t[:3]: (v, d) for t, v, d in run.claims(numbers)}  # noqa: E731
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    for m in ("facets_coarse", "facets_fine"):
        n = numbers[m]
        for stage in run.STAGES:  # as many increments and iterations as Nagata
            n["stages"][stage]["increments"] = numbers["nagata"]["stages"][stage]["increments"]
            n["stages"][stage]["iterations"] = numbers["nagata"]["stages"][stage]["iterations"]
        n["increments"], n["iterations"] = (numbers["nagata"]["increments"],
                                            numbers["nagata"]["iterations"])
        n["wall_s"] = numbers["nagata"]["wall_s"]
    limited(numbers, 0.02)
    got = claims(numbers)
    for c in ("(d)", "(e)", "(g)"):
        verdict, detail = got[c]
        assert verdict == "does not hold", (c, detail)
        assert "cause: the increment control" in detail, (c, detail)
    assert "Faceted-coarse: the iterations" in got["(e)"][1]
    limited(numbers, 0.3)
    got = claims(numbers)
    for c in ("(d)", "(g)"):
        assert "cause not computed" in got[c][1] and "increment control (" not in got[c][1]
    # The time per iteration as the cause: the coarse facets' contact search doubled.
    numbers["facets_coarse"]["wall_s"] = 0.5 * numbers["nagata"]["wall_s"]
    numbers["facets_coarse"]["per_iteration_s"]["contact"] = 0.03
    detail = claims(numbers)["(e)"][1]
    assert "Faceted-coarse: the time per iteration (0.5" in detail, detail
    assert "most of the difference in contact" in detail, detail


def test_the_shape_claim_reads_where_the_errors_sit() -> None:
    """(i): Nagata's largest positive error on die 1 and negative on punch 2, the fine
    facets' largest about twice Nagata's; moved to another tool, it does not hold."""
    shape = {tool: {m: {"max_signed_um": 5.0, "min_signed_um": -3.0} for m in run.MODELS}
             for tool in run.TOOLS}
    shape["die1"]["nagata"]["max_signed_um"] = 9.6
    shape["punch2"]["nagata"]["min_signed_um"] = -6.2
    shape["die1"]["facets_fine"]["max_signed_um"] = 19.0
    assert run.shape_claim(shape)[1] == "holds"
    shape["holder2"]["nagata"]["max_signed_um"] = 12.0
    assert run.shape_claim(shape)[1] == "does not hold"


def test_the_convergence_table_names_what_does_not_converge_and_why() -> None:
    """Three blanks of one model: the two finest agree within 3 % on every quantity but
    the stage-2 force (+10 %), which is named; the reason reads the runs' setups: the
    same element, contact and code make it the blank's refinement, others no pure mesh
    effect; and the values over the blanks: converging (with the geometric limit of the
    changes) or not, and for blank-holder 1's reaction the fixed gap it is held at."""
    by_mesh = {}
    for k, mesh in enumerate(make_case_meshes()):
        n = synthetic_run("nagata").numbers
        n["discretization"] = "solid-shell, Gauss-point contact"
        for stage in run.STAGES:
            n["stages"][stage]["end"]["balance"] = {
                h: {"reaction_N": 1000.0, "mismatch_N": 0.0, "relative": 0.0, "nodes": 5}
                for h in ("holder1", "holder2")}
            n["stages"][stage]["end"]["nodes_in_contact"]["holder1"] = 5
        if k == 2:
            n["stages"]["stage2"]["max_force_N"] *= 1.10
        by_mesh[mesh] = {"nagata": n}
    lines = run.convergence_section(by_mesh)
    text = "\n".join(lines)
    assert "Not converged between medium and paper: stage2: largest punch force (+10.0 %)" \
        in text
    # The paper blank's deck sets rmin_yield 0.3: its measured effect (0.55 % of the
    # forces) is weighed against the miss.
    assert ("The two runs share their element, contact and code; their decks differ in "
            "`rmin_yield` 0.1 against 0.3, measured to move the tool forces by at most "
            "0.55 % (make_case.SETTING_MOVES), less than the 10.0 % here, so this is the "
            "blank's refinement.") in text
    assert text.count("(outside)") == 1
    moves = run.make_case.SETTING_MOVES
    try:
        run.make_case.SETTING_MOVES = {"rmin_yield": 0.2}
        assert ("`rmin_yield` 0.1 against 0.3 too, whose effect on it is as large as the "
                "change: the blank's refinement or that setting.") in "\n".join(
                    run.convergence_section(by_mesh))
        run.make_case.SETTING_MOVES = {}
        assert "whose effect on it is not measured" in "\n".join(
            run.convergence_section(by_mesh))
    finally:
        run.make_case.SETTING_MOVES = moves
    # Why, from the values over the three blanks: unchanged, then +10 % is no trend
    # toward a limit.
    assert ("- stage2: largest punch force: from blank to blank +0.0 % then +10.0 % "
            "(coarse -> medium -> paper): not converging with the blank (the change "
            "grew)") in text
    # Changes of +25 % then +10 %: converging at 0.4 per refinement, the limit
    # 1.1 + 0.1 x 0.4 / 0.6 of the medium value, +6.1 % from the paper's.
    force = by_mesh["medium"]["nagata"]["stages"]["stage2"]["max_force_N"]
    by_mesh["coarse"]["nagata"]["stages"]["stage2"]["max_force_N"] = force / 1.25
    text = "\n".join(run.convergence_section(by_mesh))
    assert ("from blank to blank +25.0 % then +10.0 % (coarse -> medium -> paper): "
            "converging, each refinement changes it 0.40 times as much as the last; if it "
            f"goes on so, the limit is about {force * (1.1 + 0.1 * 0.4 / 0.6):.4g} (+6.1 % "
            "from the finest)") in text
    # Blank-holder 1's reaction names the fixed gap and the thickened flange it squeezes.
    by_mesh["paper"]["nagata"]["stages"]["stage1"]["end"]["balance"]["holder1"][
        "reaction_N"] = 900.0
    thickest = [by_mesh[m]["nagata"]["stages"]["stage1"]["end"]["thickness_mm"][1]
                for m in make_case_meshes()]
    text = "\n".join(run.convergence_section(by_mesh))
    assert "- stage1: holder1's reaction: from blank to blank +0.0 % then -10.0 %" in text
    assert "Blank-holder 1 is held at a fixed gap of 1.13 mm, so its reaction" in text
    # The same squeeze on every blank, the reaction changing: the data do not show it.
    assert ("It does not follow the squeeze from blank to blank (the thickest sheet at the "
            "stage's end " + " / ".join(f"{t:.4g}" for t in thickest) + " mm, "
            "70.0 / 70.0 / 70.0 um beyond the gap; nodes under it 5 / 5 / 5), so these runs "
            "do not show what sets its size on each blank: not explained.") in text
    # A reaction that grows and falls with the squeeze is shown set by it.
    for mesh, thick, reaction in zip(make_case_meshes(), (1.14, 1.16, 1.135),
                                     (1000.0, 1100.0, 900.0), strict=True):
        end = by_mesh[mesh]["nagata"]["stages"]["stage1"]["end"]
        end["thickness_mm"] = [0.8, thick]
        end["balance"]["holder1"]["reaction_N"] = reaction
    text = "\n".join(run.convergence_section(by_mesh))
    assert "10.0 / 30.0 / 5.0 um beyond the gap" in text
    assert "It follows the squeeze from blank to blank (" in text
    for mesh in make_case_meshes():
        end = by_mesh[mesh]["nagata"]["stages"]["stage1"]["end"]
        end["thickness_mm"] = [0.8, 1.2]
        end["balance"]["holder1"]["reaction_N"] = 1000.0
    by_mesh["coarse"]["nagata"]["stages"]["stage2"]["max_force_N"] = force
    # The decks' own settings per blank are stated, from make_case.
    assert ("Deck settings that differ between the blanks (coarse / medium / paper): "
            "`max_increment` 0.5 / 0.25 / 0.25; `rmin_yield` 0.1 / 0.1 / 0.3") in text
    by_mesh["paper"]["nagata"]["discretization"] = "hexahedron, node-to-surface contact"
    assert "no pure mesh effect" in "\n".join(run.convergence_section(by_mesh))
    by_mesh["paper"]["nagata"]["stages"]["stage2"]["max_force_N"] /= 1.10
    assert "Every quantity of medium and paper agrees" in "\n".join(
        run.convergence_section(by_mesh))
    # A finest run that stopped in stage 1 compares nothing: the table must not say it
    # agrees.
    by_mesh["paper"]["nagata"]["stages"]["stage1"]["complete"] = False
    by_mesh["paper"]["nagata"]["stages"]["stage2"]["complete"] = False
    text = "\n".join(run.convergence_section(by_mesh))
    assert "agrees" not in text
    assert ("Not compared between medium and paper (a run did not reach where it is "
            "measured): stage1: largest punch force, stage1: cup height") in text


def make_case_meshes() -> tuple[str, ...]:
    return ("coarse", "medium", "paper")


def test_a_failing_contact_claim_names_the_cause_the_runs_show() -> None:
    """(c) and (f), when they fail, weigh the count's change with the contact's
    discretization (Nagata at DD3IMP's element and contact, make_case.REFERENCE) against
    its change with the tool model: a count three times another's at DD3IMP's
    discretization names the code's discretization; the same count there clears it; no
    such run leaves the cause not computed."""
    reference = run.make_case.REFERENCE
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    numbers["nagata"]["stages"]["stage2"]["die_contact_mean"] = 50.0  # (c) fails
    numbers["facets_fine"]["stages"]["stage1"]["die_contact_mean"] = 70.0  # (f) fails
    detail = {t[:3]: d for t, _, d in run.claims(numbers)}
    assert "cause: not computed" in detail["(c)"] and "cause: not computed" in detail["(f)"]
    numbers[reference] = synthetic_run("nagata").numbers
    for k, stage in enumerate(run.STAGES):
        numbers[reference]["stages"][stage]["die_contact_mean"] = (26.0, 20.0)[k]
    detail = {t[:3]: d for t, _, d in run.claims(numbers)}
    for claim in ("(c)", "(f)"):
        assert "cause the data show is the code's discretization" in detail[claim], claim
        assert "stage1: Nagata 78.0 nodes at the defaults, 26.0 at DD3IMP's" in detail[claim]
    for k, stage in enumerate(run.STAGES):
        numbers[reference]["stages"][stage]["die_contact_mean"] = (78.0, 50.0)[k]
    detail = {t[:3]: d for t, _, d in run.claims(numbers)}
    assert "not the cause" in detail["(c)"]
    base = {m: synthetic_run(m).numbers for m in run.MODELS}
    assert "cause" not in {t[:3]: d for t, _, d in run.claims(base)}["(c)"]


def test_the_shape_claim_names_the_reconstruction_where_the_tools_differ() -> None:
    """(i) failing on the negative error's tool: holder 2 and punch 2, both shaped
    otherwise than the paper's (make_case.TABLE5_NOT_MET), name the reconstruction; the
    positive error moved from die 1 to punch 1, two tools recorded as the paper's, names
    neither shape nor meshing but the code."""
    shape = {tool: {m: {"max_signed_um": 5.0, "min_signed_um": -1.0} for m in run.MODELS}
             for tool in run.TOOLS}
    shape["die1"]["nagata"]["max_signed_um"] = 9.6
    shape["holder2"]["nagata"]["min_signed_um"] = -3.0
    shape["die1"]["facets_fine"]["max_signed_um"] = 19.0
    verdict, detail = run.shape_claim(shape)[1:]
    assert verdict == "does not hold"
    assert "negative errors by tool: holder2 -3.00 um" in detail
    assert "cause: the reconstruction (punch2: our flat end" in detail
    assert run.make_case.TABLE5_NOT_MET[("holder2", "nagata")] in detail
    shape["holder2"]["nagata"]["min_signed_um"] = -1.0
    shape["punch2"]["nagata"]["min_signed_um"] = -3.0
    shape["punch1"]["nagata"]["max_signed_um"] = 12.0
    verdict, detail = run.shape_claim(shape)[1:]
    assert verdict == "does not hold" and "negative errors" not in detail
    assert "positive errors by tool: punch1 12.00 um, die1 9.60 um" in detail
    assert "the code's interpolation is to be checked" in detail
    assert "largest error is on" not in detail  # the ratio holds: 19.0 / 12.0
    shape["holder1"]["facets_fine"]["min_signed_um"] = -40.0  # 40 / 12: not about twice
    detail = run.shape_claim(shape)[2]
    assert "the fine facets' largest error is on holder1, Nagata's on punch1" in detail
    assert "cause not computed" in detail


def test_claim_d_lists_limits_of_equal_weight_by_name() -> None:
    """Two limits that differ from Nagata's by as many increments come in their names'
    order, not in the order of a set's string hashes (which changes between processes)."""
    numbers = {m: synthetic_run(m).numbers for m in run.MODELS}
    for m in ("nagata", "facets_coarse", "facets_fine"):
        for stage in run.STAGES:
            numbers[m]["stages"][stage]["limits"] = {
                "yield": 5, "strain": 5 if m == "nagata" else 2,
                "rotation": 1 if m == "nagata" else 4}
    text = run.increment_cause(numbers, ("nagata", "facets_coarse", "facets_fine"))
    assert "Faceted-coarse against Nagata: rotation +6, strain -6;" in text, text


def _timed(wall_s: float, threads: int = 2, status: str = "completed",
           iterations: int = 3650) -> dict[str, Any]:
    numbers = {**synthetic_run("nagata").numbers, "wall_s": wall_s, "threads": threads,
               "status": status, "iterations": iterations, "factorizations": 100,
               "krylov_iterations": 700, "lu_s": 0.05, "peak_memory_mb": 900.0,
               "discretization": "solid-shell, Gauss-point contact", "code": "def5678"}
    return run.timing_record(numbers, "paper", 2, "Some CPU", 2.1)


def test_the_timed_run_is_judged_against_the_target_and_its_column(tmp_path: Path) -> None:
    numbers = {"nagata": synthetic_run("nagata").numbers}  # 3650 iterations, 920 increments
    assert "Not measured" in "\n".join(run.timing_section(None, numbers, "paper"))
    limit = run.TIMING_TARGET_MIN * 60.0
    met = "\n".join(run.timing_section(_timed(limit - 60.0), numbers, "paper"))
    assert "**Target (at most 60 min alone on the machine, both stages): met**" in met
    assert "59.0 min" in met and "def5678" in met and "Some CPU" in met
    # per iteration 5 x 0.01 s over one LU of 0.05 s
    assert "| per iteration / one LU | 1.00 |" in met
    assert "so the same computation" in met
    for timed in (_timed(limit + 60.0), _timed(limit - 60.0, threads=1),
                  _timed(limit - 60.0, status="partial")):
        assert ": not met**" in "\n".join(run.timing_section(timed, numbers, "paper"))
    unrecorded = {**_timed(limit), "load_average": None}
    assert "load average not recorded" in "\n".join(
        run.timing_section(unrecorded, numbers, "paper"))
    other = "\n".join(run.timing_section(_timed(limit, iterations=3000), numbers, "paper"))
    assert "another computation" in other and "3650 iterations" in other
    assert "the code moved between them" in other
    numbers["nagata"]["code"] = "def5678"  # the timed run's code, on other threads
    other = "\n".join(run.timing_section(_timed(limit, iterations=3000), numbers, "paper"))
    assert "the same code on another number of threads" in other, other
    # the record lives in the runs file beside the kept runs, which skip it
    path = tmp_path / "runs.json"
    run.keep_runs(path, {"nagata": synthetic_run("nagata")})
    run.keep_timing(path, _timed(limit))
    run.keep_runs(path, {"bezier": synthetic_run("bezier")})
    assert set(run.kept_runs(path)) == {"nagata", "bezier"}
    assert run.kept_timing(path) == _timed(limit)
    text = run.report("paper", numbers, SHAPE, {"nagata": "map.png"}, FIGURES, 2,
                      timing=run.kept_timing(path))
    assert "### Speed at the defaults, alone on the machine" in text
