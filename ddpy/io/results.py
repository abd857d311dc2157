"""Results of a run: one HDF5 file (h5py) and an XDMF file beside it that ParaView opens.

Layout (docs/results-format.md; units in each dataset's ``units`` attribute, mm, N, MPa, s)::

    /                     attrs: format, version, title, case, units, tools, phases, created
    /mesh/nodes           (n, 3)   initial coordinates
    /mesh/elements        (m, 8)   hexahedra, 0-based node indices
    /mesh/node_ids        (n,)     labels of the mesh deck;  /mesh/element_ids (m,)
    /increments/<name>    one row per converged increment (attrs count: rows complete)
    /iterations/<name>    one row per Newton iteration: increment, iteration, residuals
    /tools/<tool>         the tool's surface tessellated (points, cells) and placed at the
                          frames (coordinates/<frame>)
    /fields/<frame>       the fields at chosen increments, frame 000000 the initial state
                          (attrs count: frames complete; each frame attrs increment, phase,
                          travel, time: the lead tools' travel over the run)

Every increment and every frame is flushed to disk as soon as it is written, the row counts
last: a run killed at any moment leaves a file that reads back up to the last complete
increment. The XDMF file is rewritten (atomically) after each frame.
"""

from __future__ import annotations

import contextlib
import ctypes
import datetime
import errno
import functools
import os
import re
import shutil
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import __version__
from ddpy.geometry.tessellation import TRIANGLE, tessellate
from ddpy.io.output_folder import RESULT_MODE, atomic_write
from ddpy.model.forming_limits import FormingLimitCurve, hardening_exponent
from ddpy.model.forming_quantities import SURFACES, FieldFrame, SheetMeasures, nodal_average
from ddpy.model.mesh import element_volumes

__all__ = ["CONTACT_STATES", "FORMAT", "LIMITS", "TENSOR6", "VOIGT", "Frame", "ResultsReader",
           "ResultsWriteError", "ResultsWriter", "Timings", "frame_bytes", "xdmf_frame",
           "xdmf_text"]

FORMAT = "ddpy-results"
VERSION = 1
#: Free disk space kept beyond what the next frame needs: a write that would leave less
#: ends the run first. HDF5 that ran out of space in a write failed its later writes, then
#: crashed the process while closing the file and left groups pointing past its end.
MIN_FREE = 1 << 20
#: fallocate(2)'s flag: allocate blocks beyond the end of the file, its size unchanged.
_KEEP_SIZE = 1
#: Contact state of a node in the fields (``contact_state``).
CONTACT_STATES = {0: "free", 1: "stick", 2: "slip"}
#: Field names of files written before a rename: old name -> new (the reader takes both).
RENAMED = {"contact_status": "contact_state"}
#: The XDMF time of a frame is the lead tools' travel summed over the run (mm); a frame
#: without travel since the last one (springback) comes this much later.
TIME_WITHOUT_TRAVEL = 1e-3
#: What limited an increment (the ``limit`` column): codes and meanings.
LIMITS = {0: "max_increment", 1: "yield", 2: "strain", 3: "rotation", 4: "contact_touch",
          5: "contact_release", 6: "phase_end", 7: "output", 8: "cutback"}

#: Stored stress components (XDMF Tensor6 order) from ddpy's Voigt order xx yy zz xy yz zx,
#: and back.
TENSOR6 = np.array([0, 3, 5, 1, 4, 2])
VOIGT = np.argsort(TENSOR6)

#: Per-increment scalar columns: name -> (dtype, units, meaning).
#: The per-tool column of the deepest penetration: name and dtype, units and meaning.
_PENETRATION = ("penetration", "f8")
_PENETRATION_TEXT = ("mm", "deepest penetration of the blank into each tool")
_SCALARS: dict[str, tuple[str, str, str]] = {
    "increment": ("i4", "1", "increment number, from 1 over the whole run"),
    "phase": ("i4", "1", "index of the phase (root attribute 'phases')"),
    "step": ("f8", "mm", "increment size: travel of the phase's lead tool in the increment"),
    "travel": ("f8", "mm", "travel of the lead tool since the start of the phase"),
    "iterations": ("i4", "1", "Newton iterations of the converged increment"),
    "cutbacks": ("i4", "1", "cuts of the increment before it converged"),
    "factorizations": ("i4", "1", "LU factorizations in the increment, its rejected trials "
                       "included (the other corrections are solved with older factors)"),
    "krylov_iterations": ("i4", "1", "GMRES iterations of the corrections solved with older "
                          "factors in the increment, rejected trials included"),
    "newton_iterations": ("i4", "1", "Newton corrections spent on the increment, its "
                          "rejected trials (cut, or redone shorter by a limit) included"),
    "evaluations": ("i4", "1", "residual and tangent evaluations of the increment (line-search "
                    "trials and rejected trials included)"),
    "residual_force": ("f8", "1", "relative residual force at convergence"),
    "residual_displacement": ("f8", "1", "relative displacement error at convergence, as the "
                              "convergence test estimates it"),
    "rmin": ("f8", "1", "r_min factor applied to the trial increment"),
    "limit": ("i1", "1", "what limited the increment (attribute 'codes')"),
    "time_assembly": ("f8", "s", "wall time in assembly (internal forces, tangent)"),
    "time_contact": ("f8", "s", "wall time in the contact search"),
    "time_factorization": ("f8", "s", "wall time in LU factorizations (files written "
                           "before time_solve existed: factorizations and solutions)"),
    "time_solve": ("f8", "s", "wall time in solutions with the LU factors, GMRES with "
                   "older factors included"),
    "time_rest": ("f8", "s", "wall time in everything else"),
    "time_total": ("f8", "s", "wall time of the increment"),
    "volume_change": ("f8", "1", "the blank's volume change since the start of the run, "
                      "V / V0 - 1 (exact volumes of its hexahedra; plastic flow keeps the "
                      "volume, so beyond the elastic part it is the elements' error)"),
}
_ITERATION_COLUMNS: dict[str, tuple[str, str, str]] = {
    "increment": ("i4", "1", "increment number"),
    "iteration": ("i4", "1", "Newton iteration, from 1"),
    "residual_force": ("f8", "1", "relative residual force"),
    "residual_displacement": ("f8", "1", "relative displacement correction"),
    "step": ("f8", "1", "length of the Newton step that led to the iterate (0 at the start)"),
    "points_switched": ("i4", "1", "contact points whose pressure turned on or off since the "
                        "previous iterate"),
    "pairs_switched": ("i4", "1", "contact pairs whose state (open, stick, slip) changed since "
                       "the previous iterate"),
    "yield_switched": ("i4", "1", "integration points of the blank that turned from elastic "
                       "to plastic or back since the previous iterate"),
    "displacement_error": ("f8", "1", "relative error of the iterate as the convergence test "
                           "estimates it: the correction, or less once whole Newton steps "
                           "contract"),
}
#: The columns of an increment's residual history, in its order (ddpy.model.newton.Iteration).
_HISTORY_COLUMNS = list(_ITERATION_COLUMNS)[2:]
_CHUNK = 256


