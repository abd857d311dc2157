"""Bad input and faults a user can cause: each ends in a clear message naming the file and
the line (or the option), before any numerics start; legitimate input is not refused."""

from __future__ import annotations

import contextlib
import io
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from ddpy.app.cli import main
from ddpy.core.parallel import set_threads, thread_limit
from ddpy.io.decks import DeckError, read_case
from tests.deckutil import EXAMPLES, copy_example, edit
from tests.test_forming import block_on_plane

BUILT_IN = Path(__file__).resolve().parents[1] / "ddpy" / "cases" / "cylindrical_bending"


@contextlib.contextmanager
def mounted(folder: Path, options: str) -> Iterator[Path]:
    """A tmpfs mounted on ``folder`` with ``options`` (e.g. "ro,size=1m") while the block
    runs (skips without root)."""
    folder.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)],
                          capture_output=True)
    if done.returncode != 0:
        pytest.skip("cannot mount a file system here (needs root)")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], capture_output=True)


def small_disk(folder: Path, size: str) -> contextlib.AbstractContextManager[Path]:
    """A tmpfs of ``size`` mounted on ``folder`` while the block runs."""
    return mounted(folder, f"size={size}")


def errors_of(case: Path) -> str:
    with pytest.raises(DeckError) as caught:
        read_case(case)
    return str(caught.value)


def test_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    path = case / "material.dat"
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert read_case(case).material.material.E == 210000.0


@pytest.mark.parametrize("separator", ["\f", "\v", "\u2028", "\x1c", "\x85"])
def test_only_ascii_line_ends_end_a_line(tmp_path: Path, separator: str) -> None:
    # A separator inside a comment stays in the comment, and the line numbers of the errors
    # after it stay those an editor shows.
    case = copy_example("bending", tmp_path)
    edit(case, "material.dat", "# ddpy material deck: the blank.",
         f"# ddpy material deck:{separator}hardening nonsense")
    edit(case, "material.dat", "n 0.252", "n 7")
    message = errors_of(case)
    assert "material.dat:5:" in message and "Swift exponent n must lie in [0, 1]" in message
    assert "nonsense" not in message


@pytest.mark.parametrize("word", ["210_000", "２１００００", "0x1p3", "1_0", "1e", ".", "Infinity"])
def test_numbers_follow_the_documented_grammar(tmp_path: Path, word: str) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "material.dat", "E 210000", f"E {word}")
    message = errors_of(case)
    assert "material.dat:3:" in message and "expected a number" in message


def test_numbers_in_mesh_blocks_follow_the_grammar_too(tmp_path: Path) -> None:
    case = copy_example("strip_draw", tmp_path)
    edit(case, "mesh.dat", "\n   1     0 0 0\n", "\n   1     1_0 0 0\n")
    line = (case / "mesh.dat").read_text().splitlines().index("   1     1_0 0 0") + 1
    assert f"mesh.dat:{line}: expected numbers X Y Z, got '1_0 0 0'" in errors_of(case)


@pytest.mark.parametrize("version", ["2", "4"])
def test_gmsh_element_count_is_checked(tmp_path: Path, version: str) -> None:
    # meshio reads as many elements as the count says and drops the rest without a word.
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    msh = case / "mesh.msh"
    if version == "4":
        meshio = pytest.importorskip("meshio")
        meshio.write(msh, meshio.read(msh), file_format="gmsh", binary=False)
    text = msh.read_text()
    lines = text.split("\n")
    at = lines.index("$Elements")
    header = lines[at + 1].split()
    index = 0 if version == "2" else 1
    header[index] = str(int(header[index]) - 98)
    lines[at + 1] = " ".join(header)
    msh.write_text("\n".join(lines))
    message = errors_of(case)
    assert f"mesh.msh:{at + 2}: $Elements says" in message


