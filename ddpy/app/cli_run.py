"""``ddpy run``: run a case with a progress display; Ctrl-C stops cleanly (docs/running.md)."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import TYPE_CHECKING, TextIO

from ddpy.core import mpi
from ddpy.model.forming_limits import MARGINAL_BAND

if TYPE_CHECKING:
    from ddpy.app.runner import Progress

__all__ = ["ProgressDisplay", "add_post", "add_run"]

#: Exit codes of ``ddpy run``.
EXIT = {"completed": 0, "stopped": 0, "failed": 1, "interrupted": 130}


class ProgressDisplay:
    """A progress bar rewritten in place on a terminal, one plain line per increment
    otherwise (a log file, a pipe, and under mpirun, which hands rank 0 a terminal of its
    own whatever mpirun's output is)."""

    def __init__(self, stream: TextIO, width: int = 24,
                 clock: Callable[[], float] = time.perf_counter) -> None:
        self.stream, self.width, self.clock = stream, width, clock
        self.tty = stream.isatty() and mpi.launched_size() == 1
        self.start = clock()
        self._open = False
        # Where the rate of progress is measured from: the first increment shown (a
        # restart starts part-way).
        self._origin: tuple[float, float] | None = None

    def eta(self, fraction: float) -> str:
        """The time left at this pace, from the share of the run done since the first
        increment shown ('--' before there is a pace)."""
        now = self.clock()
        if self._origin is None:
            self._origin = (now, fraction)
            return "--"
        t0, f0 = self._origin
        if fraction <= f0 or now <= t0:
            return "--"
        return _duration((now - t0) / (fraction - f0) * (1.0 - fraction))

    def __call__(self, p: Progress) -> None:
        elapsed = self.clock() - self.start
        run = min(max(p.run_fraction, 0.0), 1.0)
        eta = self.eta(run)
        lead = f"{p.lead} {p.travel:.4f}/{p.phase_travel:g} mm" if p.lead else "tools off"
        if not self.tty:
            print(f"increment {p.increment} phase {p.phase} ({p.phase_index + 1}/{p.phases}) "
                  f"{lead} step {p.step:.4g} iterations {p.iterations} limit {p.limit} "
                  f"{elapsed:.1f} s, run {100 * run:.1f} % done, ETA {eta}", file=self.stream,
                  flush=True)
            return
        filled = int(round(self.width * run))
        bar = "#" * filled + "-" * (self.width - filled)
        line = (f"\r[{bar}] {100 * run:5.1f}% ETA {eta}  {p.phase} ({p.phase_index + 1}/"
                f"{p.phases})  inc {p.increment}  {lead}  it {p.iterations}  {elapsed:.0f} s")
        self.stream.write(line + "\033[K")
        self.stream.flush()
        self._open = True

    def close(self) -> None:
        if self._open:
            self.stream.write("\n")
            self.stream.flush()
            self._open = False


def _duration(seconds: float) -> str:
    """'42 s', '3 min 05 s', '2 h 07 min'."""
    seconds = max(0.0, seconds)
    if seconds < 60:
        return f"{seconds:.0f} s"
    minutes, rest = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {rest:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


class _Interrupt:
    """SIGINT sets a flag the run polls after each increment; a second one aborts."""

    def __init__(self) -> None:
        self.requested = False
        self._previous = signal.getsignal(signal.SIGINT)

    def __enter__(self) -> _Interrupt:
        signal.signal(signal.SIGINT, self._handle)
        return self

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        print("\nddpy run: stopping after this increment (Ctrl-C again to abort)",
              file=sys.stderr, flush=True)

    def __call__(self) -> bool:
        return self.requested

    def __exit__(self, *exc: object) -> None:
        signal.signal(signal.SIGINT, self._previous)


class _LogLines(logging.Handler):
    """The solver's messages on standard error, each on a line of its own: an open progress
    bar line is ended first."""

    def __init__(self, display: ProgressDisplay) -> None:
        super().__init__()
        self.display = display
        self.setFormatter(logging.Formatter("  %(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        self.display.close()
        print(self.format(record), file=sys.stderr, flush=True)


@contextmanager
def _solver_log(verbose: int, display: ProgressDisplay) -> Iterator[None]:
    """The solver's cut and restarted increments, and with -v every Newton iteration, on
    standard error while the run lasts: a run that cuts back is seen doing so. The handler
    goes with it (ddpy.app.cli.main may be called again)."""
    handler = _LogLines(display)
    logger = logging.getLogger("ddpy")
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG if verbose else logging.INFO)
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


def _run(args: argparse.Namespace) -> int:
    from ddpy.app.runner import RunError, case_folder, default_output, run_case
    from ddpy.io.checkpoint import CheckpointError
    from ddpy.io.decks import DeckError, read_case
    from ddpy.io.output_folder import OutputFolderError, check_output_folder
    from ddpy.io.results import ResultsWriteError

    folder = case_folder(args.case)
    if args.case and str(args.case).lower().endswith(".inp"):
        from ddpy.app.convert import convert_command

        converted = convert_command(str(args.case), None, args.tools or "facets", args.element,
                                    False, "run")
        if converted is None:
            return 2
        folder = converted
    elif args.tools or args.element:
        print("ddpy run: --tools and --element are for an input file (MODEL.inp); a case "
              "folder names its tools in tools.dat", file=sys.stderr)
        return 2
    try:
        case = read_case(folder)
    except DeckError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        print(f"{folder}: {len(error.errors)} error(s); see 'ddpy check'", file=sys.stderr)
        return 2
    for warning in case.warnings:  # the same as 'ddpy check' prints
        print(f"warning: {warning}", file=sys.stderr)
    try:  # the path's faults before anything starts (run_case checks them again)
        output = (check_output_folder(args.output) if args.output is not None
                  else default_output(folder))
    except OutputFolderError as error:
        print(f"ddpy run: error: {error}", file=sys.stderr)
        return 1
    display = ProgressDisplay(sys.stdout)
    verb = "continuing" if args.restart else "running"
    print(f"ddpy run: {verb} {case.title} ({folder}) -> {output}", flush=True)
    try:
        with _Interrupt() as interrupt, _solver_log(args.verbose, display):
            outcome = run_case(case, output, restart=args.restart, progress=display,
                               stop=interrupt, overwrite=args.overwrite,
                               checkpoint_every=args.checkpoint_every,
                               max_increments=args.stop_after, threads=args.threads)
    except ResultsWriteError as error:  # disk full or an I/O error while running
        display.close()
        print(f"ddpy run: error: {error}; the results written so far are kept",
              file=sys.stderr)
        return 1
    except (RunError, CheckpointError, ValueError) as error:
        display.close()
        print(f"ddpy run: error: {error}", file=sys.stderr)
        return 1
    except OSError as error:  # the file system: permissions, space, a vanished folder
        display.close()
        where = error.filename or output
        print(f"ddpy run: error: {where}: {error.strerror or error}; the results written so "
              "far are kept", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        display.close()
        print("ddpy run: aborted; the results and the last checkpoint are kept",
              file=sys.stderr)
        return 130
    display.close()
    print(f"ddpy run: {outcome.status} after {outcome.increments} increments, "
          f"{outcome.frames} frames, {outcome.wall_time:.1f} s"
          + (f": {outcome.message}" if outcome.message else ""))
    print(f"  results: {outcome.results} (open {outcome.results.with_suffix('.xdmf')} in "
          "ParaView)")
    if outcome.status in ("interrupted", "stopped"):
        again = ["ddpy run", *([str(args.case)] if args.case else []), "--restart",
                 "--output", str(output)]
        print(f"  continue with: {' '.join(again)}")
    return EXIT[outcome.status]


def _at_least(low: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``low``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got '{text}'") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be at least {low}, got {value}")
        return value

    return parse


_at_least_one = _at_least(1)


def _threads(text: str) -> int:
    """An argparse type: a thread count that ddpy.core.parallel.set_threads accepts."""
    from ddpy.core.parallel import thread_limit

    value = _at_least_one(text)
    if value > thread_limit():
        raise argparse.ArgumentTypeError(f"must be at most {thread_limit()} (four per core of "
                                         f"this machine, at least 64), got {value}")
    return value


def add_run(commands: argparse._SubParsersAction) -> None:
    """The ``run`` subcommand."""
    run = commands.add_parser(
        "run", help="run a case (default: the built-in coarse cylindrical bending)",
        description="Run the phases of a case folder, writing results.h5/.xdmf, checkpoints "
        "and status.json to the output folder. Ctrl-C stops after the current increment and "
        "keeps the results; --restart continues from the last checkpoint.")
    run.add_argument("case", nargs="?", metavar="CASE",
                     help="case folder, a built-in case: cylindrical-bending (the "
                     "default), deep-drawing or square-cup, or an Abaqus / CalculiX input file "
                     "MODEL.inp, converted first into MODEL_case beside it (ddpy convert)")
    run.add_argument("--output", metavar="DIR",
                     help="output folder (default: results/<case folder name>)")
    run.add_argument("--restart", action="store_true",
                     help="continue from the output folder's last checkpoint")
    run.add_argument("--overwrite", action="store_true",
                     help="replace results already in the output folder")
    run.add_argument("--threads", type=_threads, metavar="N",
                     help="OpenMP threads of the core (default: OMP_NUM_THREADS)")
    run.add_argument("--checkpoint-every", type=_at_least_one, default=10, metavar="N",
                     help="write a checkpoint every N increments (default 10; also at the "
                     "end of every phase)")
    run.add_argument("--stop-after", type=_at_least(0), metavar="N",
                     help="stop after N increments of the whole run (restartable); 0: "
                     "before the first, once the run has checked and prepared everything")
    run.add_argument("--tools", choices=("facets", "nagata"),
                     help="with MODEL.inp: the tools as given (facets, the default) or Nagata "
                     "patches over them")
    run.add_argument("--element", choices=("hexahedron", "solid-shell"),
                     help="with MODEL.inp: the blank's element (default by its type)")
    run.add_argument("-v", "--verbose", action="count", default=0,
                     help="report every Newton iteration's residual and step length on "
                     "standard error, besides the cut increments and why (always)")
    run.set_defaults(handler=_run)


def _post(args: argparse.Namespace) -> int:
    from ddpy.app.post import post_run

    try:
        paths = post_run(args.target, args.output, args.fld_margin)
    except (FileNotFoundError, ValueError, KeyError) as error:
        print(f"ddpy post: error: {error}", file=sys.stderr)
        return 1
    for path in paths:
        print(path)
    return 0


def _compare(args: argparse.Namespace) -> int:
    from ddpy.app.post import compare_runs

    labels = [x.strip() for x in args.labels.split(",")] if args.labels else None
    # A usage error exits 2, as argparse's do; a RUN without results or a results file
    # that cannot be read exits 1, as in ddpy post.
    if labels is not None and len(labels) != len(args.runs):
        print(f"ddpy compare: error: --labels gives {len(labels)} labels for "
              f"{len(args.runs)} runs: expected one per RUN, in order", file=sys.stderr)
        return 2
    try:
        paths, table = compare_runs(args.runs, args.output, labels)
    except (FileNotFoundError, ValueError, KeyError) as error:
        print(f"ddpy compare: error: {error}", file=sys.stderr)
        return 1
    print(table, end="")
    for path in paths:
        print(path, file=sys.stderr)
    return 0


def _margin(text: str) -> float:
    """--fld-margin: a strain from 0 to 1."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"expected a major strain from 0 to 1, got {text!r}")
    return value


def add_post(commands: argparse._SubParsersAction) -> None:
    """The ``post`` and ``compare`` subcommands."""
    post = commands.add_parser(
        "post", help="figures (PNG) and tables (CSV, markdown) of a run",
        description="Write force_stroke.png, increments.png, contact.png, plastic_strain.png, "
        "thinning.png, fld.png (the forming limit diagram), increments.csv, phases.csv, "
        "iterations.csv (Newton iterations by their place in an increment) and summary.md "
        "for a run.")
    post.add_argument("target", metavar="CASE_OR_RESULTS",
                      help="a results file, an output folder, or a case folder (its default "
                      "output results/<name>)")
    post.add_argument("--output", metavar="DIR", help="where to write (default: beside the "
                      "results file)")
    post.add_argument("--fld-margin", type=_margin, default=MARGINAL_BAND, metavar="STRAIN",
                      help="the forming limit diagram's marginal band: elements within this "
                      "major strain below the forming limit curve are marginal (default "
                      f"{MARGINAL_BAND:g})")
    post.set_defaults(handler=_post)
    compare = commands.add_parser(
        "compare", help="overlay the force-stroke curves of several runs",
        description="Overlay the lead tool's force against stroke of several runs "
        "(compare_force.png) and tabulate increments, iterations, cutbacks, force and time "
        "(compare.csv, compare.md; the table is also printed).")
    compare.add_argument("runs", nargs="+", metavar="RUN",
                         help="results files, output folders or case folders")
    compare.add_argument("--output", default="compare", metavar="DIR",
                         help="where to write (default: compare)")
    compare.add_argument("--labels", metavar="A,B,...", help="names of the runs in the legend "
                         "(default: their folder names)")
    compare.set_defaults(handler=_compare)
