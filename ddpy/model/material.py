"""Elastoplastic material of the blank: isotropic elasticity, Hill'48 anisotropy, Swift, Voce
or tabulated isotropic hardening, optionally with an Armstrong-Frederick backstress (mixed
isotropic-kinematic hardening), integrated by the core's backward-Euler return mapping
(docs/theory/material.md).

Material axes: 1 = rolling direction (RD), 2 = transverse direction (TD), 3 = normal direction
(ND). Voigt order (11, 22, 33, 12, 23, 31); strains carry engineering shears (gamma = 2 eps),
stresses are plain, so ``stress @ strain`` is the work.

>>> steel = Material(210e3, 0.3, Hill48.from_r_values(1.73, 1.23, 2.02),
...                  Swift(K=568.3, eps0=0.0059, n=0.233))
>>> stress, ep, tangent, plastic = steel.update(np.zeros(6), 0.0, [0.01, 0, 0, 0, 0, 0])
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array
from ddpy.core.constants import constant

__all__ = ["ArmstrongFrederick", "HardeningTable", "Hill48", "Material", "PROP_COUNT",
           "ReturnMappingError", "Swift", "TABLE_MAX_POINTS", "TablePointError", "Voce",
           "check_backstress", "check_elastic", "initial_yield_stress", "yield_landing"]

#: Points a hardening table may hold, and where they start in the property vector.
TABLE_MAX_POINTS, _TABLE_START = constant("material_table_max_points"), \
    constant("material_table_offset")
#: Length of the property vector the core takes (``Material.props()``).
PROP_COUNT = constant("material_prop_count")
#: Where C_X and X_sat of the kinematic hardening sit in the property vector (0-based).
KINEMATIC_OFFSET = constant("material_kinematic_offset")
#: Where the rest sits (0-based): Young's modulus, Poisson's ratio, Hill's F, G, H, L, M, N
#: (6 from HILL_OFFSET), the hardening law, its 3 parameters (from HARDENING_OFFSET).
YOUNG_OFFSET, POISSON_OFFSET, HILL_OFFSET, LAW_OFFSET, HARDENING_OFFSET = (
    constant(f"material_{name}_offset") for name in
    ("young", "poisson", "hill", "law", "hardening"))

_STATUS = {1: "the return mapping did not converge", 2: "invalid material properties",
           3: "non-finite or negative input"}


def _real(value: float, name: str) -> float:
    """``value`` as a finite float, or ValueError naming it."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {number}")
    return number


def check_elastic(E: float, nu: float) -> tuple[float, float]:
    """Young's modulus and Poisson's ratio as floats, checked: E > 0, -1 < nu < 1/2 (the one
    check, Material's and material.dat's), else ValueError (TypeError: not a number)."""
    E, nu = _real(E, "Young's modulus E"), _real(nu, "Poisson's ratio nu")
    if E <= 0:
        raise ValueError(f"Young's modulus E must be positive, got {E:g}")
    if not -1 < nu < 0.5:
        raise ValueError(f"Poisson's ratio nu must lie in (-1, 0.5), got {nu:g}")
    return E, nu


@dataclass(frozen=True)
class Swift:
    """Swift hardening Y = K (eps0 + ep)^n, ep the equivalent plastic strain.

    K > 0 (stress), eps0 > 0 (initial yield stress K eps0^n), 0 <= n <= 1."""

    K: float
    eps0: float
    n: float
    law: ClassVar[int] = constant("hardening_swift")

    def __post_init__(self) -> None:
        for name in ("K", "eps0", "n"):
            object.__setattr__(self, name, _real(getattr(self, name), f"Swift {name}"))
        if self.K <= 0:
            raise ValueError(f"Swift K must be positive, got {self.K}")
        if self.eps0 <= 0:
            raise ValueError(
                f"Swift eps0 must be positive (the initial yield stress is K eps0^n), "
                f"got {self.eps0}")
        if not 0 <= self.n <= 1:
            raise ValueError(f"Swift exponent n must lie in [0, 1], got {self.n}")

    @property
    def initial_yield_stress(self) -> float:
        """Y at ep = 0."""
        return self.K * self.eps0**self.n

    def parameters(self) -> tuple[float, ...]:
        return (self.K, self.eps0, self.n)


