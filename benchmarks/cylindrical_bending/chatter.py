"""The punch force chatter of bending runs (docs/theory/contact.md, Gauss-point contact):
for each results folder, the RMS of the punch force minus its moving mean over +-0.5 mm of
stroke (the mean of the increments within the window), from 3 mm to the end of forming,
over the mean force there; the force at 1, 5, 10 and 20 mm; increments, Newton iterations,
time by part; the flange angles after forming and springback (beta_1, beta_2).

    python benchmarks/cylindrical_bending/chatter.py NAME=RESULTS_DIR ...
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ddpy.io.results import ResultsReader
from ddpy.studies.bending import force_oscillation, line_angle

#: strokes (mm) at which the punch force is reported
STROKES = (1.0, 5.0, 10.0, 20.0)
#: the material beyond the die shoulder at the start: the free flange (as run.FLANGE_X)
FLANGE_X = 45.0


def chatter(stroke: np.ndarray, force: np.ndarray, start: float = 3.0) -> tuple[float, float]:
    """RMS of force minus its moving mean (order-0 smooth_curve over a 1 mm window) from
    ``start``, over the mean force there; and that mean force."""
    mean = float(np.mean(force[stroke >= start]))
    return force_oscillation(stroke, force, 1.0, order=0, start=start) / mean, mean


def measure(folder: Path) -> dict[str, float | str]:
    """The numbers of one run's results.h5."""
    with ResultsReader(folder / "results.h5") as r:
        history = r.history()
        forming = history["phase"] == 0
        stroke = history["travel"][forming]
        force = r.tool_force("punch")[forming][:, 2]
        frames = r.frames
        formed = max((f for f in frames if f.phase == 0), key=lambda f: f.increment)
        sprung = frames[-1] if frames[-1].phase == 1 else None
        initial = r.nodes
        flange = initial[:, 0] >= FLANGE_X - 1e-9
        beta1 = line_angle(r.field("coordinates", formed.index)[flange], along=2, up=0)
        beta2 = (line_angle(r.field("coordinates", sprung.index)[flange], along=2, up=0)
                 if sprung is not None else float("nan"))
        value, mean = chatter(stroke, force)
        out: dict[str, float | str] = {
            "chatter_percent": 100.0 * value, "mean_force": mean,
            "increments": int(forming.sum()),
            "iterations": int(history["iterations"][forming].sum()),
            "time_s": float(history["time_total"][forming].sum()),
            "end_stroke": float(stroke[-1]), "beta1": beta1, "beta2": beta2}
        for key in ("time_assembly", "time_contact", "time_factorization"):
            if key in history:
                out[key] = float(history[key][forming].sum())
        for s in STROKES:
            out[f"F{s:g}"] = float(np.interp(s, stroke, force)) if stroke[-1] >= s else \
                float("nan")
        return out


def main(argv: list[str]) -> int:
    for item in argv:
        name, _, folder = item.partition("=")
        numbers = measure(Path(folder))
        print(name, " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                             for k, v in numbers.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
