"""Fuzzing the decks: valid example decks mutated at random (lines deleted, duplicated, swapped,
tokens replaced by random text, numbers, NaN or huge values, files truncated or replaced by
random bytes, titles and phase counts changed) are either accepted or refused with a
DeckError: never another exception, never a hang; and ddpy check and ddpy run agree on them
(what the check accepts the run starts, what it refuses the run refuses). The blank's Gmsh
file (node indices 0, -1 or beyond, element types changed, ids like '1_0'), STL tool meshes
(scaled by 1e30 or 3e-11, a vertex at 1e308) and special files (a fifo, /dev/zero,
/dev/urandom, a folder as a deck, mesh or tool file) are refused by the command line with
exit code 2 and one message naming the file."""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import signal
import subprocess
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from deckutil import EXAMPLES, install_toolfile
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ddpy.app.cli import main
from ddpy.app.runner import BUILT_IN_CASES
from ddpy.io.decks import DECKS, DeckError, read_case

#: The most phases and title characters a case may have (docs/input-format.md).
MAX_PHASES = MAX_TITLE = 1000
#: Seconds one example may take before it counts as a hang.
HANG = 20
#: More examples, drawn afresh each run: DDPY_FUZZ_EXAMPLES=5000 pytest tests/test_decks_fuzz.py
EXAMPLES_RUN = int(os.environ.get("DDPY_FUZZ_EXAMPLES", "0"))

#: The case folders mutated: the shipped examples, and for ddpy check against ddpy run the
#: built-in bending case too (its blank is a Gmsh file; the deep drawing's checks take
#: seconds, so tests/test_plausibility.py takes it unchanged).
FOLDERS = {"bending": EXAMPLES / "bending", "strip_draw": EXAMPLES / "strip_draw",
           "cylindrical_bending": BUILT_IN_CASES["cylindrical-bending"]}
ALL_BASES = {name: {deck: (folder / deck).read_text() for deck in DECKS}
             for name, folder in FOLDERS.items()}
BASES = {name: ALL_BASES[name] for name in ("bending", "strip_draw")}
TOOL_FILES = {name: {f"tools/{p.name}": p.read_text()
                     for p in sorted((folder / "tools").glob("*.tool"))}
              for name, folder in FOLDERS.items()}

SPECIAL = ["nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e999", "0", "-0", "-1", "1e-320",
           "99999999999999999999", "-99999999999999999999", "0x10", "1_000", "end", "phase",
           "tool", "nodes", "hexahedra", "box", "file", "x", "y", "z", "top", "bottom",
           "facing", "springback", "forming", "punch", "die", "holder", "centre", "all",
           "#", "1-", "-", "1-999999999", "ids", "plane", "\u00e9", "\u0663", "\x00", "''"]

