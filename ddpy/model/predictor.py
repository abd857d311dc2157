"""The start of an increment's Newton loop: the last increment's displacement rate carried
over, with the blank taken back out of the tools' barriers (docs/theory/contact.md, "The
barrier", "A start clear of the barrier")."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.search import NONE
from ddpy.model.mesh import face_area_vectors
from ddpy.model.tool import BARRIER_WIDTH, RigidTool

__all__ = ["clear_of_barriers"]


def clear_of_barriers(guess: NDArray[np.float64], nodes: NDArray[np.float64],
                      tools: Sequence[RigidTool], faces: Sequence[NDArray[np.integer]],
                      positions: Mapping[str, NDArray[np.float64]], thickness: float,
                      column: NDArray[np.integer], reach: float
                      ) -> tuple[NDArray[np.float64], int]:
    """The start ``guess`` (n, 3 displacements of the blank's ``nodes``) with every slave
    node of a Gauss-point tool with a barrier that it carries past the end of the barrier's
    ramp (deeper than d_b + w, the tool at ``positions[name]``) brought back along the
    tool's normal to the middle of the ramp (depth d_b + w / 2), and the number of such
    nodes. As in the core's search, a tool's patches count only where they face the blank:
    ``faces[k]`` are the blank faces that meet ``tools[k]`` (``contact_faces``), whose
    area-weighted normals at the start are its slaves' for the facing filter.

    The whole through-thickness column of the node moves (``column``: per node, one node
    of its column, the same for all of it, e.g. the bottom of
    ``through_thickness_columns``): moving a surface node alone strains its layer across
    its thickness by the move over the layer's thickness (17 % on the square cup's blank),
    a residual far larger than the barrier's. Where two slaves of one column are moved
    (squeezed between two tools), the column takes the sum of their moves.

    Why: an extrapolated start carries a node that slides round a tool's radius R by s in
    an increment s^2 / 2R into the tool (0.016 mm for 0.5 mm round an 8 mm radius, four
    times the barrier's d_b on a 0.81 mm sheet), where the barrier's linear part pushes it
    out with E / T times the excess: the square cup's increments started with contact
    forces of 3.6e4 to 8.7e4 N where the converged ones carried 2e3 N, and the line search
    crawled out at steps of 1/64."""
    x = nodes + guess
    shift = np.zeros_like(guess)
    moved = 0
    width = BARRIER_WIDTH * thickness
    for tool, meeting in zip(tools, faces, strict=True):
        if tool.barrier is None or tool.contact != "gauss":
            continue
        start = tool.barrier * thickness
        normals = np.zeros_like(x)
        area = face_area_vectors(x, meeting)
        for corner in range(4):
            np.add.at(normals, meeting[:, corner], area)
        found = tool.search.project(x[tool.slaves], positions[tool.name],
                                    node_normals=normals[tool.slaves], reach=reach)
        depth = np.where(found.status != NONE, -found.distance, -np.inf)
        deep = depth > start + width
        if not deep.any():
            continue
        np.add.at(shift, column[tool.slaves[deep]],
                  (depth[deep] - start - 0.5 * width)[:, None] * found.normal[deep])
        moved += int(deep.sum())
    if not moved:
        return guess, 0
    return guess + shift[column], moved