@dataclass(frozen=True)
class Timings:
    """Wall time of one increment, s, by part of the work."""

    assembly: float = 0.0
    contact: float = 0.0
    factorization: float = 0.0
    rest: float = 0.0
    solve: float = 0.0

    @property
    def total(self) -> float:
        return self.assembly + self.contact + self.factorization + self.solve + self.rest


@dataclass(frozen=True)
class Frame:
    """A set of fields in the file: ``index`` (0 the initial state), the increment it belongs
    to, the phase index, the lead tool's travel in the phase and the XDMF time."""

    index: int
    increment: int
    phase: int
    travel: float
    time: float


#: Fields of a frame: name -> (centre, components, dtype, units, meaning).
_FIELDS: dict[str, tuple[str, int, str, str, str]] = {
    "displacement": ("Node", 3, "f8", "mm", "nodal displacement from the initial state"),
    "coordinates": ("Node", 3, "f8", "mm", "current nodal coordinates"),
    "thickness": ("Node", 1, "f8", "mm", "distance between the top and bottom node of the "
                  "node's through-thickness column"),
    "thinning": ("Node", 1, "f8", "%", "100 (t0 - t) / t0: the loss of the node's column "
                 "thickness t from its initial t0, in %"),
    "contact_state": ("Node", 1, "i1", "1", "0 free, 1 stick, 2 slip"),
    "contact_tool": ("Node", 1, "i2", "1", "index of the tool in contact, -1 none"),
    "contact_force": ("Node", 3, "f8", "N", "contact force on the node (from the tool)"),
    "stress": ("Cell", 6, "f8", "MPa", "Cauchy stress averaged over the Gauss points, "
               "components xx xy xz yy yz zz (the XDMF Tensor6 order)"),
    "von_mises": ("Cell", 1, "f8", "MPa", "von Mises equivalent of the averaged stress"),
    "plastic_strain": ("Cell", 1, "f8", "1", "equivalent plastic strain averaged over the "
                       "Gauss points"),
    "plastic_strain_nodal": ("Node", 1, "f8", "1", "equivalent plastic strain at the node: "
                             "each element's Gauss points extrapolated to its nodes, "
                             "averaged over the elements around the node"),
    "contact_pressure": ("Node", 1, "f8", "MPa", "normal contact force on the node over the "
                         "area of the blank's contact faces it stands for"),
    **{f"{which}_strain_{surface}": (
        "Cell", 1, "f8", "1", f"{which} in-plane logarithmic strain of the {surface} face "
        "of the element's column through the thickness")
       for surface in SURFACES for which in ("major", "minor")},
    "volume_change": ("Cell", 1, "f8", "1", "the element's volume over its initial one, "
                      "minus 1 (plastic flow keeps the volume: beyond the elastic change it is "
                      "the element's error)"),
    "increment": ("Cell", 1, "i4", "1", "the frame's increment number (the same in every "
                  "element: the XDMF time is the lead tools' travel)"),
}


def _mesh_arrays(mesh: Any) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """Nodes, elements, labels and the sheet normal of a HexMesh or (nodes, elements)."""
    if isinstance(mesh, tuple):
        nodes, elements = mesh
        ids, eids, normal = None, None, (0.0, 0.0, 1.0)
    else:
        nodes, elements = mesh.nodes, mesh.elements
        ids, eids = getattr(mesh, "node_ids", None), getattr(mesh, "element_ids", None)
        normal = getattr(mesh, "normal", (0.0, 0.0, 1.0))
    nodes = np.asarray(nodes, dtype=np.float64)
    elements = np.asarray(elements, dtype=np.int64)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or elements.ndim != 2 or elements.shape[1] != 8:
        raise ValueError(f"mesh must have nodes (n, 3) and hexahedra (m, 8), got "
                         f"{nodes.shape} and {elements.shape}")
    if elements.size and (elements.min() < 0 or elements.max() >= len(nodes)):
        raise ValueError("mesh elements refer to nodes out of range")
    n, m = len(nodes), len(elements)
    ids = np.arange(1, n + 1) if ids is None else np.asarray(ids, dtype=np.int64)
    eids = np.arange(1, m + 1) if eids is None else np.asarray(eids, dtype=np.int64)
    return nodes, elements.astype(np.int32), ids, eids, np.asarray(normal, dtype=float)


def frame_bytes(n_nodes: int, n_elements: int, tool_points: int = 0) -> int:
    """Bytes one frame of fields takes in results.h5: 8 a number, 19 numbers per node
    (displacement, contact force and state, thickness, thinning, pressure...), 18 per
    element (stress, plastic strain, surface strains, volume change...) and 3 per tool point
    (the tools' placed surfaces)."""
    return 8 * (19 * n_nodes + 18 * n_elements + 3 * tool_points)


class ResultsWriteError(OSError):
    """Writing the results failed (disk full, I/O error); the file was closed at once, so
    the increments and frames written before stay readable."""

    def __init__(self, path: Path, reason: str) -> None:
        super().__init__(f"writing {path} failed: {reason}")
        self.path, self.reason = path, reason