token = st.one_of(
    st.sampled_from(SPECIAL),
    st.text(max_size=12),
    st.integers(min_value=-10**30, max_value=10**30).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@st.composite
def mutation(draw: st.DrawFn, text: str) -> str:
    """One random change of a deck's text."""
    lines = text.splitlines()
    kind = draw(st.sampled_from(["token"] * 4 + ["number"] * 4 + ["delete", "delete",
                                 "duplicate", "duplicate", "swap", "insert", "truncate",
                                 "replace"]))
    if kind == "truncate":
        return text[: draw(st.integers(0, len(text)))]
    if kind == "replace":
        return draw(st.text(max_size=200))
    if not lines:
        return text
    i = draw(st.integers(0, len(lines) - 1))
    if kind == "delete":
        del lines[i]
    elif kind == "duplicate":
        lines.insert(i, lines[i])
    elif kind == "swap":
        j = draw(st.integers(0, len(lines) - 1))
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "insert":
        lines.insert(i, " ".join(draw(st.lists(token, min_size=1, max_size=6))))
    else:
        words = lines[i].split()
        if words:
            k = draw(st.integers(0, len(words) - 1))
            words[k] = draw(token) if kind == "token" else _nudge(words[k], draw(NUDGE))
            lines[i] = " ".join(words)
    return "\n".join(lines) + "\n"


#: Changes of a number that keep it a number: sign, scale, zero, off by one.
NUDGE = st.sampled_from([-1.0, 0.0, 0.5, 2.0, 10.0, 1e6, -1e-6, 1e300])


def _nudge(word: str, factor: float) -> str:
    try:
        value = float(word)
    except ValueError:
        return word
    if word.lstrip("-").isdigit():
        return str(int(value * factor) if abs(value * factor) < 1e18 else int(value) + 1)
    return repr(value * factor)


def with_title(text: str, title: str) -> str:
    """control.dat with this title."""
    kept = [line for line in text.split("\n") if line.split()[:1] != ["title"]]
    return "\n".join([f"title {title}", *kept])


def with_phases(text: str, total: int) -> str:
    """control.dat with its first phase repeated under new names to ``total`` phases."""
    lines = text.split("\n")
    phases = [i for i, line in enumerate(lines) if line.split()[:1] == ["phase"]]
    start = phases[0]
    end = next(i for i in range(start, len(lines)) if lines[i].split()[:1] == ["end"])
    name = lines[start].split()[1]
    copies = [f"phase {name}_{k}" if i == start else lines[i]
              for k in range(total - len(phases)) for i in range(start, end + 1)]
    return "\n".join(lines[:end + 1] + copies + lines[end + 1:])


@st.composite
def control_change(draw: st.DrawFn, text: str) -> str:
    """control.dat with another title (control characters, a NUL byte, too long) or its first
    phase repeated, to the most phases a case may have or one more."""
    if draw(st.booleans()):
        return with_title(text, draw(st.one_of(st.text(max_size=20), st.sampled_from(
            ["a\x00b", "\x1b[31mred", "tab\there", "x" * MAX_TITLE, "x" * (MAX_TITLE + 1)]))))
    return with_phases(text, draw(st.sampled_from([4, MAX_PHASES, MAX_PHASES + 1])))


@st.composite
def mutated_case(draw: st.DrawFn, bases: dict[str, dict[str, str]] = BASES
                 ) -> tuple[str, dict[str, str | bytes]]:
    """An example case with one or two of its decks changed, sometimes a tool file too,
    sometimes its title or its number of phases."""
    name = draw(st.sampled_from(sorted(bases)))
    decks: dict[str, str | bytes] = dict(bases[name])
    if draw(st.integers(0, 9)) == 0:  # what the results file keeps: title, phase names
        decks["control.dat"] = draw(control_change(bases[name]["control.dat"]))
    if draw(st.integers(0, 5)) == 0:  # a tool file, now and then
        tool = draw(st.sampled_from(sorted(TOOL_FILES[name])))
        decks[tool] = draw(mutation(TOOL_FILES[name][tool]))
    for _ in range(draw(st.integers(1, 2))):
        deck = draw(st.sampled_from(DECKS))
        current = decks[deck]
        if isinstance(current, bytes) or draw(st.integers(0, 39)) == 0:
            decks[deck] = draw(st.binary(max_size=200))
        else:
            for _ in range(draw(st.integers(1, 2))):
                current = draw(mutation(current))
            decks[deck] = current
    return name, decks


class Hang(Exception):
    pass


def _alarm(signum: int, frame: object) -> None:
    raise Hang(f"reading the decks took more than {HANG} s")


@pytest.fixture(scope="module")
def folder() -> Iterator[Path]:
    """A scratch case folder whose tools/ links to the example's tool files."""
    with pytest.MonkeyPatch.context() as patch, tempfile.TemporaryDirectory() as tmp:
        install_toolfile(patch)
        yield Path(tmp)


def _write(folder: Path, name: str, decks: dict[str, str | bytes]) -> Path:
    """Write the decks to a new case folder; tools/ links to the example's tool files unless
    one of them is changed, its other files (a mesh file) are linked."""
    case = Path(tempfile.mkdtemp(prefix=f"{name}-", dir=folder))
    tools = case / "tools"
    if any(deck.startswith("tools/") for deck in decks):
        tools.mkdir()
        for deck, content in TOOL_FILES[name].items():
            (case / deck).write_text(content)
    else:
        os.symlink(FOLDERS[name] / "tools", tools)
    for other in FOLDERS[name].iterdir():
        if other.name not in DECKS and other.name != "tools":
            os.symlink(other, case / other.name)
    for deck, content in decks.items():
        path = case / deck
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8", errors="surrogatepass")
    return case


def _read_or_refuse(case: Path) -> None:
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG)
    try:
        read_case(case)
    except DeckError as error:
        assert error.errors and all(isinstance(e, DeckError) for e in error.errors)
        assert str(error)  # the message can be printed
        for e in error.errors:
            assert e.path is not None
            assert e.line is None or e.line >= 1
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@settings(max_examples=EXAMPLES_RUN or 1000, deadline=5000, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_case())
def test_mutated_decks_accepted_or_refused(folder: Path, mutated) -> None:
    name, decks = mutated
    _read_or_refuse(_write(folder, name, decks))


