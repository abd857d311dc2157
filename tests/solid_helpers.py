"""Shared helpers of the solid tests: material vectors, meshes, dense tangents."""

from __future__ import annotations

import numpy as np

from ddpy import _core
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid, SolidState

E, NU = 210e3, 0.3
#: DDQ steel of the paper's Table 4 (reverse deep drawing), MPa.
DDQ = dict(E=E, nu=NU, hill=(0.3137, 0.3663, 0.6337, 1.5, 1.5, 1.1764),
           swift=(568.3, 0.0059, 0.233))


def props_vector(e: float = E, nu: float = NU,
                 hill: tuple[float, ...] = (0.5, 0.5, 0.5, 1.5, 1.5, 1.5),
                 swift: tuple[float, float, float] = (1e9, 1.0, 0.0)) -> np.ndarray:
    """The core's 216 material properties: Hill'48 (von Mises by default), Swift hardening; the
    default yield stress of 1e9 MPa keeps the material elastic."""
    props = np.zeros(216)
    props[:12] = [e, nu, *hill, 1.0, *swift]
    return props


def ddq_props() -> np.ndarray:
    return props_vector(DDQ["E"], DDQ["nu"], DDQ["hill"], DDQ["swift"])


def material_is_plastic() -> bool:
    """False while the core carries the elastic stand-in of the material module."""
    props = ddq_props()
    mesh = HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1)
    u = np.zeros((8, 3))
    u[:, 0] = 0.02 * mesh.nodes[:, 0]
    _, trial = Solid(mesh, props).internal_force(u)
    return bool(trial.ep.max() > 0.0)


def linear_elastic_pk2(f: np.ndarray, e: float = E, nu: float = NU) -> np.ndarray:
    """Saint Venant-Kirchhoff S(E) in Voigt order 11, 22, 33, 12, 23, 31."""
    green = 0.5 * (f.T @ f - np.eye(3))
    lam, mu = e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))
    s = lam * np.trace(green) * np.eye(3) + 2 * mu * green
    return np.array([s[0, 0], s[1, 1], s[2, 2], s[0, 1], s[1, 2], s[2, 0]])


def hencky_elastic_cauchy(f: np.ndarray, e: float = E, nu: float = NU) -> np.ndarray:
    """Cauchy stress (3, 3) of isotropic elasticity on the logarithmic strain:
    sigma = (lambda tr(ln V) I + 2 mu ln V) / det F, V the left stretch of f."""
    w, v = np.linalg.eigh(f @ f.T)
    log_v = v @ np.diag(0.5 * np.log(w)) @ v.T
    lam, mu = e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))
    return (lam * np.trace(log_v) * np.eye(3) + 2 * mu * log_v) / np.linalg.det(f)


def voigt(t: np.ndarray) -> np.ndarray:
    """Voigt vector (11, 22, 33, 12, 23, 31) of a symmetric tensor."""
    return t[[0, 1, 2, 0, 1, 2], [0, 1, 2, 1, 2, 0]]


def distorted_box(nx: int, ny: int, nz: int, amount: float, seed: int,
                  size: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> HexMesh:
    """A box mesh with every node moved at random by up to ``amount`` of an element size."""
    mesh = HexMesh.box(*size, nx, ny, nz)
    h = np.array(size) / [nx, ny, nz]
    rng = np.random.default_rng(seed)
    return HexMesh(mesh.nodes + amount * h * rng.uniform(-1, 1, mesh.nodes.shape),
                   mesh.elements)


def dense_tangent(solid: Solid, u: np.ndarray, state: SolidState | None = None) -> np.ndarray:
    rows, cols, values = solid.tangent(u, state)
    k = np.zeros((solid.n_dofs, solid.n_dofs))
    np.add.at(k, (rows, cols), values)
    return k


def fd_tangent(solid: Solid, u: np.ndarray, state: SolidState | None = None,
               h: float = 1e-7) -> np.ndarray:
    """Central finite differences of the internal forces, column by column."""
    k = np.zeros((solid.n_dofs, solid.n_dofs))
    for j in range(solid.n_dofs):
        du = np.zeros(solid.n_dofs)
        du[j] = h
        plus, _ = solid.internal_force(u + du.reshape(-1, 3), state)
        minus, _ = solid.internal_force(u - du.reshape(-1, 3), state)
        k[:, j] = (plus - minus).ravel() / (2 * h)
    return k


def rotation(axis: str, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    q = np.eye(3)
    q[i, i], q[i, j], q[j, i], q[j, j] = c, -s, s, c
    return q


assert _core.material_prop_count() == 216


def assert_rotations_objective(solid: Solid, u: np.ndarray, plastic: bool,
                               elastic_state_kept: bool = True) -> None:
    """Superposing 90 degree rotations about z, x and -y on the deformation u leaves the
    rotated stress, plastic strain and strain state unchanged, rotates the internal forces
    and the Cauchy stresses, and from the converged state is no strain increment at all
    (the same state as a zero increment, which may return a plastic stress that the
    non-coaxial part of the first increment left off the yield surface); with
    ``elastic_state_kept``, an elastic state is then the converged one itself."""
    mesh = solid.mesh
    f1, state1 = solid.internal_force(u)
    assert (state1.ep.min() > 0.01) == plastic
    for q in (rotation("z", 90.0), rotation("x", 90.0), rotation("y", -90.0)):
        u_rot = (mesh.nodes + u) @ q.T - mesh.nodes
        f2, state2 = solid.internal_force(u_rot)
        scale = np.abs(state1.stress).max()
        assert np.abs(state2.stress - state1.stress).max() <= 1e-11 * scale
        assert np.abs(state2.ep - state1.ep).max() <= 1e-13
        assert np.abs(state2.strain - state1.strain).max() <= 1e-13
        assert np.abs(f2 - f1 @ q.T).max() <= 1e-11 * np.abs(f1).max()
        _, sigma1, _ = solid.stresses(u, state1)
        _, sigma2, _ = solid.stresses(u_rot, state2)
        i, j = [0, 1, 2, 0, 1, 2], [0, 1, 2, 1, 2, 0]
        full = np.zeros(sigma1.shape[:2] + (3, 3))
        full[..., i, j] = sigma1
        full[..., j, i] = sigma1
        rotated = (q @ full @ q.T)[..., i, j]
        assert np.abs(sigma2 - rotated).max() <= 1e-10 * np.abs(sigma1).max()
        _, state3 = solid.internal_force(u_rot, state1)
        _, state4 = solid.internal_force(u, state1)
        assert np.abs(state3.stress - state4.stress).max() <= 1e-11 * scale
        assert np.abs(state3.ep - state4.ep).max() <= 1e-13
        if elastic_state_kept and not plastic:
            assert np.abs(state3.stress - state1.stress).max() <= 1e-11 * scale
