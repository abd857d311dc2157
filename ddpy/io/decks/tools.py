"""tools.dat: per tool its description, tool file (read and checked against the description when
ddpy.io.toolfile is available), friction, contact side, augmentation and contact
discretization (with its penalty and Gauss points per face direction).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ddpy.io.decks.lines import (
    BadValue,
    Deck,
    check_arity,
    first_time,
    read_choice,
    read_float,
    read_int,
    read_name,
    read_unit,
    show,
)
from ddpy.model.contact import check_friction
from ddpy.model.tool import CONTACT_DISCRETIZATIONS, check_contact_settings


@dataclass
class _ToolDraft:
    name: str
    line: int
    values: dict[str, Any] = field(default_factory=dict)
    seen: dict[str, int] = field(default_factory=dict)
    model: Any = None


_TOOL_KEYS = ("description", "file", "friction", "contact", "augmentation", "discretization",
              "penalty", "points", "barrier")
_TOOL_REQUIRED = ("description", "file", "friction", "contact")
_DESCRIPTIONS = ("bezier", "nagata", "facets")
#: Most tools of a case: the results file names them in an HDF5 attribute, which holds about
#: 4,000 names at most, and each tool is searched at every Newton iteration.
MAX_TOOLS = 1000


def _contact_setting(key: str, value: Any) -> Any:
    """``value`` of a tool's contact setting ``key`` (discretization, augmentation,
    penalty, points, barrier) checked by the model's one check
    (ddpy.model.tool.check_contact_settings), its message the deck's error."""
    try:
        check_contact_settings(**{key: value})
    except ValueError as error:
        raise BadValue(str(error)) from None
    return value


def _parse_tools(deck: Deck) -> list[_ToolDraft]:
    tools: list[_ToolDraft] = []
    names: dict[str, int] = {}
    tool: _ToolDraft | None = None
    for line in deck.lines:
        key, w = line.key, line.words
        try:
            if key == "tool":
                check_arity(line, "tool NAME", 1)
                if tool is not None:
                    deck.error(tool.line, f"tool '{tool.name}' is not closed: expected 'end' "
                               f"before the next 'tool' (line {line.number})")
                    _finish_tool(deck, tool)
                tool = _ToolDraft(read_name(w[1], "the tool"), line.number)
                if tool.name in names:
                    deck.error(line.number, f"tool '{tool.name}' defined twice (first at line "
                               f"{names[tool.name]})")
                names.setdefault(tool.name, line.number)
                tools.append(tool)
            elif key == "end":
                check_arity(line, "end", 0)
                if tool is None:
                    raise BadValue("'end' without a 'tool NAME' to close")
                _finish_tool(deck, tool)
                tool = None
            elif key in _TOOL_KEYS:
                if tool is None:
                    raise BadValue(f"'{key}' belongs inside a tool: expected 'tool NAME' ... 'end' "
                               "around it")
                if not first_time(deck, tool.seen, line):
                    continue
                if key == "description":
                    check_arity(line, "description bezier|nagata|facets", 1)
                    tool.values[key] = read_choice(w[1], "the description", _DESCRIPTIONS)
                elif key == "file":
                    check_arity(line, "file PATH", 1)
                    path = Path(w[1])
                    tool.values[key] = path if path.is_absolute() else deck.path.parent / path
                elif key == "discretization":
                    check_arity(line, f"discretization {'|'.join(CONTACT_DISCRETIZATIONS)}", 1)
                    tool.values[key] = _contact_setting(key, w[1])
                elif key == "penalty":
                    check_arity(line, "penalty EPS", 1)
                    tool.values[key] = _contact_setting(
                        key, read_float(w[1], "the contact penalty (N/mm^3)"))
                elif key == "barrier":
                    check_arity(line, "barrier FRACTION|off", 1)
                    tool.values[key] = None if w[1] == "off" else _contact_setting(key, read_float(
                        w[1], "the barrier depth (a fraction of the blank's thickness) or off"))
                elif key == "points":
                    check_arity(line, "points N", 1)
                    tool.values[key] = _contact_setting(key, read_int(
                        w[1], "the Gauss points per direction of a blank face"))
                elif key == "augmentation":
                    check_arity(line, "augmentation R", 1)
                    tool.values[key] = _contact_setting(
                        key, read_float(w[1], "the augmentation parameter"))
                elif key == "friction":
                    check_arity(line, "friction MU", 1)
                    mu = read_float(w[1], "friction")
                    try:
                        check_friction(mu)
                    except ValueError as error:
                        raise BadValue(str(error)) from None
                    if mu > 1:
                        deck.warn(line.number, f"friction coefficient {mu:g} is above 1")
                    tool.values[key] = mu
                else:
                    check_arity(line, "contact top|bottom|facing NX NY NZ", 1, 4)
                    side = read_choice(w[1], "the contact side", ("top", "bottom", "facing"))
                    if side == "facing":
                        check_arity(line, "contact facing NX NY NZ", 4)
                        tool.values[key] = (side, read_unit(w[2:], "the facing direction"))
                    else:
                        check_arity(line, f"contact {side}", 1)
                        tool.values[key] = (side, None)
            else:
                where = "in a tool" if tool is not None else "at the top of tools.dat"
                raise BadValue(f"unknown keyword {show(key)} {where}: expected "
                           + ("description, file, friction, contact, augmentation, "
                              "discretization, penalty, points, barrier or end" if tool
                   else "tool"))
        except BadValue as bad:
            deck.error(line.number, str(bad))
    if tool is not None:
        deck.error(tool.line, f"tool '{tool.name}' is not closed: expected 'end' before the "
                   "end of the file")
    if not tools and not deck.errors:
        deck.error(None, "no tool: expected at least one 'tool NAME' ... 'end' block")
    if len(tools) > MAX_TOOLS:
        deck.error(tools[MAX_TOOLS].line, f"tool {MAX_TOOLS + 1:,} of {len(tools):,}: a case "
                   f"has at most {MAX_TOOLS:,} tools")
    return tools


def _finish_tool(deck: Deck, tool: _ToolDraft) -> None:
    """Check a closed tool block: required keywords, the file and its description."""
    forms = {"description": "description bezier|nagata|facets", "file": "file PATH",
             "friction": "friction MU",
             "contact": "contact top|bottom|facing NX NY NZ (the blank surface it touches)"}
    for key in _TOOL_REQUIRED:
        if key not in tool.seen:
            extra = " (a tool with no contact partner)" if key == "contact" else ""
            deck.error(tool.line, f"tool '{tool.name}' has no '{key}'{extra}: expected "
                       f"'{forms[key]}'")
    path = tool.values.get("file")
    if path is None:
        return
    line = tool.seen["file"]
    if not path.exists():
        deck.error(line, f"tool file {path} not found")
        return
    try:
        from ddpy.io import toolfile
    except ImportError:  # the tool file reader is not part of this build
        return
    try:
        model = toolfile.read_tool(path)
    except Exception as error:  # ToolFileError, or anything a broken file provokes
        kind = "" if isinstance(error, ValueError) else f"{type(error).__name__}: "
        deck.error(line, f"cannot read tool file: {kind}{error}")
        return
    description = tool.values.get("description")
    if description is not None and description != model.description and not (
            description == "facets" and model.description == "nagata"):
        deck.error(tool.seen["description"], f"description {description}, but {path.name} is a "
                   f"{model.description} tool file (a nagata file may also be used as facets)")
        return
    tool.model = model