class ResultsWriter:
    """Writes the results of one run to ``path`` (HDF5) and ``path`` with suffix .xdmf.

    ``mesh`` is a :class:`ddpy.model.mesh.HexMesh` (or a tuple nodes, elements); ``tools`` and
    ``phases`` name the tools and phases, in the order of the per-tool arrays and phase
    indices. Frame 0, the initial state, is written at once. Use as a context manager or call
    :meth:`close`; a writer never closed still leaves a readable file. An existing file at
    ``path`` is an error, or with ``overwrite`` removed for a new one (never truncated: a
    process that has it open keeps reading it whole). ``surfaces``: each tool's surface
    (BezierSurface or NagataSurface, in the order of ``tools``; None: no tool drawn),
    written once tessellated (ddpy.geometry.tessellation) and placed at every frame by the
    tool's displacement.
    """

    def __init__(self, path: str | os.PathLike[str], mesh: Any, tools: Sequence[str],
                 phases: Sequence[str] = (), *, title: str = "", case: str = "",
                 element: str = "hexahedron", overwrite: bool = False,
                 surfaces: Sequence[Any] | None = None) -> None:
        import h5py

        self.path = Path(path)
        self.xdmf_path = self.path.with_suffix(".xdmf")
        nodes, elements, ids, eids, normal = _mesh_arrays(mesh)
        self.nodes, self.elements = nodes, elements
        self.tools = tuple(str(t) for t in tools)
        self.phases = tuple(str(p) for p in phases)
        if not self.tools:
            raise ValueError("tools must name at least one tool")
        self._measures = _measures(nodes, elements, normal)
        self._volumes = element_volumes(nodes, elements)
        if surfaces is not None and len(surfaces) != len(self.tools):
            raise ValueError(f"{len(surfaces)} tool surfaces for {len(self.tools)} tools")
        self._tool_points = 0
        if overwrite:
            # Removed, not truncated: a process that has the old file open keeps it whole.
            self.path.unlink(missing_ok=True)
        self._file = h5py.File(self.path, "w-")
        os.chmod(self.path, RESULT_MODE)  # as the XDMF file beside it, whatever the umask
        self.failed = ""  # why a write failed; the file is closed then
        with self._writing():
            self._create(nodes, elements, ids, eids, normal, title, case, element,
                         surfaces or [None] * len(self.tools))

    def _create(self, nodes: NDArray, elements: NDArray, ids: NDArray, eids: NDArray,
                normal: NDArray, title: str, case: str, element: str,
                surfaces: Sequence[Any]) -> None:
        """The groups and columns of a new file, and frame 0."""
        f = self._file
        f.attrs.update(_storable({"format": FORMAT, "version": VERSION, "title": title,
                                  "case": case, "element": element,
                                  "units": "mm N MPa s", "tools": list(self.tools),
                                  "phases": list(self.phases), "ddpy": __version__,
                                  "created": datetime.datetime.now().isoformat(
                                      timespec="seconds")}))
        g = f.create_group("mesh")
        for name, data, units in (("nodes", nodes, "mm"), ("elements", elements, "1"),
                                  ("node_ids", ids, "1"), ("element_ids", eids, "1")):
            g.create_dataset(name, data=data).attrs["units"] = units
        g.attrs["normal"] = normal
        g["elements"].attrs["description"] = ("8-node hexahedra, 0-based node indices, bottom "
                                              "face 0-3 counter-clockwise seen from 4-7")
        t = len(self.tools)
        inc = f.create_group("increments")
        for name, (dtype, units, meaning) in _SCALARS.items():
            self._column(inc, name, dtype, (), units, meaning)
        self._column(inc, "tool_displacement", "f8", (t, 3), "mm",
                     "displacement of each tool since the start of the run")
        self._column(inc, "tool_force", "f8", (t, 3), "N", "reaction force on each tool")
        self._column(inc, "nodes_in_contact", "i4", (t,), "1", "nodes in contact, per tool")
        self._column(inc, *_PENETRATION, (t,), *_PENETRATION_TEXT)
        inc["limit"].attrs["codes"] = str(LIMITS)
        inc.attrs["count"] = 0
        it = f.create_group("iterations")
        for name, (dtype, units, meaning) in _ITERATION_COLUMNS.items():
            self._column(it, name, dtype, (), units, meaning)
        it.attrs["count"] = 0
        tools = f.create_group("tools")
        for name, surface in zip(self.tools, surfaces, strict=True):
            if surface is not None:
                _write_tool(tools.create_group(name), surface)
        self._tool_points = _tool_points(tools)
        fields = f.create_group("fields")
        fields.attrs["count"] = 0
        self._count = 0
        self._iterations = 0
        self._keep_columns()
        self._frames: list[Frame] = []
        self._grids: list[list[str]] = []  # each frame's XDMF grids (xdmf_frame)
        self._phase = 0
        self._travel = 0.0
        self._stroke = 0.0
        self._write_frame(0, np.zeros_like(nodes), np.zeros((len(elements), 6)),
                          np.zeros(len(elements)), np.zeros(len(nodes), np.int8),
                          np.zeros_like(nodes), np.full(len(nodes), -1, np.int16), None, 0.0,
                          np.zeros(len(nodes)), {})

    @contextlib.contextmanager
    def _writing(self, frame: bool = True) -> Iterator[None]:
        """Where the file is written. HDF5 must not run out of disk inside a write: it then
        fails its later writes, prints errors while it frees its objects and crashes the
        process when the file is closed. So before each write the disk blocks for a frame
        and MIN_FREE are allocated beyond the file's end (``_hold``): once held, another
        process filling the disk cannot take them. When they cannot be held (or, where
        the file system cannot allocate ahead, less free space is left), the file is
        closed while HDF5 can still do so cleanly. A write that fails all the same (h5py
        raises OSError or RuntimeError) closes the file at once. Each becomes
        ResultsWriteError, and so does any later write."""
        if self.failed:
            raise ResultsWriteError(self.path, self.failed)
        needed = self._needed() if frame else MIN_FREE
        held, free = self._hold(needed), ""
        if held is None and frame:  # nothing held here: the free space as seen now
            space = shutil.disk_usage(self.path.parent).free
            held, free = space >= needed, f", {space / 1e6:.3g} MB free"
        if held is False:
            self.failed = (f"No space left on device (the next frame needs "
                           f"{needed / 1e6:.3g} MB{free})")
            with contextlib.suppress(Exception):
                self._file.attrs.update(status="failed", message=self.failed)
            self._close()
            raise ResultsWriteError(self.path, self.failed)
        try:
            yield
            if self._file.id.valid:
                self._file.flush()  # written now, into the blocks held
        except (OSError, RuntimeError) as error:
            # HDF5's messages run over several lines; its errno text says what happened.
            cause = re.search(r"error message = '([^']+)'", str(error))
            self.failed = (error.strerror if isinstance(error, OSError) and error.strerror
                           else cause.group(1) if cause
                           else str(error).split("\n")[0] or type(error).__name__)
            self._close()
            where = error.filename if isinstance(error, OSError) and error.filename else None
            raise ResultsWriteError(Path(where or self.path), self.failed) from error

    def _close(self) -> None:
        """Close the file (as far as HDF5 can) and give back the blocks held beyond its
        end: a truncation to its own size frees them (ext4, tmpfs)."""
        with contextlib.suppress(Exception):
            self._file.close()
        with contextlib.suppress(OSError):
            os.truncate(self.path, self.path.stat().st_size)

    def _hold(self, size: int) -> bool | None:
        """Allocate ``size`` bytes of disk beyond the end of the file, its size unchanged
        (Linux fallocate with FALLOC_FL_KEEP_SIZE): True when held, False when the disk
        has not that much room, None when this system or file system cannot."""
        try:
            handle = self._file.id.get_vfd_handle()
            fallocate = _libc().fallocate
        except (AttributeError, OSError, RuntimeError, TypeError):
            return None
        end = os.fstat(handle).st_size
        if fallocate(handle, _KEEP_SIZE, end, size) == 0:
            return True
        code = ctypes.get_errno()
        return False if code in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG) else None

    def _needed(self) -> int:
        """Bytes a frame takes (frame_bytes), the XDMF file rewritten beside the old one,
        and MIN_FREE."""
        try:
            xdmf = self.xdmf_path.stat().st_size
        except OSError:
            xdmf = 0
        return (frame_bytes(len(self.nodes), len(self.elements), self._tool_points) + xdmf
                + MIN_FREE)

    @classmethod
    def for_case(cls, path: str | os.PathLike[str], case: Any, overwrite: bool = False,
                 surfaces: Sequence[Any] | None = None) -> ResultsWriter:
        """A writer for a :class:`ddpy.io.case.Case`: its mesh, tools (their surfaces:
        ``surfaces``, or else read from the case's tool files), phases and title."""
        if surfaces is None:
            surfaces = [t.model().surface for t in case.tools]
        writer = cls(path, case.mesh, case.tool_names, [p.name for p in case.phases],
                     title=case.title, case=str(case.folder), element=case.element,
                     overwrite=overwrite, surfaces=surfaces)
        curve = case.material.forming_limit
        if curve is None and writer._measures is not None:
            n = hardening_exponent(case.material.material)
            if n > 0:  # (a hardening law with no hardening has no Keeler-Brazier curve)
                thickness = float(np.median(writer._measures.initial_thickness))
                curve = FormingLimitCurve.keeler_brazier(n, thickness)
        writer.describe_part(case.boundary.symmetry_axes, curve)
        return writer

    def describe_part(self, symmetry: str, forming_limit: FormingLimitCurve | None) -> None:
        """Record what post-processing needs of the case: the normal axis of each symmetry
        plane (``symmetry``, e.g. "xy" for a quarter model) and the forming limit curve
        (None: none)."""
        with self._writing(frame=False):
            self._file.attrs["symmetry"] = symmetry
            if "forming_limit" in self._file:
                del self._file["forming_limit"]
            if forming_limit is not None:
                g = self._file.create_group("forming_limit")
                c = forming_limit
                g.attrs.update({"kind": c.kind, "n": c.n, "thickness": c.thickness,
                                "origin": c.origin, "description": c.describe()})
                if c.kind == "table":
                    g.create_dataset("minor", data=np.array(c.minor)).attrs["units"] = "1"
                    g.create_dataset("major", data=np.array(c.major)).attrs["units"] = "1"
            self._file.flush()

    @classmethod
    def reopen(cls, path: str | os.PathLike[str], increments: int, iterations: int,
               frames: int) -> ResultsWriter:
        """Open an existing results file to continue a run from a checkpoint: rows and
        frames past the counts given (written after the checkpoint) are dropped."""
        import h5py

        self = cls.__new__(cls)
        self.failed = ""
        self.path = Path(path)
        self.xdmf_path = self.path.with_suffix(".xdmf")
        f = h5py.File(self.path, "r+")
        if f.attrs.get("format") != FORMAT:
            f.close()
            raise ValueError(f"{self.path} is not a ddpy results file")
        inc, it, fields = f["increments"], f["iterations"], f["fields"]
        have = (int(inc.attrs["count"]), int(it.attrs["count"]), int(fields.attrs["count"]))
        if increments > have[0] or iterations > have[1] or not 1 <= frames <= have[2]:
            f.close()
            raise ValueError(f"{self.path} holds {have[0]} increments, {have[1]} iterations "
                             f"and {have[2]} frames, fewer than the checkpoint's "
                             f"{increments}, {iterations} and {frames}")
        for group, count in ((inc, increments), (it, iterations)):
            group.attrs["count"] = count
            for d in group.values():
                d.resize(count, axis=0)
        for name, (dtype, units, meaning) in _SCALARS.items():
            if name not in inc:  # a file of an older version: the column starts at zero
                cls._column(inc, name, dtype, (), units, meaning)
                inc[name].resize(increments, axis=0)
        if _PENETRATION[0] not in inc:
            cls._column(inc, *_PENETRATION, (len(f.attrs["tools"]),), *_PENETRATION_TEXT)
            inc[_PENETRATION[0]].resize(increments, axis=0)
        for name, (dtype, units, meaning) in _ITERATION_COLUMNS.items():
            if name not in it:  # a file of an older version: -1 in the rows written before
                cls._column(it, name, dtype, (), units, meaning)
                it[name].resize(iterations, axis=0)
                it[name][:] = -1
        fields.attrs["count"] = frames
        for index in range(frames, have[2]):
            del fields[f"{index:06d}"]
        tools = f.require_group("tools")  # (files of earlier versions have no tools)
        for group in tools.values():
            for index in range(frames, have[2]):
                if f"{index:06d}" in group["coordinates"]:
                    del group[f"coordinates/{index:06d}"]
        self._file = f
        self.nodes, self.elements = f["mesh/nodes"][()], f["mesh/elements"][()]
        self.tools = tuple(str(t) for t in f.attrs["tools"])
        self.phases = tuple(str(p) for p in f.attrs["phases"])
        self._measures = _measures(self.nodes, self.elements, f["mesh"].attrs["normal"])
        self._volumes = element_volumes(self.nodes, self.elements)
        self._tool_points = _tool_points(tools)
        self._count, self._iterations = increments, iterations
        self._keep_columns()
        self._stroke = float(inc["step"][:increments].sum())
        self._frames = []
        self._grids = []
        for index in range(frames):
            a = fields[f"{index:06d}"].attrs
            self._frames.append(Frame(index, int(a["increment"]), int(a["phase"]),
                                      float(a["travel"]), float(a["time"])))
        self._phase = int(inc["phase"][increments - 1]) if increments else 0
        self._travel = float(inc["travel"][increments - 1]) if increments else 0.0
        if "closed" in f.attrs:
            del f.attrs["closed"]
        f.flush()
        self._write_xdmf()
        return self

    def attribute(self, name: str, default: Any = None) -> Any:
        """A root attribute set before (e.g. by an earlier part of a continued run)."""
        return self._file.attrs.get(name, default)

    def peak_memory_mb(self, this_part: float) -> float:
        """The run's peak memory with ``this_part``'s: the largest of its parts (a run
        continued with --restart is several processes)."""
        return max(float(self._file.attrs.get("peak_memory_mb", 0.0)), float(this_part))

    def annotate(self, **attrs: Any) -> None:
        """Set root attributes (e.g. the run's status) and flush."""
        with self._writing(frame=False):
            self._file.attrs.update(_storable(attrs))
            self._file.flush()

    @staticmethod
    def _column(group: Any, name: str, dtype: str, shape: tuple[int, ...], units: str,
                meaning: str) -> None:
        d = group.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype=dtype,
                                 chunks=(_CHUNK, *shape))
        d.attrs["units"] = units
        d.attrs["description"] = meaning

    def _keep_columns(self) -> None:
        """The row columns' datasets and the rows they have room for. A row written per
        increment looked each column up in its group and grew it by one row, 7.5 ms per
        increment with h5py (5 % of a small blank's run); the columns now grow by _CHUNK rows
        and the count attribute says which rows are complete (the readers take no more; a
        closed file has exactly those)."""
        inc, it = self._file["increments"], self._file["iterations"]
        self._increment_columns = dict(inc.items())
        self._iteration_columns = dict(it.items())
        self._room = min(d.shape[0] for d in self._increment_columns.values())
        self._iteration_room = min(d.shape[0] for d in self._iteration_columns.values())

    def _trim_columns(self) -> None:
        """The columns cut to their complete rows."""
        for columns, count in ((self._increment_columns, self._count),
                               (self._iteration_columns, self._iterations)):
            for d in columns.values():
                if d.shape[0] != count:
                    d.resize(count, axis=0)
        self._room, self._iteration_room = self._count, self._iterations

    # --------------------------------------------------------------------------- increments

    @property
    def increments(self) -> int:
        """Increments written so far."""
        return self._count

    @property
    def iteration_rows(self) -> int:
        """Newton iteration rows written so far."""
        return self._iterations

    @property
    def frame_count(self) -> int:
        """Frames written so far, the initial state included."""
        return len(self._frames)

    def increment(self, *, phase: int, step: float, travel: float,
                  tool_displacement: ArrayLike, tool_force: ArrayLike, iterations: int,
                  residual_force: float, residual_displacement: float,
                  timings: Timings = Timings(), nodes_in_contact: ArrayLike | None = None,
                  cutbacks: int = 0, rmin: float = 1.0, limit: int | str = 0,
                  residual_history: ArrayLike | None = None, factorizations: int = 0,
                  krylov_iterations: int = 0, newton_iterations: int = 0,
                  evaluations: int = 0, penetration: ArrayLike | None = None,
                  volume_change: float = 0.0) -> int:
        """Append one converged increment; return its number (from 1). ``tool_displacement``
        and ``tool_force`` are (tools, 3); ``residual_history`` (iterations, 2 or 7) holds the
        force and displacement residuals of each Newton iteration, and may add the step's
        length, the points switched, pairs switched and yield points switched and the
        estimated displacement error (ddpy.model.newton.Iteration; else those columns are
        written as -1);
        ``penetration`` (tools,) the deepest penetration of the blank into each tool
        (mm); ``volume_change`` the blank's V / V0 - 1."""
        t = len(self.tools)
        u = _shaped(tool_displacement, (t, 3), "tool_displacement")
        force = _shaped(tool_force, (t, 3), "tool_force")
        contact = (np.zeros(t, np.int32) if nodes_in_contact is None
                   else _shaped(nodes_in_contact, (t,), "nodes_in_contact"))
        depth = (np.zeros(t) if penetration is None
                 else _shaped(penetration, (t,), "penetration"))
        if int(phase) < 0 or (self.phases and int(phase) >= len(self.phases)):
            raise ValueError(f"phase {phase} is not an index of phases {list(self.phases)}")
        code = _limit_code(limit)
        history = None
        if residual_history is not None:
            history = np.asarray(residual_history, dtype=float)
            history = history.reshape(len(history), -1) if history.size else history.reshape(0, 2)
            if history.shape[1] not in (2, len(_HISTORY_COLUMNS)):
                raise ValueError(f"residual_history must have 2 or {len(_HISTORY_COLUMNS)} "
                                 f"columns, got {history.shape[1]}")
            # the step and the switches unknown (-1) where only the residuals are given
            history = np.hstack([history, np.full((len(history),
                                                   len(_HISTORY_COLUMNS) - history.shape[1]),
                                                  -1.0)])
        k = self._count
        row = {"increment": k + 1, "phase": int(phase), "step": float(step),
               "travel": float(travel), "iterations": int(iterations),
               "cutbacks": int(cutbacks), "factorizations": int(factorizations),
               "krylov_iterations": int(krylov_iterations),
               "newton_iterations": int(newton_iterations), "evaluations": int(evaluations),
               "residual_force": float(residual_force),
               "residual_displacement": float(residual_displacement), "rmin": float(rmin),
               "limit": code, "time_assembly": timings.assembly,
               "time_contact": timings.contact, "time_factorization": timings.factorization,
               "time_solve": timings.solve, "time_rest": timings.rest, "time_total": timings.total,
               "tool_displacement": u, "tool_force": force, "nodes_in_contact": contact,
               "penetration": depth, "volume_change": float(volume_change)}
        with self._writing():
            inc = self._increment_columns
            if k >= self._room:
                self._room = k + _CHUNK
                for d in inc.values():
                    d.resize(self._room, axis=0)
            for name, value in row.items():
                inc[name][k] = value
            if history is not None:
                it = self._iteration_columns
                start, end = self._iterations, self._iterations + len(history)
                if end > self._iteration_room:
                    self._iteration_room = end + _CHUNK
                    for d in it.values():
                        d.resize(self._iteration_room, axis=0)
                columns = {"increment": np.full(len(history), k + 1),
                           "iteration": np.arange(1, len(history) + 1),
                           **dict(zip(_HISTORY_COLUMNS, history.T, strict=True))}
                for name, values in columns.items():
                    it[name][start:end] = values
                self._iterations = end
                self._file["iterations"].attrs["count"] = end
            self._count = k + 1
            self._phase, self._travel = int(phase), float(travel)
            self._stroke += float(step)
            self._file["increments"].attrs["count"] = self._count  # last: the row is complete
            self._file.flush()
            return self._count

    # --------------------------------------------------------------------------- fields

    def fields(self, *, displacement: ArrayLike, stress: ArrayLike, plastic_strain: ArrayLike,
               contact_state: ArrayLike, contact_force: ArrayLike,
               contact_tool: ArrayLike | None = None, thickness: ArrayLike | None = None,
               contact_pressure: ArrayLike | None = None, time: float | None = None,
               extra: Mapping[str, ArrayLike] | None = None) -> Frame:
        """Write the fields of the last increment as a new frame (also visible in the XDMF).

        displacement (n, 3); stress (m, 6) or per Gauss point (m, g, 6), Voigt xx yy zz xy
        yz zx, averaged per element (stored in the XDMF order xx xy xz yy yz zz);
        plastic_strain (m,) or per Gauss point (m, 8) (averaged per element, and
        extrapolated to the nodes: plastic_strain_nodal); contact_state (n,) 0/1/2;
        contact_force (n, 3); contact_tool (n,) tool index or -1; contact_pressure (n,) MPa
        (default zero); thickness (n,) (computed from the displacement when the mesh is
        layered, with the thinning and the surface strains); ``time`` for the XDMF
        (default: the lead tools' travel over the run, TIME_WITHOUT_TRAVEL more than the
        last frame's when there was none); ``extra`` more arrays, (n, ...) or (m, ...)."""
        n, m = len(self.nodes), len(self.elements)
        u = _shaped(displacement, (n, 3), "displacement")
        s = np.asarray(stress, dtype=float)
        if s.ndim == 3:
            s = s.mean(axis=1)
        s = _shaped(s, (m, 6), "stress")
        ep = np.asarray(plastic_strain, dtype=float)
        if ep.ndim == 2 and ep.shape[1] != 8:
            ep = ep.mean(axis=1)  # (Gauss points of another rule: no extrapolation)
        if ep.shape not in ((m,), (m, 8)):
            raise ValueError(f"plastic_strain must have shape {(m,)} or {(m, 8)}, got "
                             f"{ep.shape}")
        state = _shaped(contact_state, (n,), "contact_state").astype(np.int8)
        cf = _shaped(contact_force, (n, 3), "contact_force")
        tool = (np.full(n, -1, np.int16) if contact_tool is None
                else _shaped(contact_tool, (n,), "contact_tool").astype(np.int16))
        th = None if thickness is None else _shaped(thickness, (n,), "thickness")
        pressure = (np.zeros(n) if contact_pressure is None
                    else _shaped(contact_pressure, (n,), "contact_pressure"))
        index = len(self._frames)
        if time is None:
            frame_time = self._stroke
            if self._frames and frame_time <= self._frames[-1].time:
                frame_time = self._frames[-1].time + TIME_WITHOUT_TRAVEL
        else:
            frame_time = float(time)
        if self._frames and frame_time <= self._frames[-1].time:
            raise ValueError(f"frame time {frame_time} must exceed the previous frame's "
                             f"{self._frames[-1].time}")
        with self._writing():
            return self._write_frame(index, u, s, ep, state, cf, tool, th, frame_time,
                                     pressure, dict(extra or {}))

    def _write_frame(self, index: int, u: NDArray, s: NDArray, ep: NDArray, state: NDArray,
                     cf: NDArray, tool: NDArray, thickness: NDArray | None, time: float,
                     pressure: NDArray, extra: dict[str, ArrayLike]) -> Frame:
        n, m = len(self.nodes), len(self.elements)
        x = self.nodes + u
        d = s[:, :3] - s[:, :3].mean(axis=1, keepdims=True)
        mises = np.sqrt(1.5 * ((d**2).sum(axis=1) + 2 * (s[:, 3:] ** 2).sum(axis=1)))
        data = {"displacement": u, "coordinates": x, "contact_state": state,
                "contact_tool": tool, "contact_force": cf, "contact_pressure": pressure,
                "stress": s[:, TENSOR6], "von_mises": mises,
                "plastic_strain": ep.mean(axis=1) if ep.ndim == 2 else ep,
                "plastic_strain_nodal": nodal_average(self.elements, ep, n),
                "volume_change": element_volumes(x, self.elements) / self._volumes - 1.0,
                "increment": np.full(m, self._count, dtype=np.int32)}
        if self._measures is not None:
            if thickness is None:
                thickness = self._measures.thickness(u)
            data["thinning"] = self._measures.thinning(thickness=thickness)
            for key, value in self._measures.surface_strains(u).items():
                which, surface = key.split("_")
                data[f"{which}_strain_{surface}"] = value
        if thickness is not None:
            data["thickness"] = thickness
        fields = self._file["fields"]
        group = fields.create_group(f"{index:06d}")
        frame = Frame(index, self._count, self._phase, self._travel, time)
        placed = self._place_tools(index)
        group.attrs.update({"increment": frame.increment, "phase": frame.phase,
                            "travel": frame.travel, "time": frame.time,
                            "tool_displacement": self._tool_displacement(),
                            "tool_geometry": placed})
        for name, array in data.items():
            centre, _, dtype, units, meaning = _FIELDS[name]
            ds = group.create_dataset(name, data=np.asarray(array, dtype=dtype))
            ds.attrs.update({"units": units, "centre": centre, "description": meaning})
        for name, array in extra.items():
            a = np.asarray(array)
            if name in data or "/" in name or not name:
                raise ValueError(f"extra field name {name!r} is empty, taken or has a '/'")
            if a.shape[:1] not in ((n,), (m,)) or a.dtype.kind not in "iuf" or a.ndim > 2:
                raise ValueError(f"extra field {name!r} must be numbers of shape (n,), (n, k),"
                                 f" (m,) or (m, k), got {a.shape} {a.dtype}")
            ds = group.create_dataset(name, data=a)
            ds.attrs.update({"units": "", "centre": "Node" if len(a) == n else "Cell",
                             "description": "extra field"})
        self._frames.append(frame)
        fields.attrs["count"] = len(self._frames)  # last: the frame is complete
        self._file.flush()
        self._write_xdmf()
        return frame

    def _tool_displacement(self) -> NDArray[np.float64]:
        """Each tool's displacement at the last increment (t, 3) (zero before the first)."""
        if not self._count:
            return np.zeros((len(self.tools), 3))
        return self._file["increments/tool_displacement"][self._count - 1]

    def _place_tools(self, index: int) -> list[str]:
        """Each drawn tool's surface where it is at frame ``index``: the path of its
        coordinates, written as /tools/NAME/coordinates/<index> unless the tool has not
        moved since the frame whose coordinates the last frame used ("" for a tool not
        drawn)."""
        tools = self._file["tools"]
        moved = self._tool_displacement()
        last = (self._file["fields"][f"{index - 1:06d}"].attrs.get("tool_geometry")
                if index else None)
        paths = []
        for t, name in enumerate(self.tools):
            if name not in tools:
                paths.append("")
                continue
            group = tools[name]
            if last is not None and str(last[t]):
                before = self._file[str(last[t])]
                if np.array_equal(before.attrs["displacement"], moved[t]):
                    paths.append(str(last[t]))
                    continue
            ds = group["coordinates"].create_dataset(f"{index:06d}",
                                                     data=group["points"][()] + moved[t])
            ds.attrs.update({"units": "mm", "displacement": moved[t]})
            paths.append(ds.name)
        return paths

    def _write_xdmf(self) -> None:
        """Rewrite the XDMF file (atomically) with the frames' grids, each read from the
        file once (``_grids``): rebuilding every frame's at every frame grew as the
        square of the frames."""
        while len(self._grids) < len(self._frames):
            self._grids.append(xdmf_frame(self.path.name, self._file, len(self._grids)))
        text = xdmf_text(self.path.name, self._file, self._grids)
        with atomic_write(self.xdmf_path) as out:  # the last complete XDMF stays on failure
            out.write(text)

    # --------------------------------------------------------------------------- closing

    def close(self) -> None:
        """Mark the file closed and close it (nothing to do after a failed write)."""
        if self._file.id.valid:
            with self._writing(frame=False):
                self._trim_columns()
                self._file.attrs["closed"] = datetime.datetime.now().isoformat(
                    timespec="seconds")
            self._close()

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