@pytest.mark.parametrize("option, value, message", [
    ("--threads", "100000", "must be at most"),
    ("--threads", str(2**40), "must be at most"),
    ("--threads", "0", "must be at least 1"),
    ("--stop-after", "-1", "must be at least 0"),
    ("--checkpoint-every", "1.5", "expected an integer"),
])
def test_run_options_out_of_range_are_refused(tmp_path: Path, option: str, value: str,
                                              message: str) -> None:
    done = subprocess.run([sys.executable, "-m", "ddpy", "run", option, value, "--output",
                           str(tmp_path / "out")], capture_output=True, text=True)
    assert done.returncode == 2
    assert f"argument {option}: {message}" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_thread_counts_beyond_the_machine_are_refused() -> None:
    for n in (0, thread_limit() + 1, 2**40):
        with pytest.raises(ValueError, match="number of threads"):
            set_threads(n)
    with pytest.raises(TypeError):
        set_threads(2.0)


def test_an_increment_too_small_for_the_travel_is_refused(tmp_path: Path) -> None:
    # 1e-300 mm increments would keep the process busy for ever.
    case = copy_example("bending", tmp_path)
    text = (case / "control.dat").read_text()
    line = next(n for n, x in enumerate(text.split("\n"), start=1)
                if x.split()[:1] == ["max_increment"])
    edit(case, "control.dat", text.split("\n")[line - 1].split()[1], "1e-300")
    message = errors_of(case)
    assert f"control.dat:{line}:" in message and "needs at least 2.85e+301 increments; a " \
        "phase may take at most 1,000,000" in message
    problem, _ = block_on_plane(0.0)
    with pytest.raises(ValueError, match=r"needs at least 1e\+297 increments; a phase may take "
                       "at most 1,000,000"):  # the deck's check, the same function
        problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-300)


