"""Reading CAD files through gmsh's OpenCASCADE, with the checks that keep a damaged file
from crashing or hanging the process: a STEP file is checked line by line first
(:func:`check_step`), then read once in a child process with a time limit, then read.

Errors (:class:`CadError`) name the CAD file and, for STEP, the line.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

from ddpy._validate import TOOL_LIMIT, InputFileError, check_input_file, read_input_file

__all__ = ["CadError", "CAD_SUFFIXES", "check_step", "gmsh_session", "load_cad", "quiet"]

CAD_SUFFIXES = {".step": "STEP", ".stp": "STEP", ".iges": "IGES", ".igs": "IGES",
                ".brep": "BREP", ".brp": "BREP"}
#: Longest time (s) the CAD kernel may take to read a file in the trial read of load_cad.
CAD_READ_TIMEOUT = 600.0


class CadError(ValueError):
    """A CAD model that cannot become a tool model; the message names the file and face."""


# ------------------------------------------------------------------------------------ gmsh


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence what OpenCASCADE prints on the process's stdout (STEP and IGES writers)."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):  # no real stdout (captured): nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@contextlib.contextmanager
def gmsh_session() -> Iterator[None]:
    """Initialize gmsh without output if it is not running; finalize only what was started."""
    import gmsh

    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(["", "-nopopup"], readConfigFiles=False, interruptible=False)
    terminal = gmsh.option.getNumber("General.Terminal")
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield
    finally:
        if own:
            gmsh.finalize()
        else:
            gmsh.option.setNumber("General.Terminal", terminal)


def load_cad(path: str | os.PathLike[str]) -> list[int]:
    """Import a CAD file into a new gmsh model (inside :func:`gmsh_session`); its face tags.

    Faces that touch are made to share their edges (``removeAllDuplicates``), so the same file
    always gives the same tags: tool files refer to faces by these tags.
    """
    import gmsh

    path = Path(path)
    kind = CAD_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise CadError(f"{path}: unknown CAD format '{path.suffix}': expected STEP (.step, "
                       ".stp), IGES (.iges, .igs) or BREP (.brep)")
    if not path.exists():
        raise CadError(f"{path}: no such CAD file")
    try:
        check_input_file(path, "a CAD file", TOOL_LIMIT)
    except InputFileError as error:
        raise CadError(str(error)) from None
    declared = check_step(path) if kind == "STEP" else 0
    _trial_read(path, kind)
    gmsh.model.add(path.stem)
    occ = gmsh.model.occ
    try:
        with quiet():
            occ.importShapes(str(path))
            read = len(occ.getEntities(2))
            occ.removeAllDuplicates()
            occ.synchronize()
    except Exception as error:  # gmsh raises a bare Exception with its last message
        raise CadError(f"{path}: cannot read the {kind} file: {error}") from None
    if read < declared:
        raise CadError(f"{path}: the CAD kernel read {read} of the {declared} faces the file "
                       f"defines: {declared - read} are broken (their surface or edges)")
    tags = [t for _, t in gmsh.model.getEntities(2)]
    if not tags:
        raise CadError(f"{path}: the {kind} file holds no faces (surfaces): nothing to model")
    return tags


def _trial_read(path: Path, kind: str) -> None:
    """Read the file once in a child process first: a file the checks let through may still
    crash the CAD kernel (a segmentation fault inside OpenCASCADE) or keep it reading for
    ever. Either then ends that process only, and here becomes a CadError. Costs about half
    a second (a Python with gmsh started)."""
    if not sys.executable:
        return
    # The child ends itself a little after the timeout (SIGALRM), should this process be
    # killed meanwhile and leave it reading.
    script = (f"import signal, sys, gmsh\nsignal.alarm({int(CAD_READ_TIMEOUT) + 5})\n"
              "gmsh.initialize(['', '-nopopup'], readConfigFiles=False, interruptible=False)\n"
              "gmsh.option.setNumber('General.Terminal', 0)\n"
              "gmsh.model.occ.importShapes(sys.argv[1])\n"
              "gmsh.model.occ.removeAllDuplicates()\n"
              "gmsh.model.occ.synchronize()\n")
    try:
        child = subprocess.run([sys.executable, "-c", script, str(path)],
                               capture_output=True, timeout=CAD_READ_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise CadError(f"{path}: the CAD kernel did not finish reading the {kind} file in "
                       f"{CAD_READ_TIMEOUT:g} s") from None
    if child.returncode < 0:  # killed by a signal: the kernel crashed on this file
        try:
            name = signal.Signals(-child.returncode).name
        except ValueError:
            name = f"signal {-child.returncode}"
        raise CadError(f"{path}: the CAD kernel crashed reading the {kind} file ({name}): "
                       "the file is damaged or uses what the kernel cannot read")


_STEP_STRING = re.compile(r"'(?:[^']|'')*'")
_STEP_ENTITY = re.compile(r"#(\d+)\s*=\s*([A-Za-z_0-9]*)")
_STEP_REFERENCE = re.compile(r"#(\d+)")
#: Entities whose first (count) numbers after their last reference are radii, > 0.
_STEP_RADII = {"CIRCLE": 1, "CYLINDRICAL_SURFACE": 1, "SPHERICAL_SURFACE": 1,
               "TOROIDAL_SURFACE": 2, "ELLIPSE": 2}
_STEP_FACES = ("ADVANCED_FACE", "FACE_SURFACE")
#: Smallest and largest lengths (radii, VECTOR magnitudes, in the file's unit) taken: the
#: CAD kernel's confusion tolerance is 1e-7, and a VECTOR of magnitude 1e-300 kept it
#: reading for ever; beyond 1e10 a length is no tool's either.
_STEP_LENGTHS = (1e-7, 1e10)
_POINT, _DIRECTION, _PLACEMENT_3D = ("CARTESIAN_POINT",), ("DIRECTION",), ("AXIS2_PLACEMENT_3D",)
#: Curves, surfaces and loops of ISO 10303-42; '*' stands for any start of the name.
_CURVES = ("*_CURVE", "LINE", "CIRCLE", "ELLIPSE", "PARABOLA", "HYPERBOLA", "POLYLINE", "PCURVE",
           "*_CURVE_WITH_KNOTS")
#: Swept surfaces among them: OpenCASCADE writes a torus whose tube is wider than its ring
#: (a square punch's corner: nose radius above the corner's plan radius less the nose) as a
#: SURFACE_OF_REVOLUTION.
_SURFACES = ("*_SURFACE", "PLANE", "*_SURFACE_WITH_KNOTS", "SURFACE_OF_REVOLUTION",
             "SURFACE_OF_LINEAR_EXTRUSION")
_LOOPS = ("EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP")
#: The references of entities OpenCASCADE follows without checking what they are (a VECTOR
#: whose direction was a product definition ended gmsh in a segmentation fault): per entity,
#: (argument index, its name in ISO 10303-42, the entity types allowed, may be '$').
_STEP_TYPES: dict[str, tuple[tuple[int, str, tuple[str, ...], bool], ...]] = {
    "VECTOR": ((1, "orientation", _DIRECTION, False),),
    "AXIS1_PLACEMENT": ((1, "location", _POINT, False), (2, "axis", _DIRECTION, True)),
    "AXIS2_PLACEMENT_2D": ((1, "location", _POINT, False),
                           (2, "ref_direction", _DIRECTION, True)),
    "AXIS2_PLACEMENT_3D": ((1, "location", _POINT, False), (2, "axis", _DIRECTION, True),
                           (3, "ref_direction", _DIRECTION, True)),
    "LINE": ((1, "pnt", _POINT, False), (2, "dir", ("VECTOR",), False)),
    "CIRCLE": ((1, "position", ("AXIS2_PLACEMENT_2D", "AXIS2_PLACEMENT_3D"), False),),
    "ELLIPSE": ((1, "position", ("AXIS2_PLACEMENT_2D", "AXIS2_PLACEMENT_3D"), False),),
    "PLANE": ((1, "position", _PLACEMENT_3D, False),),
    "CYLINDRICAL_SURFACE": ((1, "position", _PLACEMENT_3D, False),),
    "CONICAL_SURFACE": ((1, "position", _PLACEMENT_3D, False),),
    "SPHERICAL_SURFACE": ((1, "position", _PLACEMENT_3D, False),),
    "TOROIDAL_SURFACE": ((1, "position", _PLACEMENT_3D, False),),
    "SURFACE_OF_REVOLUTION": ((1, "swept_curve", _CURVES, False),
                              (2, "axis_position", ("AXIS1_PLACEMENT",), False)),
    "SURFACE_OF_LINEAR_EXTRUSION": ((1, "swept_curve", _CURVES, False),
                                    (2, "extrusion_axis", ("VECTOR",), False)),
    "VERTEX_POINT": ((1, "vertex_geometry", _POINT, False),),
    "EDGE_CURVE": ((1, "edge_start", ("VERTEX_POINT",), False),
                   (2, "edge_end", ("VERTEX_POINT",), False),
                   (3, "edge_geometry", _CURVES, False)),
    "ORIENTED_EDGE": ((3, "edge_element", ("EDGE_CURVE", "ORIENTED_EDGE"), False),),
    "FACE_BOUND": ((1, "bound", _LOOPS, False),),
    "FACE_OUTER_BOUND": ((1, "bound", _LOOPS, False),),
    "ADVANCED_FACE": ((2, "face_geometry", _SURFACES, False),),
}
_STEP_NAME = re.compile(r"([A-Za-z_][A-Za-z_0-9]*)\s*\(")
_STEP_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_STEP_NOT_A_NUMBER = re.compile(r"(?<![A-Za-z_0-9.])[+-]?(?:nan|inf(?:inity)?)(?![A-Za-z_0-9])",
                                re.IGNORECASE)


def check_step(path: Path) -> int:
    """Refuse a STEP file that gmsh's reader (OpenCASCADE) would crash or hang on: a value
    that is not a number (nan, inf) or a reference to an entity the file does not define
    (a CARTESIAN_POINT of nans and a deleted LINE each ended the process with a
    segmentation fault, a VECTOR of magnitude nan never returned), a circle or surface
    whose radius is not positive (a cylinder of radius 0 made the kernel merge 13 of 17
    faces into 4), a VECTOR whose magnitude is not positive (0 never returned), a DIRECTION
    of zeros, or a reference of a placement, point, vector, line, conic, elementary or
    swept surface, vertex or edge to an entity of the wrong type (a VECTOR whose orientation
    is not a DIRECTION: a segmentation fault). CadError names the line and what was expected.
    Returns the number of faces the file defines.
    """
    try:
        text = read_input_file(path, "a CAD file", TOOL_LIMIT).decode("latin-1")
    except InputFileError as error:
        raise CadError(str(error)) from None
    except OSError as error:
        raise CadError(f"{path}: cannot read: {error.strerror or error}") from None
    # Strings may hold anything, ';' and '#' included: blank them out, keeping the length.
    bare = _STEP_STRING.sub(lambda m: "'" + " " * (len(m.group()) - 2) + "'", text)
    start = bare.find("DATA;")
    if start < 0:
        raise CadError(f"{path}: not a STEP file (no DATA section)")
    end = bare.find("ENDSEC;", start)
    end = len(bare) if end < 0 else end

    def line_of(position: int) -> int:
        return text.count("\n", 0, position) + 1

    kinds: dict[int, set[str]] = {}  # entity id -> its type (the parts of a complex one)
    faces = 0
    uses: list[tuple[int, int, int]] = []  # (referenced id, position, entity id)
    # (referenced id, position, entity id, its type, argument name, types allowed)
    typed: list[tuple[int, int, int, str, str, tuple[str, ...]]] = []
    position = start + len("DATA;")
    for record in bare[position:end].split(";"):
        head = _STEP_ENTITY.search(record)
        if head is not None:
            entity = int(head.group(1))
            body = record[head.end():]
            kinds[entity] = ({head.group(2).upper()} if head.group(2) else
                             {m.group(1).upper() for m in _STEP_NAME.finditer(body)})
            bad = _STEP_NOT_A_NUMBER.search(body)
            if bad is not None:
                where = position + head.end() + bad.start()
                raise CadError(f"{path}:{line_of(where)}: entity #{entity} {head.group(2)} "
                               f"holds '{bad.group()}' where a number is expected")
            if body.count("(") != body.count(")"):  # strings are blanked: no parentheses
                raise CadError(f"{path}:{line_of(position + head.end())}: entity #{entity}: "
                               f"{body.count('(')} '(' against {body.count(')')} ')'")
            uses += [(int(m.group(1)), position + head.end() + m.start(), entity)
                     for m in _STEP_REFERENCE.finditer(body)]
            kind = head.group(2).upper()
            if kind in _STEP_RADII:
                tail = _STEP_REFERENCE.sub("", "#" + body.rsplit("#", 1)[-1])  # without the id
                values = [float(v) for v in _STEP_NUMBER.findall(tail)]
                lo, hi = _STEP_LENGTHS
                if len(values) < _STEP_RADII[kind] or \
                        not all(lo <= v <= hi for v in values[:_STEP_RADII[kind]]):
                    where = position + head.end()
                    raise CadError(f"{path}:{line_of(where)}: entity #{entity} {kind} needs "
                                   f"{_STEP_RADII[kind]} radius value(s) from {lo:g} to "
                                   f"{hi:g}, got "
                                   f"{values[:_STEP_RADII[kind]]} (a degenerate surface or "
                                   "curve: the CAD kernel drops or merges such faces)")
            if kind in _STEP_FACES:
                faces += 1
            if kind in _STEP_TYPES or kind in ("VECTOR", "DIRECTION", "CARTESIAN_POINT"):
                at = position + head.end()
                arguments = _step_arguments(body)
                if arguments is None:
                    raise CadError(f"{path}:{line_of(at)}: entity #{entity} {kind}: expected "
                                   "its arguments in parentheses")
                typed += _step_references(path, line_of, entity, kind, arguments, at)
                _step_values(path, line_of, entity, kind, arguments, at)
        position += len(record) + 1
    for target, where, entity in uses:
        if target not in kinds:
            raise CadError(f"{path}:{line_of(where)}: entity #{entity} refers to #{target}, "
                           "which the file does not define")
    for target, where, entity, kind, name, allowed in typed:
        if not any(_step_is(k, allowed) for k in kinds[target]):
            raise CadError(f"{path}:{line_of(where)}: entity #{entity} {kind}: its {name} "
                           f"#{target} is {' '.join(sorted(kinds[target])) or 'a nameless entity'}"
                           f", expected {' or '.join(allowed)}")
    return faces


def _step_is(kind: str, allowed: tuple[str, ...]) -> bool:
    """Whether an entity type is among ``allowed`` ('*X' also takes any name ending in X)."""
    return any(kind == a or (a.startswith("*") and kind.endswith(a[1:])) for a in allowed)


def _step_arguments(body: str) -> list[tuple[str, int]] | None:
    """The top-level arguments of an entity instance ``(a, (b, c), #1)`` (strings blanked)
    with their offsets in ``body``; None when the parentheses do not enclose them."""
    opening = body.find("(")
    if opening < 0 or body[:opening].strip():
        return None
    arguments, depth, begin = [], 0, opening + 1
    for i in range(opening, len(body)):
        c = body[i]
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth == 0:
                arguments.append((body[begin:i].strip(), begin))
                return arguments if body[i + 1:].strip() == "" else None
        elif c == "," and depth == 1:
            arguments.append((body[begin:i].strip(), begin))
            begin = i + 1
    return None


def _step_references(path: Path, line_of: Callable[[int], int], entity: int, kind: str,
                     arguments: list[tuple[str, int]], at: int
                     ) -> list[tuple[int, int, int, str, str, tuple[str, ...]]]:
    """The references of a typed entity to check once every entity is known; CadError for
    one that is missing or not a reference."""
    found = []
    for index, name, allowed, optional in _STEP_TYPES.get(kind, ()):
        text, offset = arguments[index] if index < len(arguments) else ("", 0)
        match = re.fullmatch(r"#(\d+)", text)
        if match is not None:
            found.append((int(match.group(1)), at + offset, entity, kind, name, allowed))
        elif not (optional and text == "$"):
            raise CadError(f"{path}:{line_of(at + offset)}: entity #{entity} {kind}: expected "
                           f"a reference to a {' or '.join(allowed)} as its {name} (argument "
                           f"{index + 1}), got '{text}'")
    return found


def _step_values(path: Path, line_of: Callable[[int], int], entity: int, kind: str,
                 arguments: list[tuple[str, int]], at: int) -> None:
    """Refuse a VECTOR whose magnitude is not within _STEP_LENGTHS (OpenCASCADE never
    returned from one of 0 or 1e-300), a DIRECTION whose ratios are all zero (accepted
    without a word) or one beyond 1e10 (1e300 never returned), and a CARTESIAN_POINT
    beyond 1e10."""
    if kind == "VECTOR":
        text, offset = arguments[2] if len(arguments) > 2 else ("", 0)
        lo, hi = _STEP_LENGTHS
        if not _STEP_NUMBER.fullmatch(text) or not lo <= float(text) <= hi:
            raise CadError(f"{path}:{line_of(at + offset)}: entity #{entity} VECTOR: expected "
                           f"a magnitude from {lo:g} to {hi:g} (argument 3), got '{text}'")
    elif kind in ("DIRECTION", "CARTESIAN_POINT"):
        text, offset = arguments[1] if len(arguments) > 1 else ("", 0)
        values = text[1:-1].split(",") if text.startswith("(") and text.endswith(")") else []
        numbers = [float(r) for r in values if _STEP_NUMBER.fullmatch(r.strip())]
        hi = _STEP_LENGTHS[1]
        if kind == "DIRECTION" and (not 2 <= len(values) <= 3 or len(numbers) != len(values)
                                    or not any(abs(r) > 0.0 for r in numbers)
                                    or max(abs(r) for r in numbers) > hi):
            raise CadError(f"{path}:{line_of(at + offset)}: entity #{entity} DIRECTION: "
                           f"expected 2 or 3 direction ratios, not all zero, none beyond "
                           f"{hi:g}, got '{text}'")
        if kind == "CARTESIAN_POINT" and any(abs(x) > hi for x in numbers):
            raise CadError(f"{path}:{line_of(at + offset)}: entity #{entity} CARTESIAN_POINT: "
                           f"expected coordinates within {hi:g}, got '{text}'")
