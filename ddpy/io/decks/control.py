"""control.dat: the title, solver settings (defaults of every phase) and the phases, each with
its type, active tools, motions (move, gap), lead tool, output travels and increments.
"""

from __future__ import annotations

import unicodedata
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ddpy.io.decks.lines import (
    MAX_LENGTH,
    BadValue,
    Deck,
    Line,
    check_arity,
    first_time,
    read_choice,
    read_float,
    read_int,
    read_name,
    read_vector,
    show,
)
from ddpy.model.control import (
    FormingTuning,
    IncrementLimits,
    NewtonSettings,
    tuned,
    tuning_ranges,
)


def _model_setting(key: str, model: type, name: str,
                   read: Callable[[str, str], Any]) -> Callable[[str], Any]:
    """The reader of a deck setting that is a field of a model class (IncrementLimits,
    NewtonSettings): the word is read as a number here, and its range is the class's own
    check, the one place it is written (its message, with the deck's key for the field)."""

    def parse(word: str) -> Any:
        value = read(word, key)
        try:
            model(**{name: value})
        except ValueError as error:
            # The class names its field and Python's None; the deck says the key and "off".
            message = str(error)
            if message.startswith(name):
                message = key + message[len(name):]
            message = message.replace(" or be None (no cap)", " or be off (no cap)")
            raise BadValue(message.replace(" or be None", "")) from None
        return value

    return parse


def _count_or_off(word: str, what: str) -> int | None:
    return None if word == "off" else read_int(word, what)


#: Settings allowed at the top of control.dat (defaults of every phase) and inside a phase.
_SETTINGS: dict[str, Callable[[str], Any]] = {
    # (max_increment's range, and min_increment's against it, are the model's: cross.py)
    "max_increment": lambda w: read_float(w, "max_increment", le=MAX_LENGTH),
    "min_increment": lambda w: read_float(w, "min_increment", le=MAX_LENGTH),
    "rmin_yield": _model_setting("rmin_yield", IncrementLimits, "yield_tolerance", read_float),
    "rmin_strain": _model_setting("rmin_strain", IncrementLimits, "strain", read_float),
    "rmin_rotation": _model_setting("rmin_rotation", IncrementLimits, "rotation_deg",
                                    read_float),
    "rmin_contact": lambda w: read_choice(w, "rmin_contact", ("on", "off")) == "on",
    "rmin_touch": _model_setting("rmin_touch", IncrementLimits, "touch", lambda w, _: w),
    "rmin_release": _model_setting("rmin_release", IncrementLimits, "release_share",
                                   read_float),
    "rmin_release_redos": _model_setting("rmin_release_redos", IncrementLimits,
                                         "release_redos", _count_or_off),
    "newton_force": _model_setting("newton_force", NewtonSettings, "force_tolerance",
                                   read_float),
    "newton_displacement": _model_setting("newton_displacement", NewtonSettings,
                                          "displacement_tolerance", read_float),
    "max_iterations": _model_setting("max_iterations", NewtonSettings, "max_iterations",
                                     read_int),
    "cutback": _model_setting("cutback", NewtonSettings, "cutback", read_float),
    "penetration_limit": _model_setting("penetration_limit", NewtonSettings, "penetration",
                                        read_float),
    "gauss_augmentation": lambda w: read_choice(w, "gauss_augmentation", ("on", "off")) == "on",
    "output_every": lambda w: read_int(w, "output_every", 0, 10**9),
}
_PHASE_KEYS = ("type", "tools", "move", "gap", "force", "lead", "output_at", "increments")
#: Largest force a tool may be held under (N): 1e9 N presses 100,000 t, far past any press.
MAX_FORCE = 1e9
#: Default largest increment: this fraction of the lead tool's travel.
DEFAULT_INCREMENT_FRACTION = 0.01
DEFAULT_OUTPUT_EVERY = 10
#: Most phases of a case: the results file names each phase and its lead tool in an HDF5
#: attribute, which holds about 4,000 names at most (20,000 phases ended a run with "object
#: header message is too large"), and a forming process has a handful.
MAX_PHASES = 1000
#: Longest title (characters): it is written to the results and shown by ParaView.
MAX_TITLE = 1000


