"""Run a case: from the validated decks (:class:`ddpy.io.case.Case`) through its phases to the
results file, with checkpoints to continue an interrupted run (docs/running.md).

>>> from ddpy.io.decks import read_case
>>> from ddpy.app.runner import run_case
>>> outcome = run_case(read_case("examples/bending"), "bending-results")  # doctest: +SKIP
>>> outcome.status, outcome.increments                                     # doctest: +SKIP

The output folder holds ``results.h5`` and ``results.xdmf`` (docs/results-format.md),
``checkpoint.npz`` (the last checkpoint) and ``status.json`` (running, completed,
interrupted, stopped or failed). ``run_case(..., restart=True)`` continues from the
checkpoint; the results then end as those of an uninterrupted run (to the bit while the
Newton loop factorizes every iteration; docs/running.md).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import resource
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy.io.case import Case, HoldForce, HoldGap, Move, Phase
from ddpy.io.checkpoint import (
    CheckpointError,
    forming_state_arrays,
    forming_state_from_arrays,
    read_checkpoint,
    write_checkpoint,
)
from ddpy.io.output_folder import (
    FolderLock,
    OutputFolderError,
    atomic_write,
    check_output_folder,
)
from ddpy.io.results import (
    MIN_FREE,
    ResultsReader,
    ResultsWriteError,
    ResultsWriter,
    Timings,
    frame_bytes,
)
from ddpy.model.forming import (
    FieldFrame,
    FormingError,
    FormingProblem,
    FormingResult,
    PhaseProgress,
    RigidTool,
)
from ddpy.model.solid import Solid

_log = logging.getLogger(__name__)

__all__ = ["BUILT_IN_CASES", "CHECKPOINT", "DEFAULT_CASE", "RESULTS", "STATUS", "Progress",
           "RunError", "RunOutcome", "build_problem", "case_folder", "default_output",
           "read_status", "run_case"]

#: The case ``ddpy run`` runs when given none: the coarse cylindrical bending packaged with
#: ddpy (for now a copy of examples/bending, kept equal by a test). To change the default,
#: replace the decks and tool files in this folder (and their list in meson.build).
DEFAULT_CASE = Path(__file__).resolve().parents[1] / "cases" / "cylindrical_bending"
#: The cases packaged with ddpy, by the name ``ddpy run NAME`` and ``ddpy check NAME`` take:
#: the coarse cases of the paper's two examples and of the Numisheet'93 square cup
#: (benchmarks/*/make_case.py --default-case).
BUILT_IN_CASES = {"cylindrical-bending": DEFAULT_CASE,
                  "deep-drawing": DEFAULT_CASE.parent / "reverse_deep_drawing",
                  "square-cup": DEFAULT_CASE.parent / "square_cup"}
RESULTS = "results.h5"


def default_output(case_folder: Path) -> Path:
    """Where a run writes when no --output is given: results/<case folder name>."""
    return Path("results") / case_folder.resolve().name


def case_folder(case: str | os.PathLike[str] | None) -> Path:
    """The folder of a case given as a folder or as the name of a built-in case (a folder of
    that name wins); the default case for None."""
    if case is None:
        return DEFAULT_CASE
    path = Path(case)
    if not path.exists() and str(case) in BUILT_IN_CASES:
        return BUILT_IN_CASES[str(case)]
    return path

CHECKPOINT = "checkpoint.npz"
STATUS = "status.json"
#: Checkpoint every this many increments by default (and at the end of every phase).
CHECKPOINT_EVERY = 10
#: The blank's volume change past which a run warns, once: plastic flow keeps the volume
#: and the elastic change is the mean stress over the bulk modulus (0.2 % at 350 MPa for
#: steel), so beyond 1 % the elements are wrong somewhere: a solid-shell blank too coarse
#: for a tool radius it wraps (docs/theory/solid_shell.md, "Volume").
VOLUME_LIMIT = 0.01
#: What limited an increment in ddpy.model.forming -> the ``limit`` names of ddpy.io.results.
_LIMITS = {"max": "max_increment", "touch": "contact_touch", "strain": "strain",
           "rotation": "rotation", "yield": "yield", "cut": "cutback", "regrow": "cutback",
           "release": "contact_release",
           "springback": "max_increment"}


class RunError(RuntimeError):
    """A run cannot start or continue (output exists, no checkpoint, the case changed...)."""


@dataclass(frozen=True)
class Progress:
    """What the progress callback receives after each increment."""

    phase: str
    phase_index: int
    phases: int
    increment: int
    lead: str | None
    travel: float
    phase_travel: float
    step: float
    iterations: int
    limit: str
    #: The share of the whole run done, in [0, 1]: the phases weighed by their increments
    #: (a forming phase's travel over its largest increment, a springback's increments).
    run_fraction: float = 0.0


def _phase_weight(phase: Phase) -> float:
    """A phase's expected increments, its weight in the run's progress."""
    if phase.is_springback:
        return float(max(phase.increments, 1))
    return max(phase.travel / phase.max_increment, 1.0) if phase.max_increment else 1.0


@dataclass(frozen=True)
class RunOutcome:
    """How a run ended: ``status`` is completed, interrupted (stop requested), stopped
    (``max_increments`` reached) or failed (``message`` says why)."""

    status: str
    message: str
    increments: int
    frames: int
    wall_time: float
    output: Path

    @property
    def results(self) -> Path:
        return self.output / RESULTS

    def field_frames(self) -> list[FieldFrame]:
        """The blank's fields at every frame of the results (displacement, stress, plastic
        strain, thickness and thinning, contact pressure, surface strains; each frame's
        ``to_meshio()`` gives a meshio mesh), frame 0 the initial state."""
        with ResultsReader(self.results) as r:
            return [r.field_frame(k) for k in range(len(r.frames))]


def read_status(output: str | os.PathLike[str]) -> dict[str, Any]:
    """The status document of an output folder."""
    return json.loads((Path(output) / STATUS).read_text())


def discretization(case: Case) -> str:
    """What the case's decks resolve to with this code's defaults: the blank's element and
    each tool's contact and points. A checkpoint keeps it: a default that changed between
    the run and its restart (the element, the contact) would otherwise go unseen, the decks
    being the same."""
    tools = ", ".join(f"{t.name} {t.discretization}"
                      + (f" {t.face_points}" if t.face_points else "") for t in case.tools)
    return f"{case.element}; {tools}"


def case_fingerprint(case: Case) -> str:
    """SHA-256 of the decks and tool files of a case: a restart refuses a changed case."""
    digest = hashlib.sha256()
    from ddpy.io.decks import DECKS

    for path in [case.folder / name for name in DECKS] + [t.file for t in case.tools]:
        digest.update(path.name.encode())
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()


def _rolling_angle(case: Case) -> float:
    """The rolling direction as the Solid takes it: degrees from x about z."""
    axis = case.mesh.normal_axis
    if axis != 2:
        raise RunError(f"{case.material.origin or case.folder}: the solid takes the rolling "
                       "direction about z only; a sheet normal along "
                       f"{'xyz'[axis]} is not supported yet")
    sign = 1.0 if case.mesh.normal[2] > 0 else -1.0
    return sign * case.material.rolling_angle


def build_problem(case: Case) -> FormingProblem:
    """The Solid (material, rolling direction, element), the rigid tools and the
    FormingProblem with the case's tuning (control.dat's ``tune`` lines). A restart builds
    it again from the same decks (the checkpoint refuses changed ones), so it runs on with
    the same tuning."""
    solid = Solid(case.mesh, case.material.material, _rolling_angle(case), element=case.element)
    tools = [RigidTool(t.name, t.model().surface, t.contact_nodes(case.mesh),
                       friction=t.friction, facing=t.facing, augmentation=t.augmentation,
                       contact=t.discretization, penalty=t.penalty,
                       points=t.points, barrier=t.barrier)
             for t in case.tools]
    return FormingProblem(solid, tools, tuning=case.control.tuning)


def _write_atomic(path: Path, text: str) -> None:
    with atomic_write(path) as out:
        out.write(text)


def _segments(phase: Phase) -> list[float]:
    """Lead travels at which the phase's sub-runs end: the output_at travels, then the end."""
    ends = [t for t in phase.output_at if 0.0 < t < phase.travel * (1 - 1e-12)]
    return [*ends, phase.travel]