def initial_yield_stress(props: NDArray[np.float64]) -> float:
    """The yield stress at ep = 0 (MPa) of a material's property vector (Material.props):
    Swift K eps0^n, Voce Y0, a table's first stress."""
    law = int(props[LAW_OFFSET])
    k, eps0, n = props[HARDENING_OFFSET:HARDENING_OFFSET + 3]
    if law == Swift.law:
        return float(k * eps0 ** n)
    if law == HardeningTable.law:
        return float(props[_TABLE_START + 1])
    return float(k)


@dataclass(frozen=True)
class Voce:
    """Voce hardening Y = Y0 + Q (1 - exp(-b ep)); Y0 > 0, Q >= 0, b >= 0."""

    Y0: float
    Q: float
    b: float
    law: ClassVar[int] = constant("hardening_voce")

    def __post_init__(self) -> None:
        for name in ("Y0", "Q", "b"):
            object.__setattr__(self, name, _real(getattr(self, name), f"Voce {name}"))
        if self.Y0 <= 0:
            raise ValueError(f"Voce Y0 must be positive, got {self.Y0}")
        if self.Q < 0:
            raise ValueError(f"Voce Q must be non-negative (no softening), got {self.Q}")
        if self.b < 0:
            raise ValueError(f"Voce b must be non-negative, got {self.b}")

    @property
    def initial_yield_stress(self) -> float:
        """Y at ep = 0."""
        return self.Y0

    def parameters(self) -> tuple[float, ...]:
        return (self.Y0, self.Q, self.b)


class TablePointError(ValueError):
    """A hardening table's point ``point`` (0-based) is refused: a reader of a table in a
    file names that point's line."""

    def __init__(self, point: int, message: str) -> None:
        super().__init__(message)
        self.point = point


@dataclass(frozen=True)
class HardeningTable:
    """Tabulated hardening: the yield stress Y at equivalent plastic strains ep, interpolated
    linearly between the points and constant beyond the last (Abaqus' *PLASTIC). ep starts at
    0 and increases, Y > 0 does not decrease (no softening); 1 to TABLE_MAX_POINTS points."""

    strains: tuple[float, ...]
    stresses: tuple[float, ...]
    law: ClassVar[int] = constant("hardening_table")

    def __post_init__(self) -> None:
        ep = tuple(_real(v, "tabulated plastic strain") for v in self.strains)
        y = tuple(_real(v, "tabulated yield stress") for v in self.stresses)
        object.__setattr__(self, "strains", ep)
        object.__setattr__(self, "stresses", y)
        if len(ep) != len(y):
            raise ValueError(f"the table has {len(ep)} strains and {len(y)} stresses")
        if not 1 <= len(ep) <= TABLE_MAX_POINTS:
            raise ValueError(f"a hardening table holds 1 to {TABLE_MAX_POINTS} points, got "
                             f"{len(ep)}")
        if ep[0] != 0.0:
            raise TablePointError(0, f"the table's first plastic strain must be 0 (the initial "
                                  f"yield stress), got {ep[0]:g}")
        for i in range(len(ep)):
            if y[i] <= 0:
                raise TablePointError(i, f"yield stress {i + 1} of the table must be positive, "
                                      f"got {y[i]:g}")
            if i and ep[i] <= ep[i - 1]:
                raise TablePointError(i, f"plastic strain {i + 1} of the table ({ep[i]:g}) must "
                                      f"be above the one before ({ep[i - 1]:g})")
            if i and y[i] < y[i - 1]:
                raise TablePointError(i, f"yield stress {i + 1} of the table ({y[i]:g}) is "
                                      f"below the one before ({y[i - 1]:g}): softening is not "
                                      "supported")

    @property
    def initial_yield_stress(self) -> float:
        """Y at ep = 0."""
        return self.stresses[0]

    def parameters(self) -> tuple[float, ...]:
        return (float(len(self.strains)), 0.0, 0.0)