@dataclass
class _PhaseDraft:
    name: str
    line: int
    kind: str = "forming"
    tools: list[str] = field(default_factory=list)
    tools_line: int | None = None
    moves: list[tuple[str, tuple[float, float, float], int]] = field(default_factory=list)
    gaps: list[tuple[str, str, float, int]] = field(default_factory=list)
    forces: list[tuple[str, float, bool, int]] = field(default_factory=list)
    lead: tuple[str, int] | None = None
    output_at: tuple[list[float], int] | None = None
    increments: tuple[int, int] | None = None
    settings: dict[str, tuple[Any, int]] = field(default_factory=dict)
    seen: dict[str, int] = field(default_factory=dict)


@dataclass
class _ControlDraft:
    title: str | None = None
    settings: dict[str, tuple[Any, int]] = field(default_factory=dict)
    phases: list[_PhaseDraft] = field(default_factory=list)
    #: ``tune NAME VALUE`` lines: the value and line of each name
    tunes: dict[str, tuple[float, int]] = field(default_factory=dict)
    tuning: FormingTuning = field(default_factory=FormingTuning)


def _parse_control(deck: Deck) -> _ControlDraft:
    draft = _ControlDraft()
    seen: dict[str, int] = {}
    phase: _PhaseDraft | None = None
    for line in deck.lines:
        key = line.key
        try:
            if key == "phase":
                check_arity(line, "phase NAME", 1)
                if phase is not None:
                    deck.error(phase.line, f"phase '{phase.name}' is not closed: expected "
                               f"'end' before the next 'phase' (line {line.number})")
                phase = _PhaseDraft(read_name(line.words[1], "the phase"), line.number)
                draft.phases.append(phase)
            elif key == "end":
                check_arity(line, "end", 0)
                if phase is None:
                    raise BadValue("'end' without a 'phase NAME' to close")
                phase = None
            elif key == "title":
                if phase is not None:
                    raise BadValue("'title' belongs at the top of control.dat, not in a phase")
                if first_time(deck, seen, line):
                    draft.title = _title(line.text[len("title"):].strip())
            elif key == "tune":
                if phase is not None:
                    raise BadValue("'tune' belongs at the top of control.dat (a tuning holds "
                                   "for the whole run), not in a phase")
                _tune(draft, line)
            elif key in _SETTINGS:
                check_arity(line, f"{key} VALUE", 1)
                target = phase.settings if phase is not None else draft.settings
                where = phase.seen if phase is not None else seen
                if first_time(deck, where, line):
                    target[key] = (_SETTINGS[key](line.words[1]), line.number)
            elif key in _PHASE_KEYS:
                if phase is None:
                    raise BadValue(f"'{key}' belongs inside a phase: expected 'phase NAME' ... "
                               "'end' around it")
                _phase_line(deck, phase, line)
            else:
                where = "in a phase" if phase is not None else "at the top of control.dat"
                allowed = (_PHASE_KEYS + ("end",)) if phase is not None else (
                    "title", "tune", "phase")
                raise BadValue(f"unknown keyword {show(key)} {where}: expected one of "
                           f"{', '.join(allowed + tuple(_SETTINGS))}")
        except BadValue as bad:
            deck.error(line.number, str(bad))
    if phase is not None:
        deck.error(phase.line, f"phase '{phase.name}' is not closed: expected 'end' before "
                   "the end of the file")
    _tuning(deck, draft)
    if not draft.phases and not deck.errors:
        deck.error(None, "no phase: expected at least one 'phase NAME' ... 'end' block")
    if len(draft.phases) > MAX_PHASES:
        deck.error(draft.phases[MAX_PHASES].line, f"phase {MAX_PHASES + 1:,} of "
                   f"{len(draft.phases):,}: a case has at most {MAX_PHASES:,} phases")
    return draft


def _tune(draft: _ControlDraft, line: Line) -> None:
    """``tune NAME VALUE``: the name known and given once, the value a number of its kind
    (its range is the tuning classes' own check, in ``_tuning``)."""
    check_arity(line, "tune NAME VALUE", 2)
    name, word = line.words[1], line.words[2]
    ranges = tuning_ranges()
    if name not in ranges:
        raise BadValue(f"unknown tuning name {show(name)}: expected one of "
                       f"{', '.join(ranges)}")
    if name in draft.tunes:
        raise BadValue(f"'tune {name}' given twice (first at line {draft.tunes[name][1]})")
    what = f"tune {name}"
    value = read_int(word, what) if ranges[name].integer else read_float(word, what)
    draft.tunes[name] = (value, line.number)


