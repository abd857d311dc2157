"""material.dat: elasticity, the yield criterion (von Mises, Hill'48 from coefficients or
Lankford coefficients), hardening (Swift, Voce, a table), an optional Armstrong-Frederick
kinematic hardening (mixed hardening) and the rolling direction.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from ddpy.io.case import BlankMaterial
from ddpy.io.decks.lines import (
    BadValue,
    Deck,
    Line,
    check_arity,
    first_time,
    read_choice,
    read_float,
    read_int,
    read_pairs,
    show,
)
from ddpy.model.forming_limits import FLC_MAX_POINTS, FormingLimitCurve
from ddpy.model.material import (
    TABLE_MAX_POINTS,
    ArmstrongFrederick,
    HardeningTable,
    Hill48,
    Material,
    Swift,
    TablePointError,
    Voce,
    check_backstress,
    check_elastic,
)

#: Plausibility bounds of the material (docs/input-format.md): stresses, including the
#: initial yield stress, at most 1e5 MPa (a hundred times the strongest steels); Swift's
#: eps0 at most 10 (a strain: 1e300 made the yield stress infinite).
MAX_STRESS, MAX_EPS0 = 1e5, 10.0
#: Lowest initial yield stress (MPa): lead and soft solders yield at a few MPa; below,
#: the hardening law is not in MPa (Swift K 1e-12, some 1e-13 MPa, was run).
MIN_YIELD = 1.0
#: Young's modulus (MPa): above the largest it is refused, below the smallest a warning
#: asks whether it is in MPa (polymers to tungsten carbide lie between).
MIN_MODULUS, MAX_MODULUS = 1e3, 1e6
#: Hill'48 coefficients at most 100: the uniaxial yield stress along an axis,
#: 1 / sqrt(G + H) etc. times the hardening law's, is then at least a tenth of it.
MAX_HILL = 100.0
#: Lankford coefficients (given, or H/G and H/F of the coefficients) outside this range are
#: warned about: sheet metals lie between about 0.2 and 3.
R_VALUE_RANGE = (0.1, 10.0)
#: The kinematic hardening's rate C_X at most this (Voce's b has the same bound): the
#: backstress saturates within a plastic strain of a few 1e-6.
MAX_KINEMATIC_RATE = 1e6
#: Forming limit table bounds (logarithmic strains): minor strains within +-1, major
#: strains above 0 and at most 2 (a sheet stretched seven times its length).
MAX_FLC_MINOR, MAX_FLC_MAJOR = 1.0, 2.0
_KINEMATIC_FORM = "kinematic armstrong-frederick C VALUE Xsat VALUE"
T = TypeVar("T")


def _parse_material(deck: Deck) -> BlankMaterial | None:
    seen: dict[str, int] = {}
    elastic: tuple[float, float] | None = None
    criterion: tuple[Hill48, str] | None = None
    hardening: Swift | Voce | HardeningTable | None = None
    kinematic: ArmstrongFrederick | None = None
    forming_limit: FormingLimitCurve | None = None
    angle = 0.0
    lines = iter(deck.lines)
    for line in lines:
        key, w = line.key, line.words
        try:
            if key == "elastic":
                if first_time(deck, seen, line):
                    v = read_pairs(line, 1, ("E", "nu"), ("E", "nu"), "elastic E VALUE nu VALUE")
                    # The range is the model's (check_elastic); the deck adds its
                    # plausibility bound on E.
                    elastic = _model(check_elastic,
                                     read_float(v["E"], "Young's modulus E", le=MAX_MODULUS),
                                     read_float(v["nu"], "Poisson's ratio nu"))
                    if elastic[0] < MIN_MODULUS:
                        deck.warn(line.number, f"Young's modulus {elastic[0]:g} MPa is outside "
                                  "1e3 to 1e6 MPa (polymers to tungsten carbide): is it in "
                                  "MPa?")
            elif key == "yield":
                check_arity(line, "yield vonmises|hill48 ...", 1, -1)
                if first_time(deck, seen, line):
                    criterion = _yield(line, deck)
            elif key == "hardening" and len(w) > 1 and w[1] == "table":
                check_arity(line, "hardening table COUNT", 2)
                count = read_int(w[2], "the number of points of the table", 1, TABLE_MAX_POINTS)
                rows = [next(lines, None) for _ in range(count)]
                if first_time(deck, seen, line):
                    hardening = _table(deck, line, rows)
            elif key == "forming_limit":
                check_arity(line, "forming_limit table COUNT", 2)
                read_choice(w[1], "the forming limit curve", ("table",))
                count = read_int(w[2], "the number of points of the forming limit table", 2,
                                 FLC_MAX_POINTS)
                rows = [next(lines, None) for _ in range(count)]
                if first_time(deck, seen, line):
                    forming_limit = _forming_limit(deck, line, rows)
            elif key == "hardening":
                check_arity(line, "hardening swift|voce|table ...", 1, -1)
                if first_time(deck, seen, line):
                    hardening = _hardening(line)
            elif key == "kinematic":
                check_arity(line, _KINEMATIC_FORM, 1, -1)
                if first_time(deck, seen, line):
                    kinematic = _kinematic(line)
            elif key == "rolling_direction":
                check_arity(line, "rolling_direction ANGLE", 1)
                if first_time(deck, seen, line):
                    angle = read_float(w[1], "the rolling direction angle", ge=-360, le=360)
            else:
                raise BadValue(f"unknown keyword {show(key)}: expected elastic, yield, "
                               "hardening, kinematic, rolling_direction or forming_limit")
        except BadValue as bad:
            deck.error(line.number, str(bad))
    for key, form in (("elastic", "elastic E VALUE nu VALUE"),
                      ("yield", "yield vonmises | yield hill48 ..."),
                      ("hardening", "hardening swift ... | voce ... | table COUNT")):
        if key not in seen:
            deck.error(None, f"no '{key}' line: expected '{form}'")
    if "kinematic" in seen and "hardening" not in seen:
        deck.error(seen["kinematic"], "a kinematic hardening needs the isotropic one it is mixed "
                   "with: expected a 'hardening swift ... | voce ... | table COUNT' line too")
    if deck.errors or elastic is None or criterion is None or hardening is None:
        return None
    initial = hardening.initial_yield_stress
    if initial < MIN_YIELD:
        deck.error(seen["hardening"], f"the initial yield stress {initial:.3g} MPa is below "
                   f"{MIN_YIELD:g} MPa: expected the hardening law in MPa")
        return None
    if kinematic is not None:
        try:
            check_backstress(kinematic, hardening)
        except ValueError as error:
            deck.error(seen["kinematic"], f"{error}; the hardening of line {seen['hardening']}")
            return None
    try:
        material = Material(elastic[0], elastic[1], criterion[0], hardening, kinematic)
    except (ValueError, TypeError) as error:
        deck.error(seen["elastic"], f"invalid material: {error}")
        return None
    return BlankMaterial(material, angle, criterion[1], deck.where(seen["yield"]),
                         forming_limit)


def _yield(line: Line, deck: Deck) -> tuple[Hill48, str]:
    kind = read_choice(line.words[1], "the yield criterion", ("vonmises", "hill48"))
    if kind == "vonmises":
        check_arity(line, "yield vonmises", 1)
        return Hill48.von_mises(), "von Mises"
    keys = line.words[2::2]
    try:
        if "r0" in keys or "r45" in keys or "r90" in keys:
            form = "yield hill48 r0 VALUE r45 VALUE r90 VALUE"
            v = read_pairs(line, 2, ("r0", "r45", "r90"), ("r0", "r45", "r90"), form)
            r = {k: read_float(v[k], k) for k in ("r0", "r45", "r90")}
            hill = Hill48.from_r_values(r["r0"], r["r45"], r["r90"])
            text = f"Hill'48 from r0 = {r['r0']:g}, r45 = {r['r45']:g}, r90 = {r['r90']:g}"
        else:
            form = "yield hill48 F VALUE G VALUE H VALUE [L VALUE M VALUE] N VALUE"
            v = read_pairs(line, 2, ("F", "G", "H", "L", "M", "N"), ("F", "G", "H", "N"), form)
            c = {k: read_float(x, f"Hill48 {k}") for k, x in v.items()}
            hill = Hill48(**c)
            text = "Hill'48 " + ", ".join(f"{k} = {x:g}" for k, x in c.items())
            r = {k: hill.H / d for k, d in (("r0", hill.G), ("r90", hill.F)) if d > 0}
    except (ValueError, TypeError) as error:
        raise BadValue(str(error)) from None
    large = {k: x for k in "FGHLMN" if (x := getattr(hill, k)) > MAX_HILL}
    if large:
        raise BadValue(f"Hill'48 {', '.join(f'{k} = {x:.3g}' for k, x in large.items())} above "
                   f"{MAX_HILL:g}: a yield stress below a tenth of the hardening law's along "
                   "an axis (coefficients are normalized so that G + H = 1 for the rolling "
                   "direction)")
    low, high = R_VALUE_RANGE
    odd = {k: x for k, x in r.items() if not low <= x <= high}
    if odd:
        listed = ", ".join(f"{k} = {x:.3g}" for k, x in odd.items())
        deck.warn(line.number, f"Lankford coefficient(s) {listed} outside {low:g} to "
                  f"{high:g} (sheet metals: about 0.2 to 3)")
    return hill, text


def _table_rows(deck: Deck, line: Line, rows: list[Line | None], what: str,
                form: str) -> list[Line] | None:
    """The COUNT lines of a table after its line ``line``; None (an error) when the deck
    ends inside it."""
    if any(row is None for row in rows):
        deck.error(None, f"the deck ends inside the {what} of line {line.number}: expected "
                   f"{len(rows)} lines '{form}'")
        return None
    return [row for row in rows if row is not None]


def _forming_limit(deck: Deck, line: Line, rows: list[Line | None]) -> FormingLimitCurve | None:
    """The COUNT lines ``MINOR MAJOR`` after ``forming_limit table COUNT``; None after an
    error."""
    table = _table_rows(deck, line, rows, "forming limit table", "MINOR MAJOR")
    if table is None:
        return None
    minor: list[float] = []
    major: list[float] = []
    for row in table:
        try:
            check_arity(row, "MINOR MAJOR (a point of the forming limit table, logarithmic "
                        "strains)", 1)
            # Plausibility bounds here; the table's own rules are FormingLimitCurve's.
            minor.append(read_float(row.words[0], "the minor strain", ge=-MAX_FLC_MINOR,
                                    le=MAX_FLC_MINOR))
            major.append(read_float(row.words[1], "the major strain", le=MAX_FLC_MAJOR))
        except BadValue as bad:
            deck.error(row.number, str(bad))
            return None
    return _checked_table(deck, line, table,
                          lambda: FormingLimitCurve.table(minor, major, deck.where(line.number)))


def _table(deck: Deck, line: Line, rows: list[Line | None]) -> HardeningTable | None:
    """The COUNT lines ``EP Y`` after ``hardening table COUNT``; None after an error."""
    strains: list[float] = []
    stresses: list[float] = []
    table = _table_rows(deck, line, rows, "hardening table", "EP Y")
    if table is None:
        return None
    for row in table:
        try:
            check_arity(row, "EP Y (a point of the hardening table)", 1)
            # Plausibility bounds here; the table's own rules are HardeningTable's.
            strains.append(read_float(row.words[0], "the plastic strain EP", le=MAX_EPS0))
            stresses.append(read_float(row.words[1], "the yield stress Y", le=MAX_STRESS))
        except BadValue as bad:
            deck.error(row.number, str(bad))
            return None
    return _checked_table(deck, line, table,
                          lambda: HardeningTable(tuple(strains), tuple(stresses)))


def _checked_table(deck: Deck, line: Line, table: list[Line], build: Callable[[], T]) -> T | None:
    """``build()``, the model's check of a whole table; its error is the deck's at the
    refused point's line (TablePointError) or at the table's header line; None after an
    error."""
    try:
        return build()
    except TablePointError as error:
        deck.error(table[error.point].number, str(error))
        return None
    except ValueError as error:  # the table as a whole
        deck.error(line.number, str(error))
        return None


def _model(check: Callable[..., T], *values: float) -> T:
    """``check(*values)``, the model's own check of a deck value, its ValueError (or
    TypeError) the deck's error at the line being read."""
    try:
        return check(*values)
    except (ValueError, TypeError) as error:
        raise BadValue(str(error)) from None


