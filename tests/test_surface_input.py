"""Bad input to the surface classes gives a clear Python exception, never a crash."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ddpy.geometry.surfaces import BezierSurface, NagataSurface, nagata_edge_coefficient

# A unit square (vertices 0-3) in z = 0 with normals +z, and a vertex 4 on the line of 0, 1.
VERTICES = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]])
NORMALS = np.tile([0.0, 0.0, 1.0], (5, 1))
SQUARE = [[0, 1, 2, 3]]


def nagata(vertices=VERTICES, normals=NORMALS, faces=SQUARE, **options):
    return NagataSurface(vertices, normals, faces, **options)


def with_row(array, row, value):
    array = np.array(array, dtype=float)
    array[row] = value
    return array


# --- Nagata construction ----------------------------------------------------------------------

NAGATA_CASES = {
    "zero normal": (dict(normals=with_row(NORMALS, 1, 0.0)), ValueError,
                    "normal of vertex 1 is zero"),
    "non-unit normal": (dict(normals=with_row(NORMALS, 2, [0, 0, 1.1])), ValueError,
                        "normal of vertex 2 is of length 1.1"),
    "NaN normal": (dict(normals=with_row(NORMALS, 0, np.nan)), ValueError, "normals.*non-finite"),
    "NaN vertex": (dict(vertices=with_row(VERTICES, 2, [0, np.nan, 0])), ValueError,
                   r"vertices has a non-finite value at index \(2, 1\)"),
    "infinite vertex": (dict(vertices=with_row(VERTICES, 0, np.inf)), ValueError,
                        "vertices has a non-finite"),
    "repeated vertex in quad": (dict(faces=[[0, 1, 1, 2]]), ValueError, "a vertex repeats"),
    "repeated vertex in triangle": (dict(faces=[[0, 2, 0, -1]]), ValueError, "a vertex repeats"),
    "collinear triangle": (dict(faces=[[0, 1, 4, -1]]), ValueError,
                           "degenerate: two of its edges are parallel"),
    "collinear quad corner": (dict(faces=[[0, 1, 4, 2]]), ValueError,
                              "degenerate: two of its edges are parallel"),
    # Its corners' areas cancel: without the check its normal is 0 / 0 and it is accepted.
    "bow-tie quad": (dict(faces=[[0, 2, 1, 3]]), ValueError,
                     "face 0 = .* is degenerate: its area is zero"),
    "bow-tie facet": (dict(faces=[[0, 2, 1, 3]], smooth=False), ValueError,
                      "face 0 = .* is degenerate: its area is zero"),
    "vertex index too large": (dict(faces=[[0, 1, 2, 5]]), ValueError,
                               r"vertex indices must lie in 0\.\.4"),
    "-1 in a wrong column": (dict(faces=[[0, -1, 2, 3]]), ValueError,
                             "use -1 only in the last column"),
    "-2 in the last column": (dict(faces=[[0, 1, 2, -2]]), ValueError,
                              r"vertex indices must lie in 0\.\.4"),
    "index beyond int32": (dict(faces=[[0, 1, 2, 2**40]]), ValueError, "32-bit"),
    "clockwise quad": (dict(faces=[[0, 3, 2, 1]]), ValueError,
                       "normal opposite to the given normal at corner 0"),
    "clockwise triangle": (dict(faces=[[1, 0, 2, -1]]), ValueError, "counter-clockwise"),
    "faces of shape (m, 3)": (dict(faces=[[0, 1, 2]]), ValueError,
                              re.escape("faces must have shape (k, 4), got (1, 3)")),
    "float faces": (dict(faces=np.array(SQUARE, dtype=float)), TypeError,
                    "faces must be an array of integers, got dtype float64"),
    "empty faces": (dict(faces=np.zeros((0, 4), dtype=int)), ValueError, "faces is empty"),
    "empty face list": (dict(faces=[]), ValueError, "faces must have shape"),
    "vertices of shape (n, 2)": (dict(vertices=VERTICES[:, :2]), ValueError,
                                 re.escape("vertices must have shape (k, 3)")),
    "string vertices": (dict(vertices=VERTICES.astype(str)), TypeError, "real numbers"),
    "complex vertices": (dict(vertices=VERTICES + 0j), TypeError, "real numbers"),
    "normals (n, 2)": (dict(normals=NORMALS[:, :2]), ValueError,
                       re.escape("normals must have shape (5, 3), got (5, 2)")),
    "normals for too few vertices": (dict(normals=NORMALS[:4]), ValueError,
                                     re.escape("normals must have shape (5, 3), got (4, 3)")),
    "corner normals (m, 3, 3)": (dict(normals=np.tile([0.0, 0, 1], (1, 3, 1))), ValueError,
                                 re.escape("normals must have shape (1, 4, 3), got (1, 3, 3)")),
    "normals of one vertex": (dict(normals=[0.0, 0, 1]), ValueError,
                              "one per vertex.*one per face corner"),
    "normals 4-D": (dict(normals=np.zeros((1, 1, 4, 3))), ValueError, "one per face corner"),
    "non-unit corner normal": (dict(normals=with_row(np.tile([0.0, 0, 1], (1, 4, 1)), (0, 2),
                                                     [0, 0, 2])),
                               ValueError, "face 0, corner 2 is of length 2"),
    "degenerate_ratio 0.5": (dict(degenerate_ratio=0.5), ValueError,
                             r"degenerate_ratio must be a finite number >= 1"),
    "degenerate_ratio NaN": (dict(degenerate_ratio=float("nan")), ValueError, "degenerate_ratio"),
    "degenerate_ratio inf": (dict(degenerate_ratio=float("inf")), ValueError, "degenerate_ratio"),
}


@pytest.mark.parametrize(("arguments", "error", "message"), list(NAGATA_CASES.values()),
                         ids=list(NAGATA_CASES))
def test_bad_nagata_input(arguments, error, message):
    with pytest.raises(error, match=message):
        nagata(**arguments)


def test_good_nagata_input_is_accepted():
    assert nagata().n_patches == 1
    assert nagata(faces=[[0, 1, 2, -1], [0, 2, 3, -1]], smooth=False).n_patches == 2
    assert nagata(normals=np.tile([0.0, 0, 1], (1, 4, 1))).n_patches == 1


def test_smallest_degenerate_ratio_keeps_parallel_normals_finite():
    # degenerate_ratio = 1 is allowed; a flat face (parallel normals) must stay finite.
    surface = nagata(degenerate_ratio=1.0)
    points, derivs, normals = surface.evaluate([0], [[0.5, 0.5]])
    assert np.all(np.isfinite(surface.coefficients))
    np.testing.assert_allclose(points, [[0.5, 0.5, 0.0]], atol=1e-15)
    np.testing.assert_allclose(normals, [[0.0, 0.0, 1.0]], atol=1e-15)


# --- Bezier construction ----------------------------------------------------------------------

#: A bilinear patch: the unit square in z = 0.
GOOD_NET = np.array([[[0.0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]])

BEZIER_CASES = {
    "degree 7": ([np.zeros((8, 8, 3))], ValueError, r"degree \(7, 7\).*between 1 and 6"),
    "degree 7 in v": ([np.zeros((3, 8, 3))], ValueError, r"degree \(2, 7\)"),
    "degree 0": ([np.zeros((1, 4, 3))], ValueError, r"degree \(0, 3\).*between 1 and 6"),
    "second patch bad": ([np.zeros((2, 2, 3)), np.zeros((2, 1, 3))], ValueError,
                         r"patch 1 has degree \(1, 0\)"),
    "last dimension 2": ([np.zeros((3, 3, 2))], ValueError,
                         re.escape("must have shape (n+1, m+1, 3), got (3, 3, 2)")),
    "last dimension 4": (np.zeros((1, 3, 3, 4)), ValueError, "must have shape"),
    "2-D net": ([np.zeros((3, 3))], ValueError, "must have shape"),
    "empty list": ([], ValueError, "control_nets is empty"),
    "empty array": (np.zeros((0, 3, 3, 3)), ValueError, "control_nets is empty"),
    "empty net": ([np.zeros((0, 0, 3))], ValueError, "degree"),
    "NaN control point": ([with_row(np.zeros((3, 3, 3)), (1, 2), np.nan)], ValueError,
                          r"non-finite value at index \(1, 2, 0\)"),
    "string net": ([np.full((3, 3, 3), "a")], TypeError, "real numbers"),
    "complex net": ([np.zeros((3, 3, 3), dtype=complex)], TypeError, "real numbers"),
    # Nets collapsed to a point, a straight line or a curve have no area: their normals
    # would be zero, or the unit vector of rounding noise.
    "net at a point": ([np.full((3, 3, 3), 2.5)], ValueError,
                       "patch 0 is degenerate: its tangents are zero or parallel"),
    "net on a line": ([GOOD_NET, (np.linspace(0, 1, 12)[:, None] * [0.3, -1.7, 2.9]
                                  + [1, 2, 3]).reshape(3, 4, 3)], ValueError,
                      "patch 1 is degenerate"),
    "net on a curve": ([np.broadcast_to(np.array([[0.0, 0, 0], [1, 1, 0], [2, 0, 1]])[:, None],
                                        (3, 4, 3))], ValueError, "patch 0 is degenerate"),
}


@pytest.mark.parametrize(("nets", "error", "message"), list(BEZIER_CASES.values()),
                         ids=list(BEZIER_CASES))
def test_bad_bezier_input(nets, error, message):
    with pytest.raises(error, match=message):
        BezierSurface(nets)


# --- queries ----------------------------------------------------------------------------------


@pytest.fixture(params=["bezier", "nagata"])
def surface(request):
    if request.param == "bezier":
        rng = np.random.default_rng(0)
        return BezierSurface([rng.normal(size=(3, 4, 3)), rng.normal(size=(2, 2, 3))])
    return nagata(faces=[[0, 1, 2, -1], [0, 2, 3, -1]])


QUERY_CASES = {
    "patch id too large": ([2], [[0.5, 0.5]], IndexError, r"patch_ids\[0\] = 2 is not a patch"),
    "negative patch id": ([0, -1], [[0.5, 0.5]] * 2, IndexError,
                          r"patch_ids\[1\] = -1 is not a patch.*0 <= id < 2"),
    "float patch ids": ([0.0], [[0.5, 0.5]], TypeError, "patch_ids must be an array of integers"),
    "bool patch ids": ([True], [[0.5, 0.5]], TypeError, "patch_ids must be an array of integers"),
    "2-D patch ids": ([[0]], [[0.5, 0.5]], ValueError, "patch_ids must have shape"),
    "params (k, 3)": ([0], [[0.5, 0.5, 0.5]], ValueError,
                      re.escape("params must have shape (1, 2), got (1, 3)")),
    "params (2,)": ([0], [0.5, 0.5], ValueError, re.escape("params must have shape (1, 2)")),
    "fewer params than ids": ([0, 1], [[0.5, 0.5]], ValueError,
                              re.escape("params must have shape (2, 2), got (1, 2)")),
    "params but no ids": ([], [[0.5, 0.5]], ValueError, re.escape("params must have shape (0, 2)")),
    "complex params": ([0], [[0.5 + 1j, 0.5]], TypeError, "params must be an array of real"),
    "string params": ([0], [["a", "b"]], TypeError, "params must be an array of real"),
    "None params": ([0], None, TypeError, "params must be an array of real"),
    "NaN params": ([0, 0], [[0.5, 0.5], [0.1, np.nan]], ValueError,
                   r"params has a non-finite value at index \(1, 1\)"),
    "infinite params": ([0], [[np.inf, 0.5]], ValueError, "params has a non-finite value"),
    # Far outside the domain the polynomial overflows (-inf at 1e300): refused.
    "params 1e300": ([0], [[1e300, 0.5]], ValueError,
                     re.escape("params[0] = [1e+300, 0.5] is outside patch 0")),
    "params beyond the margin": ([1, 0], [[0.5, 0.5], [0.5, -1.001]], ValueError,
                                 r"params\[1\] = .* is outside patch 0: expected parameters in "
                                 r"\[0, 1\] \(up to 1 beyond: -1 to 2\)"),
}


@pytest.mark.parametrize("method", ["evaluate", "second_derivatives"])
@pytest.mark.parametrize(("ids", "params", "error", "message"), list(QUERY_CASES.values()),
                         ids=list(QUERY_CASES))
def test_bad_queries(surface, method, ids, params, error, message):
    with pytest.raises(error, match=message):
        getattr(surface, method)(ids, params)


@pytest.mark.parametrize(("ids", "params", "error", "message"), list(QUERY_CASES.values())[:3],
                         ids=list(QUERY_CASES)[:3])
def test_bad_de_casteljau_queries(ids, params, error, message):
    rng = np.random.default_rng(0)
    surface = BezierSurface([rng.normal(size=(3, 4, 3)), GOOD_NET])
    with pytest.raises(error, match=message):
        surface.evaluate_de_casteljau(ids, params)


@pytest.mark.parametrize("params", [np.zeros((0, 2)), []], ids=["(0, 2) array", "empty list"])
def test_empty_batch(surface, params):
    points, derivs, normals = surface.evaluate(np.zeros(0, dtype=int), params)
    assert points.shape == (0, 3) and derivs.shape == (0, 2, 3) and normals.shape == (0, 3)
    assert surface.second_derivatives([], params).shape == (0, 3, 3)


def test_empty_de_casteljau_batch():
    surface = BezierSurface([GOOD_NET])
    assert surface.evaluate_de_casteljau(np.zeros(0, dtype=int), np.zeros((0, 2))).shape == (0, 3)


def test_parameters_within_the_margin_are_evaluated(surface):
    """Up to DOMAIN_MARGIN outside the domain the polynomial is evaluated (extrapolation,
    finite differences at an edge); the edges of the margin themselves included."""
    params = [[-1.0, 0.5], [2.0, 2.0], [0.5, -1.0], [1.5, 0.25]]
    points, _, _ = surface.evaluate([0, 1, 0, 1], params)
    assert np.isfinite(points).all()


def test_scalar_patch_id_is_one_query(surface):
    points, _, _ = surface.evaluate(1, [[0.5, 0.25]])
    assert points.shape == (1, 3)


# --- the edge coefficient ---------------------------------------------------------------------

EDGE = ([0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 1], [0.6, 0, 0.8])
EDGE_CASES = {
    "zero normal": ((EDGE[0], EDGE[1], [0.0, 0, 0], EDGE[3]), ValueError, "n0.*is zero"),
    "non-unit normal": ((*EDGE[:3], [0.0, 0, 2]), ValueError, "n1.*of length 2"),
    "NaN point": (([0.0, np.nan, 0], *EDGE[1:]), ValueError, "x0 has a non-finite value"),
    "2-D points": (([0.0, 0], [1.0, 0], [0.0, 1], [1.0, 0]), ValueError, "x0 must have shape"),
    "batch size mismatch": ((np.zeros((2, 3)), np.ones((3, 3)), [[0.0, 0, 1]] * 2,
                             [[0.0, 0, 1]] * 2),
                            ValueError, re.escape("x1 must have shape (2, 3)")),
}


@pytest.mark.parametrize(("arguments", "error", "message"), list(EDGE_CASES.values()),
                         ids=list(EDGE_CASES))
def test_bad_edge_input(arguments, error, message):
    with pytest.raises(error, match=message):
        nagata_edge_coefficient(*arguments)


def test_empty_edge_batch():
    empty = np.zeros((0, 3))
    assert nagata_edge_coefficient(empty, empty, empty, empty).shape == (0, 3)


def test_edge_coefficient_refuses_a_bad_ratio_and_stays_finite():
    for ratio in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="degenerate_ratio"):
            nagata_edge_coefficient([0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 1], [0.0, 0, 1],
                                    degenerate_ratio=ratio)
    c = nagata_edge_coefficient([0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 1], [0.0, 0, 1],
                                degenerate_ratio=1.0)
    assert np.all(c == 0.0)
