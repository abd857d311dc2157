"""Forming limit curves: the largest major strain a sheet takes before necking, as a function
of the minor strain, and a strain point's distance to it (docs/theory/forming_limits.md).

Strains are in-plane logarithmic (true) strains, as the results' major and minor surface
strains. The default curve is Keeler and Brazier's from the hardening exponent n and the
sheet thickness; a measured curve is given as a table of points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.model.material import Material, Swift, TablePointError

__all__ = ["FLC_MAX_POINTS", "KEELER_MAX_THICKNESS", "MARGINAL_BAND", "FormingLimitCurve",
           "SAFE", "MARGINAL", "FAILED", "hardening_exponent"]

#: Points a forming limit table may hold.
FLC_MAX_POINTS = 200
#: Keeler-Brazier's thickness effect stops at 3 mm (0.118 in): thicker sheets take 3 mm.
KEELER_MAX_THICKNESS = 3.0
#: The right branch's slope, d(major)/d(minor) in engineering strains.
KEELER_RIGHT_SLOPE = 0.6
#: Default width of the marginal band below the curve, in major (logarithmic) strain: the
#: usual 10 % safety margin of stamping practice.
MARGINAL_BAND = 0.10
#: Zones of a strain point: below the band, inside the band, on or above the curve.
SAFE, MARGINAL, FAILED = 0, 1, 2
#: Plastic strains (10 % and 20 %) between which the exponent of a Voce or tabulated
#: hardening law is measured, as a tensile test's n-value (ISO 10275's two-point form).
N_VALUE_STRAINS = (0.10, 0.20)


def hardening_exponent(material: Material) -> float:
    """The hardening exponent n of a material: Swift's n, or for Voce and tabulated
    hardening the slope of log Y against log ep between 10 % and 20 % plastic strain."""
    if isinstance(material.hardening, Swift):
        return float(material.hardening.n)
    low, high = N_VALUE_STRAINS
    y = material.yield_stress(np.array(N_VALUE_STRAINS))
    return float(math.log(y[1] / y[0]) / math.log(high / low))


@dataclass(frozen=True)
class FormingLimitCurve:
    """A forming limit curve. ``kind`` "keeler-brazier" (from ``n`` and ``thickness`` mm)
    or "table" (``minor``, ``major``: logarithmic strains, minor increasing; constant
    beyond its ends). Build it with :meth:`keeler_brazier` or :meth:`table`."""

    kind: str
    n: float = 0.0
    thickness: float = 0.0
    minor: tuple[float, ...] = ()
    major: tuple[float, ...] = ()
    origin: str = ""

    def __post_init__(self) -> None:
        if self.kind == "keeler-brazier":
            if not (math.isfinite(self.n) and self.n > 0):
                raise ValueError(f"the hardening exponent n must be positive, got {self.n}")
            if not (math.isfinite(self.thickness) and self.thickness > 0):
                raise ValueError(f"the thickness must be positive, got {self.thickness}")
        elif self.kind == "table":
            minor = tuple(float(v) for v in self.minor)
            major = tuple(float(v) for v in self.major)
            object.__setattr__(self, "minor", minor)
            object.__setattr__(self, "major", major)
            if len(minor) != len(major) or not 2 <= len(minor) <= FLC_MAX_POINTS:
                raise ValueError(f"a forming limit table holds 2 to {FLC_MAX_POINTS} points "
                                 f"(minor, major), got {len(minor)} and {len(major)}")
            # Point by point (TablePointError: a deck names the point's line), the one check
            # of a table, material.dat's too.
            for i, (e2, e1) in enumerate(zip(minor, major, strict=True)):
                if not (math.isfinite(e2) and math.isfinite(e1)):
                    raise TablePointError(i, f"point {i + 1} of the forming limit table is not "
                                          f"finite: {e2:g}, {e1:g}")
                if i and e2 <= minor[i - 1]:
                    raise TablePointError(i, f"the minor strain {e2:g} of point {i + 1} must be "
                                          f"above the one before ({minor[i - 1]:g}): list the "
                                          "points from left to right")
                if not e1 > 0:
                    raise TablePointError(i, f"the major strain of point {i + 1} must be > 0, "
                                          f"got {e1:g}")
                if e1 < e2:
                    raise TablePointError(i, f"the major strain {e1:g} of point {i + 1} is below "
                                          f"its minor strain {e2:g}: expected major >= minor")
        else:
            raise ValueError(f"kind must be 'keeler-brazier' or 'table', got {self.kind!r}")

    @classmethod
    def keeler_brazier(cls, n: float, thickness: float) -> FormingLimitCurve:
        """Keeler and Brazier's curve for hardening exponent n and thickness (mm)."""
        return cls("keeler-brazier", n=float(n), thickness=float(thickness))

    @classmethod
    def table(cls, minor: ArrayLike, major: ArrayLike, origin: str = "") -> FormingLimitCurve:
        """A measured curve: logarithmic minor and major strains."""
        return cls("table", minor=tuple(np.ravel(minor)), major=tuple(np.ravel(major)),
                   origin=origin)

    @property
    def flc0(self) -> float:
        """The plane-strain limit (minor strain 0) as an engineering major strain: for
        Keeler-Brazier (23.3 + 14.13 t) n / 0.21 percent, t in mm up to 3."""
        if self.kind == "keeler-brazier":
            t = min(self.thickness, KEELER_MAX_THICKNESS)
            return (23.3 + 14.13 * t) * self.n / 0.21 / 100.0
        return math.expm1(float(self.major_limit(0.0)))

    def major_limit(self, minor: ArrayLike) -> NDArray[np.float64]:
        """The limit major strain (logarithmic) at logarithmic minor strains."""
        e2 = np.asarray(minor, dtype=float)
        if self.kind == "table":
            return np.interp(e2, self.minor, self.major)
        limit0 = math.log1p(self.flc0)
        # Left: a line of constant thickness strain (major + minor = its plane-strain value,
        # in logarithmic strains); right: slope 0.6 in engineering strains.
        left = limit0 - e2
        right = np.log1p(self.flc0 + KEELER_RIGHT_SLOPE * np.expm1(np.maximum(e2, 0.0)))
        return np.where(e2 < 0.0, left, right)

    def margin(self, major: ArrayLike, minor: ArrayLike) -> NDArray[np.float64]:
        """The distance of strain points below the curve, in major strain (negative above
        it)."""
        return self.major_limit(minor) - np.asarray(major, dtype=float)

    def zone(self, major: ArrayLike, minor: ArrayLike,
             band: float = MARGINAL_BAND) -> NDArray[np.int8]:
        """SAFE, MARGINAL (within ``band`` below the curve) or FAILED (on or above it) of
        each strain point."""
        if not band >= 0:
            raise ValueError(f"the marginal band must be >= 0, got {band}")
        m = self.margin(major, minor)
        return np.where(m <= 0.0, FAILED, np.where(m < band, MARGINAL, SAFE)).astype(np.int8)

    def describe(self) -> str:
        """One line saying which curve this is."""
        if self.kind == "keeler-brazier":
            capped = (f" (taken as {KEELER_MAX_THICKNESS:g} mm)"
                      if self.thickness > KEELER_MAX_THICKNESS else "")
            return (f"Keeler-Brazier, n = {self.n:.3g}, t = {self.thickness:.4g} mm{capped}: "
                    f"FLC0 = {100 * self.flc0:.3g} % engineering major strain")
        where = f" ({self.origin})" if self.origin else ""
        return f"table of {len(self.minor)} points{where}"