def _carried(last: PhaseProgress, share: float, next_share: float,
             position: dict[str, NDArray[np.float64]]) -> PhaseProgress:
    """The progress that starts the next segment of a phase where ``last`` ended one: the
    rates and the trial step of the phase go on, rescaled from the old segment's factor
    (``share`` of the phase) to the new one's, so an output frame costs no careful start."""
    scale = next_share / share  # d(old factor) / d(new factor) is share_new / share_old
    # A step limited by nothing but the largest increment is the new segment's nominal one
    # (FormingProblem.run clamps it): a segment shorter than the largest increment clipped
    # its own.
    step = math.inf if last.reason == "max" else last.step / scale
    return PhaseProgress(
        start={name: x.copy() for name, x in position.items()}, offsets=last.offsets,
        factor=0.0, step=step, reason=last.reason,
        last_du=None if last.last_du is None else last.last_du * scale,
        last_dp=None if last.last_dp is None else last.last_dp * scale,
        last_size=None if last.last_size is None else last.last_size / scale,
        before_du=None if last.before_du is None else last.before_du * scale,
        before_size=None if last.before_size is None else last.before_size / scale,
        start_weight=last.start_weight)


class _Run:
    """One run of a case; its counters are what a checkpoint stores."""

    def __init__(self, case: Case, output: Path, progress: Callable[[Progress], None] | None,
                 stop: Callable[[], bool] | None, checkpoint_every: int,
                 max_increments: int | None) -> None:
        self.case, self.output = case, output
        self.progress, self.stop = progress, stop
        self.checkpoint_every, self.max_increments = checkpoint_every, max_increments
        self.problem = build_problem(case)
        self.fingerprint = case_fingerprint(case)
        self.discretization = discretization(case)
        self.names = [t.name for t in self.problem.tools]
        self.slaves = np.concatenate([t.slaves for t in self.problem.tools])
        self.tool_of = np.concatenate([np.full(t.slaves.size, i)
                                       for i, t in enumerate(self.problem.tools)])
        # Counters (checkpointed).
        self.phase_index = 0
        self.segment = 0
        self.phase_increments = 0
        self.last_frame = 0
        self.elapsed = 0.0
        self.resume: PhaseProgress | None = None
        self.writer: ResultsWriter | None = None
        # Increments, iteration rows and frames of the results file at the checkpoint.
        self._reopen_at = (0, 0, 0)
        self.halt = ""  # why the run stops early: "interrupted" or "stopped"
        self.warned: set[str] = set()  # tools whose penetration limit a warning named
        self.volume_warned = False
        self.element_volumes = self.problem.solid.mesh.element_volumes()
        self._clock = time.perf_counter()
        self._since_checkpoint = 0

    # -- checkpoints -----------------------------------------------------------------

    def save(self, progress: PhaseProgress | None) -> None:
        """Write a checkpoint of the present state (``progress``: inside a forming phase)."""
        assert self.writer is not None
        arrays = forming_state_arrays(self.problem.state())
        meta: dict[str, Any] = {
            "fingerprint": self.fingerprint, "discretization": self.discretization,
            "phase_index": self.phase_index,
            "segment": self.segment, "phase_increments": self.phase_increments,
            "last_frame": self.last_frame, "increments": self.writer.increments,
            "iterations": self.writer.iteration_rows, "frames": self.writer.frame_count,
            "elapsed": self.elapsed + time.perf_counter() - self._clock, "progress": None}
        if progress is not None:
            meta["progress"] = {"factor": progress.factor, "step": progress.step,
                                "reason": progress.reason, "last_size": progress.last_size,
                                "before_size": progress.before_size,
                                "start_weight": progress.start_weight,
                                "offsets": {k: o for k, (o, _) in progress.offsets.items()}}
            arrays.update({f"start/{k}": v for k, v in progress.start.items()})
            arrays.update({f"offset/{k}": v for k, (_, v) in progress.offsets.items()})
            for name in ("last_du", "last_dp", "before_du"):
                if getattr(progress, name) is not None:
                    arrays[name] = getattr(progress, name)
        write_checkpoint(self.output / CHECKPOINT, meta, arrays)
        self._since_checkpoint = 0

    def load(self) -> None:
        """Restore the state and counters of the checkpoint, reopen the results there."""
        path = self.output / CHECKPOINT
        meta, arrays = read_checkpoint(path)
        try:
            self._restore(path, meta, arrays)
        except CheckpointError:
            raise
        except KeyError as error:  # an array or counter removed (an edited or foreign file)
            raise CheckpointError(f"{path}: the entry '{error.args[0]}' is missing; run again "
                                  "without --restart") from None
        except (TypeError, ValueError, AttributeError, IndexError) as error:
            raise CheckpointError(f"{path}: damaged ({error}); run again without --restart"
                                  ) from None
        results = self.output / RESULTS
        if not results.is_file():
            raise RunError(f"{results}: missing; the checkpoint continues it, so run again "
                           "without --restart")
        try:
            self.writer = ResultsWriter.reopen(results, *self._reopen_at)
        except (OSError, KeyError, ValueError) as error:
            raise RunError(f"{results}: cannot be continued ({error}); run again without "
                           "--restart") from None

    def _restore(self, path: Path, meta: dict[str, Any], arrays: dict[str, NDArray]) -> None:
        """The problem's state and the counters from a checkpoint read from ``path``."""
        if meta["fingerprint"] != self.fingerprint:
            raise CheckpointError(f"{path}: the case's decks or tool files changed since the "
                                  "checkpoint was written; run again without --restart")
        written = meta.get("discretization")  # (checkpoints before it was kept lack it)
        if written is not None and written != self.discretization:
            raise CheckpointError(
                f"{path}: written with {written}, and this code reads the case as "
                f"{self.discretization} (a default changed); run again without --restart, "
                "or name the element and contact in the decks")
        try:
            self.problem.restore(forming_state_from_arrays(arrays, self.names, str(path)))
        except ValueError as error:
            if isinstance(error, CheckpointError):
                raise
            raise CheckpointError(f"{path}: written for another mesh, tools or material "
                                  f"({error}); run again without --restart") from None
        self.phase_index, self.segment = int(meta["phase_index"]), int(meta["segment"])
        self.phase_increments, self.last_frame = (int(meta["phase_increments"]),
                                                  int(meta["last_frame"]))
        self.elapsed = float(meta["elapsed"])
        prog = meta["progress"]
        if prog is not None:
            self.resume = PhaseProgress(
                start={k: arrays[f"start/{k}"] for k in self.names},
                offsets={k: (o, arrays[f"offset/{k}"]) for k, o in prog["offsets"].items()},
                factor=float(prog["factor"]), step=float(prog["step"]),
                reason=str(prog["reason"]), last_du=arrays.get("last_du"),
                last_dp=arrays.get("last_dp"), last_size=prog.get("last_size"),
                before_du=arrays.get("before_du"), before_size=prog.get("before_size"),
                start_weight=float(prog.get("start_weight", 0.0)))
        self._reopen_at = (int(meta["increments"]), int(meta["iterations"]),
                           int(meta["frames"]))

    # -- output ----------------------------------------------------------------------

    def fields(self, result: FormingResult | None) -> None:
        """A frame of the present state (contact states from the last increment)."""
        assert self.writer is not None
        p = self.problem
        if self.writer.increments == self.last_frame:
            return
        n = p.u.shape[0]
        node_state = np.zeros(n, np.int8)
        tool = np.full(n, -1, np.int16)
        last = None if result is None else result.last
        if last is not None and all(k in last.contact_states for k in self.names):
            states = np.concatenate([last.contact_states[k] for k in self.names])
            touching = states != 0
            node_state[self.slaves[touching]] = states[touching]
            tool[self.slaves[touching]] = self.tool_of[touching]
        contact = np.zeros((n, 3))
        np.add.at(contact, self.slaves, p.force)
        cauchy = p.solid.stresses(p.u, p.solid_state)[1]
        self.writer.fields(displacement=p.u, stress=cauchy, plastic_strain=p.solid_state.ep,
                           contact_state=node_state, contact_force=contact, contact_tool=tool,
                           contact_pressure=p.contact_pressure())
        self.last_frame = self.writer.increments

    def record(self, phase: Phase, result: FormingResult, step: float, travel: float,
               limit: str, timings: Timings, counts: dict[str, int]) -> None:
        """Write the last increment of ``result`` as a row of the results; ``counts``, the
        increment's share of the COUNTERS of a FormingResult."""
        assert self.writer is not None
        # Per iteration (FormingResult.convergence): the residual over the force scale and
        # the correction over the increment's displacement, scaled up to a whole
        # increment's when the increment is smaller; the step, what changed, and the
        # iterate's estimated error, which the convergence test judged with the residual.
        history = result.convergence[-1]
        depth = [result.penetration[k][-1] if result.penetration.get(k) else 0.0
                 for k in self.names]
        self._warn_penetration(phase, depth)
        volumes = self.problem.solid.mesh.element_volumes(self.problem.u)
        volume_change = float(volumes.sum() / self.element_volumes.sum() - 1.0)
        if abs(volume_change) > VOLUME_LIMIT and not self.volume_warned:
            self.volume_warned = True
            self._warn_volume(phase, volume_change, volumes / self.element_volumes - 1.0)
        self.writer.increment(
            phase=self.phase_index, step=step, travel=travel,
            tool_displacement=np.array([self.problem.position[k] for k in self.names]),
            tool_force=np.array([result.tool_forces[k][-1] if result.tool_forces.get(k)
                                 else np.zeros(3) for k in self.names]),
            iterations=len(history) - 1, residual_force=history[-1].residual,
            residual_displacement=history[-1].error, timings=timings,
            nodes_in_contact=[result.contacts[k][-1] if result.contacts.get(k) else 0
                              for k in self.names],
            cutbacks=counts["cuts"], rmin=min(1.0, step / phase.max_increment)
            if phase.max_increment else 1.0, limit=limit, residual_history=history,
            factorizations=counts["factorizations"],
            krylov_iterations=counts["krylov_iterations"],
            newton_iterations=counts["newton_iterations"], evaluations=counts["evaluations"],
            penetration=depth, volume_change=volume_change)
        self.phase_increments += 1
        self._since_checkpoint += 1
        if self.progress is not None:
            weights = [_phase_weight(q) for q in self.case.phases]
            done = self.phase_increments / weights[self.phase_index] if phase.is_springback \
                else travel / phase.travel if phase.travel > 0 else 1.0
            fraction = (sum(weights[:self.phase_index]) + weights[self.phase_index]
                        * min(max(done, 0.0), 1.0)) / sum(weights)
            self.progress(Progress(phase.name, self.phase_index, len(self.case.phases),
                                   self.writer.increments, phase.lead, travel, phase.travel,
                                   step, len(history) - 1, limit, fraction))

    def _warn_penetration(self, phase: Phase, depth: list[float]) -> None:
        """Warn, once per tool and run, where the blank lies deeper in a tool than the
        phase's penetration_limit (a fraction of the blank's thickness)."""
        thickness = self.problem.thickness
        limit = phase.newton.penetration * thickness
        for name, d in zip(self.names, depth, strict=True):
            if d > limit and name not in self.warned:
                self.warned.add(name)
                _log.warning(
                    "warning: the blank lies %.3g mm (%.1f %% of its %.3g mm thickness) inside "
                    "tool %s in phase %s, deeper than penetration_limit %g; the run goes on "
                    "(docs/theory/contact.md, \"Penetration\")", d, 100.0 * d / thickness,
                    thickness, name, phase.name, phase.newton.penetration)

    def _warn_volume(self, phase: Phase, change: float, elements: NDArray[np.float64]
                     ) -> None:
        """Warn that the blank's volume has changed by ``change`` since the start, more than
        VOLUME_LIMIT, naming the element whose own change (``elements``) is the largest."""
        mesh = self.problem.solid.mesh
        worst = int(np.argmax(np.abs(elements)))
        where = mesh.nodes[mesh.elements[worst]].mean(axis=0)
        _log.warning(
            "warning: the blank's volume changed by %+.3g %% since the start (phase %s, "
            "increment %d), more than the elastic change plastic flow allows; most in element "
            "%d (%+.3g %%, initially centred at %.4g, %.4g, %.4g mm): the elements are too long "
            "where they wrap a tool radius, refine the blank there (docs/theory/solid_shell.md, "
            "\"Volume\"); the run goes on", 100.0 * change, phase.name,
            self.writer.increments + 1 if self.writer else 0, int(mesh.element_ids[worst]),
            100.0 * elements[worst], *where)

    def _should_halt(self) -> bool:
        if self.stop is not None and self.stop():
            self.halt = "interrupted"
        elif (self.max_increments is not None and self.writer is not None
              and self.writer.increments >= self.max_increments):
            self.halt = "stopped"
        return bool(self.halt)

    # -- phases ----------------------------------------------------------------------

    def constrain(self, phase: Phase) -> None:
        """The phase's constraints, alone (those of the phase before are released)."""
        fixed = np.zeros_like(self.problem.fixed)
        nodes, components = self.case.boundary.constrained(phase.name)
        fixed[nodes, components] = True
        self.problem.constrain(fixed)

    def forming(self, phase: Phase) -> None:
        """The segments of a forming phase (split at output_at), from the resume point."""
        p = self.problem
        leads = [m for m in phase.motions if isinstance(m, Move)]
        longest = max(m.travel for m in leads)
        ratio = longest / phase.travel if phase.travel > 0 else 1.0
        ends = _segments(phase)
        while self.segment < len(ends):
            a = ends[self.segment - 1] if self.segment else 0.0
            b = ends[self.segment]
            share = (b - a) / phase.travel
            motion = {m.tool: phase.displacement(m.tool) * share for m in phase.motions
                      if isinstance(m, Move) or (isinstance(m, HoldGap) and self.segment > 0)}
            # A ramped force goes on over the segments as over the phase's lead travel.
            forces = {m.tool: (m.at(a / phase.travel), m.at(b / phase.travel))
                      for m in phase.motions if isinstance(m, HoldForce)}
            gaps = {m.tool: (m.other, m.gap, self.case.tool(m.tool).facing)
                    for m in phase.motions if isinstance(m, HoldGap)} if self.segment == 0 else {}
            result = FormingResult()
            clock = [time.perf_counter(), dict(result.timings), _counts(result)]
            last = [self.resume]  # the progress the segment has reached

            def hook(progress: PhaseProgress, a: float = a, b: float = b,
                     result: FormingResult = result, clock: list = clock,
                     last: list = last) -> bool:
                last[0] = progress
                now = time.perf_counter()
                spent = {k: v - clock[1][k] for k, v in result.timings.items()}
                counts = {k: v - clock[2][k] for k, v in _counts(result).items()}
                timing = Timings(spent["assembly"], spent["contact"], spent["factorization"],
                                 max(0.0, now - clock[0] - sum(spent.values())),
                                 spent["solve"])
                reason = result.limited_by[-1]
                limit = _LIMITS.get(reason, "max_increment")
                size = result.sizes[-1] * (b - a)
                if (reason == "max" and progress.factor >= 1.0 - 1e-12
                        and size < phase.max_increment * (1 - 1e-9)):
                    limit = "phase_end" if b >= phase.travel * (1 - 1e-12) else "output"
                self.record(phase, result, size, a + progress.factor * (b - a), limit, timing,
                            counts)
                clock[:] = [time.perf_counter(), dict(result.timings), _counts(result)]
                if progress.factor >= 1.0 - 1e-12 or (
                        phase.output_every and self.phase_increments % phase.output_every == 0):
                    self.fields(result)  # output_every, output_at, the phase end
                halt = self._should_halt()
                if halt or self._since_checkpoint >= self.checkpoint_every:
                    self.save(progress)
                return halt

            resume, self.resume = self.resume, None
            p.run(motion, phase.max_increment * ratio, active=phase.tools,
                  newton=phase.newton, limits=phase.limits, gaps=gaps, result=result,
                  on_increment=hook, resume=resume, phase=phase.name, frames=False,
                  forces=forces)
            if self.halt:
                self.fields(result)
                return
            self.segment += 1
            if self.segment < len(ends) and last[0] is not None:
                self.resume = _carried(last[0], share,
                                       (ends[self.segment] - b) / phase.travel, p.position)

    def springback(self, phase: Phase) -> None:
        result = FormingResult()
        start = time.perf_counter()
        self.problem.springback(phase.increments, phase.newton, result=result, frames=False)
        # Its steps (more than the phase's increments where one was halved) share the
        # times and counts, known per phase only.
        steps = len(result.residuals)
        share = (time.perf_counter() - start) / steps
        t = result.timings
        for k in range(steps):
            part = FormingResult(residuals=[result.residuals[k]],
                                 convergence=[result.convergence[k]])
            self.record(phase, part, 0.0, 0.0, "max_increment",
                        Timings(t["assembly"] / steps, t["contact"] / steps,
                                t["factorization"] / steps,
                                max(0.0, share - sum(t.values()) / steps), t["solve"] / steps),
                        {name: _share(total, k, steps)
                         for name, total in _counts(result).items()})
        self.fields(None)

    def run(self) -> None:
        phases = self.case.phases
        if self._should_halt():  # max_increments 0: all that comes before the numerics
            return
        while self.phase_index < len(phases):
            phase = phases[self.phase_index]
            self.constrain(phase)
            if phase.is_springback:
                self.springback(phase)
            else:
                self.forming(phase)
                if self.halt:
                    return
            self.phase_index += 1
            self.segment, self.phase_increments = 0, 0
            self.save(None)
            if self.phase_index < len(phases) and self._should_halt():
                return


