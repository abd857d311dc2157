"""Tool models from CAD (STEP files written by gmsh) and their shape error."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ddpy.cad import CadError, build_tool_models, closest_points, gmsh_session, load_cad
from ddpy.cad.examples import (
    cylinder_segment,
    cylindrical_punch,
    die_profile,
    sphere_patch,
    square_cup_tools,
    write_cad,
)
from ddpy.cad.shape_error import plot_shape_error, shape_error
from ddpy.io.toolfile import ToolModel, read_tool

gmsh = pytest.importorskip("gmsh")

R_CYL, R_SPHERE = 10.0, 10.0
# The creased tool: a plane z = 0 (x < 0) meeting a convex cylinder of radius 23.5 at x = 0.
R_CREASE, X_CREASE = 23.5, 10.0
H_CREASE = float(np.sqrt(R_CREASE**2 - X_CREASE**2))


def _creased(path: Path) -> None:
    occ = gmsh.model.occ
    p0, p1 = occ.addPoint(-10, 0, 0), occ.addPoint(0, 0, 0)
    centre, top = occ.addPoint(X_CREASE, 0, -H_CREASE), occ.addPoint(X_CREASE, 0,
                                                                      R_CREASE - H_CREASE)
    curves = [occ.addLine(p0, p1), occ.addCircleArc(p1, centre, top)]
    occ.extrude([(1, c) for c in curves], 0, 10, 0)
    write_cad(path)


def _polygon(path: Path, corners: list[tuple[float, float]]) -> None:
    occ = gmsh.model.occ
    points = [occ.addPoint(x, y, 0) for x, y in corners]
    lines = [occ.addLine(points[i], points[(i + 1) % len(points)]) for i in range(len(points))]
    occ.addPlaneSurface([occ.addCurveLoop(lines)])
    write_cad(path)


@pytest.fixture(scope="module")
def cad(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("cad")
    makers = {
        "cylinder.step": lambda p: cylinder_segment(p, radius=R_CYL),
        "sphere.step": lambda p: sphere_patch(p, radius=R_SPHERE),
        "die.step": die_profile,
        "punch.step": cylindrical_punch,
        "hemisphere.step": lambda p: sphere_patch(p, radius=R_SPHERE, latitudes=(0, np.pi / 2),
                                                  longitude=2 * np.pi),
        "crease.step": _creased,
        "trapezoid.step": lambda p: _polygon(p, [(0, 0), (10, 0), (8, 5), (2, 5)]),
        "pentagon.step": lambda p: _polygon(p, [(0, 0), (10, 0), (12, 5), (5, 9), (-2, 5)]),
        "wall.step": lambda p: (gmsh.model.occ.addRectangle(0, 0, 0, 10, 5),
                                gmsh.model.occ.rotate([(2, 1)], 0, 0, 0, 1, 0, 0, np.pi / 2),
                                write_cad(p)),
        "cone.brep": lambda p: (gmsh.model.occ.addCone(0, 0, 0, 0, 0, 10, 5, 0), write_cad(p)),
        "closed.brep": lambda p: (cylinder_segment(angle=np.pi),
                                  gmsh.model.occ.rotate(
                                      [(2, cylinder_segment(angle=np.pi)[0])], 0, 0, 0, 0, 0, 1,
                                      np.pi),
                                  write_cad(p)),
        "curve.step": lambda p: (gmsh.model.occ.addCircle(0, 0, 0, 5), write_cad(p)),
    }
    paths = {}
    with gmsh_session():
        for name, make in makers.items():
            gmsh.model.add(name)
            make(folder / name)
            gmsh.model.remove()
            paths[name.split(".")[0]] = folder / name
    (folder / "garbage.step").write_text("ISO-10303-21;\nthis is not STEP\n")
    paths["garbage"] = folder / "garbage.step"
    return paths


@pytest.fixture(scope="module")
def built(cad: dict[str, Path], tmp_path_factory: pytest.TempPathFactory
          ) -> dict[str, dict[str, ToolModel]]:
    """The three models of the cylinder, sphere, die and crease tools."""
    out = tmp_path_factory.mktemp("tools")
    options = {"cylinder": {"blank_point": (0, 0, 10)}, "sphere": {"blank_point": (0, 0, 0)},
               "die": {"size": 10.0}, "crease": {"size": 5.0},
               "punch": {"blank_side": (0, 0, -1), "size": 10.0, "facets_per_arc": 8},
               "hemisphere": {"facets_per_arc": 8}}
    models = {}
    for name, kw in options.items():
        paths = build_tool_models(cad[name], out, name, **kw)
        models[name] = {kind: read_tool(path) for kind, path in paths.items()}
    return models


def _corners(model: ToolModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertex positions, corner normals and face tags per used corner of a mesh model."""
    s = model.surface
    used = ~(s.is_triangle[:, None] & (np.arange(4) == 3))
    rows = np.repeat(np.arange(s.n_patches), 4).reshape(-1, 4)[used]
    return s.vertices[s.faces[used]], s.corner_normals[used], model.face_tags[rows]


