"""Fuzzing the command line: random options and values for every command, the case or file
always one that does not exist (so that nothing heavy starts), end in a return code or an
argparse exit, never in another exception."""

from __future__ import annotations

import contextlib
import io

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ddpy.app.cli import main

MISSING = "/nonexistent/ddpy-fuzz"
OPTIONS = {
    "run": ["--output", "--restart", "--overwrite", "--threads", "--checkpoint-every",
            "--stop-after", "-v", "-vv"],
    "check": ["--no-geometry"],
    "tools build": ["--name", "--out", "--patches-per-arc", "--facets-per-arc", "--element",
                    "--size", "--arc-size", "--blank-side", "--blank-point", "--bezier-tol",
                    "--bezier-angle-tol", "--faces", "--models"],
    "tools error": ["--cad", "--samples", "--png", "--json"],
    "post": ["--output"],
    "compare": ["--output", "--labels"],
}
VALUES = ["0", "-1", "1", "2", "64", "65", "1e-15", "1e300", "nan", "inf", "-inf", "x",
          "1,2", "1,2,3", "0,0,0", "nan,0,1", "", "quad", "tri", "nagata,bezier", "..", "../x",
          str(2**31), str(2**63), "1_0", "\u0661", MISSING]

argument = st.one_of(st.sampled_from(VALUES), st.text(max_size=10))


@st.composite
def command_line(draw: st.DrawFn) -> list[str]:
    command = draw(st.sampled_from(sorted(OPTIONS)))
    argv = command.split() + [MISSING + (".step" if command == "tools build" else "")]
    for _ in range(draw(st.integers(0, 4))):
        argv.append(draw(st.sampled_from(OPTIONS[command])))
        if draw(st.booleans()):
            argv.append(draw(argument))
    return argv


@settings(max_examples=500, deadline=5000, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(command_line())
def test_random_command_lines_end_in_a_message(argv: list[str]) -> None:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as stop:  # argparse refusing an option: usage and exit 2
            code = stop.code
    assert code in (1, 2), (argv, code, err.getvalue())
    assert "Traceback" not in err.getvalue()
    assert err.getvalue().strip(), argv  # something says what is wrong


@pytest.mark.parametrize("argv", [["run", MISSING], ["check", MISSING],
                                  ["tools", "build", MISSING + ".step"]])
def test_a_missing_case_or_file_is_named(argv: list[str],
                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) in (1, 2)
    assert "ddpy-fuzz" in capsys.readouterr().err
