"""The deformable blank: large-strain hexahedra and their assembly.

The Fortran core does the element work (``fortran/mechanics/ddpy_hex8.f90``, the default
hexahedron, or ``fortran/mechanics/ddpy_solid_shell.f90``, the solid-shell for sheets) and
assembles internal forces and the tangent straight into MUMPS coordinate storage, in parallel
(``fortran/solver/ddpy_solid_assembly.f90``); see ``docs/theory/solid.md`` and
``docs/theory/solid_shell.md`` for the formulations.
Displacements are total, in global axes; stresses are per Gauss point, Voigt order
11, 22, 33, 12, 23, 31.

Example::

    solid = Solid(HexMesh.box(10, 2, 1, 20, 4, 3), props)
    forces, _ = solid.internal_force(u, solid.initial_state())
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array
from ddpy.core.constants import constant
from ddpy.core.handles import CoreHandle, check
from ddpy.core.ordering import nested_dissection, node_adjacency
from ddpy.model.material import (
    HARDENING_OFFSET,
    HILL_OFFSET,
    KINEMATIC_OFFSET,
    LAW_OFFSET,
    POISSON_OFFSET,
    PROP_COUNT,
    YOUNG_OFFSET,
    HardeningTable,
    Material,
    Swift,
    Voce,
    initial_yield_stress,
)
from ddpy.model.mesh import HexMesh, zeta_off_normal

__all__ = ["Assembly", "DEFAULT_ELEMENT", "ELEMENTS", "Solid", "SolidState", "ElementError",
           "check_element",
           "material_props"]

#: The element kinds and their codes in the core: the mean-dilatation hexahedron
#: (docs/theory/solid.md) and the solid-shell with assumed natural and 13 enhanced strains
#: (docs/theory/solid_shell.md), whose third natural direction (nodes 0-3 on one face,
#: 4-7 on the other) must be the sheet's normal.
ELEMENTS = {"hexahedron": constant("element_hexahedron"),
            "solid-shell": constant("element_solid_shell")}
#: The blank's element by default: the solid-shell, which gives the converged bending of a
#: sheet with two layers of elements several thicknesses long; the mean-dilatation
#: hexahedron (DD3IMP's) locks there (docs/theory/solid_shell.md).
DEFAULT_ELEMENT = "solid-shell"
#: Enhanced parameters per solid-shell element.
SHELL_MODES = constant("shell_modes")
_STATUS = {constant("element_inverted"): "is inverted (det F <= 0 or det J0 <= 0 at a Gauss "
                                         "point)",
           constant("element_material_failed"): "failed in the material update (return "
                                                "mapping)",
           constant("element_bad_node"): "has a node index out of range",
           constant("element_bad_offsets"): "has inconsistent tangent slots",
           constant("element_not_converged"): "did not converge in its enhanced strains (the "
                                              "solid-shell's local iteration)",
           constant("element_back_size"): "has no backstress in the state (mixed hardening "
                                          "needs one per Gauss point)",
           constant("element_bad_blank"): "is not in the core's copy of this blank (a bug in "
                                          "the caller)"}
_COMPONENTS = {"x": 0, "y": 1, "z": 2}


class ElementError(RuntimeError):
    """An element could not be evaluated; ``element`` is its 0-based index."""

    def __init__(self, status: int, element: int) -> None:
        self.status, self.element = status, element
        super().__init__(f"element {element} {_STATUS.get(status, f'status {status}')}")


def material_props(material: Any) -> NDArray[np.float64]:
    """The PROP_COUNT material properties of ``material`` (anything with ``props()``, or the vector
    itself), checked: E > 0, -1 < nu < 0.5, a convex Hill'48 surface, a known hardening law
    with positive parameters.

    Layout: (0) E, (1) nu, (2:8) Hill F, G, H, L, M, N, (8) hardening (1 Swift, 2 Voce,
    3 table), (9:12) Swift K, eps0, n or Voce Y0, Q, b or the table's point count; (12:14)
    C_X, X_sat of the kinematic hardening (zero: none); (16:) the table's (ep, Y) pairs;
    the rest is reserved (zero). A ``Material`` arrives checked by its own class (the one
    check of a deck's material): its vector is taken as it is.
    """
    if isinstance(material, Material):
        return float_array(material.props(), "material properties", (PROP_COUNT,))
    props = material.props() if hasattr(material, "props") else material
    props = float_array(props, "material properties", (PROP_COUNT,))
    e, nu = props[YOUNG_OFFSET], props[POISSON_OFFSET]
    if not e > 0.0:
        raise ValueError(f"Young's modulus must be positive, got {e}")
    if not -1.0 < nu < 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5), got {nu}")
    hill = props[HILL_OFFSET:HILL_OFFSET + 6]
    f, g, h, l_, m, n = hill
    if min(l_, m, n) <= 0.0 or min(f + g, g + h, h + f) <= 0.0 or f * g + g * h + h * f <= 0.0:
        raise ValueError(
            f"Hill'48 coefficients F, G, H, L, M, N = {hill.tolist()} do not define a "
            "convex yield surface (need L, M, N > 0, F+G, G+H, H+F > 0, FG+GH+HF > 0)")
    law = props[LAW_OFFSET]
    parameters = props[HARDENING_OFFSET:HARDENING_OFFSET + 3]
    if law == Swift.law:
        k, eps0, n_ = parameters
        if not (k > 0.0 and eps0 > 0.0 and n_ >= 0.0):
            raise ValueError(f"Swift K, eps0 must be positive and n >= 0, got {k}, {eps0}, {n_}")
    elif law == Voce.law:
        y0, q, b = parameters
        if not (y0 > 0.0 and q >= 0.0 and b >= 0.0):
            raise ValueError(f"Voce Y0 must be positive and Q, b >= 0, got {y0}, {q}, {b}")
    elif law != HardeningTable.law:
        raise ValueError(f"hardening must be {Swift.law} (Swift), {Voce.law} (Voce) or "
                         f"{HardeningTable.law} (table), got {law}")
    c_x, x_sat = props[KINEMATIC_OFFSET:KINEMATIC_OFFSET + 2]
    if not (c_x >= 0.0 and x_sat >= 0.0):
        raise ValueError(f"kinematic hardening C_X and X_sat must be non-negative, got {c_x}, "
                         f"{x_sat}")
    y0 = float(_core.material_hardening(props, np.zeros(1))[0][0])
    if x_sat >= y0:
        raise ValueError(f"kinematic hardening X_sat = {x_sat:g} must lie below the initial "
                         f"yield stress {y0:g}")
    info = int(_core.material_check(props))
    if info:
        raise ValueError(f"material property {info - 1} (0-based) is out of range "
                         "(see ddpy.model.material for the accepted ranges)")
    return props


def check_element(element: str) -> str:
    """``element`` if it names an element kind (ELEMENTS), else ValueError: the one check,
    Solid's and mesh.dat's."""
    if element not in ELEMENTS:
        raise ValueError(f"element must be one of {', '.join(map(repr, ELEMENTS))}, got "
                         f"{element!r}")
    return element


@dataclass
class SolidState:
    """State of the blank at a converged increment, the reference configuration of the next
    (updated Lagrangian): per Gauss point the rotated Kirchhoff stress in material axes
    (m, 8, 6), the equivalent plastic strain (m, 8), the accumulated logarithmic strain in
    material axes (m, 8, 6) and the material axes as columns (m, 8, 3, 3); per node the
    displacements (n, 3); with mixed hardening the backstress in material axes (m, 8, 6),
    carried like the stress (None without it)."""

    stress: NDArray[np.float64]
    ep: NDArray[np.float64]
    strain: NDArray[np.float64]
    axes: NDArray[np.float64]
    displacement: NDArray[np.float64]
    backstress: NDArray[np.float64] | None = None

    @classmethod
    def zeros(cls, n_elements: int, n_nodes: int) -> SolidState:
        """Stress-free, undeformed state with the material axes along the global axes."""
        axes = np.broadcast_to(np.eye(3), (n_elements, 8, 3, 3)).copy()
        return cls(np.zeros((n_elements, 8, 6)), np.zeros((n_elements, 8)),
                   np.zeros((n_elements, 8, 6)), axes, np.zeros((n_nodes, 3)))

    def copy(self) -> SolidState:
        # order="K" keeps the layout of axes (a transposed view when written by assemble),
        # so that the copy goes back to the core without another copy.
        return SolidState(self.stress.copy(), self.ep.copy(), self.strain.copy(),
                          self.axes.copy(order="K"), self.displacement.copy(),
                          None if self.backstress is None else self.backstress.copy())


def _flat(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """C-ordered flat float64 view (or copy) for the core."""
    return np.ascontiguousarray(a, dtype=np.float64).ravel()


#: What the core reads for the backstress of a material without one (f2py passes no empty
#: array; the core does not read it then).
_NO_BACKSTRESS = np.zeros(48)


class Assembly(NamedTuple):
    """What one assembly returns: internal forces (n, 3), tangent values in the slots of the
    pattern, the trial state, K dp when asked for (else None) and, for the solid-shell,
    the enhanced parameters (m, 13) solved in its elements (else None)."""

    fint: NDArray[np.float64]
    values: NDArray[np.float64]
    state: SolidState
    kdu: NDArray[np.float64] | None
    alpha: NDArray[np.float64] | None = None


@dataclass
class _Pattern:
    """Equation numbers and the tangent's coordinate structure for one constraint set."""

    eqn: NDArray[np.int32]
    symmetric: bool
    offsets: NDArray[np.int32]
    rows: NDArray[np.int32]
    cols: NDArray[np.int32]


class Solid:
    """A hexahedral mesh of one material, oriented by its rolling direction.

    ``material``: a ``ddpy.model.material.Material`` or its 16-vector of properties (see
    ``material_props``). ``rolling_direction_deg``: angle of the rolling direction from the
    global x axis about z, one value or one per element. ``element``: "solid-shell" (the
    default, DEFAULT_ELEMENT; for sheets: free of shear, thickness and volumetric locking;
    every element's nodes 0-3 on one face of the sheet and 4-7 on the other, as
    ``HexMesh.box`` makes them for a sheet normal to z, ``zeta_along_normal`` for any mesh)
    or "hexahedron" (the mean-dilatation hexahedron, DD3IMP's). The core keeps its own copy
    of the mesh, element kind and material (``blank_handle``): ``props`` is read-only.
    """

    def __init__(self, mesh: HexMesh, material: Any,
                 rolling_direction_deg: float | ArrayLike = 0.0,
                 element: str = DEFAULT_ELEMENT) -> None:
        if not isinstance(mesh, HexMesh):
            raise TypeError(f"mesh must be a HexMesh, got {type(mesh).__name__}")
        check_element(element)
        if element == "solid-shell":
            _check_thickness_direction(mesh)
        self.element = element
        self._kind = ELEMENTS[element]
        self.mesh = mesh
        # The core keeps its own copy (blank_handle): this one is read-only, to stay the same.
        self.props = np.array(material_props(material))
        self.props.flags.writeable = False
        #: mixed hardening: a backstress per Gauss point in the state
        self.mixed = bool(self.props[KINEMATIC_OFFSET] > 0.0
                          and self.props[KINEMATIC_OFFSET + 1] > 0.0)
        #: the initial yield stress (MPa, of the hardening curve at ep = 0: Swift K eps0^n,
        #: Voce Y0, a table's first stress): the scale of Gauss-point contact's default
        #: penalty
        self.yield_stress = initial_yield_stress(self.props)
        angle = np.asarray(rolling_direction_deg, dtype=float)
        if angle.ndim == 0:
            angle = np.full(mesh.n_elements, float(angle))
        self.angle = np.radians(float_array(angle, "rolling_direction_deg", (mesh.n_elements,)))
        self._x = mesh.nodes.ravel()
        self._conn = mesh.elements.ravel()
        handle, status, element = _core.blank_create(self._x, self._conn, self._kind,
                                                     self.props)
        if status == constant("refusal_index"):
            raise ElementError(constant("element_bad_node"), int(element) - 1)
        check(status, "the blank's mesh and material")
        self._blank = CoreHandle(handle)

    @property
    def blank_handle(self) -> int:
        """The handle of the core's copy of this solid's mesh, element kind and material
        (fortran/mechanics/ddpy_blank.f90), which the core's assembly and problems read."""
        return self._blank.handle

    @property
    def n_dofs(self) -> int:
        return 3 * self.mesh.n_nodes

    def node_order(self) -> NDArray[np.int64]:
        """Nested-dissection elimination order of the mesh nodes (computed once)."""
        if getattr(self, "_node_order", None) is None:
            graph = node_adjacency(self.mesh.elements, self.mesh.n_nodes)
            self._node_order = nested_dissection(graph, self.mesh.nodes)
        return self._node_order

    def initial_state(self) -> SolidState:
        """Stress-free, undeformed state with no plastic strain; the material axes are the
        rolling direction, its normal in the x-y plane and z."""
        state = SolidState.zeros(self.mesh.n_elements, self.mesh.n_nodes)
        c, s = np.cos(self.angle), np.sin(self.angle)
        axes = np.zeros((self.mesh.n_elements, 3, 3))
        axes[:, 0, 0], axes[:, 1, 0] = c, s
        axes[:, 0, 1], axes[:, 1, 1] = -s, c
        axes[:, 2, 2] = 1.0
        state.axes[:] = axes[:, None, :, :]
        if self.mixed:
            state.backstress = np.zeros((self.mesh.n_elements, 8, 6))
        return state

    def backstress_in(self, state: SolidState) -> NDArray[np.float64]:
        """The flat backstress of ``state`` for the core, checked: (m, 8, 6) with mixed
        hardening (ValueError when missing), the stand-in the core ignores without it."""
        if not self.mixed:
            return _NO_BACKSTRESS
        m = self.mesh.n_elements
        if state.backstress is None or np.shape(state.backstress) != (m, 8, 6):
            raise ValueError(f"the state has no backstress of shape ({m}, 8, 6), which this "
                             "solid's mixed hardening needs (got "
                             f"{None if state.backstress is None else np.shape(state.backstress)})")
        return _flat(state.backstress)

    def state_buffer(self) -> SolidState:
        """Uninitialized arrays of a state, in the layout ``assemble`` writes (``out``)."""
        m, n = self.mesh.n_elements, self.mesh.n_nodes
        return SolidState(np.empty((m, 8, 6)), np.empty((m, 8)), np.empty((m, 8, 6)),
                          np.empty((m, 8, 3, 3)).transpose(0, 1, 3, 2), np.empty((n, 3)),
                          np.empty((m, 8, 6)) if self.mixed else None)

    def backstress_out(self, out: SolidState) -> NDArray[np.float64]:
        """The flat buffer the core writes the trial backstress into (a scratch copy of the
        stand-in without mixed hardening)."""
        if not self.mixed:
            return _NO_BACKSTRESS.copy()
        if out.backstress is None:
            out.backstress = np.empty((self.mesh.n_elements, 8, 6))
        return out.backstress.ravel()

    def pattern(self, eqn: ArrayLike | None = None, symmetric: bool = True) -> _Pattern:
        """Coordinate structure of the tangent for equation numbers ``eqn`` (n, 3) (0-based,
        -1 for a constrained dof; default: every dof free, numbered 3 node + component)."""
        if eqn is None:
            eqn = np.arange(self.n_dofs, dtype=np.int32)
        eqn = int_array(np.asarray(eqn).reshape(-1), "eqn", (self.n_dofs,))
        counts, status, element = _core.solid_coo_count(self._conn, eqn, int(symmetric))
        if status:
            raise ElementError(int(status), int(element) - 1)
        offsets = np.zeros(self.mesh.n_elements + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        if offsets[-1] > np.iinfo(np.int32).max:
            raise ValueError("the tangent has more than 2^31 entries; not supported")
        offsets = offsets.astype(np.int32)
        rows, cols, status, element = _core.solid_coo_pattern(
            self._conn, eqn, int(symmetric), offsets, int(offsets[-1]))
        if status:
            raise ElementError(int(status), int(element) - 1)
        return _Pattern(eqn, symmetric, offsets, rows, cols)

    def assemble(self, u: ArrayLike, state: SolidState | None = None,
                 pattern: _Pattern | None = None, tangent: bool = True,
                 values: NDArray[np.float64] | None = None,
                 dp: ArrayLike | None = None, out: SolidState | None = None,
                 alpha: ArrayLike | None = None) -> Assembly:
        """Internal forces (n, 3), tangent values in the slots of ``pattern`` (empty when
        ``tangent`` is False) and the trial state at total displacements ``u`` (n, 3),
        over the increment from the converged ``state`` (its displacements are the
        reference configuration); with ``dp`` (n, 3) also the product K dp of
        the tangent over all dofs with dp. ``values`` may be given as the output buffer,
        and ``out`` (from ``state_buffer`` or an earlier assembly) as the arrays of the
        trial state: it must not share memory with ``state``, and is overwritten.
        ``alpha`` (m, 13): where the solid-shell's local iteration on its enhanced
        parameters starts (default zero, the start of an increment); the solution is
        returned in ``Assembly.alpha``.
        Raises ElementError when an element is inverted or its material update fails."""
        n = self.mesh.n_nodes
        u = float_array(u, "u", (n, 3))
        state = self.initial_state() if state is None else state
        pattern = self.pattern() if pattern is None else pattern
        if not tangent:
            values = np.zeros(0)
        elif values is None or values.shape != pattern.rows.shape:
            values = np.empty(pattern.rows.shape[0])
        product = dp is not None and tangent
        dp = np.zeros(3 * n) if dp is None else float_array(dp, "dp", (n, 3)).ravel()
        # The trial state is written into given arrays (fresh ones when out is None) rather
        # than into arrays f2py allocates and zeroes: 28 MB per call on 20,000 elements.
        m = self.mesh.n_elements
        if out is None:
            out = self.state_buffer()
        else:
            for name, array, shape in (("stress", out.stress, (m, 8, 6)), ("ep", out.ep, (m, 8)),
                                       ("strain", out.strain, (m, 8, 6)),
                                       ("axes", out.axes.transpose(0, 1, 3, 2), (m, 8, 3, 3))):
                if (array.shape != shape or array.dtype != np.float64
                        or not array.flags.c_contiguous):
                    raise ValueError(f"out.{name} is not a buffer of this solid's state")
                if any(np.may_share_memory(array, held) for held in (
                        state.stress, state.ep, state.strain, state.axes)):
                    raise ValueError("out shares memory with state")
        back_old = self.backstress_in(state)
        back_out = self.backstress_out(out)
        start = np.zeros(SHELL_MODES * m) if alpha is None else \
            float_array(alpha, "alpha", (m, SHELL_MODES)).ravel()
        values, fint, kdu, stress, ep, strain, axes, back, alpha_out, status, element = \
            _core.solid_assemble(
                self.blank_handle, _flat(state.displacement), u.ravel(),
                _flat(state.axes.transpose(0, 1, 3, 2)), _flat(state.stress),
                _flat(state.ep), _flat(state.strain), back_old, start, pattern.eqn,
                int(pattern.symmetric), int(tangent), pattern.offsets, values, int(product),
                dp, out.stress.ravel(), out.ep.ravel(), out.strain.ravel(),
                out.axes.transpose(0, 1, 3, 2).ravel(), back_out)
        if status:
            raise ElementError(int(status), int(element) - 1)
        trial = SolidState(stress.reshape(m, 8, 6), ep.reshape(m, 8), strain.reshape(m, 8, 6),
                           axes.reshape(m, 8, 3, 3).transpose(0, 1, 3, 2), u.copy(),
                           back.reshape(m, 8, 6) if self.mixed else None)
        return Assembly(fint.reshape(-1, 3), values, trial,
                        kdu.reshape(-1, 3) if product else None,
                        alpha_out.reshape(m, SHELL_MODES) if self._kind else None)

    def internal_force(self, u: ArrayLike, state: SolidState | None = None,
                       ) -> tuple[NDArray[np.float64], SolidState]:
        """Internal forces (n, 3) and trial state at total displacements u (n, 3)."""
        out = self.assemble(u, state, tangent=False)
        return out.fint, out.state

    def tangent(self, u: ArrayLike, state: SolidState | None = None, symmetric: bool = False,
                ) -> tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.float64]]:
        """Tangent d fint / d u over all 3n dofs (dof 3 node + component) as a coordinate
        triple (rows, cols, values), duplicates to be summed; ``symmetric``: lower triangle
        only."""
        pattern = self.pattern(symmetric=symmetric)
        return pattern.rows, pattern.cols, self.assemble(u, state, pattern).values

    def stresses(self, u: ArrayLike, state: SolidState,
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Second Piola-Kirchhoff and Cauchy stress in global axes (m, 8, 6) and the current
        Gauss point positions (m, 8, 3) of ``state`` at total displacements ``u``."""
        u = float_array(u, "u", (self.mesh.n_nodes, 3))
        pk2, cauchy, points, status, element = _core.solid_stresses(
            self._x, self._conn, u.ravel(), _flat(state.axes.transpose(0, 1, 3, 2)),
            _flat(state.stress))
        if status:
            raise ElementError(int(status), int(element) - 1)
        m = self.mesh.n_elements
        return pk2.reshape(m, 8, 6), cauchy.reshape(m, 8, 6), points.reshape(m, 8, 3)


def _check_thickness_direction(mesh: HexMesh) -> None:
    """Refuse a mesh for the solid-shell where some element's zeta edges (0-4, 1-5, 2-6,
    3-7) are not, of its three edge directions, the one closest to the sheet normal."""
    bad = zeta_off_normal(mesh.nodes, mesh.elements, mesh.normal)
    if bad.size:
        labels = ", ".join(str(int(mesh.element_ids[e])) for e in bad[:3])
        more = f" and {bad.size - 3} more" if bad.size > 3 else ""
        raise ValueError(
            f"the solid-shell needs every element's nodes 0-3 on one face of the sheet and "
            f"4-7 on the other (edges 0-4, 1-5, 2-6, 3-7 along the sheet normal "
            f"{list(mesh.normal)}); element {labels}{more} "
            f"{'is' if bad.size == 1 else 'are'} not so ordered")


def _components(components: int | str | Iterable[int | str]) -> list[int]:
    if isinstance(components, str):
        items: list[int | str] = list(components.lower())
    elif isinstance(components, int | np.integer):
        items = [int(components)]
    else:
        items = list(components)
    out = []
    for c in items:
        c = _COMPONENTS.get(c, c) if isinstance(c, str) else c
        if not isinstance(c, int | np.integer) or not 0 <= int(c) <= 2:
            raise ValueError(f"components must be 0, 1, 2 or 'x', 'y', 'z', got {components!r}")
        out.append(int(c))
    if len(set(out)) != len(out) or not out:
        raise ValueError(f"components must be distinct and not empty, got {components!r}")
    return out