@pytest.fixture(scope="module")
def stopped_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two increments of the built-in case, a checkpoint after each."""
    out = tmp_path_factory.mktemp("stopped") / "out"
    done = subprocess.run([sys.executable, "-m", "ddpy", "run", "--output", str(out),
                           "--stop-after", "2", "--checkpoint-every", "1"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return out


def damage(folder: Path, name: str, how: str) -> None:
    path = folder / name
    if how == "remove":
        path.unlink()
    else:  # truncate to half
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])


@pytest.mark.parametrize("name, how, message", [
    ("checkpoint.npz", "truncate", "checkpoint.npz: not a readable checkpoint"),
    ("results.h5", "remove", "results.h5: missing"),
    ("results.h5", "truncate", "results.h5: cannot be continued"),
])
def test_restart_from_damaged_output_says_what_is_wrong(stopped_run: Path, tmp_path: Path,
                                                       name: str, how: str,
                                                       message: str) -> None:
    out = tmp_path / "out"
    shutil.copytree(stopped_run, out)
    damage(out, name, how)
    done = subprocess.run([sys.executable, "-m", "ddpy", "run", "--output", str(out),
                           "--restart"], capture_output=True, text=True)
    assert done.returncode == 1
    assert message in done.stderr and "without --restart" in done.stderr
    assert "Traceback" not in done.stderr


def test_output_naming_a_file_is_refused(tmp_path: Path) -> None:
    taken = tmp_path / "taken"
    taken.write_text("not a folder")
    done = subprocess.run([sys.executable, "-m", "ddpy", "run", "--output", str(taken)],
                          capture_output=True, text=True)
    assert done.returncode == 1
    assert "a file is there; the output must be a folder" in done.stderr
    assert "Traceback" not in done.stderr and taken.read_text() == "not a folder"


@pytest.mark.parametrize("old, new, line, message", [
    ("eps0 0.0102", "eps0 1e300", 5, "Swift eps0 must be <= 10"),
    ("K 645.3", "K 6.453e8", 5, "initial yield stress K eps0^n"),
])
def test_absurd_material_values_are_refused(tmp_path: Path, old: str, new: str, line: int,
                                            message: str) -> None:
    case = edit(copy_example("bending", tmp_path), "material.dat", old, new)
    text = errors_of(case)
    assert f"material.dat:{line}:" in text and message in text


def test_a_tolerance_that_reaches_the_next_row_of_nodes_is_refused(tmp_path: Path) -> None:
    # 100 mm fixed every node of the blank.
    case = copy_example("bending", tmp_path)
    text = (case / "bc.dat").read_text()
    if "tolerance" not in text:
        (case / "bc.dat").write_text("tolerance 100\n" + text)
        line = 1
    else:
        line = next(n for n, x in enumerate(text.split("\n"), start=1)
                    if x.split()[:1] == ["tolerance"])
        edit(case, "bc.dat", text.split("\n")[line - 1], "tolerance 100")
    message = errors_of(case)
    assert f"bc.dat:{line}: tolerance 100 mm is not below half the shortest element edge" \
        in message


def test_run_prints_the_warnings_of_check(tmp_path: Path) -> None:
    case = edit(copy_example("bending", tmp_path), "tools.dat", "friction     0.148",
                "friction     1.5")
    check = subprocess.run([sys.executable, "-m", "ddpy", "check", str(case)],
                           capture_output=True, text=True)
    run = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                          str(tmp_path / "out"), "--stop-after", "1"],
                         capture_output=True, text=True)
    assert check.returncode == 0 and run.returncode == 0, run.stderr
    assert "friction coefficient 1.5 is above 1" in check.stdout
    assert "warning: " in run.stderr and "friction coefficient 1.5 is above 1" in run.stderr


def test_exit_codes_say_how_the_run_ended(tmp_path: Path) -> None:
    # 0 completed or stopped (docs/running.md), 1 failed (here: one Newton iteration allowed
    # and no room to cut), 2 deck errors.
    def run(case: Path, *extra: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                               str(case.parent / "out"), *extra],
                              capture_output=True, text=True)

    ok = copy_example("bending", tmp_path / "ok")
    assert run(ok, "--stop-after", "2").returncode == 0
    failing = copy_example("bending", tmp_path / "failing")
    control = (failing / "control.dat").read_text()
    line = next(x for x in control.split("\n") if x.split()[:1] == ["max_iterations"])
    edit(failing, "control.dat", line, "max_iterations 1\nmin_increment 0.114")
    failed = run(failing)
    assert failed.returncode == 1 and "failed after" in failed.stdout, failed.stdout
    broken = edit(copy_example("bending", tmp_path / "broken"), "material.dat", "nu 0.3",
                  "nu 0.7")
    refused = run(broken)
    assert refused.returncode == 2 and "material.dat:3:" in refused.stderr


def lift_tool_file(path: Path, dz: float) -> None:
    """Move the vertices of a Nagata tool file by dz along z."""
    lines = path.read_text().split("\n")
    at = next(i for i, x in enumerate(lines) if x.split()[:1] == ["vertices"])
    for i in range(at + 1, at + 1 + int(lines[at].split()[1])):
        x, y, z = (float(w) for w in lines[i].split()[:3])
        lines[i] = f"{x!r} {y!r} {z + dz!r}"
    path.write_text("\n".join(lines))


def test_a_punch_moving_away_or_never_reaching_the_blank_is_questioned(tmp_path: Path) -> None:
    assert not read_case(copy_example("bending", tmp_path / "as_given")).warnings
    away = edit(copy_example("bending", tmp_path / "away"), "control.dat", "0 0 -28.5",
                "0 0 28.5")
    assert any("the lead tool 'punch' moves away from the blank" in w
               for w in read_case(away).warnings)
    far = copy_example("bending", tmp_path / "far")
    lift_tool_file(far / "tools" / "punch.tool", 1000.0)
    warnings = read_case(far).warnings
    assert any("starts 1000 mm from the blank and moves 28.5 mm towards it" in w
               for w in warnings), warnings


def test_contact_facing_side_on_to_the_tool_is_refused(tmp_path: Path) -> None:
    # The search pairs a node with a tool surface within 60 degrees of facing it: a die
    # whose contact direction is horizontal would never be touched.
    case = edit(copy_example("bending", tmp_path), "tools.dat", "contact      bottom",
                "contact      facing 1 0 0")
    message = errors_of(case)
    assert "faces no node of the blank's" in message and "tools.dat" in message


def test_a_model_too_large_for_memory_ends_with_a_message(tmp_path: Path) -> None:
    # 4,000,000 hexahedra in a process allowed 2 GB: out of memory while checking the mesh.
    resource = pytest.importorskip("resource")
    case = copy_example("bending", tmp_path)
    (case / "mesh.dat").write_text("normal z\nbox 60 15 1  2000 1000 2\n")

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (2_000_000_000, 2_000_000_000))

    for argv in (["check", str(case)], ["run", str(case), "--output", str(tmp_path / "out")]):
        done = subprocess.run([sys.executable, "-m", "ddpy", *argv], capture_output=True,
                              text=True, preexec_fn=limit)
        assert done.returncode == 1, done.stderr
        assert f"ddpy {argv[0]}: error: out of memory" in done.stderr
        assert "Traceback" not in done.stderr


def test_an_internal_error_is_one_line_unless_debug(monkeypatch: pytest.MonkeyPatch,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    import ddpy.io.decks
    from ddpy.app.cli import main

    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("a defect")

    monkeypatch.setattr(ddpy.io.decks, "read_case", broken)
    assert main(["check", str(BUILT_IN)]) == 1
    err = capsys.readouterr().err
    assert "ddpy check: internal error: RuntimeError: a defect" in err and "--debug" in err
    with pytest.raises(RuntimeError, match="a defect"):
        main(["--debug", "check", str(BUILT_IN)])


def test_a_modulus_not_in_mpa_is_questioned(tmp_path: Path) -> None:
    case = edit(copy_example("bending", tmp_path / "gpa"), "material.dat", "E 210000", "E 210")
    assert any("material.dat:3: Young's modulus 210 MPa is outside" in w
               for w in read_case(case).warnings)
    case = edit(copy_example("bending", tmp_path / "pa"), "material.dat", "E 210000",
                "E 2.1e11")
    assert "Young's modulus E must be <= 1e+06" in errors_of(case)


def test_a_run_on_a_full_file_system_does_not_start(tmp_path: Path) -> None:
    # 64 KB free: HDF5 ended the run in a segmentation fault while it closed the file.
    with small_disk(tmp_path / "full", "64k") as full:
        done = subprocess.run([sys.executable, "-m", "ddpy", "run", "--output",
                               str(full / "out"), "--stop-after", "3"],
                              capture_output=True, text=True)
        assert done.returncode == 1, done.stderr
        assert "MB free, the results of this mesh need at least" in done.stderr
        assert "Traceback" not in done.stderr


def test_an_augmentation_far_from_the_blank_stiffness_is_questioned(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "tools.dat", "  contact      top", "  contact      top\n  augmentation 1e300")
    warnings = read_case(case).warnings
    assert any("augmentation 1e+300 N/mm is" in w and "times the blank's stiffness" in w
               for w in warnings), warnings


#: The cases whose mutations must run when ddpy check accepts them.
AGREE_CASES = {"bending": EXAMPLES / "bending", "strip_draw": EXAMPLES / "strip_draw",
               "cylindrical_bending": BUILT_IN}
#: Control settings and values at and beyond the edges of what the decks and the run take.
AGREE_SETTINGS = ["rmin_strain", "rmin_yield", "rmin_rotation", "rmin_release", "cutback",
                  "newton_force", "newton_displacement", "max_iterations", "min_increment"]
AGREE_VALUES = ["0", "1e-6", "0.02", "0.5", "0.999", "1", "1.0", "1.5", "90", "91"]
#: Depths (mm) a tool is moved into the blank: around rmin_strain x element size.
AGREE_DEPTHS = [0.0, 0.01, 0.02, 0.03, 0.05, 0.2]


def set_control(case: Path, key: str, value: str) -> None:
    """Give a control setting at the top of control.dat (replacing one given there)."""
    path = case / "control.dat"
    lines = path.read_text().split("\n")
    first_phase = next(i for i, x in enumerate(lines) if x.split()[:1] == ["phase"])
    given_at = [i for i in range(first_phase) if lines[i].split()[:1] == [key]]
    if given_at:
        lines[given_at[0]] = f"{key} {value}"
    else:
        lines.insert(first_phase, f"{key} {value}")
    path.write_text("\n".join(lines))


def cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


mutation = st.one_of(
    st.tuples(st.just("setting"), st.sampled_from(AGREE_SETTINGS), st.sampled_from(AGREE_VALUES)),
    st.tuples(st.just("sink"), st.integers(0, 2), st.sampled_from(AGREE_DEPTHS)))


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(sorted(AGREE_CASES)), mutation)
@example("cylindrical_bending", ("setting", "rmin_strain", "1.5"))
@example("cylindrical_bending", ("setting", "rmin_yield", "1.0"))
@example("cylindrical_bending", ("sink", 0, 0.05))
@example("cylindrical_bending", ("sink", 0, 0.03))
def test_what_check_accepts_run_starts(name: str, change: tuple[str, object, object]) -> None:
    # ddpy check and the start of ddpy run agree: a deck check passes runs its first
    # increment (or fails it as a run, exit 1), a deck check refuses is refused by run.
    with tempfile.TemporaryDirectory() as tmp:
        case = Path(tmp) / name
        shutil.copytree(AGREE_CASES[name], case)
        kind, what, value = change
        if kind == "setting":
            set_control(case, str(what), str(value))
        else:
            tools = read_case(case).tools
            tool = tools[int(str(what)) % len(tools)]
            lift_tool_file(tool.file, -float(tool.facing[2]) * float(str(value)))
        checked, _, check_err = cli(["check", str(case)])
        ran, out, err = cli(["run", str(case), "--output", str(Path(tmp) / "out"),
                             "--stop-after", "1"])
    assert "Traceback" not in check_err + err
    if checked == 0:
        assert ran == 0 or (ran == 1 and "failed after" in out), (change, out, err)
    else:
        assert checked == ran == 2, (change, check_err, err)


@pytest.mark.parametrize("change, where, message", [
    ("rmin_strain 1.5", "control.dat:11", "rmin_strain must lie in [0.0001, 1), got 1.5"),
    ("rmin_yield 1.0", "control.dat:10",
     "rmin_yield must lie in [0, 1), got 1.0"),
    ("sink 0.05", "tools.dat:5", "tool 'punch' starts inside the blank: node 3 at (0, 0, 1) "
     "is 0.05 mm behind its surface, more than the first phase's rmin_strain times the "
     "element size (0.02 x 1.36 = 0.0271 mm)"),
])
def test_check_refuses_what_run_refuses_at_once(tmp_path: Path, change: str, where: str,
                                                message: str,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    key, value = change.split()
    if key == "sink":
        lift_tool_file(case / "tools" / "punch.tool", -float(value))
    else:
        set_control(case, key, value)
    assert main(["check", str(case)]) == 2
    assert f"{case / where}: {message}" in capsys.readouterr().err


@pytest.mark.parametrize("n, rows, message", [
    (2**30, [0], "has empty rows: structurally singular"),        # MUMPS wanted ~23 GB
    (2**31, [0], "matrix size must lie in 1..2147483647"),        # an OverflowError
    (2**31 - 1, [0], "has empty rows"),                           # a Fortran abort
    (0, [], "matrix size must lie in 1.."),
    (2.5, [0], "matrix size must be an integer"),
    (3, [0, 1, 3], "rows and cols must lie in 0..2"),
])
def test_a_matrix_size_mumps_cannot_take_is_refused_before_it(
        monkeypatch: pytest.MonkeyPatch, n: object, rows: list[int], message: str) -> None:
    import ddpy.core.linalg
    from ddpy.core.linalg import MumpsSolver

    def analyse(*args: object) -> int:  # the core's analysis would allocate for all n
        raise AssertionError("MUMPS was called")

    monkeypatch.setattr(ddpy.core.linalg._core, "solver_analyse", analyse)
    with MumpsSolver() as solver, pytest.raises(ValueError, match=message):
        solver.analyse(n, rows, rows)  # type: ignore[arg-type]


@pytest.mark.parametrize("entry", ["start/die", "position/punch", "forming/u"])
def test_restart_from_a_checkpoint_without_an_entry_names_it(
        stopped_run: Path, tmp_path: Path, entry: str,
        capsys: pytest.CaptureFixture[str]) -> None:
    import numpy as np

    out = tmp_path / "out"
    shutil.copytree(stopped_run, out)
    checkpoint = out / "checkpoint.npz"
    with np.load(checkpoint) as data:
        arrays = {name: data[name] for name in data.files}
    del arrays[entry]
    with open(checkpoint, "wb") as file:  # np.savez adds '.npz' to a name without it
        np.savez(file, **arrays)
    assert main(["run", "--output", str(out), "--restart"]) == 1
    err = capsys.readouterr().err
    assert f"{checkpoint}: the entry '{entry}' is missing; run again without --restart" in err
    assert "internal error" not in err and "Traceback" not in err


def test_a_disk_filling_during_a_run_ends_it_with_one_message(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    # HDF5 fails to write the second increment's row, as on a full disk: h5py raised a
    # traceback and the process ended in a segmentation fault.
    import errno

    import h5py

    from ddpy.io.results import ResultsReader

    write = h5py.Dataset.__setitem__

    def full(self: h5py.Dataset, key: object, value: object) -> None:
        if self.name.startswith("/increments/") and key == 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        write(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", full)
    out = tmp_path / "out"
    assert main(["run", "--output", str(out), "--stop-after", "3"]) == 1
    err = capsys.readouterr().err
    results = out / "results.h5"
    assert (f"ddpy run: error: writing {results} failed: No space left on device; the "
            "results written so far are kept") in err
    assert "Traceback" not in err and "internal error" not in err
    monkeypatch.undo()
    with ResultsReader(results) as reader:
        assert reader.n_increments == 1 and len(reader.frames) == 1
        assert reader.field("displacement", 0).shape == reader.nodes.shape


FILL_THE_DISK = """
import sys
from pathlib import Path
import ddpy.io.results
from ddpy.app.cli import main