#: Most names in one list attribute (tools, phases, leads): HDF5 keeps an attribute in its
#: object's header, 64 KiB at most, 16 bytes a name (5,000 names ended a run with "object
#: header message is too large"). The decks take at most 1,000 phases and tools.
MAX_NAMES = 4000


def _storable(attrs: dict[str, Any]) -> dict[str, Any]:
    """Attributes as HDF5 stores them: text as UTF-8 without NUL bytes (HDF5 refuses them)
    and without lone surrogates (a file name's undecodable bytes, which UTF-8 cannot hold),
    each written as a backslash escape; a list of names refused beyond MAX_NAMES."""

    def text(value: str) -> str:
        try:  # a file name's bytes as they were
            data = value.encode("utf-8", "surrogateescape")
        except UnicodeEncodeError:  # other lone surrogates
            data = value.encode("utf-8", "surrogatepass")
        return data.decode("utf-8", "backslashreplace").replace("\0", "\\x00")

    out: dict[str, Any] = {}
    for name, value in attrs.items():
        if isinstance(value, str):
            value = text(value)
        elif isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
            if len(value) > MAX_NAMES:
                raise ValueError(f"the attribute {name} lists {len(value):,} names; HDF5 "
                                 f"holds at most about {MAX_NAMES:,}")
            value = [text(v) for v in value]
        out[name] = value
    return out