#: What a FormingResult counts over its increments (cut increments, LU factorizations,
#: GMRES iterations, Newton corrections and evaluations of all trials).
COUNTERS = ("cuts", "factorizations", "krylov_iterations", "newton_iterations", "evaluations")


def _counts(result: FormingResult) -> dict[str, int]:
    return {name: int(getattr(result, name)) for name in COUNTERS}


def _share(total: int, k: int, parts: int) -> int:
    """Part k of a count spread evenly over ``parts`` (the springback's counts are known per
    phase only, like its timings), the parts summing to ``total``."""
    return (k + 1) * total // parts - k * total // parts


def _bytes_to_start(case: Case) -> int:
    """The free space a run of ``case`` needs to start: a few frames (results.frame_bytes)
    and checkpoints (per node about 15 numbers, per element 8 Gauss points of 8) of its mesh
    beyond the results writer's MIN_FREE. HDF5 ended a run started with 64 KB free in a
    segmentation fault while it closed the file."""
    n, m = case.mesh.n_nodes, case.mesh.n_elements
    checkpoint = 8 * (15 * n + 64 * m)
    return MIN_FREE + 4 * (frame_bytes(n, m) + checkpoint)  # the writer's margin, and more


def _no_checkpoint(output: Path) -> RunError:
    return RunError(f"{output / CHECKPOINT}: no checkpoint to restart from; run without "
                    "--restart")


