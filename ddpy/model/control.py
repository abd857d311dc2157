"""The settings of an incremental solution, one class each, with the defaults that the decks,
the Python API and the examples share: the r_min increment control (:class:`IncrementLimits`)
and the Newton loop's convergence (:class:`NewtonSettings`). A deck that sets nothing runs
with exactly these (docs/input-format.md lists them with their deck keywords)."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["IncrementLimits", "NewtonSettings", "next_step"]

#: Most Newton iterations of an increment, and most redos of one at a release: beyond, a
#: run only spends time (a stalled increment is cut instead).
MAX_ITERATIONS, MAX_REDOS = 1000, 10**6
#: Which free nodes first touch lands (IncrementLimits.touch).
TOUCH_RULES = ("new", "every")
#: Ranges of the Newton loop's settings (docs/input-format.md). The relative tolerances:
#: below the lowest the rounding of the sums (1e-16 a term) is all that is left to reduce,
#: above the highest an increment is accepted far from equilibrium. Cut-back factors: below
#: the lowest a cut throws the increment away (1e-300 made the first cut the last), above
#: the highest a failing increment is tried again almost as it was.
TOLERANCE_RANGE = (1e-14, 0.1)
CUTBACK_RANGE = (0.1, 0.9)
#: Lowest r_min strain and rotation limits (rmin_strain, rmin_rotation in degrees): below,
#: every increment is cut to the smallest one. Lowest smallest increment as a share of the
#: largest (min_increment / max_increment): below, a failing increment is cut 20 times and
#: more before the run gives up.
MIN_STRAIN, MIN_ROTATION, MIN_FRACTION = 1e-4, 1e-3, 1e-6


@dataclass(frozen=True)
class IncrementLimits:
    """Limits of the r_min increment control (docs/theory/contact.md). An increment is
    scaled by r_min = min(1, r_i) over:

    - ``strain`` (deck ``rmin_strain``): the largest equivalent strain increment at a
      Gauss point;
    - ``rotation_deg`` (``rmin_rotation``): the largest rigid rotation of an element, in
      degrees (from the least-squares linear fit of its nodes' displacement increments);
    - ``yield_tolerance`` (``rmin_yield``): the elasto-plastic transition. A Gauss point
      elastic at the start of the increment whose elastic trial stress would overshoot the
      yield stress by more than this fraction makes the increment land it on the yield
      surface (None: off). In a bend a point starts to yield in almost every increment:
      0.01 landed them one by one (docs/input-format.md);
    - ``first_touch`` (``rmin_contact``): a free node that would pass through a tool lands
      on it instead; gaps below ``touch_gap`` times the element size count as touching;
    - ``touch`` (``rmin_touch``): which free nodes land: ``"new"`` (the default) only a
      node that opens a new contact zone; a node linked to a node in contact with that
      tool by a chain of element neighbours that all touch within the increment joins the
      contact inside it (the semi-smooth Newton closes it), so a contact front advancing
      over a tool does not end every increment (docs/theory/contact.md, increment
      control). ``"every"``: every free node, as DD3IMP's r_min;
    - ``release`` (``rmin_contact``): a node in contact at the start of the increment and
      released at its end, whose release (interpolated where its augmented pressure
      p - r g reaches zero) falls before the last ``release`` fraction of the increment,
      makes the increment be redone to end just past the release (None: off). A node that
      carries at most ``release_share`` (``rmin_release``) of its tool's normal force at the
      start of the increment is released inside it instead (0: every release limits the
      increment); after ``release_redos`` (``rmin_release_redos``) redos at a release the
      increment is accepted with the release inside it (None: no cap; 0: the limit acts
      ahead only, from the pressure trend: on faceted tools each redo tends to find
      another node released earlier, a cascade that took half of a run's time);
    - ``min_fraction``: no increment is made smaller than this fraction of the nominal one
      (a deck sets it as min_increment / max_increment). A cut that would go below it stops
      the run.
    """

    strain: float = 0.02
    rotation_deg: float = 1.0
    yield_tolerance: float | None = 0.1
    first_touch: bool = True
    touch: str = "new"
    touch_gap: float = 1e-3
    release: float | None = 0.05
    release_share: float = 0.1
    release_redos: int | None = 0
    min_fraction: float = 1e-3

    def __post_init__(self) -> None:
        if not MIN_STRAIN <= self.strain < 1.0:
            raise ValueError(f"strain must lie in [{MIN_STRAIN:g}, 1), got {self.strain}")
        if not MIN_ROTATION <= self.rotation_deg <= 90.0:
            raise ValueError(f"rotation_deg must lie in [{MIN_ROTATION:g}, 90] (degrees), got "
                             f"{self.rotation_deg}")
        if not MIN_FRACTION <= self.min_fraction <= 1.0 or not self.touch_gap >= 0.0:
            raise ValueError(f"min_fraction must lie in [{MIN_FRACTION:g}, 1] and touch_gap be "
                             ">= 0")
        if self.touch not in TOUCH_RULES:
            raise ValueError(f"touch must be one of {', '.join(TOUCH_RULES)}, got "
                             f"{self.touch!r}")
        if not 0.0 <= self.release_share <= 1.0:
            raise ValueError(f"release_share must lie in [0, 1], got {self.release_share}")
        if self.release_redos is not None and not 0 <= self.release_redos <= MAX_REDOS:
            raise ValueError(f"release_redos must lie in 0..{MAX_REDOS:,} or be None (no cap), "
                             f"got {self.release_redos}")
        if self.yield_tolerance is not None and not 0.0 <= self.yield_tolerance < 1.0:
            raise ValueError(f"yield_tolerance must lie in [0, 1) or be None, got "
                             f"{self.yield_tolerance}")
        if self.release is not None and not 0.0 < self.release < 1.0:
            raise ValueError(f"release must lie in (0, 1) or be None, got {self.release}")

    def max_cuts(self, cutback: float) -> int:
        """Cuts in a row (each by ``cutback``) that take the nominal increment down to
        ``min_fraction`` of it: what a failing increment may try before the run stops."""
        return max(1, math.ceil(math.log(1.0 / self.min_fraction) / -math.log(cutback)))


#: The deepest the blank may lie inside a tool, as a fraction of its thickness, past which
#: a run warns unless a deck sets penetration_limit: 1 %, below what a forming engineer
#: reads off a part.
DEFAULT_PENETRATION = 0.01


@dataclass(frozen=True)
class NewtonSettings:
    """Convergence of the Newton loop (deck ``newton_force``, ``newton_displacement``,
    ``max_iterations``, ``cutback``, ``penetration_limit``): converged when the residual is
    below ``force_tolerance`` times the force scale and the correction below
    ``displacement_tolerance`` times the increment's displacement, scaled up to that of an
    increment of the phase's largest size when it is smaller (cut or limited: a scale that
    does not vanish, docs/theory/contact.md, "The convergence test"); an increment that has not
    converged in ``max_iterations`` is cut by ``cutback`` and tried again. ``penetration``
    (deck ``penetration_limit``): the deepest the blank may lie inside a tool at a
    converged increment, as a fraction of its thickness; a run warns once per tool where
    it does not hold. ``augment`` (deck ``gauss_augmentation``): Gauss-point contact
    carries its pressures from increment to increment and augments them (Uzawa) until the
    limit holds, instead of the plain penalty (docs/theory/contact.md, "Penetration")."""

    force_tolerance: float = 1e-4
    displacement_tolerance: float = 1e-4
    max_iterations: int = 25
    cutback: float = 0.5
    penetration: float = DEFAULT_PENETRATION
    augment: bool = False

    def __post_init__(self) -> None:
        low, high = TOLERANCE_RANGE
        for name in ("force_tolerance", "displacement_tolerance"):
            value = getattr(self, name)
            if not low <= value <= high:
                raise ValueError(f"{name} must lie in [{low:g}, {high:g}], got {value}")
        if not (isinstance(self.max_iterations, int)
                and 1 <= self.max_iterations <= MAX_ITERATIONS):
            raise ValueError(f"max_iterations must be an integer in 1..{MAX_ITERATIONS}, got "
                             f"{self.max_iterations}")
        low, high = CUTBACK_RANGE
        if not low <= self.cutback <= high:
            raise ValueError(f"cutback must lie in [{low:g}, {high:g}], got {self.cutback}")
        if not 0.0 < self.penetration < 1.0:
            raise ValueError(f"penetration must lie in (0, 1) (a fraction of the blank's "
                             f"thickness), got {self.penetration}")


def next_step(step: float, nominal: float, reason: str, strain_ratio: float,
              rotation_ratio: float) -> tuple[float, str]:
    """The trial size of the next increment and what set it, after one of ``step`` that
    ``reason`` limited, whose largest strain and rotation increments were these fractions
    of their limits. As in DD3IMP's r_min, each increment tries the nominal size again:
    the touch, release and yield limits are found before or in the first iteration and
    cost little to apply once more. Two things are remembered: a strain or rotation limit
    is found only after convergence, so the next size is predicted from this increment's
    rates (strain and rotation grow about linearly with the size), to 90 % of the limit;
    and after a cut (divergence) the size at most doubles per increment."""
    grow = 0.9 / max(strain_ratio, rotation_ratio, 1e-12)
    cap = 2.0 if reason in ("cut", "regrow") else math.inf
    if min(grow, cap) * step >= nominal:
        return nominal, "max"
    if cap < grow:
        return cap * step, "regrow"
    return grow * step, "strain" if strain_ratio >= rotation_ratio else "rotation"