write_frame = ddpy.io.results.ResultsWriter._write_frame
filler = Path(sys.argv[1]) / "filler"

def fill_then_write(self, index, *args, **kwargs):
    # Another process takes every free byte of the disk while the fields of frame 1 are
    # written: after the writer's free-space check, before HDF5 writes them.
    if index == 1 and not filler.exists():
        with open(filler, "wb") as f:
            while True:
                try:
                    f.write(bytes(1 << 16))
                    f.flush()
                except OSError:
                    break
    write_frame(self, index, *args, **kwargs)

ddpy.io.results.ResultsWriter._write_frame = fill_then_write
sys.exit(main(["run", "--output", str(Path(sys.argv[1]) / "out"), "--stop-after", "3"]))
"""


def test_a_disk_filled_by_another_process_during_a_run(tmp_path: Path) -> None:
    # Issue 19: a disk filled between the free-space check and a write: HDF5 failed the
    # write, printed tracebacks while freeing its objects and crashed the process at exit.
    # The writer holds the disk blocks of a frame beyond the file's end before it writes;
    # the run stops with one message, the results readable up to the last increment.
    from ddpy.io.results import ResultsReader

    with small_disk(tmp_path / "disk", "4m") as disk:
        done = subprocess.run([sys.executable, "-c", FILL_THE_DISK, str(disk)],
                              capture_output=True, text=True)
        results = disk / "out" / "results.h5"
        assert done.returncode == 1, done.stderr  # not a signal (-11: a crash)
        assert done.stderr.count("\n") == 1, done.stderr
        assert "No space left on device" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr and "internal error" not in done.stderr
        (disk / "filler").unlink()
        with ResultsReader(results) as reader:
            assert reader.n_increments == 3 and len(reader.frames) >= 1
            assert reader.field("displacement", 0).shape == reader.nodes.shape
