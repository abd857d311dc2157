"""``ddpy convert``: an Abaqus / CalculiX forming model (.inp) to a ddpy case folder
(docs/abaqus-import.md).

:func:`convert_inp` reads the model (:func:`ddpy.io.inp_model.read_inp`, which refuses what
it cannot map, naming file and line), writes the five decks, and the tools' faces as
Nagata and facet tool files (:func:`ddpy.cad.mesh_tools.build_surface_tool_models`); the
case's tools.dat names the facets (the tools as given) or, with ``tools="nagata"``, the
Nagata patches smoothed over them.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ddpy.cad.mesh_tools import build_surface_tool_models
from ddpy.cad.surface_mesh import SurfaceMesh
from ddpy.io.decks import DECKS
from ddpy.io.inp_model import InpModel, InpTool, read_inp
from ddpy.model.control import MIN_FRACTION

__all__ = ["STAMP", "TOOL_MODELS", "Conversion", "convert_command", "convert_inp", "deck_texts",
           "source_digest"]

#: The file in a converted case that records what it was converted from: the input file's
#: digest (with its includes) and the options; ``ddpy run MODEL.inp`` reuses the case only
#: when both are unchanged.
STAMP = ".ddpy-converted.json"

#: What tools.dat may name: the faces as given, or Nagata patches over them.
TOOL_MODELS = ("facets", "nagata")
#: The blank's element by Abaqus type: the incompatible-mode brick becomes the solid-shell
#: (enhanced strains, free of shear locking in bending); C3D8 and C3D8R the mean-dilatation
#: hexahedron.
ELEMENTS = {"C3D8": "hexahedron", "C3D8R": "hexahedron", "C3D8I": "solid-shell"}
_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclass
class Conversion:
    """What convert_inp wrote: the case folder, the model read, the notes (what was ignored,
    each with its file:line)."""

    folder: Path
    model: InpModel
    notes: list[str]


def _ranges(ids: Sequence[int]) -> str:
    parts, ids = [], sorted(ids)
    start = prev = ids[0]
    for i in [*ids[1:], None]:
        if i is not None and i == prev + 1:
            prev = i
            continue
        parts.append(str(start) if start == prev else f"{start}-{prev}")
        if i is not None:
            start = prev = i
    return " ".join(parts)


def _number(value: float) -> str:
    return f"{value:.10g}"


def deck_texts(model: InpModel, tools: str = "facets", element: str | None = None
               ) -> dict[str, str]:
    """The five decks of the case of ``model`` (tools.dat naming tools/<name>.<tools>.tool)."""
    source = model.path.name
    head = f"# ddpy {{}} deck, converted from {source} by ddpy convert.  Units mm, N, MPa.\n"
    element = element or ELEMENTS[model.element_type]
    mesh = [head.format("mesh"),
            f"# The blank's {model.element_type} elements, Abaqus ids (docs/abaqus-import.md).",
            f"normal   {model.normal}", f"element  {element}", f"nodes {len(model.nodes)}"]
    mesh += [f"  {n} " + " ".join(_number(c) for c in xyz) for n, xyz in model.nodes.items()]
    mesh += [f"hexahedra {len(model.elements)}"]
    mesh += [f"  {e} " + " ".join(map(str, nodes)) for e, nodes in model.elements.items()]

    bc = [head.format("boundary")]
    for name, ids in model.nodesets.items():
        bc.append(f"nodeset  {name}  ids {_ranges(ids)}")
    for name, components, phases in model.constraints:
        bc.append(f"fix      {name}  {components}" + (f"  phase {' '.join(phases)}"
                                                       if phases else ""))

    material = [head.format("material"), "elastic    E " + _number(model.elastic[0]) + "  nu "
                + _number(model.elastic[1]), "yield      vonmises",
                f"hardening  table {len(model.hardening)}      # plastic strain, yield stress"]
    material += [f"  {_number(ep)} {_number(y)}" for ep, y in model.hardening]

    tool_lines = [head.format("tools")]
    for t in model.tools:
        contact = t.side if t.facing is None else \
            "facing " + " ".join(_number(v) for v in t.facing)
        tool_lines += [f"tool {t.name}                      # {t.where}",
                       f"  description     {tools}",
                       f"  file            tools/{t.name}.{tools}.tool",
                       f"  friction        {_number(t.friction)}",
                       f"  contact         {contact}",
                       f"  discretization  {t.discretization}", "end", ""]

    control = [head.format("control"), f"title  {model.title}", ""]
    for p in model.phases:
        control.append(f"phase {p.name}                      # {p.where}")
        control.append(f"  type  {p.kind}")
        if p.kind == "springback":
            control += [f"  increments  {p.increments}", "end", ""]
            continue
        control.append(f"  tools  {' '.join(p.tools)}")
        for name, move in p.moves.items():
            control.append(f"  move   {name}  " + " ".join(_number(v) for v in move))
        travel = max(float(np.linalg.norm(m)) for m in p.moves.values())
        if p.max_fraction is not None:
            largest = travel * min(p.max_fraction, 1.0)
            control.append(f"  max_increment  {_number(largest)}    # *STATIC's largest "
                           "increment")
            if p.min_fraction is not None and p.min_fraction <= p.max_fraction:
                # Abaqus takes 1e-8 of the period and less; the decks, a millionth of the
                # largest increment at least.
                smallest = max(travel * p.min_fraction, largest * MIN_FRACTION)
                raised = "    # raised to max_increment / 1e6" \
                    if smallest > travel * p.min_fraction else ""
                control.append(f"  min_increment  {_number(smallest)}{raised}")
        control += ["end", ""]
    return {"mesh.dat": "\n".join(mesh) + "\n", "bc.dat": "\n".join(bc) + "\n",
            "material.dat": "\n".join(material) + "\n", "tools.dat": "\n".join(tool_lines),
            "control.dat": "\n".join(control)}


def _surface(tool: InpTool) -> SurfaceMesh:
    ids = sorted(tool.points)
    index = {n: i for i, n in enumerate(ids)}
    faces = np.array([[index[n] if n >= 0 else -1 for n in f] for f in tool.faces],
                     dtype=np.int64)
    return SurfaceMesh(tool.source or Path(tool.where.rsplit(":", 1)[0]), "Abaqus",
                       np.array([tool.points[n] for n in ids], dtype=np.float64), faces,
                       np.ones(len(faces), dtype=np.int64), np.array(tool.lines, dtype=np.int64),
                       {1: tool.name})


def _blank_side(tool: InpTool, normal: str) -> tuple[float, float, float]:
    """Where the blank lies seen from the tool: below a tool on its top, etc."""
    if tool.facing is not None:
        return tuple(-v for v in tool.facing)  # type: ignore[return-value]
    axis = _AXES[normal]
    sign = -1.0 if tool.side == "top" else 1.0
    return tuple(sign * v for v in axis)  # type: ignore[return-value]


def convert_inp(inp: str | os.PathLike[str], folder: str | os.PathLike[str],
                tools: str = "facets", element: str | None = None,
                overwrite: bool = False) -> Conversion:
    """Write the case folder of an Abaqus / CalculiX forming model. Raises DeckError (the
    model cannot be mapped), MeshFileError (a tool surface cannot become a tool model) or
    ValueError (options, an occupied folder)."""
    if tools not in TOOL_MODELS:
        raise ValueError(f"tools must be one of {', '.join(TOOL_MODELS)}, got '{tools}'")
    if element not in (None, "hexahedron", "solid-shell"):
        raise ValueError(f"element must be hexahedron or solid-shell, got '{element}'")
    out = Path(folder)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: a file is there; the case must be a folder")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise ValueError(f"{out}: the folder is not empty (give --force to write the case "
                         "into it)")
    model = read_inp(inp)
    texts = deck_texts(model, tools, element)
    out.mkdir(parents=True, exist_ok=True)
    for t in model.tools:
        build_surface_tool_models(_surface(t), out / "tools", t.name,
                                  blank_side=_blank_side(t, model.normal))
    for name in DECKS:
        (out / name).write_text(texts[name])
    stamp = {"source": str(Path(inp).name), "sha256": source_digest(model.sources),
             "tools": tools, "element": element}
    (out / STAMP).write_text(json.dumps(stamp, indent=1) + "\n")
    return Conversion(out, model, list(model.ignored))


def source_digest(paths: Sequence[Path]) -> str:
    """The SHA-256 of an input file and the files it includes (names and contents)."""
    digest = hashlib.sha256()
    for path in sorted(set(paths)):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _reuse(inp: str, out: Path, tools: str, element: str | None) -> str | None:
    """Why the converted case ``out`` cannot serve ``ddpy run inp`` (None: it can)."""
    from ddpy.io.inp_cards import read_cards

    again = f"convert again with 'ddpy convert {inp} {out} --force' (which overwrites any " \
        "edits in the case)"
    try:
        stamp = json.loads((out / STAMP).read_text())
        recorded = (stamp["sha256"], stamp["tools"], stamp["element"])
    except (OSError, ValueError, KeyError, TypeError):
        return f"{out} holds something else than a case converted by ddpy: move it away, " \
            "or convert into another folder with 'ddpy convert'"
    sources = [Path(inp)] + [card.path for card in read_cards(inp)]
    if recorded[0] != source_digest(sources):
        return f"{inp} changed since {out} was converted from it: {again}"
    if recorded[1:] != (tools, element):
        return f"{out} was converted with --tools {recorded[1]}" + (
            f" --element {recorded[2]}" if recorded[2] else "") + f": {again}, or run it " \
            f"as it is with 'ddpy run {out}'"
    return None


def convert_command(inp: str, folder: str | None, tools: str, element: str | None,
                    overwrite: bool, command: str = "convert") -> Path | None:
    """The conversion of the ``convert`` and ``run`` commands: the case folder written and
    checked (default: MODEL_case beside the file), or None after printing every error."""
    from ddpy.cad.read import CadError
    from ddpy.io.decks import DeckError, read_case

    out = Path(folder) if folder else Path(inp).with_name(Path(inp).stem + "_case")
    if command == "run" and out.is_dir() and any(out.iterdir()):
        try:
            refusal = _reuse(inp, out, tools, element)
        except DeckError as error:
            refusal = str(error)
        if refusal is not None:
            print(f"ddpy {command}: error: {refusal}", file=sys.stderr)
            return None
        print(f"ddpy {command}: {out} was converted from {inp} as it is now: running it")
        return out
    try:
        done = convert_inp(inp, out, tools, element, overwrite)
        case = read_case(out)
    except DeckError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        count = len(error.errors)
        nothing = "nothing run" if command == "run" else "no case written"
        print(f"ddpy {command}: {inp}: {count} error{'s' if count > 1 else ''}; {nothing}",
              file=sys.stderr)
        return None
    except (CadError, ValueError) as error:
        print(f"ddpy {command}: error: {error}", file=sys.stderr)
        return None
    for note in done.notes:
        print(f"  ignored: {note}")
    print(case.summary())
    print(f"ddpy {command}: {inp} -> {out}: ok")
    return out
