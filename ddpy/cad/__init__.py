"""Tool models from CAD: STEP, IGES and BREP files read through gmsh's OpenCASCADE
(:mod:`ddpy.cad.read`) become Nagata, facet and Bezier tool files
(:mod:`ddpy.cad.build`), whose shape error against the CAD is measured by
:mod:`ddpy.cad.shape_error`."""

from ddpy.cad.build import ToolBuilder, build_tool_models
from ddpy.cad.geometry import closest_points
from ddpy.cad.read import CAD_SUFFIXES, CadError, gmsh_session, load_cad, quiet

__all__ = ["CAD_SUFFIXES", "CadError", "ToolBuilder", "build_tool_models", "closest_points",
           "gmsh_session", "load_cad", "quiet"]