def _kinematic(line: Line) -> ArmstrongFrederick:
    """``kinematic armstrong-frederick C VALUE Xsat VALUE``."""
    read_choice(line.words[1], "the kinematic hardening law", ("armstrong-frederick",))
    v = read_pairs(line, 2, ("C", "Xsat"), ("C", "Xsat"), _KINEMATIC_FORM)
    return _model(
        ArmstrongFrederick,
        read_float(v["C"], "the kinematic hardening rate C", le=MAX_KINEMATIC_RATE),
        read_float(v["Xsat"], "the kinematic hardening saturation Xsat", le=MAX_STRESS))


def _hardening(line: Line) -> Swift | Voce:
    kind = read_choice(line.words[1], "the hardening law", ("swift", "voce", "table"))
    try:
        if kind == "swift":
            v = read_pairs(line, 2, ("K", "eps0", "n"), ("K", "eps0", "n"),
                       "hardening swift K VALUE eps0 VALUE n VALUE")
            law = Swift(read_float(v["K"], "Swift K"),
                        read_float(v["eps0"], "Swift eps0", le=MAX_EPS0),
                        read_float(v["n"], "Swift n"))
            initial = law.K * law.eps0**law.n
            if not initial <= MAX_STRESS:
                raise BadValue(f"the initial yield stress K eps0^n = {initial:.3g} MPa is beyond "
                           f"{MAX_STRESS:g} MPa: K or eps0 is not in MPa or not a strain")
            return law
        v = read_pairs(line, 2, ("Y0", "Q", "b"), ("Y0", "Q", "b"),
                   "hardening voce Y0 VALUE Q VALUE b VALUE")
        return Voce(read_float(v["Y0"], "Voce Y0", le=MAX_STRESS),
                    read_float(v["Q"], "Voce Q", le=MAX_STRESS),
                    read_float(v["b"], "Voce b", le=MAX_KINEMATIC_RATE))
    except (ValueError, TypeError) as error:
        raise BadValue(str(error)) from None