@dataclass(frozen=True)
class ArmstrongFrederick:
    """Armstrong-Frederick kinematic hardening with saturation, Lemaitre and Chaboche's form as
    DD3IMP has it: the backstress X (Voigt, deviatoric) evolves as

        dX = C_X (X_sat (s' - X) / sigma(s - X) - X) dep,

    sigma the Hill'48 equivalent stress of the relative stress, ep the equivalent plastic
    strain. C_X >= 0 (rate), X_sat >= 0 (stress; the backstress's Hill norm saturates there,
    and it must stay below the initial yield stress, checked by ``Material``). In uniaxial
    tension X = X_sat (1 - exp(-C_X ep)) adds to the isotropic Y(ep)."""

    C: float
    X_sat: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "C", _real(self.C, "kinematic hardening C_X"))
        object.__setattr__(self, "X_sat", _real(self.X_sat, "kinematic hardening X_sat"))
        if self.C < 0:
            raise ValueError(f"kinematic hardening C_X must be non-negative, got {self.C}")
        if self.X_sat < 0:
            raise ValueError(f"kinematic hardening X_sat must be non-negative, got {self.X_sat}")

    @property
    def active(self) -> bool:
        """The backstress can grow (both parameters positive)."""
        return self.C > 0 and self.X_sat > 0


def check_backstress(kinematic: ArmstrongFrederick,
                     hardening: Swift | Voce | HardeningTable) -> None:
    """ValueError unless the backstress's saturation X_sat lies below the initial yield
    stress of ``hardening`` (the one check, Material's and material.dat's)."""
    y0 = hardening.initial_yield_stress
    if kinematic.X_sat >= y0:
        raise ValueError(
            f"kinematic hardening X_sat = {kinematic.X_sat:g} must lie below the initial yield "
            f"stress {y0:.4g}: in the Lemaitre-Chaboche form the backstress grows towards "
            "X_sat, and from X_sat = Y0 on the stress-free state leaves the yield surface "
            "(unloading alone would yield the material)")


