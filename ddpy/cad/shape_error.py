"""Shape error of a tool model against its CAD (paper Fig. 8 and 14-16).

Every patch is sampled on a grid of parameters; each sample is projected on the surface of the
CAD face the patch came from (:func:`ddpy.cad.closest_points`). The distance error is signed by
the CAD normal oriented like the tool (towards the blank): positive where the model stands out
of the CAD surface towards the blank, negative where it lies inside the tool. The normal error
is the angle between the model's normal and the exact CAD normal at the projection; samples
where the model's normal is undefined (a Bezier patch collapsed to a pole) are left out of it
and counted."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.cad import CadError, closest_points, gmsh_session, load_cad
from ddpy.io.toolfile import ToolModel

__all__ = ["ShapeError", "plot_shape_error", "sample_parameters", "shape_error"]


@dataclass
class ShapeError:
    """Samples of a tool model and their errors against the CAD (mm and degrees)."""

    name: str
    description: str
    n_patches: int
    points: NDArray[np.float64]    # (k, 3) points of the model
    patch: NDArray[np.int64]       # (k,) patch of each sample
    distance: NDArray[np.float64]  # (k,) signed distance to the CAD surface, mm
    angle: NDArray[np.float64]     # (k,) normal angle error, degrees
    cells: NDArray[np.int64]       # (c, 4) samples around each cell of the grids (for maps)

    @property
    def max_distance(self) -> float:
        """Largest |distance| (mm)."""
        return float(np.abs(self.distance).max())

    @property
    def mean_distance(self) -> float:
        """Mean |distance| over the samples (mm)."""
        return float(np.abs(self.distance).mean())

    @property
    def max_angle(self) -> float:
        """Largest normal angle error (degrees), where the model's normal is defined."""
        return float(np.nanmax(self.angle)) if np.isfinite(self.angle).any() else float("nan")

    @property
    def undefined_normals(self) -> int:
        """Samples where the model's normal is undefined (a patch collapsed to a point)."""
        return int(np.isnan(self.angle).sum())

    def summary(self) -> dict[str, float | int | str]:
        """The numbers per tool: patches, max and mean |distance| (um), max angle (degrees)."""
        return {"name": self.name, "description": self.description, "patches": self.n_patches,
                "samples": int(len(self.distance)),
                "max_distance_um": 1e3 * self.max_distance,
                "mean_distance_um": 1e3 * self.mean_distance,
                "min_signed_um": 1e3 * float(self.distance.min()),
                "max_signed_um": 1e3 * float(self.distance.max()),
                "max_angle_deg": self.max_angle,
                "undefined_normals": self.undefined_normals}


def sample_parameters(samples: int, triangle: bool) -> NDArray[np.float64]:
    """Grid of (u, v) on [0, 1]^2, or on the triangle 0 <= v <= u <= 1: (k, 2)."""
    g = np.linspace(0.0, 1.0, samples)
    u, v = np.repeat(g, samples), np.tile(g, samples)
    uv = np.column_stack([u, v])
    return uv[v <= u + 1e-12] if triangle else uv


def shape_error(model: ToolModel, cad: str | os.PathLike[str] | None = None,
                samples: int = 9) -> ShapeError:
    """Errors of ``model`` against its CAD on a ``samples`` x ``samples`` grid per patch.

    ``cad`` defaults to the model's source file; without one, the faces of the current gmsh
    model are used. An odd ``samples`` includes the patch centre (where facets err most).
    """
    if samples < 2:
        raise ValueError(f"samples must be >= 2, got {samples}")
    surface = model.surface
    triangles = getattr(surface, "is_triangle", np.zeros(surface.n_patches, dtype=bool))
    ids, params, cells = [], [], []
    start = 0
    for triangle in (False, True):
        patches = np.flatnonzero(triangles == triangle)
        uv = sample_parameters(samples, triangle)
        ids.append(np.repeat(patches, len(uv)))
        params.append(np.tile(uv, (len(patches), 1)))
        grid = _grid_cells(samples, triangle)
        cells.append((start + len(uv) * np.arange(len(patches))[:, None, None] + grid
                      ).reshape(-1, 4))
        start += len(uv) * len(patches)
    patch = np.concatenate(ids)
    points, derivatives, normals = surface.evaluate(patch, np.concatenate(params))
    tangent = np.linalg.norm(derivatives, axis=2).max(axis=1)
    cross = np.linalg.norm(np.cross(derivatives[:, 0], derivatives[:, 1]), axis=1)
    undefined = cross <= 1e-6 * tangent**2
    tags = model.face_tags[patch]
    distance = np.empty(len(patch))
    angle = np.empty(len(patch))
    source = cad if cad is not None else model.source
    with gmsh_session(), _faces_of(source) as (available, label):
        import gmsh

        for face in np.unique(tags):
            if int(face) not in available:
                raise CadError(f"{label}: face {int(face)} of tool '{model.name}' is not in the "
                               "CAD model (was the tool built from another file?)")
            rows = np.flatnonzero(tags == face)
            closest, uv = closest_points(int(face), points[rows])
            exact = np.asarray(gmsh.model.getNormal(int(face), uv.ravel())).reshape(-1, 3)
            dots = np.einsum("ij,ij->i", exact, normals[rows])
            exact *= 1.0 if dots[~undefined[rows]].sum() >= 0.0 else -1.0
            distance[rows] = np.einsum("ij,ij->i", points[rows] - closest, exact)
            cosine = np.clip(np.einsum("ij,ij->i", exact, normals[rows]), -1.0, 1.0)
            angle[rows] = np.where(undefined[rows], np.nan, np.degrees(np.arccos(cosine)))
    return ShapeError(model.name, model.description, model.n_patches, points,
                      patch.astype(np.int64), distance, angle, np.concatenate(cells))