def _die_normal(x: np.ndarray, tags: np.ndarray, order: list[int]) -> np.ndarray:
    """Exact normals of the die (towards +z, the blank) at points x on faces ``tags``."""
    land, fillet, cylinder = order
    n = np.zeros_like(x)
    n[tags == land] = [0, 0, 1]
    f = tags == fillet
    n[f] = np.column_stack([x[f, 0], 0 * x[f, 0], x[f, 2] + 4]) / 4
    c = tags == cylinder
    n[c] = np.column_stack([27.5 - x[c, 0], 0 * x[c, 0], -4 - x[c, 2]]) / 23.5
    return n


def _die_faces(model: ToolModel) -> list[int]:
    """Face tags of land, fillet and cylinder, told apart by the x of their vertices."""
    x, _, tags = _corners(model)
    mean = {int(t): x[tags == t, 0].mean() for t in np.unique(tags)}
    return sorted(mean, key=mean.get)


def test_cylinder_segment(built: dict[str, dict[str, ToolModel]]) -> None:
    nagata, facets = built["cylinder"]["nagata"], built["cylinder"]["facets"]
    assert nagata.n_patches == 4 and facets.n_patches == 30  # per 90 degrees, one lengthwise
    for model in (nagata, facets):
        x, normals, _ = _corners(model)
        radius = np.hypot(x[:, 0], x[:, 1])
        np.testing.assert_allclose(radius, R_CYL, atol=1e-9)      # on the CAD surface
        exact = -np.column_stack([x[:, 0], x[:, 1], 0 * radius]) / radius[:, None]
        np.testing.assert_allclose(normals, exact, atol=1e-8)      # towards the axis (blank)
    assert Path(nagata.source).name == "cylinder.step"
    bezier = built["cylinder"]["bezier"]
    assert bezier.surface.degrees.max() > 2       # a circle is not a non-rational quadratic
    assert shape_error(bezier).max_distance < 1e-3


def test_sphere_patch(built: dict[str, dict[str, ToolModel]]) -> None:
    for kind in ("nagata", "facets"):
        x, normals, _ = _corners(built["sphere"][kind])
        radius = np.linalg.norm(x, axis=1)
        np.testing.assert_allclose(radius, R_SPHERE, atol=1e-9)
        np.testing.assert_allclose(normals, -x / radius[:, None], atol=1e-8)
    errors = {k: shape_error(m) for k, m in built["sphere"].items()}
    assert errors["bezier"].max_distance < 1e-3 and errors["bezier"].max_angle < 0.01
    assert errors["nagata"].max_distance < errors["facets"].max_distance
    assert errors["nagata"].max_angle < 0.5 < errors["facets"].max_angle


def test_die_normals_exact_and_tangent_joints_share_one(
        built: dict[str, dict[str, ToolModel]]) -> None:
    for kind in ("nagata", "facets"):
        model = built["die"][kind]
        x, normals, tags = _corners(model)
        order = _die_faces(model)
        np.testing.assert_allclose(normals, _die_normal(x, tags, order), atol=1e-8)
        # Tangent joints: one normal per vertex, whatever face the corner belongs to.
        s = model.surface
        for v in np.flatnonzero(np.isclose(s.vertices[:, 0], 0.0, atol=1e-12)):
            at_v = normals[np.all(x == s.vertices[v], axis=1)]
            assert len(np.unique(at_v.round(12), axis=0)) == 1
    # Every patch faces the blank (above): its normal at the centre has n_z > 0.
    for model in built["die"].values():
        centres = np.full((model.n_patches, 2), 0.5)
        _, _, n = model.surface.evaluate(np.arange(model.n_patches), centres)
        assert np.all(n[:, 2] > 0)