def run_case(case: Case, output: str | os.PathLike[str], restart: bool = False,
             progress: Callable[[Progress], None] | None = None,
             stop: Callable[[], bool] | None = None, overwrite: bool = False,
             checkpoint_every: int = CHECKPOINT_EVERY, max_increments: int | None = None,
             threads: int | None = None) -> RunOutcome:
    """Run the phases of ``case`` in order, writing to the folder ``output``.

    ``restart``: continue from the folder's checkpoint. ``progress`` is called after every
    increment; ``stop`` is polled after every increment and a true return stops the run
    there (status interrupted, a checkpoint written: restart continues). ``max_increments``
    stops after that many increments of the whole run (status stopped); 0 stops before the
    first increment, once the run has checked and written all it does before its numerics
    (the problem built, the results file with the initial frame, a checkpoint). ``overwrite``
    replaces earlier results; without it an existing results file is an error. ``threads``:
    OpenMP threads of the core. A failed increment (no convergence after the cuts allowed)
    ends with status failed; the results so far and the last checkpoint stay."""
    if checkpoint_every < 1:
        raise ValueError(f"checkpoint_every must be >= 1, got {checkpoint_every}")
    if max_increments is not None and max_increments < 0:
        raise ValueError(f"max_increments must be >= 0 or None, got {max_increments}")
    try:
        output = check_output_folder(output, _bytes_to_start(case))
    except OutputFolderError as error:
        raise RunError(str(error)) from error
    if threads is not None:
        from ddpy.core.parallel import set_threads

        set_threads(threads)
    if restart and not output.is_dir():
        raise _no_checkpoint(output)  # (and no folder made for it)
    output.mkdir(parents=True, exist_ok=True)
    # The folder is this run's from here to the end; another run, an --overwrite or a
    # --restart of it is refused before anything in it is read or changed.
    lock = FolderLock(output)
    try:
        lock.acquire()
    except OutputFolderError as error:
        raise RunError(str(error)) from error
    try:
        return _run_locked(case, output, restart, progress, stop, overwrite,
                           checkpoint_every, max_increments)
    finally:
        lock.release()


