"""Checkpoints of a run: everything needed to continue it exactly, in one ``.npz`` file.

A checkpoint holds named arrays and a JSON document of counters. It is written to a temporary
file in the same folder, flushed to disk and renamed over the previous one (``os.replace``),
so the file on disk is always a complete checkpoint, even when the run is killed while
writing. A forming problem's state (:class:`ddpy.model.forming.FormingState`, what
``FormingProblem.state()`` gives and ``restore`` takes) is stored field by field
(``dataclasses.fields``): its arrays under ``forming/``, its solid state's under ``state/``
and the tools' positions under ``position/``, so new fields of either are saved without
changes here.
"""

from __future__ import annotations

import dataclasses
import json
import os
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy.io.output_folder import atomic_write
from ddpy.model.forming import FormingState
from ddpy.model.solid import SolidState

__all__ = ["CheckpointError", "forming_state_arrays", "forming_state_from_arrays",
           "read_checkpoint", "state_arrays", "state_from_arrays", "write_checkpoint"]

#: Version of the checkpoint layout; a checkpoint of another version is refused. 2: the
#: forming problem's state as FormingState's fields (1 named the problem's attributes).
VERSION = 2
_META = "__meta__"


class CheckpointError(ValueError):
    """A checkpoint that cannot be used: missing, damaged, or of another case or version."""


def write_checkpoint(path: str | os.PathLike[str], meta: Mapping[str, Any],
                     arrays: Mapping[str, NDArray]) -> None:
    """Write ``arrays`` and the JSON-able ``meta`` atomically to ``path``."""
    path = Path(path)
    if _META in arrays:
        raise ValueError(f"array name {_META!r} is reserved")
    document = json.dumps({"version": VERSION, **meta})
    with atomic_write(path, binary=True) as out:
        np.savez(out, **{_META: np.array(document)}, **dict(arrays))


def read_checkpoint(path: str | os.PathLike[str]) -> tuple[dict[str, Any], dict[str, NDArray]]:
    """The meta document and the arrays of a checkpoint; CheckpointError when unusable."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"{path}: no checkpoint")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        meta = json.loads(str(arrays.pop(_META)))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:
        raise CheckpointError(f"{path}: not a readable checkpoint ({error}); run again "
                              "without --restart") from None
    if meta.get("version") != VERSION:
        raise CheckpointError(f"{path}: checkpoint version {meta.get('version')}, this ddpy "
                              f"reads version {VERSION} only; run again without --restart")
    return meta, arrays


def state_arrays(state: Any, prefix: str = "state/") -> dict[str, NDArray]:
    """The array fields of a dataclass state (e.g. SolidState) under ``prefix`` + name."""
    out = {}
    for f in dataclasses.fields(state):
        value = getattr(state, f.name)
        if value is not None:
            out[prefix + f.name] = np.asarray(value)
    return out


def state_from_arrays(cls: type, arrays: Mapping[str, NDArray], prefix: str = "state/",
                      where: str = "checkpoint") -> Any:
    """Rebuild a dataclass state of type ``cls`` from :func:`state_arrays`' output. Fields
    with a default may be missing (None is stored as missing); others must be there."""
    values: dict[str, Any] = {}
    names = {f.name for f in dataclasses.fields(cls)}
    extra = sorted(k[len(prefix):] for k in arrays if k.startswith(prefix)
                   and k[len(prefix):] not in names)
    if extra:
        raise CheckpointError(f"{where}: {cls.__name__} has no fields {extra} (written by "
                              "another version of ddpy)")
    for f in dataclasses.fields(cls):
        key = prefix + f.name
        if key in arrays:
            values[f.name] = np.array(arrays[key])
        elif (f.default is dataclasses.MISSING
              and f.default_factory is dataclasses.MISSING):  # type: ignore[misc]
            raise CheckpointError(f"{where}: {cls.__name__} field {f.name!r} is missing "
                                  "(written by another version of ddpy)")
    return cls(**values)


def forming_state_arrays(state: FormingState) -> dict[str, NDArray]:
    """The arrays of a forming problem's state, each under its place in a checkpoint."""
    out: dict[str, NDArray] = {}
    for f in dataclasses.fields(state):
        value = getattr(state, f.name)
        if isinstance(value, SolidState):
            out.update(state_arrays(value, "state/"))
        elif isinstance(value, dict):
            out.update({f"position/{name}": np.asarray(p) for name, p in value.items()})
        else:
            out[f"forming/{f.name}"] = np.asarray(value)
    return out


def forming_state_from_arrays(arrays: Mapping[str, NDArray], tools: list[str],
                              where: str = "checkpoint") -> FormingState:
    """The forming state of :func:`forming_state_arrays`' output, with the positions of
    ``tools``; CheckpointError naming ``where`` and the entry when one is missing."""
    values: dict[str, Any] = {}
    for f in dataclasses.fields(FormingState):
        if f.name == "solid":
            values[f.name] = state_from_arrays(SolidState, arrays, "state/", where)
            continue
        keys = [f"position/{name}" for name in tools] if f.name == "positions" else \
            [f"forming/{f.name}"]
        missing = [k for k in keys if k not in arrays]
        if missing:
            raise CheckpointError(f"{where}: the entry '{missing[0]}' is missing; run again "
                                  "without --restart")
        values[f.name] = ({name: np.array(arrays[k]) for name, k in zip(tools, keys,
                                                                         strict=True)}
                          if f.name == "positions" else np.array(arrays[keys[0]]))
    return FormingState(**values)