def test_crease_vertices_carry_one_normal_per_face(
        built: dict[str, dict[str, ToolModel]]) -> None:
    for kind in ("nagata", "facets"):
        model = built["crease"][kind]
        x, normals, tags = _corners(model)
        on_crease = np.isclose(x[:, 0], 0.0, atol=1e-12) & np.isclose(x[:, 2], 0.0, atol=1e-12)
        assert on_crease.sum() >= 4
        plane = tags == tags[np.argmin(x[:, 0])]
        np.testing.assert_allclose(normals[plane], [[0, 0, 1]] * plane.sum(), atol=1e-8)
        centre = np.array([X_CREASE, 0.0, -H_CREASE])
        radial = (x - centre) * [1, 0, 1]
        np.testing.assert_allclose(normals[~plane], radial[~plane] / R_CREASE, atol=1e-8)
        # Read back from the tool file: each crease vertex has exactly two normals.
        for v in np.unique(x[on_crease].round(9), axis=0):
            at_v = np.all(np.isclose(x, v, atol=1e-9), axis=1)
            assert len(np.unique(normals[at_v].round(9), axis=0)) == 2


def test_revolved_punch_structured_on_seams_and_disc_in_bezier(
        built: dict[str, dict[str, ToolModel]]) -> None:
    """Full revolutions (faces closed on a seam) get structured quadrilaterals; the disc of the
    punch nose gets an O-grid of Bezier patches."""
    def exact(x: np.ndarray, tags: np.ndarray, order: list[int]) -> np.ndarray:
        disc, fillet, wall = order
        rho = np.hypot(x[:, 0], x[:, 1])
        radial = np.column_stack([x[:, 0], x[:, 1], 0 * rho]) / np.maximum(rho, 1e-300)[:, None]
        n = np.zeros_like(x)
        n[tags == disc] = [0, 0, -1]
        f = tags == fillet
        n[f] = (x[f] - (40.0 * radial[f] + [0, 0, 8])) / 8.0
        n[tags == wall] = radial[tags == wall]
        return n

    for kind in ("nagata", "facets"):
        model = built["punch"][kind]
        x, normals, tags = _corners(model)
        mean_z = {int(t): x[tags == t, 2].mean() for t in np.unique(tags)}
        order = sorted(mean_z, key=mean_z.get)           # disc (z = 0), fillet, wall
        np.testing.assert_allclose(normals, exact(x, tags, order), atol=1e-8)
        rows = np.isin(model.face_tags, order[1:])
        assert not model.surface.is_triangle[rows].any()  # structured around the seams
    nagata = built["punch"]["nagata"]
    assert np.sum(nagata.face_tags == order[2]) == 16 * 4   # 16 round, 32 mm / 10 mm
    errors = {k: shape_error(m) for k, m in built["punch"].items()}
    bezier = built["punch"]["bezier"]
    assert np.sum(bezier.face_tags == order[0]) == 5        # the O-grid of the disc
    assert errors["bezier"].max_distance < 1e-3 and errors["bezier"].max_angle < 0.01
    assert errors["nagata"].max_distance < errors["facets"].max_distance


def test_hemisphere_pole(built: dict[str, dict[str, ToolModel]]) -> None:
    """A pole: triangles around it, one normal there; Bezier patches collapse to it."""
    for kind in ("nagata", "facets"):
        model = built["hemisphere"][kind]
        x, normals, _ = _corners(model)
        radius = np.linalg.norm(x, axis=1)
        np.testing.assert_allclose(radius, R_SPHERE, atol=1e-9)
        np.testing.assert_allclose(normals, x / radius[:, None], atol=1e-8)
        s = model.surface
        pole = np.flatnonzero(np.isclose(s.vertices[:, 2], R_SPHERE, atol=1e-9))
        assert len(pole) == 1
        around = np.any(s.faces == pole[0], axis=1)
        assert s.is_triangle[around].all() and not s.is_triangle[~around].any()
    bezier = shape_error(built["hemisphere"]["bezier"])
    assert bezier.max_distance < 1e-3 and bezier.max_angle < 0.01
    assert bezier.undefined_normals > 0        # the collapsed row at the pole