@settings(max_examples=EXAMPLES_RUN // 4 or 300, deadline=5000, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(DECKS), st.lists(st.lists(token, min_size=1, max_size=8), max_size=12))
def test_random_lines_accepted_or_refused(folder: Path, deck: str, rows: list[list[str]]
                                          ) -> None:
    decks: dict[str, str | bytes] = dict(BASES["bending"])
    decks[deck] = "\n".join(" ".join(r) for r in rows) + "\n"
    _read_or_refuse(_write(folder, "bending", decks))


def cli(argv: list[str]) -> tuple[int, str, str]:
    """The ddpy command in this process: exit code, standard output and error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def check_and_run_agree(case: Path) -> tuple[int, str]:
    """``ddpy check`` and ``ddpy run --stop-after 0`` (all the run does before its first
    increment) on one case folder agree: what the check accepts the run starts, what the
    check refuses the run refuses with the same errors (exit 2). The check's exit code and
    standard error."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG)
    try:
        checked, _, check_err = cli(["check", str(case)])
        ran, run_out, run_err = cli(["run", str(case), "--output", f"{case}-out",
                                     "--stop-after", "0"])
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert "Traceback" not in check_err + run_err
    if checked == 0:
        assert ran == 0 and "stopped after 0 increments" in run_out, (run_out, run_err)
    else:
        assert (checked, ran) == (2, 2), (check_err, run_err)
        assert check_err.splitlines()[:-1] == run_err.splitlines()[:-1]  # the same errors
    return checked, check_err


@settings(max_examples=EXAMPLES_RUN // 5 or 120, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_case(ALL_BASES))
def test_check_and_run_agree_on_mutated_decks(folder: Path, mutated) -> None:
    name, decks = mutated
    check_and_run_agree(_write(folder, name, decks))


@pytest.mark.parametrize("name, change, checked", [
    ("bending", lambda text: with_title(text, "a\x00b"), 2),  # HDF5: embedded NULs
    ("strip_draw", lambda text: with_phases(text, 5000), 2),  # object header too large
    ("cylindrical_bending", lambda text: with_phases(text, MAX_PHASES), 0),
], ids=["NUL in the title", "5,000 phases", "1,000 phases"])
def test_check_and_run_agree_on_what_the_results_file_refused(
        folder: Path, name: str, change: Callable[[str], str], checked: int) -> None:
    decks: dict[str, str | bytes] = {**ALL_BASES[name],
                                     "control.dat": change(ALL_BASES[name]["control.dat"])}
    assert check_and_run_agree(_write(folder, name, decks))[0] == checked


@pytest.mark.parametrize("name", [*FOLDERS, "deep-drawing"])
def test_check_and_run_agree_on_every_example(tmp_path: Path, name: str) -> None:
    source = FOLDERS.get(name) or BUILT_IN_CASES[name]
    case = tmp_path / source.name
    shutil.copytree(source, case)
    assert check_and_run_agree(case) == (0, "")


def test_valid_examples_still_read(folder: Path) -> None:
    for name, decks in BASES.items():
        case = _write(folder, name, decks)
        assert read_case(case).mesh.n_elements > 0


def _bezier_tool_text() -> str:
    """A small Bezier tool file written by ddpy: a flat patch and a curved one."""
    from ddpy.geometry.surfaces import BezierSurface
    from ddpy.io.toolfile import ToolModel, write_tool

    u, v = np.meshgrid(np.linspace(0, 1, 3), np.linspace(0, 1, 4), indexing="ij")
    flat = np.stack([u, v, np.zeros_like(u)], axis=-1)
    bent = np.stack([u + 1.0, v, 0.3 * u**2], axis=-1)
    with tempfile.TemporaryDirectory() as tmp:
        model = ToolModel("die", "bezier", BezierSurface([flat, bent]), [1, 2])
        return write_tool(Path(tmp) / "die.bezier.tool", model).read_text()


TOOL_TEXTS = {"nagata": TOOL_FILES["bending"]["tools/punch.tool"],
              "bezier": _bezier_tool_text()}


@settings(max_examples=EXAMPLES_RUN or 600, deadline=5000, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.sampled_from(sorted(TOOL_TEXTS)), st.data())
def test_mutated_tool_files_read_or_refused(tmp_path_factory: pytest.TempPathFactory,
                                            kind: str, data: st.DataObject) -> None:
    from ddpy.io.toolfile import ToolFileError, read_tool

    text = TOOL_TEXTS[kind]
    for _ in range(data.draw(st.integers(1, 3))):
        text = data.draw(mutation(text))
    path = tmp_path_factory.mktemp("tool") / f"die.{kind}.tool"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG)
    try:
        model = read_tool(path)
        assert np.isfinite(model.surface.evaluate([0], [[0.5, 0.5]])[0]).all()
    except ToolFileError as error:
        assert str(error).startswith(str(path))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


# ------------------------------------------------------------------ mesh files, tool meshes
# Mutations of the files meshio or ddpy's own readers take: each is refused by the command
# line with exit code 2 and one message naming the file (and the line, where it has lines).

BUILT_IN_CASE = Path(__file__).resolve().parent.parent / "ddpy" / "cases" / "cylindrical_bending"


def _cli(argv: list[str]) -> tuple[int, str]:
    """The ddpy command run in this process: its exit code and what it wrote to stderr."""
    import contextlib
    import io

    from ddpy.app.cli import main

    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as stop:
            code = stop.code
    return int(code or 0), err.getvalue()


def _gmsh_texts() -> dict[str, str]:
    """The built-in case's blank as ASCII Gmsh 2.2 (the case's own file) and 4.1."""
    import meshio

    with tempfile.TemporaryDirectory() as tmp:
        v41 = Path(tmp) / "mesh.msh"
        meshio.write(v41, meshio.read(BUILT_IN_CASE / "mesh.msh"), file_format="gmsh",
                     binary=False)
        return {"2.2": (BUILT_IN_CASE / "mesh.msh").read_text(), "4.1": v41.read_text()}


GMSH_TEXTS = _gmsh_texts()


#: Mutations of a blank's Gmsh file: (what, the new word); nodes 0, -1, beyond the 732
#: nodes; element types other than the 8-node hexahedron (5), known or not; an id with '_'.
GMSH_CHANGES = st.one_of(
    st.tuples(st.just("node"), st.sampled_from(["0", "-1", "733", "1732", str(2**31)])),
    st.tuples(st.just("type"), st.sampled_from([str(t) for t in (0, 1, 2, 3, 4, 6, 7, 12, 15,
                                                                 16, 17, 92, 99, 200)])),
    st.tuples(st.just("id"), st.just("_")))


def _mutate_gmsh(version: str, element: int, position: int, change: tuple[str, str]
                 ) -> tuple[str, int]:
    """The blank's Gmsh text with one element changed, and the line a refusal must name."""
    lines = GMSH_TEXTS[version].split("\n")
    head = lines.index("$Elements") + 1
    first = head + (1 if version == "2.2" else 2)  # after the count (and the block header)
    row = first + element
    words = lines[row].split()
    what, new = change
    if what == "node":
        words[(5 if version == "2.2" else 1) + position] = new
    elif what == "type" and version == "2.2":
        words[1] = new
    elif what == "type":  # the type is the block's
        row = first - 1
        words = lines[row].split()
        words[2] = new
    else:
        words[0] = "1_0" if len(words[0]) == 1 else words[0][:1] + "_" + words[0][1:]
    lines[row] = " ".join(words)
    return "\n".join(lines), row + 1


@settings(max_examples=EXAMPLES_RUN or 40, deadline=10000, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(sorted(GMSH_TEXTS)), st.integers(0, 359), st.integers(0, 7),
       GMSH_CHANGES)
def test_mutated_gmsh_blank_refused_at_its_line(tmp_path_factory: pytest.TempPathFactory,
                                                version: str, element: int, position: int,
                                                change: tuple[str, str]) -> None:
    # A node 0 wired the element to the last node, a changed type dropped the hexahedron
    # and '1_0' read as 10, all without a word; a node beyond the nodes was a bare IndexError.
    text, line = _mutate_gmsh(version, element, position, change)
    case = tmp_path_factory.mktemp("gmsh") / "case"
    shutil.copytree(BUILT_IN_CASE, case)
    (case / "mesh.msh").write_text(text)
    code, err = _cli(["check", "--no-geometry", str(case)])
    assert code == 2, err
    errors = err.strip().splitlines()[:-1]  # the last line counts them
    assert len(errors) == 1 and f"mesh.msh:{line}: " in errors[0], (line, err)


@pytest.mark.parametrize("version", ["gmsh22", "gmsh"])
@pytest.mark.parametrize("index", [-1, -2, 732])   # node tags 0, -1 and one beyond the nodes
def test_binary_gmsh_node_out_of_range_refused(tmp_path: Path, version: str,
                                               index: int) -> None:
    import meshio

    mesh = meshio.read(BUILT_IN_CASE / "mesh.msh")
    cells = np.array(mesh.cells[0].data)
    cells[7, 3] = index
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN_CASE, case)
    meshio.write(case / "mesh.msh", meshio.Mesh(mesh.points, [("hexahedron", cells)]),
                 file_format=version, binary=True)
    code, err = _cli(["check", "--no-geometry", str(case)])
    assert code == 2
    assert f"mesh.msh: $Elements entry 8: element 8 refers to node {index + 1}, which is not " \
        "in $Nodes" in err