@dataclass(frozen=True, kw_only=True)
class Hill48:
    """Hill'48 yield function in the material axes (1 = RD, 2 = TD, 3 = ND):

    2 f = F (s22 - s33)^2 + G (s33 - s11)^2 + H (s11 - s22)^2
          + 2 L s23^2 + 2 M s31^2 + 2 N s12^2,   equivalent stress sqrt(2 f).

    With G + H = 1 the hardening curve is the RD uniaxial yield stress. Keywords only:
    ``Hill48(F=..., G=..., H=..., N=...)``; L = M = 1.5 (isotropic through the thickness)
    unless given. The quadratic form must be positive definite on the deviatoric stresses.
    """

    F: float
    G: float
    H: float
    L: float = 1.5
    M: float = 1.5
    N: float

    def __post_init__(self) -> None:
        for name in ("F", "G", "H", "L", "M", "N"):
            object.__setattr__(self, name, _real(getattr(self, name), f"Hill48 {name}"))
        F, G, H = self.F, self.G, self.H
        for name in ("L", "M", "N"):
            if getattr(self, name) <= 0:
                raise ValueError(
                    f"Hill48 {name} must be positive for a convex yield surface, "
                    f"got {getattr(self, name)}")
        if min(F + G, G + H, H + F) <= 0 or F * G + G * H + H * F <= 0:
            raise ValueError(
                "Hill48 coefficients do not define a convex yield surface: need F+G, G+H, H+F "
                f"> 0 and FG+GH+HF > 0, got F={F}, G={G}, H={H} (F+G={F + G:.4g}, "
                f"G+H={G + H:.4g}, H+F={H + F:.4g}, FG+GH+HF={F * G + G * H + H * F:.4g})")

    @classmethod
    def from_r_values(cls, r0: float, r45: float, r90: float) -> Hill48:
        """Coefficients with G + H = 1 and L = M = 1.5 from the r-values at 0, 45 and 90
        degrees to RD (docs/theory/material.md)."""
        r = [_real(v, name) for v, name in ((r0, "r0"), (r45, "r45"), (r90, "r90"))]
        if min(r) <= 0:
            raise ValueError(f"r-values must be positive, got r0={r0}, r45={r45}, r90={r90}")
        F, G, H, L, M, N = (float(c) for c in _core.hill48_from_r_values(*r))
        return cls(F=F, G=G, H=H, L=L, M=M, N=N)

    @classmethod
    def von_mises(cls) -> Hill48:
        """The isotropic case F = G = H = 1/2, L = M = N = 3/2."""
        return cls(F=0.5, G=0.5, H=0.5, L=1.5, M=1.5, N=1.5)

    @property
    def coefficients(self) -> tuple[float, float, float, float, float, float]:
        """(F, G, H, L, M, N), the order of the core's property vector."""
        return astuple(self)

    @property
    def r0(self) -> float:
        """Lankford coefficient along RD, H / G."""
        return self.H / self.G

    @property
    def r45(self) -> float:
        """Lankford coefficient at 45 degrees, N / (F + G) - 1/2."""
        return self.N / (self.F + self.G) - 0.5

    @property
    def r90(self) -> float:
        """Lankford coefficient along TD, H / F."""
        return self.H / self.F

    def r_value(self, angle: ArrayLike) -> NDArray[np.float64]:
        """Lankford coefficient of in-plane uniaxial tension at ``angle`` (radians) to RD:
        r = [H + (2N - F - G - 4H) sin^2 cos^2] / (F sin^2 + G cos^2)."""
        s2, c2 = np.sin(angle) ** 2, np.cos(angle) ** 2
        F, G, H, N = self.F, self.G, self.H, self.N
        return (H + (2 * N - F - G - 4 * H) * s2 * c2) / (F * s2 + G * c2)

    def yield_stress_ratio(self, angle: ArrayLike) -> NDArray[np.float64]:
        """Uniaxial yield stress at ``angle`` (radians) to RD over the RD one:
        sqrt((G + H) / (F sin^4 + G cos^4 + H cos^2(2 angle) + 2 N sin^2 cos^2))."""
        s, c = np.sin(angle), np.cos(angle)
        F, G, H, N = self.F, self.G, self.H, self.N
        return np.sqrt((G + H) / (F * s**4 + G * c**4 + H * np.cos(2 * angle) ** 2
                                  + 2 * N * s**2 * c**2))

    def plane_strain_ratio(self, angle: ArrayLike) -> NDArray[np.float64]:
        """In-plane tension at ``angle`` (radians) to RD with no strain across it (a cup's
        wall held by the punch): the stress along the angle over the equivalent stress,
        1 / sqrt(A11 - A12^2 / A22), where 2 f = A11 s1^2 + 2 A12 s1 s2 + A22 s2^2 in the
        stresses along and across the angle; (1 + r) / sqrt(1 + 2 r) under normal
        anisotropy r, 2 / sqrt(3) for von Mises (docs/theory/material.md)."""
        s2, c2 = np.sin(angle) ** 2, np.cos(angle) ** 2
        F, G, H, N = self.F, self.G, self.H, self.N
        h, shear = H * np.cos(2 * np.asarray(angle)) ** 2, 2 * N * s2 * c2
        a11 = F * s2**2 + G * c2**2 + h + shear
        a12 = (F + G) * s2 * c2 - h - shear
        a22 = F * c2**2 + G * s2**2 + h + shear
        return 1.0 / np.sqrt(a11 - a12**2 / a22)

    def equivalent_stress(self, stress: ArrayLike) -> NDArray[np.float64]:
        """sqrt(2 f) of Voigt stresses (..., 6) in the material axes."""
        s = np.asarray(stress, dtype=float)
        F, G, H, L, M, N = self.coefficients
        return np.sqrt(F * (s[..., 1] - s[..., 2]) ** 2 + G * (s[..., 2] - s[..., 0]) ** 2
                       + H * (s[..., 0] - s[..., 1]) ** 2
                       + 2 * (L * s[..., 4] ** 2 + M * s[..., 5] ** 2 + N * s[..., 3] ** 2))


class ReturnMappingError(RuntimeError):
    """The return mapping failed at some points (``points``, 0-based; ``codes``, core status):
    cut the increment."""

    def __init__(self, points: NDArray[np.intp], codes: NDArray[np.int32]) -> None:
        self.points = points
        self.codes = codes
        first = int(points[0])
        reason = _STATUS.get(int(codes[0]), "unknown status")
        super().__init__(
            f"return mapping failed at {points.size} point(s), first at point {first} "
            f"(status {int(codes[0])}: {reason})")


