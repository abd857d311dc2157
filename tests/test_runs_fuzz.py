"""Fuzzing concurrent runs on one output folder (docs/running.md, *The output folder*).

- While a run holds a folder, any ``ddpy run`` on it (plain, ``--overwrite``, ``--restart``,
  with other options) is refused with one line naming the holder's pid, and every file of
  the folder keeps its bytes and its modification time.
- With no holder (no lock file, or one left behind with any content), the same command runs
  as it would alone and leaves neither a lock file nor a lock.
- Runs started together on one folder each end in results or in a refusal, and the results
  are those of a lone run.

More examples, drawn afresh each run: DDPY_FUZZ_EXAMPLES=200 pytest tests/test_runs_fuzz.py
"""

from __future__ import annotations

import contextlib
import fcntl
import io
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from deckutil import EXAMPLES
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from ddpy.app.cli import main
from ddpy.io.output_folder import LOCK, FolderLock
from tests.test_runner import compare

EXAMPLES_RUN = int(os.environ.get("DDPY_FUZZ_EXAMPLES", "0"))
CASE = EXAMPLES / "bending"
ENV = {**os.environ, "OMP_NUM_THREADS": "1"}
IN_USE = re.compile(r"ddpy run: error: (.+): in use by another ddpy run \((?:process (\d+)|a "
                    r"process that has not written its pid yet)\); nothing in it was changed: "
                    r"wait for that run to end, or choose another --output")


def snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file of a folder: its bytes and modification time."""
    return {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.iterdir())}


def ddpy_run(*argv: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "ddpy", "run", str(CASE), *argv],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)


@pytest.fixture(scope="module")
def lone(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """examples/bending stopped after two increments, run alone (restartable)."""
    out = tmp_path_factory.mktemp("lone") / "out"
    process = ddpy_run("--output", str(out), "--stop-after", "2")
    _, stderr = process.communicate(timeout=300)
    assert process.returncode == 0, stderr
    return out


# -- one command against a folder in every state --------------------------------------------

options = st.fixed_dictionaries({
    "overwrite": st.booleans(), "restart": st.booleans(),
    "checkpoint_every": st.sampled_from([None, "1", "3"]), "verbose": st.booleans()})


@settings(max_examples=EXAMPLES_RUN or 12, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(state=st.sampled_from(["missing", "empty", "stopped"]),
       lock=st.one_of(*[st.tuples(st.just("held"), st.integers(1, 2**22))] * 4,
                      st.tuples(st.just("left"), st.binary(max_size=24)),
                      st.tuples(st.just("none"), st.none())),
       chosen=options)
@example(state="stopped", lock=("left", b"4242\n"),  # a killed run's folder, continued
         chosen={"overwrite": False, "restart": True, "checkpoint_every": None,
                 "verbose": False})
def test_a_command_on_a_held_folder_is_refused_and_on_a_free_one_runs(
        lone: Path, state: str, lock: tuple[str, object], chosen: dict) -> None:
    kind, value = lock
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        if state == "stopped":
            shutil.copytree(lone, out)
        elif state == "empty" or kind != "none":
            out.mkdir()
        argv = ["run", str(CASE), "--output", str(out), "--stop-after", "1"]
        argv += ["--overwrite"] * chosen["overwrite"] + ["--restart"] * chosen["restart"]
        if chosen["checkpoint_every"] is not None:
            argv += ["--checkpoint-every", chosen["checkpoint_every"]]
        argv += ["-v"] * chosen["verbose"]
        with contextlib.ExitStack() as stack:
            if kind == "held":  # as a running run holds it: its own open file, locked
                fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
                stack.callback(os.close, fd)
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                os.write(fd, f"{value}\n".encode())
            elif kind == "left":  # left by a killed run: any content, no lock
                assert isinstance(value, bytes)
                (out / LOCK).write_bytes(value)
            before = snapshot(out) if out.exists() else None
            err = io.StringIO()
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                code = main(argv)
            lines = err.getvalue().splitlines()
            if kind == "held":
                assert code == 1 and len(lines) == 1, lines
                match = IN_USE.fullmatch(lines[0])
                assert match and match.group(1) == str(out) and match.group(2) == str(value)
                assert snapshot(out) == before
                return
        # No holder: what the command does alone (docs/running.md), and no lock left.
        assert "Traceback" not in err.getvalue()
        if chosen["restart"] and state != "stopped":
            assert code == 1 and "no checkpoint to restart from" in lines[-1], lines
        elif not chosen["restart"] and state == "stopped" and not chosen["overwrite"]:
            assert code == 1 and "exists: continue it with --restart" in lines[-1], lines
        else:
            assert code == 0, lines
        if code == 0:
            assert not (out / LOCK).exists()
        if out.exists():
            with FolderLock(out) as taken:
                assert taken.held


# -- runs started together ------------------------------------------------------------------


@settings(max_examples=EXAMPLES_RUN // 10 or 2, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(contenders=st.lists(st.booleans(), min_size=2, max_size=3))
def test_runs_started_together_end_in_results_or_a_refusal(lone: Path,
                                                           contenders: list[bool]) -> None:
    # Each contender: a plain run or an --overwrite, all on one new folder at once.
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        runs = [ddpy_run("--output", str(out), "--stop-after", "2",
                         *(["--overwrite"] if overwrite else [])) for overwrite in contenders]
        ended = [(run, *run.communicate(timeout=300)) for run in runs]
        pids = {str(run.pid) for run in runs}
        completed = 0
        for run, stdout, stderr in ended:
            if run.returncode == 0:
                assert "stopped after 2 increments" in stdout, stderr
                completed += 1
                continue
            lines = stderr.splitlines()
            assert run.returncode == 1 and len(lines) == 1, stderr
            match = IN_USE.fullmatch(lines[0])
            if match:
                assert match.group(1) == str(out)
                assert match.group(2) is None or match.group(2) in pids - {str(run.pid)}
            else:  # a plain run after another's results
                assert lines[0].endswith("results.h5 exists: continue it with --restart, or "
                                         "replace it with --overwrite"), lines
        assert completed >= 1
        assert not (out / LOCK).exists()
        compare(lone, out)