def test_closest_points_beyond_the_face(cad: dict[str, Path]) -> None:
    """Below the equator of a hemisphere gmsh answers the antipode; ddpy the equator."""
    angles = np.radians(np.arange(0, 360, 30))
    points = np.column_stack([10.0 * np.cos(angles), 10.0 * np.sin(angles),
                              np.full(len(angles), -1e-4)])
    with gmsh_session():
        face = load_cad(cad["hemisphere"])[0]
        raw = np.reshape(gmsh.model.getClosestPoint(2, face, points.ravel())[0], (-1, 3))
        closest, _ = closest_points(face, points)
        gmsh.model.remove()
    assert np.linalg.norm(raw - points, axis=1).max() > 19.0   # the antipode
    np.testing.assert_allclose(closest, points * [1, 1, 0], atol=1e-9)


def test_in_memory_gmsh_model(tmp_path: Path) -> None:
    with gmsh_session():
        gmsh.model.add("memory")
        cylinder_segment(radius=R_CYL)
        paths = build_tool_models(None, tmp_path, "mem", blank_point=(0, 0, 10),
                                  models=("nagata", "bezier"))
        assert sorted(paths) == ["bezier", "nagata"]
        model = read_tool(paths["nagata"])
        assert model.source is None
        result = shape_error(model)   # against the current gmsh model
    assert 0 < result.max_distance < 1e-2


def test_shape_error_orders_and_nagata_far_better(cad: dict[str, Path], tmp_path: Path) -> None:
    """Max distance error ~h^4 (Nagata) against ~h^2 (facets); normals ~h^3 against ~h."""
    errors = {}
    for per_arc in (4, 8):
        paths = build_tool_models(cad["cylinder"], tmp_path, f"c{per_arc}",
                                  patches_per_arc=per_arc, blank_point=(0, 0, 10),
                                  models=("nagata",))
        nagata = read_tool(paths["nagata"])
        errors[per_arc] = (shape_error(nagata), shape_error(nagata.facets()))
    (n4, f4), (n8, f8) = errors[4], errors[8]
    assert n4.max_distance < f4.max_distance / 20            # same mesh, far more accurate
    assert np.log2(n4.max_distance / n8.max_distance) == pytest.approx(4.0, abs=0.3)
    assert np.log2(f4.max_distance / f8.max_distance) == pytest.approx(2.0, abs=0.1)
    assert np.log2(n4.max_angle / n8.max_angle) == pytest.approx(3.0, abs=0.3)
    assert np.log2(f4.max_angle / f8.max_angle) == pytest.approx(1.0, abs=0.05)
    # Facets of a 90/4 degree arc: sagitta r (1 - cos(11.25 deg)), normal error 11.25 deg.
    assert f4.max_distance == pytest.approx(R_CYL * (1 - np.cos(np.radians(11.25))), rel=1e-6)
    assert f4.max_angle == pytest.approx(11.25, abs=1e-6)
    # Signs: on this concave surface the chords stand out towards the blank (positive);
    # the Nagata patches bulge the other way.
    assert f4.distance.max() > 0 and n4.distance.min() < 0
    png = plot_shape_error(n4, tmp_path / "map.png")
    assert png.stat().st_size > 10_000


def test_die_shape_errors_match_the_paper(built: dict[str, dict[str, ToolModel]]) -> None:
    errors = {k: shape_error(m) for k, m in built["die"].items()}
    # Paper: fine facets (30 per arc) about 9 um and 1.5 degrees; Nagata (4 per arc) < 0.1 deg.
    assert errors["facets"].max_distance == pytest.approx(23.5 * (1 - np.cos(np.radians(1.5))),
                                                          rel=1e-6)
    assert errors["facets"].max_angle == pytest.approx(1.5, abs=1e-6)
    assert errors["nagata"].max_angle < 0.1
    assert errors["nagata"].max_distance < 5e-3
    assert errors["bezier"].max_distance < 1e-3 and errors["bezier"].max_angle < 0.01
    bezier = built["die"]["bezier"]
    land = _die_faces(built["die"]["nagata"])[0]
    assert bezier.surface.degrees[bezier.face_tags == land].tolist() == [[1, 1]]
    assert errors["bezier"].distance[np.isin(errors["bezier"].patch,
                                             np.flatnonzero(bezier.face_tags == land))
                                     ].max() < 1e-12


