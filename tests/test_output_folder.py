"""The output folder of a run (docs/running.md): one run at a time holds it (the lock), and a
folder that cannot take results (a root, an empty name, a pseudo-filesystem, a read-only or
full file system, a path through a file) is refused with one line before anything starts."""

from __future__ import annotations

import contextlib
import fcntl
import io
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from deckutil import EXAMPLES
from test_reliability import mounted

from ddpy.app.cli import main
from ddpy.app.runner import RunError, run_case
from ddpy.io.decks import read_case
from ddpy.io.output_folder import LOCK, FolderInUse, FolderLock
from ddpy.io.results import ResultsReader, ResultsWriter
from ddpy.model.mesh import HexMesh

CASE = EXAMPLES / "bending"


def run_cli(*argv: str) -> tuple[int, str]:
    """``ddpy ARGV`` in this process: its exit code and standard error."""
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, err.getvalue()


def snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file of a folder: its bytes and modification time."""
    return {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def stopped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output of examples/bending stopped after two increments (restartable)."""
    out = tmp_path_factory.mktemp("stopped") / "out"
    assert run_case(read_case(CASE), out, max_increments=2).status == "stopped"
    return out


@contextlib.contextmanager
def held(folder: Path, pid: int) -> Iterator[None]:
    """The folder's lock held as a running run holds it (its own open file, so that the
    runner's lock conflicts with it in this process too), its lock file naming ``pid``."""
    fd = os.open(folder / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, f"{pid}\n".encode())
        yield
    finally:
        os.close(fd)


# -- the lock -------------------------------------------------------------------------------