def _tuning(deck: Deck, draft: _ControlDraft) -> None:
    """The run's FormingTuning from the ``tune`` lines; a value the classes refuse is an
    error at its line, with their message (the field named as the deck names it)."""
    if not draft.tunes:
        return
    try:
        draft.tuning = tuned({name: value for name, (value, _) in draft.tunes.items()})
    except ValueError as error:
        message = str(error)
        # The classes' message starts with the field it is about (krylov_tight's bound
        # names krylov_loose too): the error goes to that field's line.
        name = message.split(" ", 1)[0]
        line = draft.tunes[name][1] if name in draft.tunes else min(
            at for _, at in draft.tunes.values())
        deck.error(line, f"tune {message}")


def _title(text: str) -> str:
    """The title as the results keep it: text without control characters (HDF5 refuses a
    NUL byte in a string), of at most MAX_TITLE characters."""
    if not text:
        raise BadValue("expected 'title TEXT'")
    control = next((c for c in text if unicodedata.category(c) == "Cc" and c != "\t"), None)
    if control is not None:
        what = "a NUL byte" if control == "\0" else f"U+{ord(control):04X}"
        raise BadValue(f"the title holds a control character ({what}): expected printable "
                       "text")
    if len(text) > MAX_TITLE:
        raise BadValue(f"the title has {len(text):,} characters: expected at most "
                       f"{MAX_TITLE:,}")
    return text


def _phase_line(deck: Deck, phase: _PhaseDraft, line: Line) -> None:
    key, words = line.key, line.words
    if key == "type":
        check_arity(line, "type forming|springback", 1)
        if first_time(deck, phase.seen, line):
            phase.kind = read_choice(words[1], "the phase type", ("forming", "springback"))
    elif key == "tools":
        check_arity(line, "tools TOOL...", 1, -1)
        if first_time(deck, phase.seen, line):
            names = [read_name(w, "a tool") for w in words[1:]]
            repeated = sorted({n for n in names if names.count(n) > 1})
            if repeated:
                raise BadValue(f"tool '{repeated[0]}' listed twice")
            phase.tools, phase.tools_line = names, line.number
    elif key == "move":
        check_arity(line, "move TOOL DX DY DZ", 4)
        tool = read_name(words[1], "the tool")
        phase.moves.append((tool, read_vector(words[2:], "the displacement", MAX_LENGTH),
                            line.number))
    elif key == "gap":
        check_arity(line, "gap TOOL OTHER VALUE", 3)
        tool, other = read_name(words[1], "the tool"), read_name(words[2], "the other tool")
        if tool == other:
            raise BadValue(f"a tool cannot keep a gap to itself: expected 'gap TOOL OTHER VALUE' "
                       f"with two tools, got '{tool}' twice")
        gap = read_float(words[3], "the gap", gt=0, le=MAX_LENGTH)
        phase.gaps.append((tool, other, gap, line.number))
    elif key == "force":
        check_arity(line, "force TOOL VALUE [ramp]", 2, 3)
        tool = read_name(words[1], "the tool")
        value = read_float(words[2], "the force (N, pressing the tool on the blank)", gt=0,
                           le=MAX_FORCE)
        if len(words) == 4 and words[3] != "ramp":
            raise BadValue(f"expected 'ramp' or nothing after the force, got {show(words[3])}")
        phase.forces.append((tool, value, len(words) == 4, line.number))
    elif key == "lead":
        check_arity(line, "lead TOOL", 1)
        if first_time(deck, phase.seen, line):
            phase.lead = (read_name(words[1], "the lead tool"), line.number)
    elif key == "output_at":
        check_arity(line, "output_at TRAVEL...", 1, -1)
        if first_time(deck, phase.seen, line):
            values = [read_float(w, "an output travel", gt=0, le=MAX_LENGTH) for w in words[1:]]
            if any(b <= a for a, b in zip(values, values[1:], strict=False)):
                raise BadValue("output_at travels must increase strictly, got "
                           + " ".join(words[1:]))
            phase.output_at = (values, line.number)
    elif key == "increments":
        check_arity(line, "increments N", 1)
        if first_time(deck, phase.seen, line):
            phase.increments = (read_int(words[1], "increments", 1, 1_000_000), line.number)