def _stl_tool(path: Path, scale: float = 1.0) -> list[int]:
    """An ASCII STL of a gently curved strip, 50 x 20 mm; the lines of its vertices."""
    x, y = np.meshgrid(np.linspace(0, 50, 5), np.linspace(0, 20, 3), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), 0.01 * x.ravel() ** 2]) * scale
    lines, vertex_lines = ["solid tool"], []
    for i in range(4):
        for j in range(2):
            a = 3 * i + j
            for triangle in ((a, a + 3, a + 4), (a, a + 4, a + 1)):
                lines += ["  facet normal 0 0 1", "    outer loop"]
                for k in triangle:
                    vertex_lines.append(len(lines) + 1)
                    lines.append("      vertex " + " ".join(f"{c:.9g}" for c in points[k]))
                lines += ["    endloop", "  endfacet"]
    path.write_text("\n".join(lines + ["endsolid tool"]) + "\n")
    return vertex_lines


@pytest.mark.parametrize("scale", [1e30, 3e-11])
def test_stl_scaled_absurdly_refused(tmp_path: Path, scale: float) -> None:
    path = tmp_path / "die.stl"
    _stl_tool(path, scale)
    code, err = _cli(["tools", "build", str(path), "--out", str(tmp_path / "out")])
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and str(path) in err, err
    assert not (tmp_path / "out").exists()