def test_bezier_tolerance_and_trimmed_faces(cad: dict[str, Path], tmp_path: Path) -> None:
    paths = build_tool_models(cad["cylinder"], tmp_path, "tight", blank_point=(0, 0, 10),
                              bezier_tol=1e-6, models=("bezier",))
    tight = read_tool(paths["bezier"])
    assert tight.n_patches > 1                                  # split to reach 1 nm
    assert shape_error(tight).max_distance < 1e-6
    # A trimmed 4-sided face (a trapezoid): a Coons map of its edges, bilinear and exact.
    paths = build_tool_models(cad["trapezoid"], tmp_path, "trap", models=("bezier", "nagata"))
    trap = read_tool(paths["bezier"])
    assert trap.surface.degrees.tolist() == [[1, 1]]
    corners = np.sort(trap.surface.evaluate([0] * 4, [[0, 0], [1, 0], [1, 1], [0, 1]])[0], 0)
    np.testing.assert_allclose(corners, np.sort([[0, 0, 0], [10, 0, 0], [8, 5, 0],
                                                 [2, 5, 0]], 0), atol=1e-12)
    # A trimmed 5-sided face meshes, but has no Bezier description.
    build_tool_models(cad["pentagon"], tmp_path, "pent", models=("nagata",))
    with pytest.raises(CadError, match=r"pentagon.step: face 1: is trimmed and has 5 edges"):
        build_tool_models(cad["pentagon"], tmp_path, "pent", models=("bezier",))


def test_triangles(cad: dict[str, Path], tmp_path: Path) -> None:
    paths = build_tool_models(cad["die"], tmp_path, "tri", element="tri", size=10.0,
                              models=("nagata",))
    model = read_tool(paths["nagata"])
    assert model.surface.is_triangle.all()
    assert shape_error(model).max_angle < 0.2


@pytest.mark.parametrize(("name", "kwargs", "message"), [
    ("missing", {}, "missing.step: no such CAD file"),
    ("garbage", {}, "garbage.step: "),
    ("curve", {}, "curve.step: the STEP file holds no faces"),
    ("cone", {}, "cone.brep: face 1: the surface normal is undefined at (0, 0, 10)"),
    ("closed", {"blank_side": (0, 1, 0)}, "closed.brep: face 2: points away from the blank"),
    ("wall", {}, "wall.step: face 1: is edge-on to the blank side"),
    ("die", {"faces": [1, 99]}, "die.step: face 99 is not in the model"),
])
def test_errors_name_file_and_face(cad: dict[str, Path], tmp_path: Path, name: str,
                                   kwargs: dict, message: str) -> None:
    path = cad.get(name, tmp_path / "missing.step")
    with pytest.raises(CadError) as error:
        build_tool_models(path, tmp_path, name, models=("nagata",), **kwargs)
    assert message in str(error.value)


def test_arc_size_bounds_the_elements_along_curved_edges(cad: dict[str, Path],
                                                         tmp_path: Path) -> None:
    # The quarter cylinder's arcs are 5 pi = 15.7 mm long: by the angle 2 (Nagata) and 4
    # (facets) elements; elements of at most 1.5 mm need 11. The straight edges keep one.
    paths = build_tool_models(cad["cylinder"], tmp_path, "c", patches_per_arc=2,
                              facets_per_arc=4, blank_point=(0, 0, 10), arc_size=1.5,
                              models=("nagata", "facets"))
    assert read_tool(paths["nagata"]).n_patches == 11
    assert read_tool(paths["facets"]).n_patches == 11
    paths = build_tool_models(cad["cylinder"], tmp_path, "d", patches_per_arc=2,
                              blank_point=(0, 0, 10), arc_size=100.0, models=("nagata",))
    assert read_tool(paths["nagata"]).n_patches == 2
    with pytest.raises(ValueError, match="arc_size must be positive"):
        build_tool_models(cad["cylinder"], tmp_path, "e", arc_size=0.0, models=("nagata",))


def test_bad_arguments(cad: dict[str, Path], tmp_path: Path) -> None:
    with pytest.raises(CadError, match="unknown CAD format '.stl'"):
        build_tool_models(tmp_path / "a.stl", tmp_path, "a")
    with pytest.raises(ValueError, match="element must be 'quad' or 'tri'"):
        build_tool_models(cad["die"], tmp_path, "a", element="hex")
    with pytest.raises(ValueError, match="models must be among"):
        build_tool_models(cad["die"], tmp_path, "a", models=("nurbs",))
    with pytest.raises(ValueError, match="blank_side must be 3 finite numbers"):
        build_tool_models(cad["die"], tmp_path, "a", blank_side=(0, 1))


