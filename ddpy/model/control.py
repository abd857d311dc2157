"""The settings of an incremental solution, one class each, with the defaults that the decks,
the Python API and the examples share: the r_min increment control (:class:`IncrementLimits`)
and the Newton loop's convergence (:class:`NewtonSettings`). A deck that sets nothing runs
with exactly these (docs/input-format.md lists them with their deck keywords).

The increment policy itself lives here too: :class:`IncrementController` decides each
increment's size from those limits (touch, release, yield, strain, rotation), when an
increment is cut or redone and what the next one tries; its constants are the fields of
:class:`IncrementTuning`, and those of the forming problem's loop and contact (the search's
reach, GMRES on older factors, the line search...) the fields of :class:`FormingTuning`,
which control.dat's ``tune NAME VALUE`` sets (:func:`tuned`).
The measurements behind each default are in docs/theory/contact.md and speed.md."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["FormingTuning", "IncrementController", "IncrementLimits",
           "IncrementTuning", "MAX_INCREMENTS", "NewtonSettings", "Range",
           "check_max_increment", "next_step",
           "tuned", "tuning_default", "tuning_ranges"]

#: Most Newton iterations of an increment, and most redos of one at a release: beyond, a
#: run only spends time (a stalled increment is cut instead).
MAX_ITERATIONS, MAX_REDOS = 1000, 10**6
#: Most increments a phase may take at its largest increment: a max_increment smaller than
#: the travel over this would only keep the process busy (1e-300 mm ran for ever).
MAX_INCREMENTS = 1_000_000
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
      degrees (from the least-squares linear fit of its nodes' displacement increments;
      2 rather than 1 saved the deep drawing 23 % of its iterations, docs/theory/speed.md,
      "The rotation limit");
    - ``yield_tolerance`` (``rmin_yield``): the elasto-plastic transition. A Gauss point
      that has not yielded yet whose elastic trial stress would overshoot the yield stress
      by more than this fraction makes the increment land it on the yield surface (None:
      off); a point that yielded before reloads without a landing (on faceted tools every
      facet edge unloads and reloads the points sliding over it). In a bend a point starts
      to yield in almost every increment: 0.01 landed them one by one
      (docs/input-format.md);
    - ``first_touch`` (``rmin_contact``): a free node that would pass through a tool lands
      on it instead; gaps below ``touch_gap`` times the element size count as touching
      (1e-2: at 1e-3 the paper bending blank's first increment landed a punch node 0.44 um
      away, an increment with forces of the floor's order that took 51 iterations and 35
      LU; docs/theory/speed.md);
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
    rotation_deg: float = 2.0
    yield_tolerance: float | None = 0.1
    first_touch: bool = True
    touch: str = "new"
    touch_gap: float = 1e-2
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
        what = "min_fraction (the smallest increment over the largest)"
        if not self.min_fraction <= 1.0:
            raise ValueError(f"{what} must be at most 1, got {self.min_fraction:.3g}")
        if not self.min_fraction >= MIN_FRACTION:
            raise ValueError(f"{what} must be at least {MIN_FRACTION:g}, got "
                             f"{self.min_fraction:.3g}: below, a failing increment would be "
                             "cut more than 20 times (by half) before the run stops")
        if not self.touch_gap >= 0.0:
            raise ValueError(f"touch_gap must be >= 0, got {self.touch_gap}")
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
    below ``force_tolerance`` times the force scale and the iterate's error (the last
    correction, or less once whole Newton steps contract) below
    ``displacement_tolerance`` times the increment's displacement, scaled up to that of an
    increment of the phase's largest size when it is smaller (cut or limited: a scale that
    does not vanish, docs/theory/contact.md, "The convergence test"); an increment that has not
    converged in ``max_iterations`` is cut by ``cutback`` and tried again. ``penetration``
    (deck ``penetration_limit``): the deepest the blank may lie inside a tool at a
    converged increment, as a fraction of its thickness; a run warns once per tool where
    it does not hold. ``augment`` (deck ``gauss_augmentation``): Gauss-point contact
    carries its pressures from increment to increment and augments them (Uzawa) until the
    limit holds, instead of the plain penalty (docs/theory/contact.md, "Penetration")."""

    force_tolerance: float = 1e-3
    displacement_tolerance: float = 1e-3
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