@pytest.mark.parametrize("how", ["run", "overwrite", "restart"])
def test_a_locked_folder_is_refused_at_once_and_left_as_it_was(
        stopped: Path, tmp_path: Path, how: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    for p in stopped.iterdir():
        (out / p.name).write_bytes(p.read_bytes())
    with held(out, 4242):
        before = snapshot(out)
        with pytest.raises(RunError) as caught:
            run_case(read_case(CASE), out, overwrite=how == "overwrite",
                     restart=how == "restart")
        assert str(caught.value) == (
            f"{out}: in use by another ddpy run (process 4242); nothing in it was changed: "
            "wait for that run to end, or choose another --output")
        assert isinstance(caught.value.__cause__, FolderInUse)
        assert caught.value.__cause__.pid == 4242
        code, err = run_cli("run", str(CASE), "--output", str(out),
                            *{"run": [], "overwrite": ["--overwrite"],
                              "restart": ["--restart"]}[how])
        assert code == 1
        assert err.splitlines() == [f"ddpy run: error: {caught.value}"]
        assert snapshot(out) == before


def test_a_lock_left_by_a_killed_run_is_taken_over(stopped: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    for p in stopped.iterdir():
        (out / p.name).write_bytes(p.read_bytes())
    # A process that takes the lock as a run does and is killed while it holds it.
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys; from ddpy.io.output_folder import FolderLock; "
         "FolderLock(sys.argv[1]).acquire(); print('held', flush=True); sys.stdin.read()",
         str(out)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert holder.stdout is not None and holder.stdout.readline() == "held\n"
    with pytest.raises(RunError, match=f"process {holder.pid}"):
        run_case(read_case(CASE), out, restart=True)
    holder.kill()
    holder.wait(timeout=30)
    assert (out / LOCK).read_text() == f"{holder.pid}\n"  # the file stays; the lock went
    outcome = run_case(read_case(CASE), out, restart=True, max_increments=3)
    assert outcome.status == "stopped" and outcome.increments == 3, outcome.message
    assert not (out / LOCK).exists()


@pytest.mark.parametrize("content", [b"", b"99999999\n", b"\x00\xff junk", b"-1"])
def test_a_lock_file_no_process_holds_is_taken_over(tmp_path: Path, content: bytes) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK).write_bytes(content)
    assert run_case(read_case(CASE), out, max_increments=1).status == "stopped"
    assert not (out / LOCK).exists()
    with FolderLock(out) as lock:  # and the lock of a run names its process
        assert lock.held and (out / LOCK).read_text() == f"{os.getpid()}\n"
        with pytest.raises(FolderInUse, match=f"process {os.getpid()}"):
            FolderLock(out).acquire()


def test_a_lock_file_that_cannot_be_opened_is_named(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (out / LOCK).mkdir(parents=True)
    code, err = run_cli("run", str(CASE), "--output", str(out))
    assert code == 1
    assert err.splitlines() == [f"ddpy run: error: {out / LOCK}: cannot be opened as the "
                                "run's lock file (Is a directory); remove it, or choose "
                                "another --output"]


def test_overwritten_results_are_a_new_file_not_the_old_one_truncated(tmp_path: Path) -> None:
    # A process that has the old results open (a reader, a run of an older ddpy) keeps them.
    path = tmp_path / "results.h5"
    mesh = HexMesh.box(2.0, 1.0, 1.0, 2, 1, 1)
    with ResultsWriter(path, mesh, ("punch",), title="old"):
        pass
    with open(path, "rb") as old:
        data = old.read()
        with ResultsWriter(path, mesh, ("punch",), title="new", overwrite=True):
            pass
        old.seek(0)
        assert old.read() == data
    with ResultsReader(path) as reader:
        assert reader.title == "new"


# -- the path -------------------------------------------------------------------------------


def test_the_root_of_the_file_system_is_refused(tmp_path: Path) -> None:
    before = sorted(os.listdir("/"))
    for root in ("/", "//", "/.."):
        code, err = run_cli("run", str(CASE), "--output", root, "--stop-after", "1")
        assert code == 1
        assert err.splitlines() == [f"ddpy run: error: {Path(root)}: the root of the file "
                                    "system is not a place for results; name a folder "
                                    "(--output DIR)"]
    assert sorted(os.listdir("/")) == before


def test_an_empty_output_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # It fell back silently to the default folder results/<case>.
    monkeypatch.chdir(tmp_path)
    for empty in ("", "  "):
        code, err = run_cli("run", str(CASE), "--output", empty, "--stop-after", "1")
        assert code == 1
        assert err.splitlines() == ["ddpy run: error: the output folder's name is empty; "
                                    "name a folder (--output DIR)"]
        with pytest.raises(RunError, match="name is empty"):
            run_case(read_case(CASE), empty, max_increments=1)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("folder, kind", [("/proc", "proc"), ("/sys", "sysfs")])
def test_a_pseudo_filesystem_is_not_a_place_for_results(folder: str, kind: str) -> None:
    # It said "/proc: 0 MB free".
    if not Path(folder, "self" if kind == "proc" else "kernel").exists():
        pytest.skip(f"no {folder} here")
    code, err = run_cli("run", str(CASE), "--output", f"{folder}/ddpy-out/x")
    assert code == 1
    assert err.splitlines() == [f"ddpy run: error: {folder}/ddpy-out/x: {folder} is a {kind} "
                                "pseudo-filesystem, not a place for results; choose another "
                                "--output"]


def test_a_folder_that_cannot_be_written_is_refused(tmp_path: Path) -> None:
    if os.geteuid() == 0:  # root writes through permissions: a read-only file system
        context = mounted(tmp_path / "ro", "ro,size=1m")
        why = "its file system is mounted read-only"
    else:
        (tmp_path / "ro").mkdir(mode=0o555)
        context = contextlib.nullcontext(tmp_path / "ro")
        why = "permission denied"
    with context as ro:
        code, err = run_cli("run", str(CASE), "--output", str(ro / "out"))
        assert code == 1
        assert err.splitlines() == [f"ddpy run: error: {ro / 'out'}: {ro} is not writable "
                                    f"({why}); choose another --output"]


def test_free_space_is_that_of_the_folders_own_file_system(tmp_path: Path) -> None:
    # The output inside a small file system: measured there, on the nearest existing folder
    # (the mount point), not on the file system the mount point's folder belongs to.
    with mounted(tmp_path / "small", "size=64k") as small:
        code, err = run_cli("run", str(CASE), "--output", str(small / "b" / "c"))
        assert code == 1
        assert err.startswith(f"ddpy run: error: {small}: ")
        assert "MB free, the results of this mesh need at least" in err
        assert len(err.splitlines()) == 1
        assert list(small.iterdir()) == []


@pytest.mark.parametrize("make, message", [
    (lambda t: (t / "file").write_text("x"), "{t}/file/out: {t}/file is a file, not a folder"),
    (lambda t: (t / "link").symlink_to(t / "nowhere"),
     "{t}/link/out: {t}/link is a symbolic link to nothing; the output must be a folder"),
])
def test_a_path_through_a_file_or_a_dangling_link_is_refused(tmp_path: Path, make,
                                                              message: str) -> None:
    make(tmp_path)
    name = message.split(":")[0].format(t=tmp_path)
    code, err = run_cli("run", str(CASE), "--output", name)
    assert code == 1
    assert err.splitlines() == ["ddpy run: error: " + message.format(t=tmp_path)]



def test_atomic_write_replaces_whole_or_keeps_the_last_version(tmp_path: Path) -> None:
    """One writer for the status, the XDMF and the checkpoints: the new text replaces the
    file only when the block ends; an error inside it keeps the old version and leaves no
    temporary beside it; the file is readable by all (RESULT_MODE)."""
    from ddpy.io.output_folder import RESULT_MODE, atomic_write

    path = tmp_path / "status.json"
    with atomic_write(path) as out:
        out.write("first")
    assert path.read_text() == "first"
    assert path.stat().st_mode & 0o777 == RESULT_MODE
    with pytest.raises(RuntimeError), atomic_write(path) as out:
        out.write("half")
        raise RuntimeError("disk full")
    assert path.read_text() == "first"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["status.json"]