def _grid_cells(samples: int, triangle: bool) -> NDArray[np.int64]:
    """Cells (c, 4) of the sample grid of one patch, as indices into its samples; the cells
    along the diagonal of a triangle repeat a corner."""
    index = np.full((samples, samples), -1, dtype=np.int64)
    uv = sample_parameters(samples, triangle)
    ij = np.rint(uv * (samples - 1)).astype(np.int64)
    index[ij[:, 0], ij[:, 1]] = np.arange(len(uv))
    i, j = np.meshgrid(np.arange(samples - 1), np.arange(samples - 1), indexing="ij")
    quads = np.stack([index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]], -1)
    quads = quads.reshape(-1, 4)
    diagonal = quads[:, 3] < 0     # triangle patches: (i, i), (i+1, i), (i+1, i+1)
    quads[diagonal, 3] = quads[diagonal, 0]
    return quads[(quads >= 0).all(axis=1)]


@contextlib.contextmanager
def _faces_of(source: str | os.PathLike[str] | None) -> Iterator[tuple[set[int], str]]:
    import gmsh

    if source is None:
        yield {t for _, t in gmsh.model.getEntities(2)}, f"gmsh model '{gmsh.model.getCurrent()}'"
        return
    previous = gmsh.model.getCurrent()
    try:
        yield set(load_cad(source)), str(source)
    finally:
        if gmsh.model.getCurrent() == Path(source).stem:
            gmsh.model.remove()
            with contextlib.suppress(Exception):
                gmsh.model.setCurrent(previous)


def plot_shape_error(result: ShapeError, path: str | os.PathLike[str],
                     view: tuple[float, float] = (25.0, -60.0),
                     limit_um: float | None = None) -> Path:
    """PNG map of the distance (um) and normal (degrees) errors over the tool; the path."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    x = result.points
    span = np.maximum(np.ptp(x, axis=0), 1e-3 * max(float(np.ptp(x, axis=0).max()), 1e-12))
    um = 1e3 * result.distance
    limit = limit_um if limit_um is not None else max(float(np.abs(um).max()), 1e-6)
    fig = Figure(figsize=(11.0, 4.6), layout="constrained")
    angle = np.nan_to_num(result.angle, nan=0.0)
    panels = ((um, "coolwarm", -limit, limit, "distance error [um]"),
              (angle, "viridis", 0.0, max(float(angle.max()), 1e-9),
               "normal error [degrees]"))
    polygons = x[result.cells]
    for k, (values, cmap, lo, hi, label) in enumerate(panels):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        norm = Normalize(lo, hi)
        colours = colormaps[cmap](norm(values[result.cells].mean(axis=1)))
        ax.add_collection3d(Poly3DCollection(polygons, facecolors=colours, linewidths=0))
        for axis, lo_x, hi_x in zip("xyz", x.min(axis=0), x.max(axis=0), strict=True):
            getattr(ax, f"set_{axis}lim")(lo_x, hi_x)
            getattr(ax, f"set_{axis}label")(f"{axis} [mm]")
        ax.set_box_aspect(tuple(span))
        ax.view_init(*view)
        fig.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.7, label=label)
    fig.suptitle(f"{result.name} ({result.description}, {result.n_patches} patches): max |d| = "
                 f"{1e3 * result.max_distance:.3g} um, mean |d| = "
                 f"{1e3 * result.mean_distance:.3g} um, max normal error = "
                 f"{result.max_angle:.3g} degrees")
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