@dataclass(frozen=True)
class Range:
    """The values a setting takes: from ``low`` to ``high`` (each end open or closed), whole
    numbers only when ``integer``. Its ``text`` is what docs/input-format.md lists."""

    low: float
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    integer: bool = False

    @property
    def text(self) -> str:
        """The range in words: "real > 0", "real in (0, 1]", "integer >= 1"."""
        kind = "integer" if self.integer else "real"
        if self.high == math.inf:
            return f"{kind} {'>' if self.low_open else '>='} {self.low:g}"
        return (f"{kind} in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                f"{')' if self.high_open else ']'}")

    def holds(self, value: object) -> bool:
        """Whether ``value`` is of the kind and lies in the range."""
        if isinstance(value, bool) or not isinstance(
                value, (int, np.integer) if self.integer else (int, float, np.number)):
            return False
        number = float(value)  # type: ignore[arg-type]
        return (math.isfinite(number)
                and (number > self.low if self.low_open else number >= self.low)
                and (number < self.high if self.high_open else number <= self.high))


def check_fields(settings: object, ranges: dict[str, Range]) -> None:
    """ValueError naming the first field of ``settings`` outside its range: "slack must be
    a real >= 1, got 0.9" (a deck's reader puts its key in front and adds file and line)."""
    for name, admissible in ranges.items():
        value = getattr(settings, name)
        if not admissible.holds(value):
            article = "an" if admissible.integer else "a"
            raise ValueError(f"{name} must be {article} {admissible.text}, got {value!r}")


#: The ranges of IncrementTuning's fields (each field of it has one: tests check that).
_INCREMENT_TUNING_RANGES = {
    "slack": Range(1.0),
    "grow_to": Range(0.0, 1.0, low_open=True),
    "regrow": Range(1.0, low_open=True),
    "yield_floor": Range(0.0, 1.0, low_open=True, high_open=True),
    "touch_past": Range(0.0, 1.0, high_open=True),
    "bisect_below": Range(0.0, 1.0, low_open=True, high_open=True),
    "careful_iterations": Range(1, integer=True),
    "release_steps": Range(1, integer=True),
    "release_smallest": Range(0.0, 1.0, low_open=True),
    "max_augmentations": Range(0, integer=True),
}
#: The ranges of FormingTuning's fields but ``increment`` (krylov_tight also at most
#: krylov_loose). A GMRES tolerance of 1 or more accepts any correction (0: none, every
#: correction is then factorized after krylov_max iterations); krylov_max below 1
#: is refused by the core; a whole_step or min_step beyond 1 is a step longer than Newton's.
_FORMING_TUNING_RANGES = {
    "touching": Range(0.0),
    "reuse_from": Range(0, integer=True),
    "krylov_loose": Range(0.0, 1.0, high_open=True),
    "krylov_tight": Range(0.0, 1.0, high_open=True),
    "krylov_last": Range(0.0),
    "krylov_max": Range(1, integer=True),
    "krylov_keep": Range(0, integer=True),
    "whole_step": Range(0.0, 1.0),
    "penetration": Range(0.0, low_open=True),
    "min_step": Range(0.0, 1.0, low_open=True),
    "reach_sizes": Range(0.0, low_open=True),
    "reach_travels": Range(0.0, low_open=True),
    "touch_depth": Range(0.0, low_open=True),
    "hold_step": Range(0.0, low_open=True),
    "search_memory": Range(0, 1, integer=True),
    "single_factors": Range(0, 1, integer=True),
}


@dataclass(frozen=True)
class IncrementTuning:
    """The constants of the increment policy (:class:`IncrementController`), each measured
    where docs/theory/contact.md and speed.md say. To change one for a run, control.dat's
    ``tune increment.NAME VALUE`` or
    ``FormingProblem(..., tuning=FormingTuning(increment=IncrementTuning(...)))``; each
    field's range is in ``_INCREMENT_TUNING_RANGES`` (docs/input-format.md lists them).

    - ``slack``: a strain or rotation increment up to this times its limit is accepted (not
      redone shorter for a few percent);
    - ``grow_to``: after a strain or rotation limit the next increment is sized for this
      share of it; ``regrow``: after a cut an increment grows at most by this factor;
    - ``yield_floor``: the smallest yield tolerance used (a point landed on the yield surface
      lies within rounding of it, and at 0 it would count as elastic and be landed again);
    - ``touch_past``: first touch lands this share of the gap past the surface, so that the
      node is caught in contact;
    - ``bisect_below``: a release interpolated on the augmented pressure before this fraction
      of the increment is not trusted (p << r g: r far from the node's own stiffness biases
      it towards zero); the increment is halved instead;
    - ``careful_iterations``: a careful start (the first increment of a phase whose default
      start failed) may take this many times the deck's max_iterations: its full active-set
      steps open the pairs a blank lying on its tools does not need a few at a time (58
      iterations on the paper's deep drawing blank), once per phase;
    - ``release_steps``: tools lifted at the start of a phase let go of their forces in this
      many steps, each halved while it fails down to ``release_smallest`` of the release;
    - ``max_augmentations``: most Uzawa updates of the Gauss points' pressure multipliers
      within one increment (NewtonSettings.augment, docs/theory/contact.md, "Penetration").
    """

    slack: float = 1.05
    grow_to: float = 0.9
    regrow: float = 2.0
    yield_floor: float = 1e-6
    touch_past: float = 1e-3
    bisect_below: float = 0.1
    careful_iterations: int = 4
    release_steps: int = 4
    release_smallest: float = 1.0 / 1024.0
    max_augmentations: int = 6

    def __post_init__(self) -> None:
        check_fields(self, _INCREMENT_TUNING_RANGES)


@dataclass(frozen=True)
class FormingTuning:
    """The constants of a forming problem's Newton loop and contact, with the increment
    policy's (``increment``): control.dat's ``tune NAME VALUE`` or
    ``FormingProblem(..., tuning=...)``; each field's range is in ``_FORMING_TUNING_RANGES``
    (docs/input-format.md lists them).

    - ``touching``: gap (times the element size) within which an unloaded node counts as
      lying on a tool for the closed predictor of the first iteration: zero up to the
      rounding of the positions;
    - ``reuse_from``: unknowns from which linear_solver "auto" solves with older factors
      (GMRES) between factorizations: below, a factorization costs little more than a few
      solves (docs/theory/linear-solver.md, "Where older factors pay");
    - ``krylov_loose``, ``krylov_tight``: bounds of GMRES's relative tolerance on the older
      factors (of the preconditioned, weighted residual: the correction's relative error);
      the loose bound holds where the residual is above a tenth of the force scale, in
      practice an increment's first corrections (0.05: the deep drawing's paper blank takes
      24 to 28 % fewer factorizations than at 0.01, the bending's about the same count;
      docs/theory/linear-solver.md, "Tolerance");
      ``krylov_last``: a correction that may be the last of its increment (the residual
      near the tolerance) is solved until it leaves a linear residual of this many force
      tolerances (Eisenstat and Walker's 0.1 keeps a tenth; 1 takes fewer factorizations
      in as many Newton iterations; a phase's first increment keeps at most 0.1:
      docs/theory/linear-solver.md, "Tolerance");
      ``krylov_max``: its iterations before it gives up (a factorization costs about 14 on
      the paper's bending blank, 15 on the deep drawing's: docs/theory/speed.md);
      ``krylov_keep``: the most after which the same factors are tried again;
    - ``whole_step``: the line search's whole-step ratio (the core's Loop.whole_step);
    - ``penetration``, ``min_step``: deepest a free node may be pushed into a tool by one
      Newton step, in element sizes, and the shortest step that limit may leave;
    - ``reach_sizes``, ``reach_travels``: a slave node whose nearest admissible point of a
      tool lies farther than max(reach_sizes x element size, reach_travels x the leading
      tool's largest travel of an increment) has no partner on it (a free node, no gap).
      First touch sees a free node once it is nearer than the largest approach of the next
      increment (the tool's travel plus the node's, at most 2 travels), here with a margin
      of 2; without a reach the exact search paired nodes with far patch edges, 20 to 56 mm
      away on the coarse reverse deep drawing (docs/theory/contact.md, "Reach");
    - ``touch_depth``: a force-controlled tool that does not touch the blank at the start
      of a phase is brought this many element sizes into its nearest slave node (a Gauss
      point exactly on the tool carries no pressure, and nothing would hold the tool);
    - ``hold_step``: a force-controlled tool moves at most this share of the search's reach
      in one Newton step (the core's hold_step);
    - ``search_memory``: 1, the contact search of an increment's evaluations starts from
      what the earlier ones found, where that provably gives the same answer (0: every
      evaluation searches afresh; docs/theory/contact.md, "Search memory");
    - ``single_factors``: 1 (the default), where the loop solves with older factors
      (linear_solver "reuse", or "auto" from reuse_from unknowns), the Jacobian factorized
      in single precision (MUMPS's SMUMPS: half the factor memory and traffic), every
      correction then solved by GMRES in double precision on those factors, also right
      after a factorization and in exact and careful solves; where GMRES on fresh single
      factors misses its tolerance (a condition number near 1/eps_single), the problem
      goes back to double factors for good (docs/theory/linear-solver.md,
      "Single-precision factors"); 0: double-precision factors, a factorization's
      correction solved with them directly.
    """

    touching: float = 1e-6
    reuse_from: int = 2_000
    krylov_loose: float = 0.05
    krylov_tight: float = 1e-10
    krylov_last: float = 1.0
    krylov_max: int = 12
    krylov_keep: int = 8
    whole_step: float = 0.5
    penetration: float = 0.02
    min_step: float = 1.0 / 64.0
    reach_sizes: float = 2.0
    reach_travels: float = 4.0
    touch_depth: float = 1e-3
    hold_step: float = 0.5
    search_memory: int = 1
    single_factors: int = 1
    increment: IncrementTuning = field(default_factory=IncrementTuning)

    def __post_init__(self) -> None:
        check_fields(self, _FORMING_TUNING_RANGES)
        if self.krylov_tight > self.krylov_loose:
            raise ValueError(f"krylov_tight must not exceed krylov_loose ({self.krylov_loose:g}),"
                             f" got {self.krylov_tight:g}")
        if not isinstance(self.increment, IncrementTuning):
            raise TypeError(f"increment must be an IncrementTuning, got "
                            f"{type(self.increment).__name__}")


def check_max_increment(max_increment: float, travel: float) -> None:
    """ValueError unless ``max_increment`` > 0 and a phase's ``travel`` (mm) takes at most
    MAX_INCREMENTS of it: the one check, FormingProblem.run's and control.dat's."""
    if not max_increment > 0.0:
        raise ValueError(f"max_increment must be > 0, got {max_increment:g}")
    if travel / max_increment > MAX_INCREMENTS:
        raise ValueError(f"the travel {travel:g} mm in increments of at most {max_increment:g} "
                         f"mm needs at least {travel / max_increment:,.3g} increments; a phase "
                         f"may take at most {MAX_INCREMENTS:,} (expected a larger max_increment "
                         "or a shorter travel)")


def next_step(step: float, nominal: float, reason: str, strain_ratio: float,
              rotation_ratio: float, tuning: IncrementTuning | None = None
              ) -> tuple[float, str]:
    """The trial size of the next increment and what set it, after one of ``step`` that
    ``reason`` limited, whose largest strain and rotation increments were these fractions
    of their limits. As in DD3IMP's r_min, each increment tries the nominal size again:
    the touch, release and yield limits are found before or in the first iteration and
    cost little to apply once more. Two things are remembered: a strain or rotation limit
    is found only after convergence, so the next size is predicted from this increment's
    rates (strain and rotation grow about linearly with the size), to ``grow_to`` (90 %)
    of the limit; and after a cut (divergence) the size at most doubles (``regrow``) per
    increment."""
    tuning = IncrementTuning() if tuning is None else tuning
    grow = tuning.grow_to / max(strain_ratio, rotation_ratio, 1e-12)
    cap = tuning.regrow if reason in ("cut", "regrow") else math.inf
    if min(grow, cap) * step >= nominal:
        return nominal, "max"
    if cap < grow:
        return cap * step, "regrow"
    return grow * step, "strain" if strain_ratio >= rotation_ratio else "rotation"


class IncrementController:
    """The increment policy of one forming phase: the size of each increment trial and what
    set it (``step``, ``reason``: "max", "touch", "release", "yield", "strain",
    "rotation", "cut" or "regrow"), from the r_min ``limits`` (:class:`IncrementLimits`)
    and the Newton settings' cut-back, in phase factors of a nominal (largest) increment
    ``nominal``. The problem measures (how far a free node is from touching, where a
    release falls, the strain and rotation of a converged trial) and asks; the controller
    shortens, cuts, redoes or accepts:

    - before a trial: ``shorten`` by the touch and release-ahead fractions (not after a
      cut: the cut size stands), ``landing`` says the yield tolerance;
    - a trial that lands a yield point: ``shorten`` to it; one that fails: ``cut`` (or
      why the run must stop);
    - a converged trial: ``strain_redo``, ``rotation_redo`` and ``release_redo`` say whether
      it is redone shorter; else ``accept`` sizes the next one (:func:`next_step`).
    """

    def __init__(self, limits: IncrementLimits, cutback: float, nominal: float,
                 tuning: IncrementTuning | None = None) -> None:
        self.limits = limits
        self.tuning = IncrementTuning() if tuning is None else tuning
        self.cutback, self.nominal = cutback, nominal
        #: the smallest increment (phase factor): no limit makes one smaller
        self.smallest = limits.min_fraction * nominal
        self.max_cuts = limits.max_cuts(cutback)
        self.rotation_limit = float(np.radians(limits.rotation_deg))
        self.step, self.reason = nominal, "max"
        self.cuts_in_row = 0
        #: redos at a release of the present increment (IncrementLimits.release_redos)
        self.redos = 0
        #: the first increment's default start failed: careful starts until it converges
        self.careful = False

    def resume(self, step: float, reason: str) -> None:
        """Continue a phase whose next trial was ``step`` set by ``reason``."""
        self.step, self.reason = min(step, self.nominal), reason

    @property
    def looks_ahead(self) -> bool:
        """Whether the touch and release-ahead limits apply to the next trial (not right
        after a cut: it stands as cut)."""
        return self.reason != "cut"

    @property
    def touch(self) -> bool:
        """Whether first touch limits the next trial."""
        return self.limits.first_touch and self.looks_ahead

    def release_ahead(self, has_rate: bool) -> bool:
        """Whether the release limit looks ahead of the next trial (it needs the last
        increment's pressure rate: ``has_rate``)."""
        return self.limits.release is not None and self.looks_ahead and has_rate

    def shorten(self, fraction: float, reason: str) -> None:
        """The next trial ``fraction`` (< 1: else nothing) of its size, ``reason`` setting
        it (touch, release ahead, a yield landing), never below the smallest."""
        if fraction < 1.0:
            self.step, self.reason = max(self.step * fraction, self.smallest), reason

    def landing(self) -> float | None:
        """The yield tolerance of the next trial: None (no landing) when it is off or the
        trial is already the smallest."""
        tolerance = self.limits.yield_tolerance
        if tolerance is None or self.step <= self.smallest:
            return None
        return max(tolerance, self.tuning.yield_floor)

    def start(self, first: bool) -> bool:
        """Whether the trial starts carefully (``first``: the first increment of the
        phase, without a last increment's rate; a careful start stays one only there)."""
        self.careful = self.careful and first
        return self.careful

    def cut(self, factor: float) -> str:
        """A failed trial from phase factor ``factor``: cut the next by ``cutback``, or say
        why the run stops ("cuts": more in a row than ``max_cuts``; "smallest": a cut would
        go below the smallest increment with more of the phase left); "" when cut."""
        self.cuts_in_row += 1
        if self.cuts_in_row > self.max_cuts:
            return "cuts"
        if self.step * self.cutback < self.smallest and 1.0 - factor > self.smallest:
            # Below the smallest increment a run only crawls: cut after cut, each tiny step
            # converging and the next, larger one failing again.
            return "smallest"
        self.step, self.reason = self.step * self.cutback, "cut"
        return ""

    def strain_redo(self, strain: float) -> bool:
        """Whether a converged trial whose largest equivalent strain increment is ``strain``
        is redone shorter (then sized to the limit)."""
        limit = self.limits.strain
        if strain > self.tuning.slack * limit and self.step > self.smallest:
            self.step, self.reason = max(self.step * limit / strain, self.smallest), "strain"
            return True
        return False

    def rotation_redo(self, rotation: float) -> bool:
        """Whether a converged trial whose largest element rotation is ``rotation``
        (radians) is redone shorter (then sized to the limit)."""
        limit = self.rotation_limit
        if rotation > self.tuning.slack * limit and self.step > self.smallest:
            self.step = max(self.step * limit / rotation, self.smallest)
            self.reason = "rotation"
            return True
        return False

    @property
    def checks_release(self) -> bool:
        """Whether a converged trial is checked for a release inside it (the limit is on,
        the trial is not the smallest, and its redos are not used up)."""
        limits = self.limits
        return (limits.release is not None and self.step > self.smallest
                and (limits.release_redos is None or self.redos < limits.release_redos))

    def release_redo(self, release: float) -> bool:
        """Whether a converged trial whose first release falls at ``release`` (a fraction
        of it) is redone, ending just past the release so that the node is free at its end
        (a release within the last ``limits.release`` fraction is accepted)."""
        margin = self.limits.release
        if margin is None or not release < 1.0 - margin:
            return False
        self.step = max(self.step * release * (1.0 + margin / 2.0), self.smallest)
        self.reason = "release"
        self.redos += 1
        return True

    def accept(self, strain: float, rotation: float) -> None:
        """A trial accepted with these largest strain and rotation (radians) increments:
        the next trial's size and reason (:func:`next_step`)."""
        self.cuts_in_row = self.redos = 0
        self.step, self.reason = next_step(self.step, self.nominal, self.reason,
                                           strain / self.limits.strain,
                                           rotation / self.rotation_limit, self.tuning)


def tuning_ranges() -> dict[str, Range]:
    """Every name control.dat's ``tune NAME VALUE`` takes, with its range: the fields of
    FormingTuning, and those of IncrementTuning as ``increment.NAME``."""
    return {**_FORMING_TUNING_RANGES,
            **{f"increment.{name}": r for name, r in _INCREMENT_TUNING_RANGES.items()}}


def tuning_default(name: str) -> float:
    """The default of a tuning name (``tuning_ranges``)."""
    group, _, field_name = name.rpartition(".")
    return getattr(IncrementTuning() if group else FormingTuning(), field_name)


def tuned(values: dict[str, float]) -> FormingTuning:
    """The FormingTuning with these values (names as ``tuning_ranges`` gives them), the rest
    at their defaults; ValueError from the classes' own checks, naming the field as the
    name given (``increment.slack must be ...``); KeyError for a name not in
    ``tuning_ranges``."""
    ranges = tuning_ranges()
    unknown = [name for name in values if name not in ranges]
    if unknown:
        raise KeyError(unknown[0])
    forming = {n: v for n, v in values.items() if "." not in n}
    increment = {n.split(".", 1)[1]: v for n, v in values.items() if "." in n}
    try:
        increment_tuning = IncrementTuning(**increment)
    except ValueError as error:
        raise ValueError(f"increment.{error}") from None
    return FormingTuning(**forming, increment=increment_tuning)
