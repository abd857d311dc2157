"""Elastic bending accuracy of the hexahedron with 2 and 3 layers through the thickness.

A strip 20 x 2 x 1 (E = 210 GPa, nu = 0.3) clamped at x = 0 carries a tip load; its tip
deflection is compared with Timoshenko beam theory (shear factor 5/6) for several element
lengths along the strip. Prints a markdown table (used in docs/theory/solid.md).

    python benchmarks/solid_bending/elastic_accuracy.py
"""

from __future__ import annotations

import numpy as np

from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem

E, NU = 210e3, 0.3
LENGTH, WIDTH, THICK, LOAD = 20.0, 2.0, 1.0, 1.0
# Von Mises with a yield stress of 1e9 MPa: elastic.
PROPS = np.array([E, NU, 0.5, 0.5, 0.5, 1.5, 1.5, 1.5, 1, 1e9, 1.0, 0.0, 0, 0, 0, 0])


def tip_error(layers: int, nx: int) -> float:
    mesh = HexMesh.box(LENGTH, WIDTH, THICK, nx, 2, layers)
    problem = StaticProblem(Solid(mesh, PROPS))
    problem.fix(mesh.select(x=0.0), "xyz")
    tip = mesh.select(x=LENGTH)
    problem.load(tip, [0.0, 0.0, -LOAD / tip.size])
    w = -problem.solve().displacements[-1][tip, 2].mean()
    inertia, shear = WIDTH * THICK**3 / 12.0, E / (2.0 * (1.0 + NU))
    exact = LOAD * LENGTH**3 / (3.0 * E * inertia) + LOAD * LENGTH / (5 / 6 * shear * WIDTH
                                                                      * THICK)
    return w / exact - 1.0


def main() -> None:
    counts = (20, 40, 80, 160)
    print("| layers | " + " | ".join(f"{LENGTH / n:.3g} long ({n})" for n in counts) + " |")
    print("|---" * (len(counts) + 1) + "|")
    for layers in (2, 3):
        errors = [tip_error(layers, n) for n in counts]
        print(f"| {layers} (aspect {LENGTH / counts[0] * layers:.3g} .. "
              f"{LENGTH / counts[-1] * layers:.3g}) | "
              + " | ".join(f"{100 * e:+.1f} %" for e in errors) + " |")


if __name__ == "__main__":
    main()