def _measures(nodes: NDArray, elements: NDArray, normal: ArrayLike) -> SheetMeasures | None:
    """The thickness and surface strains of a blank meshed in layers; None otherwise."""
    try:
        return SheetMeasures(nodes, elements, normal)
    except ValueError:
        return None


#: XDMF's codes of the cells of a Mixed topology.
_XDMF_MIXED = {3: 4, 4: 5}


def _write_tool(group: Any, surface: Any) -> None:
    """A tool's surface tessellated (ddpy.geometry.tessellation) into ``group``: its
    points at rest and cells, in the XDMF topology they take (Triangle, Quadrilateral, or
    Mixed: each cell's XDMF code before its corners)."""
    points, cells, kinds = tessellate(surface)
    if (kinds == kinds[0]).all():
        topology = "Triangle" if kinds[0] == TRIANGLE else "Quadrilateral"
        connectivity = cells.reshape(-1, int(kinds[0]))
    else:
        topology = "Mixed"
        starts = np.concatenate([[0], np.cumsum(kinds)[:-1]])
        connectivity = np.concatenate([np.concatenate([[_XDMF_MIXED[int(k)]],
                                                       cells[a:a + k]])
                                       for a, k in zip(starts, kinds, strict=True)])
    group.create_dataset("points", data=points).attrs["units"] = "mm"
    ds = group.create_dataset("cells", data=connectivity.astype(np.int32))
    ds.attrs.update({"topology": topology, "count": len(kinds),
                     "description": "0-based point indices of the tessellated surface "
                                    "(Mixed: each cell's XDMF code, 4 triangle, 5 "
                                    "quadrilateral, then its corners)"})
    group.create_group("coordinates")


