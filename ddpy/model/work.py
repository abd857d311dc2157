"""The work behind a run's increments, counted the same way by the forming and the static
problem: what every increment trial of the core's Newton loop spent (``Trial.counters`` and
``Trial.timings``), the rejected trials (cut, or redone shorter by an increment limit)
included."""

from __future__ import annotations

from dataclasses import dataclass, field

from ddpy.model.newton import PARTS, Trial

__all__ = ["Work"]


@dataclass
class Work:
    """Counts of a run's work: increment trials that failed (``cuts``: each was cut and
    tried again, but for the last one of a run that stopped on it, which counts too);
    residual evaluations (line-search trials and extrapolated starts included), Newton
    corrections, LU factorizations, GMRES iterations of the corrections solved with older
    factors instead, Newton steps whose line search fell back on the residual norm
    (``fallbacks``: no step length passed the natural monotonicity test); and the seconds
    the core's loop spent in each part (``timings``: assembly, contact, factorization,
    solve; the rest of a run's time is the caller's to measure)."""

    cuts: int = 0
    evaluations: int = 0
    newton_iterations: int = 0
    factorizations: int = 0
    krylov_iterations: int = 0
    fallbacks: int = 0
    timings: dict[str, float] = field(default_factory=lambda: dict.fromkeys(PARTS, 0.0))

    def count(self, trial: Trial) -> None:
        """Add the work of one increment trial."""
        evaluations, corrections, factorizations, krylov, fallbacks = trial.counters
        self.evaluations += evaluations
        self.newton_iterations += corrections
        self.factorizations += factorizations
        self.krylov_iterations += krylov
        self.fallbacks += fallbacks
        for key, seconds in trial.timings.items():
            self.timings[key] += seconds
