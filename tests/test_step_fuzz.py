"""Fuzzing the CAD reader: the bending benchmark's STEP file (written by ddpy's own CAD code)
with entities deleted, references redirected, numbers replaced by zeros, tiny, huge or
non-numbers, entities replaced by others and characters dropped. Each file is read or
refused with a CadError; the process neither crashes (a crash of the CAD kernel inside the
check read ends that child process only) nor hangs."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ddpy.cad.read
from ddpy.cad import CadError, gmsh_session, load_cad
from ddpy.cad.examples import bending_tools

#: More examples, drawn afresh each run: DDPY_STEP_EXAMPLES=500 pytest tests/test_step_fuzz.py
EXAMPLES_RUN = int(os.environ.get("DDPY_STEP_EXAMPLES", "0"))
#: Seconds the CAD kernel may read one file here: longer counts as a hang the checks missed.
HANG = 30.0
NUMBERS = ["0.", "-0.", "-1.", "1.E-300", "1.E+300", "7.5", "NAN", "1.E+15", "$", "*", "''"]


@pytest.fixture(scope="module")
def step(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The bending benchmark's punch and die, written by ddpy's own CAD code."""
    path = tmp_path_factory.mktemp("tools") / "tools.step"
    with gmsh_session():
        bending_tools(path)
    return path


#: (which entity, which damage, a number that picks the details)
mutation = st.tuples(st.integers(0, 10**6), st.integers(0, 4), st.integers(0, 10**6))


def mutate(lines: list[str], entities: list[int], pick: int, kind: int, seed: int) -> None:
    index = entities[pick % len(entities)]
    line = lines[index]
    if kind == 0:  # the entity deleted
        lines[index] = ""
    elif kind == 1:  # a reference redirected to another entity, or to none
        refs = list(re.finditer(r"#\d+", line.split("=", 1)[-1]))
        if refs:
            m = refs[seed % len(refs)]
            start = len(line.split("=", 1)[0]) + 1
            target = f"#{seed % (len(entities) + 10) + 1}"
            lines[index] = line[:start + m.start()] + target + line[start + m.end():]
    elif kind == 2:  # a number replaced
        numbers = list(re.finditer(r"-?\d+\.\d*(E[-+]?\d+)?", line))
        if numbers:
            m = numbers[seed % len(numbers)]
            value = NUMBERS[seed // 7 % len(NUMBERS)]
            lines[index] = line[:m.start()] + value + line[m.end():]
    elif kind == 3:  # the entity replaced by another kind of entity, its id kept
        other = lines[entities[seed % len(entities)]]
        lines[index] = line.split("=", 1)[0] + "=" + other.split("=", 1)[-1]
    else:  # a character dropped
        at = seed % max(len(line) - 1, 1)
        lines[index] = line[:at] + line[at + 1:]


@settings(max_examples=EXAMPLES_RUN or 60, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(st.lists(mutation, min_size=1, max_size=3))
def test_damaged_step_files_are_read_or_refused(tmp_path_factory: pytest.TempPathFactory,
                                                 step: Path,
                                                 changes: list[tuple[int, int, int]]) -> None:
    lines = step.read_text().splitlines(keepends=True)
    entities = [i for i, line in enumerate(lines) if line.startswith("#")]
    for pick, kind, seed in changes:
        mutate(lines, entities, pick, kind, seed)
    path = tmp_path_factory.mktemp("step") / "tools.step"
    path.write_text("".join(lines))
    saved = ddpy.cad.read.CAD_READ_TIMEOUT
    ddpy.cad.read.CAD_READ_TIMEOUT = HANG
    try:
        with gmsh_session():
            faces = load_cad(path)
        assert faces
    except CadError as error:
        message = str(error)
        assert message.startswith(str(path)), message
        assert "did not finish" not in message, f"a hang the checks let through: {message}"
    finally:
        ddpy.cad.read.CAD_READ_TIMEOUT = saved


def test_a_crash_of_the_cad_kernel_becomes_a_message(step: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    # What the checks do not foresee crashes the child process of the check read, not this
    # one: here the child is made to crash (as by a segmentation fault) on a valid file.
    import subprocess
    import sys

    run = subprocess.run

    def crash(args: list[str], **kwargs: object) -> subprocess.CompletedProcess:
        if args[:2] == [sys.executable, "-c"] and "importShapes" in args[2]:
            args = [sys.executable, "-c", "import os, signal; os.kill(os.getpid(), "
                    "signal.SIGSEGV)"]
        return run(args, **kwargs)

    monkeypatch.setattr(subprocess, "run", crash)
    with pytest.raises(CadError, match=r"the CAD kernel crashed reading the STEP file "
                                       r"\(SIGSEGV\)"), gmsh_session():
        load_cad(step)
    monkeypatch.setattr(ddpy.cad.read, "CAD_READ_TIMEOUT", 0.01)
    monkeypatch.setattr(subprocess, "run", run)
    with pytest.raises(CadError, match="did not finish reading the STEP file in 0.01 s"), \
            gmsh_session():
        load_cad(step)
