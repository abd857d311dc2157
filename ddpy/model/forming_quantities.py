"""What a forming engineer reads off a deformed blank: thickness and thinning, the in-plane
major and minor logarithmic strains of its top, middle and bottom surfaces, and the
equivalent plastic strain at the nodes (definitions: docs/results-format.md).

>>> measures = SheetMeasures(mesh.nodes, mesh.elements, mesh.normal)   # doctest: +SKIP
>>> measures.thinning(u)                     # (n,) %, positive where the sheet got thinner
>>> measures.surface_strains(u)["major_top"] # (m,) per element, of its column's top face
>>> nodal_average(mesh.elements, ep, len(mesh.nodes))  # Gauss points (m, 8) to nodes (n,)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.model.mesh import HEX_EDGES, through_thickness_columns

__all__ = ["SURFACES", "FieldFrame", "SheetMeasures", "nodal_average"]

#: The sheet surfaces whose strains are measured, from the side the sheet normal points to.
SURFACES = ("top", "middle", "bottom")
#: Natural coordinates of the 8 nodes of a hexahedron (ddpy_hex8's corner table); Gauss
#: point p lies at corner p / sqrt(3).
_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
#: Trilinear extrapolation from the 8 Gauss points to the 8 nodes: row a holds the shape
#: functions of the Gauss-point "element" (corners at +-1/sqrt(3)) at node a (+-sqrt(3)).
_EXTRAPOLATION = np.prod(1.0 + np.sqrt(3.0) * _CORNERS[:, None, :] * _CORNERS[None, :, :],
                         axis=2) / 8.0
#: Of the 4 edges of each direction (HEX_EDGES), the order that walks around a face.
_AROUND = np.array([[0, 1, 3, 2], [0, 1, 3, 2], [0, 1, 2, 3]])


def nodal_average(elements: ArrayLike, values: ArrayLike, n_nodes: int) -> NDArray[np.float64]:
    """Gauss-point values (m, 8) or element values (m,) as nodal values (n,): per element
    extrapolated trilinearly from its 2 x 2 x 2 Gauss points to its nodes (exact for a field
    linear in the element), clipped at zero (a plastic strain is never negative), then
    averaged over the elements around each node. Element values are averaged as they are."""
    e = np.asarray(elements, dtype=np.int64).reshape(-1, 8)
    v = np.asarray(values, dtype=float)
    if v.shape == (len(e),):
        at_nodes = np.repeat(v[:, None], 8, axis=1)
    elif v.shape == (len(e), 8):
        at_nodes = np.maximum(v @ _EXTRAPOLATION.T, 0.0)
    else:
        raise ValueError(f"values must be (m,) or (m, 8) for {len(e)} elements, got {v.shape}")
    total = np.bincount(e.ravel(), weights=at_nodes.ravel(), minlength=n_nodes)
    count = np.bincount(e.ravel(), minlength=n_nodes)
    return np.divide(total, count, out=np.zeros(n_nodes), where=count > 0)


class SheetMeasures:
    """Thickness, thinning and surface strains of a blank meshed in layers through its
    thickness (``through_thickness_columns``; ValueError otherwise), at displacements u.

    Each element belongs to a column of elements through the thickness; the column's
    bottom and top faces are the quadrilaterals of the bottom and top nodes of the
    columns of nodes under its corners, its middle face their average. The surface strains
    of an element are those of its column's faces: one value per element, the same for
    every element of a column."""

    def __init__(self, nodes: ArrayLike, elements: ArrayLike, normal: ArrayLike) -> None:
        x = np.asarray(nodes, dtype=float).reshape(-1, 3)
        e = np.asarray(elements, dtype=np.int64).reshape(-1, 8)
        d = np.asarray(normal, dtype=float)
        self._nodes = x
        self.bottom, self.top = through_thickness_columns(x, e, d)
        self.initial_thickness = np.linalg.norm(x[self.top] - x[self.bottom], axis=1)
        # Per element, its edges through the thickness (the family closest to the normal),
        # walked around, and the lower node of each: a face of the element's column.
        edges = e[:, HEX_EDGES]                                           # (m, 3, 4, 2)
        vectors = x[edges[..., 1]] - x[edges[..., 0]]
        lengths = np.linalg.norm(vectors, axis=-1)
        family = np.argmax(np.abs(vectors @ d / np.where(lengths > 0, lengths, 1.0)).mean(
            axis=2), axis=1)
        rows = np.arange(len(e))[:, None]
        chosen = edges[rows, family[:, None], _AROUND[family]]          # (m, 4, 2)
        up = (x[chosen[..., 1]] - x[chosen[..., 0]]) @ d >= 0.0
        lower = np.where(up, chosen[..., 0], chosen[..., 1])             # (m, 4)
        self.quad_bottom, self.quad_top = self.bottom[lower], self.top[lower]
        self._metric0 = {s: _metric(self._surface(x, s)) for s in SURFACES}

    def _surface(self, x: NDArray[np.float64], surface: str) -> NDArray[np.float64]:
        """Corners (m, 4, 3) of each element's column face ``surface`` at positions x."""
        if surface == "top":
            return x[self.quad_top]
        if surface == "bottom":
            return x[self.quad_bottom]
        return 0.5 * (x[self.quad_top] + x[self.quad_bottom])

    def thickness(self, u: ArrayLike) -> NDArray[np.float64]:
        """Per node, the length of its column (top node to bottom node), mm."""
        x = self._positions(u)
        return np.linalg.norm(x[self.top] - x[self.bottom], axis=1)

    def thinning(self, u: ArrayLike | None = None, thickness: ArrayLike | None = None
                 ) -> NDArray[np.float64]:
        """Per node, 100 (t0 - t) / t0: the loss of thickness in % of the initial one
        (negative where the sheet got thicker), t at displacements ``u`` or as given
        (``thickness``, (n,))."""
        t0 = self.initial_thickness
        t = self.thickness(u) if thickness is None else np.asarray(thickness, dtype=float)
        return np.divide(100.0 * (t0 - t), t0, out=np.zeros_like(t0), where=t0 > 0)

    def surface_strains(self, u: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """Per element, the major and minor in-plane logarithmic strains of its column's
        top, middle and bottom faces at their centres: half the logarithms of the
        eigenvalues of M0^-1 M, M0 and M the metrics (first fundamental forms) of the face
        in the initial and the present positions. Keys ``major_top``, ``minor_top``,
        ``major_middle``... (m,) each; major >= minor."""
        x = self._positions(u)
        out = {}
        for s in SURFACES:
            m0, m = self._metric0[s], _metric(self._surface(x, s))
            # Eigenvalues of m0^-1 m: the squared principal stretches of the face.
            a = np.linalg.solve(m0, m)
            half = 0.5 * (a[:, 0, 0] + a[:, 1, 1])
            det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
            root = np.sqrt(np.maximum(half**2 - det, 0.0))
            out[f"major_{s}"] = 0.5 * np.log(half + root)
            out[f"minor_{s}"] = 0.5 * np.log(np.maximum(half - root, 1e-300))
        return out

    def _positions(self, u: ArrayLike) -> NDArray[np.float64]:
        return self._nodes + np.asarray(u, dtype=float).reshape(self._nodes.shape)


def _metric(corners: NDArray[np.float64]) -> NDArray[np.float64]:
    """The metric (m, 2, 2) of bilinear quadrilaterals (m, 4, 3) at their centres."""
    a, b, c, d = (corners[:, i] for i in range(4))
    t1, t2 = 0.5 * (b + c - a - d), 0.5 * (c + d - a - b)
    g12 = np.einsum("ij,ij->i", t1, t2)
    return np.stack([np.stack([np.einsum("ij,ij->i", t1, t1), g12], axis=1),
                     np.stack([g12, np.einsum("ij,ij->i", t2, t2)], axis=1)], axis=1)


@dataclass(frozen=True)
class FieldFrame:
    """The blank's fields at one state (a frame): where it was taken (the increment number
    over the run, the phase's name, the lead tool's travel in the phase, mm) and the
    fields, nodal (n, ...) or per element (m, ...): ``displacement`` (n, 3) mm, ``stress``
    (m, 6) MPa Cauchy averaged over the Gauss points in Voigt order xx yy zz xy yz zx,
    ``plastic_strain`` (m,) averaged over the Gauss points, ``plastic_strain_nodal`` (n,),
    ``thickness`` (n,) mm and ``thinning`` (n,) % (None when the mesh is not layered),
    ``contact_pressure`` (n,) MPa, and ``surface_strains`` (major and minor of the top,
    middle and bottom surfaces, (m,) each, keys ``major_top``... as
    SheetMeasures.surface_strains gives them; empty when not layered). ``to_meshio`` and
    the results file name them ``major_strain_top``..."""

    nodes: NDArray[np.float64]
    elements: NDArray[np.int32]
    increment: int
    phase: str
    travel: float
    displacement: NDArray[np.float64]
    stress: NDArray[np.float64]
    plastic_strain: NDArray[np.float64]
    plastic_strain_nodal: NDArray[np.float64]
    contact_pressure: NDArray[np.float64]
    thickness: NDArray[np.float64] | None = None
    thinning: NDArray[np.float64] | None = None
    surface_strains: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    def to_meshio(self) -> Any:
        """A meshio.Mesh of the undeformed blank (points: the initial coordinates, cells:
        hexahedra) with this frame's fields as point and cell data, the displacement among
        them (ParaView's Warp By Vector shows the deformed blank). For a time series, write
        the points and cells once and each frame's data::

            with meshio.xdmf.TimeSeriesWriter("blank.xdmf") as w:
                w.write_points_cells(mesh.points, mesh.cells)
                for t, frame in enumerate(frames):
                    m = frame.to_meshio()
                    w.write_data(t, point_data=m.point_data, cell_data=m.cell_data)
        """
        import meshio

        point_data: dict[str, NDArray] = {
            "displacement": self.displacement, "plastic_strain_nodal": self.plastic_strain_nodal,
            "contact_pressure": self.contact_pressure}
        if self.thickness is not None:
            point_data["thickness"] = self.thickness
        if self.thinning is not None:
            point_data["thinning"] = self.thinning
        cell_data = {"stress": [self.stress], "plastic_strain": [self.plastic_strain]}
        cell_data.update({f"{key.split('_')[0]}_strain_{key.split('_')[1]}": [value]
                          for key, value in self.surface_strains.items()})
        return meshio.Mesh(self.nodes, [("hexahedron", self.elements)], point_data=point_data,
                           cell_data=cell_data)