@settings(max_examples=EXAMPLES_RUN // 4 or 20, deadline=10000, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 47), st.integers(0, 2),
       st.sampled_from(["1e308", "-1e308", "1e999", "inf", "nan", "2e6"]))
def test_stl_vertex_beyond_limits_refused_at_its_line(tmp_path_factory: pytest.TempPathFactory,
                                                      vertex: int, axis: int, value: str
                                                      ) -> None:
    # 1e308 gave numpy's overflow text and no file name.
    folder = tmp_path_factory.mktemp("stl")
    path = folder / "die.stl"
    line = _stl_tool(path)[vertex]
    lines = path.read_text().split("\n")
    words = lines[line - 1].split()
    words[1 + axis] = value
    lines[line - 1] = "      " + " ".join(words)
    path.write_text("\n".join(lines))
    code, err = _cli(["tools", "build", str(path), "--out", str(folder / "out")])
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and f"{path}:{line}: " in err, err
    assert "overflow" not in err


# -------------------------------------------------------------------------- special files
# Files that are not regular files are refused with their path before anything reads them:
# a fifo made ddpy check hang, /dev/urandom and /dev/zero were read until memory ran out.
# Run in a child process under a timeout and a memory limit, so the bug cannot hang or
# swamp the tests should it come back.

SPECIAL_TIMEOUT = 60


