"""Helpers of the deck tests: example cases copied to a folder, and a tool file reader for
the geometry checks when ddpy.io.toolfile is not part of this build."""

from __future__ import annotations

import shutil
import sys
import types
from pathlib import Path

import numpy as np

from ddpy.geometry.surfaces import NagataSurface

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def copy_example(name: str, folder: Path, **texts: str) -> Path:
    """Copy examples/<name> to folder/<name>; replace decks given as keyword (mesh='...')."""
    target = folder / name
    shutil.copytree(EXAMPLES / name, target)
    for deck, text in texts.items():
        (target / f"{deck}.dat").write_text(text)
    return target


def edit(case: Path, deck: str, old: str, new: str) -> Path:
    """Replace text in one deck of a case folder (the text must be there)."""
    path = case / deck
    text = path.read_text()
    assert old in text, f"{old!r} not in {deck}"
    path.write_text(text.replace(old, new, 1))
    return case


def _read_nagata(path: str | Path) -> types.SimpleNamespace:
    """Enough of the tool file format (docs/tool-files.md) for Nagata and facet files."""
    words = [line.split("#", 1)[0].split() for line in Path(path).read_text().splitlines()]
    words = [w for w in words if w]
    header = {w[0]: w[1] for w in words[:6] if w[0] in ("name", "description")}
    i = next(k for k, w in enumerate(words) if w[0] == "vertices")
    nv = int(words[i][1])
    vertices = np.array(words[i + 1:i + 1 + nv], dtype=float)
    i += 1 + nv
    nn = int(words[i][1])
    normals = np.array(words[i + 1:i + 1 + nn], dtype=float)
    i += 1 + nn
    nf = int(words[i][1])
    faces = np.array(words[i + 1:i + 1 + nf], dtype=int)
    corner = normals[faces[:, 4:8]]
    corner /= np.linalg.norm(corner, axis=2, keepdims=True)

    def model(smooth: bool) -> types.SimpleNamespace:
        surface = NagataSurface(vertices, corner, faces[:, :4], smooth=smooth)
        return types.SimpleNamespace(name=header["name"], surface=surface,
                                     description="nagata" if smooth else "facets",
                                     facets=lambda: model(False))

    return model(header["description"] == "nagata")


def install_toolfile(monkeypatch) -> None:
    """Make ddpy.io.toolfile importable: the real one when present, else a minimal reader."""
    try:
        import ddpy.io.toolfile  # noqa: F401
    except ImportError:
        stub = types.ModuleType("ddpy.io.toolfile")
        stub.read_tool = _read_nagata  # type: ignore[attr-defined]
        monkeypatch.setitem(sys.modules, "ddpy.io.toolfile", stub)


#: Node order that turns a hexahedron upside down (top and bottom faces swapped).
UPSIDE_DOWN = [4, 5, 6, 7, 0, 1, 2, 3]


def row_mesh_deck(count: int, upside_down: tuple[int, ...] = (),
                  repeated: tuple[int, ...] = ()) -> tuple[str, list[int]]:
    """mesh.dat of a row of ``count`` unit cubes along x in own 'nodes' and 'hexahedra'
    blocks (node ids from 1, element ids from 11), with the elements at the given positions
    turned upside down or given a repeated node; and the deck line of each element."""
    from ddpy.model.mesh import HexMesh

    row = HexMesh.box(float(count), 1.0, 1.0, count, 1, 1)
    elements = row.elements + 1
    elements[list(upside_down)] = elements[list(upside_down)][:, UPSIDE_DOWN]
    elements[list(repeated), 7] = elements[list(repeated), 6]
    lines = ["normal z", f"nodes {row.n_nodes}"]
    lines += [f"{k + 1} {x:g} {y:g} {z:g}" for k, (x, y, z) in enumerate(row.nodes)]
    lines.append(f"hexahedra {count}")
    first = len(lines) + 1
    lines += [f"{11 + k} " + " ".join(map(str, e)) for k, e in enumerate(elements)]
    return "\n".join(lines) + "\n", list(range(first, first + count))