def _tool_points(tools: Any) -> int:
    """Points of every drawn tool (the bytes of a frame that places them)."""
    return sum(int(g["points"].shape[0]) for g in tools.values())


def _shaped(value: ArrayLike, shape: tuple[int, ...], name: str) -> NDArray:
    a = np.asarray(value)
    if a.dtype.kind not in "iuf" and a.dtype != bool:
        raise TypeError(f"{name} must be numbers, got dtype {a.dtype}")
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    return a


@functools.cache
def _libc() -> ctypes.CDLL:
    """The C library, for fallocate (not in the os module)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.fallocate.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int64, ctypes.c_int64]
    libc.fallocate.restype = ctypes.c_int
    return libc


def _limit_code(limit: int | str) -> int:
    if isinstance(limit, str):
        for code, name in LIMITS.items():
            if name == limit:
                return code
        raise ValueError(f"unknown limit {limit!r}: expected one of {list(LIMITS.values())}")
    if int(limit) not in LIMITS:
        raise ValueError(f"unknown limit code {limit}: expected one of {list(LIMITS)}")
    return int(limit)


def _item(h5name: str, dataset: Any) -> str:
    kind = dataset.dtype.kind
    number = "Float" if kind == "f" else ("UInt" if kind == "u" else "Int")
    dims = " ".join(str(d) for d in dataset.shape)
    return (f'<DataItem DataType="{number}" Precision="{dataset.dtype.itemsize}" '
            f'Dimensions="{dims}" Format="HDF">{escape(h5name)}:{dataset.name}</DataItem>')


def xdmf_frame(h5name: str, f: Any, index: int) -> list[str]:
    """The XDMF grids of frame ``index`` of a results file, one per collection of
    xdmf_text (each drawn tool's, then the blank's; "" where a tool has no grid). A frame
    never changes once written: the writer keeps these and writes the document from them."""
    mesh = f["mesh"]
    group = f["fields"][f"{index:06d}"]
    time = f'<Time Value="{float(group.attrs["time"])!r}"/>'
    tools = f["tools"] if "tools" in f else {}
    paths = group.attrs.get("tool_geometry")
    out = []
    for t, name in enumerate(str(t) for t in f.attrs["tools"]):
        if name not in tools:
            continue
        if paths is None or not str(paths[t]):
            out.append("")
            continue
        cells = tools[name]["cells"]
        out.append("\n        ".join([
            f'<Grid Name={quoteattr(f"{name} {index}")} GridType="Uniform">', time,
            f'<Topology TopologyType="{cells.attrs["topology"]}" NumberOfElements='
            f'"{int(cells.attrs["count"])}">{_item(h5name, cells)}</Topology>',
            f'<Geometry GeometryType="XYZ">{_item(h5name, f[str(paths[t])])}</Geometry>',
            "</Grid>"]))
    geometry = mesh["nodes"] if index == 0 else group["coordinates"]
    parts = [f'<Grid Name="frame {index}" GridType="Uniform">', time,
             f'<Topology TopologyType="Hexahedron" NumberOfElements='
             f'"{mesh["elements"].shape[0]}">{_item(h5name, mesh["elements"])}</Topology>',
             f'<Geometry GeometryType="XYZ">{_item(h5name, geometry)}</Geometry>']
    for name, ds in group.items():
        if name == "coordinates":
            continue
        centre = str(ds.attrs.get("centre", "Node"))
        width = ds.shape[1] if ds.ndim == 2 else 1
        kind = {1: "Scalar", 3: "Vector", 6: "Tensor6", 9: "Tensor"}.get(width, "Matrix")
        parts.append(f'<Attribute Name={quoteattr(name)} AttributeType="{kind}" '
                     f'Center="{centre}">{_item(h5name, ds)}</Attribute>')
    parts.append("</Grid>")
    out.append("\n        ".join(parts))
    return out


def xdmf_text(h5name: str, f: Any, frames: Sequence[list[str]] | None = None) -> str:
    """The XDMF 3 document of a results file: per drawn tool a temporal collection of its
    tessellated surface placed at each frame, then the blank's, each frame with the current
    coordinates as geometry and its fields as attributes (the HDF5 datasets). The blank's
    comes last: meshio's TimeSeriesReader reads the last temporal collection. ``frames``:
    the frames' grids as xdmf_frame gives them (default: read from the file)."""
    if frames is None:
        frames = [xdmf_frame(h5name, f, k) for k in range(int(f["fields"].attrs["count"]))]
    tools = f["tools"] if "tools" in f else {}
    names = [str(t) for t in f.attrs["tools"] if str(t) in tools]
    names.append(str(f.attrs.get("title", "")) or "ddpy")
    body = "".join(
        f"    <Grid Name={quoteattr(name)} GridType=\"Collection\" "
        "CollectionType=\"Temporal\">\n      "
        + "\n      ".join(grids[c] for grids in frames if grids[c]) + "\n    </Grid>\n"
        for c, name in enumerate(names) if any(grids[c] for grids in frames))
    return ("<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n"
            f"{body}  </Domain>\n</Xdmf>\n")