def _ddpy_child(args: list[str]) -> subprocess.CompletedProcess[str]:
    import resource
    import sys

    def limit_memory() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (2 * 2**30, 2 * 2**30))

    try:
        return subprocess.run([sys.executable, *args], capture_output=True, text=True,
                              timeout=SPECIAL_TIMEOUT, preexec_fn=limit_memory,
                              env={**os.environ, "OMP_NUM_THREADS": "1",
                                   "OPENBLAS_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        pytest.fail(f"{' '.join(args)} did not finish in {SPECIAL_TIMEOUT} s")


def test_decks_that_are_not_regular_files_refused(tmp_path: Path) -> None:
    case = tmp_path / "bending"
    shutil.copytree(EXAMPLES / "bending", case)
    for deck in ("tools.dat", "material.dat", "control.dat", "bc.dat"):
        (case / deck).unlink()
    os.mkfifo(case / "tools.dat")
    os.symlink("/dev/urandom", case / "material.dat")
    (case / "control.dat").mkdir()
    os.symlink("/dev/zero", case / "bc.dat")
    done = _ddpy_child(["-m", "ddpy", "check", str(case)])
    assert done.returncode == 2, done.stderr
    errors = done.stderr.strip().splitlines()
    assert errors[:-1] == [
        f"{case}/control.dat: a directory: expected a regular file as a deck",
        f"{case}/bc.dat: a link to /dev/zero, a character device: expected a regular file as "
        "a deck",
        f"{case}/material.dat: a link to /dev/urandom, a character device: expected a regular "
        "file as a deck",
        f"{case}/tools.dat: a fifo (named pipe): expected a regular file as a deck"]


def test_mesh_and_tool_files_that_are_not_regular_files_refused(tmp_path: Path) -> None:
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN_CASE, case)
    (case / "mesh.msh").unlink()
    os.mkfifo(case / "mesh.msh")
    (case / "tools" / "punch.tool").unlink()
    os.symlink("/dev/zero", case / "tools" / "punch.tool")
    done = _ddpy_child(["-m", "ddpy", "check", str(case)])
    assert done.returncode == 2, done.stderr
    errors = done.stderr.strip().splitlines()
    assert errors[0].endswith(f"mesh file {case}/mesh.msh: a fifo (named pipe): expected a "
                              "regular file as a mesh file")
    assert errors[1].endswith(f"cannot read tool file: {case}/tools/punch.tool: a link to "
                              "/dev/zero, a character device: expected a regular file as a "
                              "tool file")
    stl = tmp_path / "die.stl"
    os.mkfifo(stl)
    done = _ddpy_child(["-m", "ddpy", "tools", "build", str(stl), "--out",
                        str(tmp_path / "out")])
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip() == f"ddpy tools build: error: {stl}: a fifo (named pipe): " \
        "expected a regular file as a tool mesh"


def test_read_tool_refuses_dev_zero_in_the_api() -> None:
    done = _ddpy_child(["-c", "from ddpy.io.toolfile import read_tool\n"
                        "try:\n    read_tool('/dev/zero')\n"
                        "except ValueError as error:\n    print(error)\n"])
    assert done.stdout.strip() == "/dev/zero: a character device: expected a regular file as " \
        "a tool file", done.stderr


def test_a_deck_beyond_its_size_limit_is_refused_before_reading(tmp_path: Path) -> None:
    case = tmp_path / "bending"
    shutil.copytree(EXAMPLES / "bending", case)
    with open(case / "control.dat", "r+b") as deck:
        deck.truncate(17 * 2**20)  # sparse: no disk used
    with pytest.raises(DeckError) as error:
        read_case(case)
    assert str(error.value) == f"{case}/control.dat: 17 MB: larger than the 16 MB limit for " \
        "a deck"


@pytest.mark.parametrize("module, what", [("ddpy.io.decks", "a deck"),
                                          ("ddpy.io.decks.mesh", "a mesh file")])
def test_mesh_deck_and_file_limits_are_checked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               module: str, what: str) -> None:
    # The 1 GB limit is what a test cannot write: the check is the same at any limit.
    import importlib

    monkeypatch.setattr(importlib.import_module(module), "MESH_LIMIT", 300)
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN_CASE, case)
    (case / "mesh.dat").write_text("file mesh.msh\n" + "#" * 400 * (what == "a deck") + "\n")
    path = case / ("mesh.dat" if what == "a deck" else "mesh.msh")
    code, err = _cli(["check", "--no-geometry", str(case)])
    assert code == 2
    size = path.stat().st_size
    shown = f"{size} bytes" if size < 1024 else f"{size / 1024:.3g} kB"
    assert f"{path}: {shown}: larger than the 300 bytes limit for {what}" in err, err


def test_tool_mesh_limit_is_checked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import ddpy.cad.surface_mesh

    monkeypatch.setattr(ddpy.cad.surface_mesh, "TOOL_LIMIT", 300)
    path = tmp_path / "die.stl"
    _stl_tool(path)
    code, err = _cli(["tools", "build", str(path), "--out", str(tmp_path / "out")])
    assert code == 2
    assert err.strip() == f"ddpy tools build: error: {path}: " \
        f"{path.stat().st_size / 1024:.3g} kB: larger than the 300 bytes limit for a tool mesh"


def test_an_abaqus_include_of_a_fifo_is_refused(tmp_path: Path) -> None:
    (tmp_path / "model.inp").write_text("*HEADING\nfifo\n*INCLUDE, INPUT=nodes.inp\n")
    os.mkfifo(tmp_path / "nodes.inp")
    done = _ddpy_child(["-m", "ddpy", "convert", str(tmp_path / "model.inp"),
                        str(tmp_path / "case")])
    assert done.returncode == 2, done.stderr
    assert f"{tmp_path}/nodes.inp: a fifo (named pipe): expected a regular file as an Abaqus " \
        "input file" in done.stderr