def test_cli_build_and_error(cad: dict[str, Path], tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    from ddpy.app.cli import main

    def ddpy(*args: str) -> tuple[int, str, str]:
        try:
            code = main(list(args))
        except SystemExit as stop:   # argparse refusing an argument
            code = int(stop.code)
        out, err = capsys.readouterr()
        return code, out, err

    code, out, err = ddpy("tools", "build", str(cad["cylinder"]), "--name", "cyl", "--out",
                          str(tmp_path), "--patches-per-arc", "2", "--facets-per-arc", "8",
                          "--blank-point=0,0,10")
    assert code == 0, err
    files = out.split()
    assert [Path(f).name for f in files] == ["cyl.nagata.tool", "cyl.facets.tool",
                                              "cyl.bezier.tool"]
    assert read_tool(files[0]).n_patches == 2 and read_tool(files[1]).n_patches == 8
    code, out, err = ddpy("tools", "build", str(cad["cylinder"]), "--name", "cyl3", "--out",
                          str(tmp_path), "--patches-per-arc", "2", "--arc-size", "1.5",
                          "--models", "nagata", "--blank-point=0,0,10")
    assert code == 0, err
    assert read_tool(out.split()[0]).n_patches == 11
    code, out, err = ddpy("tools", "error", *files, "--json", "--png", str(tmp_path))
    assert code == 0, err
    rows = json.loads(out)
    assert [r["description"] for r in rows] == ["nagata", "facets", "bezier"]
    assert rows[0]["max_distance_um"] < rows[1]["max_distance_um"]
    assert (tmp_path / "cyl.nagata.tool.png").is_file()
    code, out, _ = ddpy("tools", "error", *files)
    assert code == 0 and "max |d| um" in out
    code, _, err = ddpy("tools", "build", str(cad["cone"]), "--out", str(tmp_path))
    assert code == 2
    assert "ddpy tools build: error: " in err and "cone.brep: face 1" in err
    # A name with a path in it would write outside --out; a tolerance below the CAD kernel's
    # precision would split the faces for ever.
    for option, value, message in (("--name", "../x", "plain file name"),
                                   ("--bezier-tol", "1e-15", "bezier_tol must lie between"),
                                   ("--bezier-angle-tol", "0", "bezier_angle_tol must lie")):
        code, _, err = ddpy("tools", "build", str(cad["cylinder"]), "--out",
                            str(tmp_path / "sub"), option, value)
        assert code == 2 and message in err, err
    assert not (tmp_path / "x.nagata.tool").exists() and not (tmp_path / "sub").exists()
    code, _, err = ddpy("tools", "build", str(cad["die"]), "--blank-side", "1,2")
    assert code == 2 and "expected X,Y,Z" in err


def test_bezier_fit_stops_at_the_patch_limit(cad: dict[str, Path], tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    # A face the tolerances make split again and again ends with a message, not in millions
    # of regions: here the limit is lowered to 1 and the cylinder needs 2 patches.
    import ddpy.cad.bezier_fit

    monkeypatch.setattr(ddpy.cad.bezier_fit, "MAX_PATCHES_PER_FACE", 1)
    with pytest.raises(CadError, match="needs more than 1 Bezier patches"):
        build_tool_models(cad["cylinder"], tmp_path, "c", models=("bezier",),
                          blank_point=(0.0, 0.0, 10.0), bezier_tol=1e-6)


@pytest.mark.parametrize("damage, message", [
    ("point", "CARTESIAN_POINT holds 'nan' where a number is expected"),
    ("vector", "VECTOR holds 'NaN' where a number is expected"),
    ("line", "which the file does not define"),
    ("radius", "CYLINDRICAL_SURFACE needs 1 radius value(s) from 1e-07 to 1e+10, got [0.0]"),
    ("tiny radius", "CYLINDRICAL_SURFACE needs 1 radius value(s) from 1e-07 to 1e+10, got "
     "[1e-300]"),
    ("magnitude", "VECTOR: expected a magnitude from 1e-07 to 1e+10 (argument 3), got '0.'"),
    ("tiny magnitude", "VECTOR: expected a magnitude from 1e-07 to 1e+10 (argument 3), got "
     "'1.E-300'"),
    ("orientation", "VECTOR: its orientation #1 is APPLICATION_PROTOCOL_DEFINITION, "
     "expected DIRECTION"),
    ("direction", "DIRECTION: expected 2 or 3 direction ratios, not all zero, none beyond "
     "1e+10, got '(0.,0.,0.)'"),
    ("huge direction", "DIRECTION: expected 2 or 3 direction ratios, not all zero, none "
     "beyond 1e+10, got '(1.,1.E+300)'"),
    ("placement", "CYLINDRICAL_SURFACE: its position #"),
    ("absent", "LINE: expected a reference to a VECTOR as its dir (argument 3), got '$'"),
])
def test_step_files_that_crash_the_cad_reader_are_refused(cad: dict[str, Path], tmp_path: Path,
                                                          damage: str, message: str) -> None:
    # Each of these ended the process inside gmsh (segmentation fault, or no return), or
    # (a direction of zeros) was read without a word.
    import re

    text = cad["cylinder"].read_text()
    if damage == "point":
        text = re.sub(r"CARTESIAN_POINT\('([^']*)',\([^)]*\)\)",
                      r"CARTESIAN_POINT('\1',(nan,nan,nan))", text, count=1)
    elif damage == "vector":
        text = re.sub(r"(VECTOR\('[^']*',#\d+,)[^)]*\)", r"\1NaN)", text, count=1)
    elif damage == "radius":  # the kernel merged the faces of such a file into a few
        text = re.sub(r"(CYLINDRICAL_SURFACE\('[^']*',#\d+,)[^)]*\)", r"\g<1>0.)", text,
                      count=1)
    elif damage == "tiny radius":
        text = re.sub(r"(CYLINDRICAL_SURFACE\('[^']*',#\d+,)[^)]*\)", r"\g<1>1.E-300)", text,
                      count=1)
    elif damage == "magnitude":  # never returned
        text = re.sub(r"(VECTOR\('[^']*',#\d+,)[^)]*\)", r"\g<1>0.)", text, count=1)
    elif damage == "tiny magnitude":  # never returned either (found by the fuzz test)
        text = re.sub(r"(VECTOR\('[^']*',#\d+,)[^)]*\)", r"\g<1>1.E-300)", text, count=1)
    elif damage == "orientation":  # a segmentation fault
        text = re.sub(r"(VECTOR\('[^']*',)#\d+", r"\1#1", text, count=1)
    elif damage == "huge direction":  # never returned (found by the fuzz test)
        text = re.sub(r"DIRECTION\('([^']*)',\([^,)]*,[^,)]*\)\)", r"DIRECTION('\1',(1.,1.E+300))",
                      text, count=1)
    elif damage == "direction":
        text = re.sub(r"DIRECTION\('([^']*)',\([^)]*\)\)", r"DIRECTION('\1',(0.,0.,0.))",
                      text, count=1)
    elif damage == "placement":  # placed by a point
        point = re.search(r"#(\d+) ?= ?CARTESIAN_POINT", text)
        assert point is not None
        text = re.sub(r"(CYLINDRICAL_SURFACE\('[^']*',)#\d+", rf"\g<1>#{point.group(1)}", text,
                      count=1)
    elif damage == "absent":
        text = re.sub(r"(LINE\('[^']*',#\d+,)#\d+", r"\1$", text, count=1)
    else:
        text = re.sub(r"\n#\d+ ?= ?LINE\([^;]*;", "", text, count=1)
    bad = tmp_path / "bad.step"
    bad.write_text(text)
    lines = text.split("\n")
    with pytest.raises(CadError, match=re.escape(message)) as error:
        build_tool_models(bad, tmp_path, "bad", blank_point=(0.0, 0.0, 10.0))
    number = int(str(error.value).split(":")[1])
    assert 1 <= number <= len(lines)
    if damage in ("point", "vector"):
        assert re.search(r"nan", lines[number - 1], re.IGNORECASE)
    if damage in ("magnitude", "tiny magnitude", "orientation", "direction", "huge direction",
                  "placement", "absent"):
        assert str(error.value).split(": ")[1].split()[1] in lines[number - 1]
    from ddpy.app.cli import main

    assert main(["tools", "build", str(bad), "--out", str(tmp_path / "out"),
                 "--blank-point=0,0,10"]) == 2


def test_step_faces_the_cad_kernel_drops_are_reported(cad: dict[str, Path], tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    # A face whose surface is a point: the kernel drops that face and reads the rest,
    # without a word. The check of the face's geometry type names it first; without that
    # check, the count of faces read against those the file defines still does.
    import re

    import ddpy.cad.read

    text = cad["die"].read_text()
    point = re.search(r"#(\d+) ?= ?CARTESIAN_POINT", text)
    assert point is not None
    text = re.sub(r"(ADVANCED_FACE\('[^']*',\([^)]*\),)#\d+", rf"\g<1>#{point.group(1)}", text,
                  count=1)
    bad = tmp_path / "bad.step"
    bad.write_text(text)
    with pytest.raises(CadError, match=r"ADVANCED_FACE: its face_geometry #\d+ is "
                                       r"CARTESIAN_POINT, expected \*_SURFACE or PLANE"):
        build_tool_models(bad, tmp_path, "bad", blank_side=(0.0, 0.0, 1.0))
    types = {k: v for k, v in ddpy.cad.read._STEP_TYPES.items() if k != "ADVANCED_FACE"}
    monkeypatch.setattr(ddpy.cad.read, "_STEP_TYPES", types)
    with pytest.raises(CadError, match=r"the CAD kernel read \d+ of the \d+ faces"):
        build_tool_models(bad, tmp_path, "bad", blank_side=(0.0, 0.0, 1.0))


def test_step_swept_surfaces_are_read_and_their_references_checked(tmp_path: Path) -> None:
    # The square cup punch's corner is a torus whose tube (the 8 mm nose) is wider than its
    # ring (10 - 8 mm): OpenCASCADE writes it as a SURFACE_OF_REVOLUTION, which the STEP
    # check once refused as no surface. Read, every face of the three tools is there; a
    # SURFACE_OF_REVOLUTION whose axis is a point is refused at its line.
    import re

    step = tmp_path / "cup.step"
    with gmsh_session():
        gmsh.model.add("cup")
        made = square_cup_tools(step)
        gmsh.model.remove()
    text = step.read_text()
    assert "SURFACE_OF_REVOLUTION" in text
    with gmsh_session():
        assert len(load_cad(step)) == sum(len(faces) for faces in made.values())
    point = re.search(r"#(\d+) ?= ?CARTESIAN_POINT", text)
    assert point is not None
    bad = tmp_path / "bad.step"
    bad.write_text(re.sub(r"(SURFACE_OF_REVOLUTION\('[^']*',#\d+,)#\d+",
                          rf"\g<1>#{point.group(1)}", text, count=1))
    with pytest.raises(CadError, match=r"bad.step:\d+: entity #\d+ SURFACE_OF_REVOLUTION: its "
                                       r"axis_position #\d+ is CARTESIAN_POINT, expected "
                                       r"AXIS1_PLACEMENT"):
        build_tool_models(bad, tmp_path, "bad", blank_side=(0.0, 0.0, 1.0))


@pytest.mark.parametrize("name", ["garbage", "cone", "missing"])
def test_a_failing_build_leaves_no_new_folder(cad: dict[str, Path], tmp_path: Path,
                                              name: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    # The file cannot be read (garbage, missing) or a face fails once meshed (cone).
    from ddpy.app.cli import main

    path = cad.get(name, tmp_path / "missing.step")
    out = tmp_path / "new" / "tools"
    assert main(["tools", "build", str(path), "--out", str(out)]) == 2
    assert "ddpy tools build: error: " in capsys.readouterr().err
    assert not (tmp_path / "new").exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    assert main(["tools", "build", str(path), "--out", str(kept)]) == 2
    assert kept.is_dir() and not any(kept.iterdir())


def test_a_build_failing_to_write_leaves_no_new_folder(cad: dict[str, Path], tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]
                                                       ) -> None:
    import errno

    import ddpy.cad.build
    from ddpy.app.cli import main

    def full(path: Path, model: ToolModel) -> Path:
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(ddpy.cad.build, "write_tool", full)
    out = tmp_path / "new" / "tools"
    assert main(["tools", "build", str(cad["cylinder"]), "--out", str(out),
                 "--blank-point=0,0,10"]) == 1
    err = capsys.readouterr().err
    assert f"ddpy tools build: error: {out / 'cylinder.nagata.tool'}: No space left" in err
    assert not (tmp_path / "new").exists()