class ResultsReader:
    """Reads a results file back: per-increment curves, Newton iterations and field frames.
    Reads files of runs still writing or killed: only complete rows and frames are seen."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        import h5py

        self.path = Path(path)
        try:
            self._file = h5py.File(self.path, "r", locking=False)
        except TypeError:  # h5py without the locking argument
            self._file = h5py.File(self.path, "r")
        f = self._file
        if f.attrs.get("format") != FORMAT:
            self._file.close()
            raise ValueError(f"{self.path} is not a ddpy results file")
        self.title = str(f.attrs["title"])
        self.tools = tuple(str(t) for t in f.attrs["tools"])
        self.phases = tuple(str(p) for p in f.attrs["phases"])
        self.units = str(f.attrs["units"])
        #: the blank's element (Solid's element): files written before it was recorded
        #: had the hexahedron, the only one then
        self.element = str(f.attrs.get("element", "hexahedron"))
        #: OpenMP threads of the run (``ddpy run``; 0 when not recorded)
        self.threads = int(f.attrs.get("threads", 0))
        #: the run's peak resident memory, MB (None: not recorded, files written before)
        peak = f.attrs.get("peak_memory_mb")
        self.peak_memory_mb = None if peak is None else float(peak)

    def attribute(self, name: str, default: Any = None) -> Any:
        """A root attribute of the file (the run's status, message, leads, threads...)."""
        return self._file.attrs.get(name, default)

    @property
    def symmetry(self) -> str | None:
        """The normal axis of each symmetry plane of the case ("xy": planes normal to x
        and to y, a quarter model; "": none); None when the file does not record them
        (written before ddpy did)."""
        value = self._file.attrs.get("symmetry")
        return None if value is None else str(value)

    def forming_limit(self) -> FormingLimitCurve | None:
        """The run's forming limit curve (material.dat's table, or Keeler-Brazier's from
        the hardening exponent and the blank's thickness); None when the file holds none."""
        g = self._file.get("forming_limit")
        if g is None:
            return None
        a = g.attrs
        if str(a["kind"]) == "table":
            return FormingLimitCurve.table(g["minor"][()], g["major"][()], str(a["origin"]))
        return FormingLimitCurve.keeler_brazier(float(a["n"]), float(a["thickness"]))

    @property
    def nodes(self) -> NDArray[np.float64]:
        return self._file["mesh/nodes"][()]

    @property
    def elements(self) -> NDArray[np.int32]:
        return self._file["mesh/elements"][()]

    @property
    def node_ids(self) -> NDArray[np.int64]:
        """The nodes' labels (the mesh deck's)."""
        return self._file["mesh/node_ids"][()]

    @property
    def element_ids(self) -> NDArray[np.int64]:
        """The elements' labels (the mesh deck's)."""
        return self._file["mesh/element_ids"][()]

    @property
    def n_increments(self) -> int:
        inc = self._file["increments"]
        return min([int(inc.attrs["count"])] + [d.shape[0] for d in inc.values()])

    def history(self) -> dict[str, NDArray]:
        """Every per-increment column, complete rows only."""
        k = self.n_increments
        return {name: d[:k] for name, d in self._file["increments"].items()}

    def curve(self, name: str) -> NDArray:
        """One per-increment column (see history)."""
        if name not in self._file["increments"]:
            raise KeyError(f"no column {name!r}: columns are {list(self._file['increments'])}")
        return self._file["increments"][name][: self.n_increments]

    def _tool(self, tool: str) -> int:
        if tool not in self.tools:
            raise KeyError(f"no tool {tool!r}: tools are {list(self.tools)}")
        return self.tools.index(tool)

    def tool_force(self, tool: str) -> NDArray[np.float64]:
        """Reaction force on ``tool`` at each increment, (k, 3) N."""
        return self.curve("tool_force")[:, self._tool(tool)]

    def tool_displacement(self, tool: str) -> NDArray[np.float64]:
        """Displacement of ``tool`` at each increment, (k, 3) mm."""
        return self.curve("tool_displacement")[:, self._tool(tool)]

    def iterations(self) -> dict[str, NDArray]:
        """Per Newton iteration: increment, iteration, the two residuals, the step's length
        and what switched since the previous iterate (files written before those columns
        existed have the first four only)."""
        it = self._file["iterations"]
        k = min([int(it.attrs["count"])] + [d.shape[0] for d in it.values()])
        return {name: d[:k] for name, d in it.items()}

    @property
    def frames(self) -> list[Frame]:
        """The complete field frames, frame 0 the initial state."""
        fields = self._file["fields"]
        out = []
        for index in range(int(fields.attrs["count"])):
            a = fields[f"{index:06d}"].attrs
            out.append(Frame(index, int(a["increment"]), int(a["phase"]), float(a["travel"]),
                             float(a["time"])))
        return out

    def field(self, name: str, frame: int = -1) -> NDArray:
        """One field of a frame (default the last); files written before a field was
        renamed (RENAMED) answer to the new name."""
        group = self._frame_group(frame)
        old = {new: old for old, new in RENAMED.items()}.get(name)
        if name not in group and old in group:
            name = old
        if name not in group:
            raise KeyError(f"no field {name!r} in frame: fields are {list(group)}")
        return group[name][()]

    def stress(self, frame: int = -1) -> NDArray[np.float64]:
        """Element stresses of a frame in ddpy's Voigt order xx yy zz xy yz zx, (m, 6) MPa."""
        return self.field("stress", frame)[:, VOIGT]

    def frame(self, frame: int = -1) -> dict[str, NDArray]:
        """All fields of a frame (default the last), by their present names (RENAMED)."""
        return {RENAMED.get(name, name): d[()]
                for name, d in self._frame_group(frame).items()}

    def field_frame(self, frame: int = -1) -> FieldFrame:
        """The blank's fields of a frame (default the last) as a FieldFrame (its
        ``to_meshio()`` gives a meshio mesh), stress in ddpy's Voigt order."""
        data = self.frame(frame)
        info = self.frames[frame]
        n = len(self.nodes)
        strains = {f"{which}_{surface}": data[f"{which}_strain_{surface}"]
                   for surface in SURFACES for which in ("major", "minor")
                   if f"{which}_strain_{surface}" in data}
        return FieldFrame(self.nodes, self.elements, info.increment,
                          self.phases[info.phase] if info.phase < len(self.phases) else "",
                          info.travel, data["displacement"], data["stress"][:, VOIGT],
                          data["plastic_strain"],
                          data.get("plastic_strain_nodal", np.zeros(n)),
                          data.get("contact_pressure", np.zeros(n)), data.get("thickness"),
                          data.get("thinning"), strains)

    def tool_surface(self, tool: str, frame: int = -1
                     ) -> tuple[NDArray[np.float64], NDArray[np.int32], str] | None:
        """A drawn tool's tessellated surface where it was at a frame (default the last):
        its points (p, 3), its cells and their XDMF topology (Triangle, Quadrilateral or
        Mixed); None for a tool not drawn (or a file written before tools were)."""
        self._tool(tool)
        paths = self._frame_group(frame).attrs.get("tool_geometry")
        if paths is None or "tools" not in self._file or tool not in self._file["tools"]:
            return None
        cells = self._file["tools"][tool]["cells"]
        path = str(paths[self.tools.index(tool)])
        return self._file[path][()], cells[()], str(cells.attrs["topology"])

    def _frame_group(self, frame: int) -> Any:
        count = int(self._file["fields"].attrs["count"])
        index = frame + count if frame < 0 else frame
        if not 0 <= index < count:
            raise IndexError(f"frame {frame} out of range: {count} frames")
        return self._file["fields"][f"{index:06d}"]

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> ResultsReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