@dataclass(frozen=True)
class Material:
    """Isotropic elasticity (E > 0, -1 < nu < 1/2), a Hill48 yield criterion in the material
    axes and Swift, Voce or tabulated hardening of the equivalent plastic strain; with
    ``kinematic`` (an ArmstrongFrederick) mixed hardening, Hill48 then acting on the stress
    minus the backstress. X_sat must lie below the initial yield stress."""

    E: float
    nu: float
    yield_criterion: Hill48
    hardening: Swift | Voce | HardeningTable
    kinematic: ArmstrongFrederick | None = None

    def __post_init__(self) -> None:
        E, nu = check_elastic(self.E, self.nu)
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)
        if not isinstance(self.yield_criterion, Hill48):
            raise TypeError(
                f"yield_criterion must be a Hill48, got {type(self.yield_criterion).__name__}")
        if not isinstance(self.hardening, Swift | Voce | HardeningTable):
            raise TypeError(f"hardening must be Swift, Voce or HardeningTable, got "
                            f"{type(self.hardening).__name__}")
        if self.kinematic is not None:
            if not isinstance(self.kinematic, ArmstrongFrederick):
                raise TypeError(f"kinematic must be an ArmstrongFrederick or None, got "
                                f"{type(self.kinematic).__name__}")
            check_backstress(self.kinematic, self.hardening)
        info = int(_core.material_check(self.props()))
        if info != 0:  # the Python checks above should have caught it
            raise ValueError(f"material property {info} (1-based) rejected by the core")

    @property
    def mixed(self) -> bool:
        """Mixed isotropic-kinematic hardening: a backstress that can grow."""
        return self.kinematic is not None and self.kinematic.active

    @property
    def shear_modulus(self) -> float:
        return self.E / (2 * (1 + self.nu))

    @property
    def bulk_modulus(self) -> float:
        return self.E / (3 * (1 - 2 * self.nu))

    def props(self) -> NDArray[np.float64]:
        """The core's property vector: E, nu, F, G, H, L, M, N, law (1 Swift, 2 Voce, 3 table),
        the three hardening parameters (K, eps0, n or Y0, Q, b, or the table's point count, 0,
        0), C_X and X_sat of the kinematic hardening (zero without it), 2 reserved zeros,
        then the table's points as pairs (ep, Y), zero-padded."""
        props = np.zeros(PROP_COUNT)
        props[YOUNG_OFFSET], props[POISSON_OFFSET] = self.E, self.nu
        props[HILL_OFFSET:HILL_OFFSET + 6] = self.yield_criterion.coefficients
        props[LAW_OFFSET] = self.hardening.law
        props[HARDENING_OFFSET:HARDENING_OFFSET + 3] = self.hardening.parameters()
        if isinstance(self.hardening, HardeningTable):
            n = len(self.hardening.strains)
            props[_TABLE_START:_TABLE_START + 2 * n:2] = self.hardening.strains
            props[_TABLE_START + 1:_TABLE_START + 2 * n:2] = self.hardening.stresses
        if self.kinematic is not None:
            props[KINEMATIC_OFFSET:KINEMATIC_OFFSET + 2] = self.kinematic.C, self.kinematic.X_sat
        return props

    def elastic_tangent(self) -> NDArray[np.float64]:
        """The 6 x 6 isotropic elasticity matrix (engineering shear strains)."""
        G, K = self.shear_modulus, self.bulk_modulus
        c = np.zeros((6, 6))
        c[:3, :3] = K - 2 * G / 3
        c[range(3), range(3)] += 2 * G
        c[range(3, 6), range(3, 6)] = G
        return c

    def yield_stress(self, ep: ArrayLike) -> NDArray[np.float64]:
        """Y(ep), the current yield stress (the RD uniaxial one when G + H = 1)."""
        return self.hardening_curve(ep)[0]

    def hardening_curve(self, ep: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Y(ep) and dY/dep from the core."""
        ep = np.asarray(ep)
        flat = float_array(ep.reshape(-1), "ep", (None,))
        y, slope = _core.material_hardening(self.props(), flat)
        return y.reshape(ep.shape), slope.reshape(ep.shape)

    def update(
        self, stress_old: ArrayLike, ep_old: ArrayLike, strain_increment: ArrayLike,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
               NDArray[np.bool_]]:
        """Backward-Euler update of k points: stress_old (k, 6), ep_old (k,), strain_increment
        (k, 6) (or one point: (6,), scalar, (6,)). Returns the stress (k, 6), the equivalent
        plastic strain (k,), the consistent tangent d stress / d strain_increment (k, 6, 6)
        and whether each point yielded (k,). Raises ReturnMappingError when the return
        mapping fails at a point (the caller cuts the increment). For mixed hardening use
        ``update_mixed``, which carries the backstress."""
        if self.mixed:
            raise ValueError("this material has a backstress (mixed hardening): use "
                             "update_mixed, which carries it")
        single = np.ndim(stress_old) == 1
        s = float_array(np.atleast_2d(stress_old), "stress_old", (None, 6))
        k = s.shape[0]
        ep = float_array(np.atleast_1d(ep_old), "ep_old", (k,))
        de = float_array(np.atleast_2d(strain_increment), "strain_increment", (k, 6))
        if np.any(ep < 0):
            raise ValueError("ep_old must be non-negative")
        stress, ep_new, tangent, plastic, status = _core.material_update(
            self.props(), s.reshape(-1), ep, de.reshape(-1))
        failed = np.flatnonzero(status)
        if failed.size:
            raise ReturnMappingError(failed, status[failed])
        # Fortran tangent(i, j, p) is C-order [p, j, i]: transpose to [p, i, j].
        tangent = tangent.reshape(k, 6, 6).transpose(0, 2, 1)
        stress = stress.reshape(k, 6)
        plastic = plastic.astype(bool)
        if single:
            return stress[0], ep_new[0], tangent[0], plastic[0]
        return stress, ep_new, tangent, plastic

    def update_mixed(
        self, stress_old: ArrayLike, backstress_old: ArrayLike, ep_old: ArrayLike,
        strain_increment: ArrayLike,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
               NDArray[np.float64], NDArray[np.bool_]]:
        """``update`` carrying the backstress: stress_old, backstress_old (k, 6), ep_old (k,),
        strain_increment (k, 6) (or one point). Returns the stress, the backstress (k, 6),
        ep (k,), the consistent tangent (k, 6, 6; not symmetric where the backstress is not
        along the relative stress) and whether each point yielded. Without a kinematic law
        (or with C_X or X_sat zero) the backstress stays as given and the rest is
        ``update``'s answer."""
        single = np.ndim(stress_old) == 1
        s = float_array(np.atleast_2d(stress_old), "stress_old", (None, 6))
        k = s.shape[0]
        back = float_array(np.atleast_2d(backstress_old), "backstress_old", (k, 6))
        ep = float_array(np.atleast_1d(ep_old), "ep_old", (k,))
        de = float_array(np.atleast_2d(strain_increment), "strain_increment", (k, 6))
        if np.any(ep < 0):
            raise ValueError("ep_old must be non-negative")
        stress, back_new, ep_new, tangent, plastic, status = _core.material_update_mixed(
            self.props(), s.reshape(-1), back.reshape(-1), ep, de.reshape(-1))
        failed = np.flatnonzero(status)
        if failed.size:
            raise ReturnMappingError(failed, status[failed])
        tangent = tangent.reshape(k, 6, 6).transpose(0, 2, 1)
        stress, back_new = stress.reshape(k, 6), back_new.reshape(k, 6)
        plastic = plastic.astype(bool)
        if single:
            return stress[0], back_new[0], ep_new[0], tangent[0], plastic[0]
        return stress, back_new, ep_new, tangent, plastic


def yield_landing(props: ArrayLike, stress_old: ArrayLike, ep_old: ArrayLike,
                  strain_increment: ArrayLike, tolerance: float) -> float:
    """The fraction of a strain increment at which the first of k material points that has
    not yielded yet (``ep_old`` 0) reaches the yield surface, if its elastic trial stress
    would overshoot it by more than ``tolerance`` (a fraction of the yield stress); 1
    otherwise (the r_min elasto-plastic transition, docs/theory/contact.md). ``props``: the
    PROP_COUNT properties (``Material.props()``); stress_old (k, 6), ep_old (k,): the
    converged state; strain_increment (k, 6), engineering shears. A point within
    ``tolerance`` below the surface counts as yielding already; a point that yielded before
    is not landed when it reloads. The fraction is that of the first landing times
    1 + tolerance / 2 (just past the surface), at least 1e-6."""
    s = float_array(np.reshape(stress_old, (-1, 6)), "stress_old", (None, 6))
    k = s.shape[0]
    ep = float_array(np.reshape(ep_old, -1), "ep_old", (k,))
    de = float_array(np.reshape(strain_increment, (-1, 6)), "strain_increment", (k, 6))
    values = float_array(props, "props", (PROP_COUNT,))
    if not 0.0 <= tolerance < 1.0:
        raise ValueError(f"tolerance must lie in [0, 1), got {tolerance}")
    return float(_core.yield_landing(values, s.ravel(), ep, de.ravel(), float(tolerance)))