def _run_locked(case: Case, output: Path, restart: bool,
                progress: Callable[[Progress], None] | None, stop: Callable[[], bool] | None,
                overwrite: bool, checkpoint_every: int, max_increments: int | None
                ) -> RunOutcome:
    """run_case once the output folder is checked and locked."""
    run = _Run(case, output, progress, stop, checkpoint_every, max_increments)
    results = output / RESULTS
    if restart:
        if not (output / CHECKPOINT).is_file():
            raise _no_checkpoint(output)
        run.load()
    else:
        if results.exists() and not overwrite:
            raise RunError(f"{results} exists: continue it with --restart, or replace it "
                           "with --overwrite")
        (output / CHECKPOINT).unlink(missing_ok=True)
        # A new file, not the old one truncated: a reader of the old results keeps them.
        run.writer = ResultsWriter.for_case(results, case, overwrite=True,
                                            surfaces=[t.surface for t in run.problem.tools])
        run.save(None)
    assert run.writer is not None
    leads = [p.lead or "" for p in case.phases]
    from ddpy.core.parallel import max_threads

    # A continued run records the fewest threads of its parts: its wall time is that of a
    # run with a thread per core only if every part had them.
    threads = max_threads()
    before = int(run.writer.attribute("threads", 0)) if restart else 0
    threads = min(threads, before) if before > 0 else threads
    # The tolerances say how closely two runs' answers can agree (docs/results-format.md).
    run.writer.annotate(status="running", message="", leads=leads, threads=threads,
                        newton_force=[p.newton.force_tolerance for p in case.phases],
                        newton_displacement=[p.newton.displacement_tolerance
                                             for p in case.phases])
    _write_atomic(output / STATUS, json.dumps({"status": "running", "case": str(case.folder)}))
    reset_peak_memory()
    status, message = "failed", "stopped by an error"
    try:
        run.run()
        status, message = run.halt or "completed", ""
        if run.halt == "interrupted":
            message = "stopped at the user's request"
        elif run.halt == "stopped":
            message = f"stopped after {run.writer.increments} increments"
    except FormingError as error:
        message = str(error)
        run.fields(error.result)
    except BaseException as error:
        message = f"{type(error).__name__}: {error}"
        raise
    finally:
        wall = run.elapsed + time.perf_counter() - run._clock
        increments, frames = run.writer.increments, run.writer.frame_count
        run.problem.close()
        failure: ResultsWriteError | None = None
        if not run.writer.failed:  # after a failed write the file is closed as it was
            try:
                run.writer.annotate(status=status, message=message, wall_time=wall,
                                    peak_memory_mb=run.writer.peak_memory_mb(peak_memory_mb()))
                run.writer.close()
            except ResultsWriteError as error:
                failure = error
        if run.writer.failed:
            status, message = "failed", f"writing {RESULTS} failed: {run.writer.failed}"
        try:
            _write_atomic(output / STATUS, json.dumps({
                "status": status, "message": message, "case": str(case.folder),
                "increments": increments, "frames": frames, "wall_time": wall}, indent=1))
        except OSError:  # the output folder went away or is full: keep the run's own error
            if status != "failed":
                raise
        if failure is not None:
            raise failure
    return RunOutcome(status, message, increments, frames, wall, output)


def reset_peak_memory() -> None:
    """Start this process's peak resident memory afresh (Linux: VmHWM), so that a run's
    peak is its own when a process makes several (benchmarks); elsewhere a no-op."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def peak_memory_mb() -> float:
    """The largest resident memory of this process since the last reset_peak_memory (the
    process's whole life where that cannot be reset), MB."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0  # kB
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux
