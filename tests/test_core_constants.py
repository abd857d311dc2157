"""Python's view of the counts, codes and indices it shares with the core, held against the
core's own (``core_constants``, fortran/api/ddpy_api.f90): the codes the Python modules use
are the core's, the sizes the doorway's signature file (fortran/ddpy_core.pyf) writes as
numbers are the core's, and every code of one kind is distinct."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import ddpy.core.linalg as linalg
import ddpy.geometry.search as search
import ddpy.model.contact as contact
import ddpy.model.material as material
import ddpy.model.newton as newton
import ddpy.model.solid as solid
from ddpy.core.constants import CORE, constant, core_constants

PYF = Path(__file__).resolve().parents[1] / "fortran" / "ddpy_core.pyf"


def test_the_python_modules_use_the_cores_codes() -> None:
    assert [newton.CONVERGED, newton.LANDING, newton.ELEMENT, newton.NOT_FINITE,
            newton.SOLVER, newton.STALLED, newton.HOLD] == [
        CORE[f"outcome_{name}"] for name in
        ("converged", "landing", "element", "not_finite", "solver", "stalled", "hold")]
    assert [newton.SEARCH_NONE, newton.SEARCH_MONOTONICITY, newton.SEARCH_ENERGY] == [
        CORE["line_search_none"], CORE["line_search_monotonicity"],
        CORE["line_search_energy"]]
    assert newton.SURFACE_CODES == {name: CORE[f"discretization_{name}"]
                                    for name in ("node", "surface", "gauss")}
    assert [contact.INACTIVE, contact.STICK, contact.SLIP] == [
        CORE["contact_open"], CORE["contact_stick"], CORE["contact_slip"]]
    assert [search.NONE, search.INSIDE, search.EDGE] == [
        CORE["projection_none"], CORE["projection_inside"], CORE["projection_edge"]]
    assert solid.ELEMENTS == {"hexahedron": CORE["element_hexahedron"],
                              "solid-shell": CORE["element_solid_shell"]}
    assert solid.SHELL_MODES == CORE["shell_modes"]
    assert material.PROP_COUNT == CORE["material_prop_count"]
    assert material.TABLE_MAX_POINTS == CORE["material_table_max_points"]
    assert material.KINEMATIC_OFFSET == CORE["material_kinematic_offset"]
    assert [material.YOUNG_OFFSET, material.POISSON_OFFSET, material.HILL_OFFSET,
            material.LAW_OFFSET, material.HARDENING_OFFSET] == [
        CORE[f"material_{name}_offset"] for name in
        ("young", "poisson", "hill", "law", "hardening")]
    assert [material.Swift.law, material.Voce.law, material.HardeningTable.law] == [
        CORE["hardening_swift"], CORE["hardening_voce"], CORE["hardening_table"]]
    # every status the solver and the elements report has its message
    assert {CORE[name] for name in CORE if name.startswith("solver_")
            and name not in ("solver_info_values", "solver_flops")} <= set(linalg._MESSAGES)
    # every statistic of solver_info is read where the core puts it
    assert linalg._INFO == {name[5:-7]: value for name, value in CORE.items()
                            if name.startswith("info_") and name != "info_infog2_offset"}
    assert sorted(linalg._FLOPS.values()) == list(range(CORE["solver_flops"]))
    assert {CORE[name] for name in CORE if name.startswith("element_")
            and name not in ("element_hexahedron", "element_solid_shell", "element_ok")
            } <= set(solid._STATUS)


def test_the_signature_files_sizes_are_the_cores() -> None:
    """The numbers the .pyf writes in its array sizes: the material vector, the solid-shell's
    enhanced parameters, the strides of Bezier and Nagata patches, the solver's statistics,
    the history's width, the names' length."""
    text = PYF.read_text()

    def sizes(name: str, routine: str) -> set[int]:
        body = re.search(rf"subroutine {routine}\(.*?end subroutine {routine}", text, re.S)
        assert body, routine
        return {int(n) for n in re.findall(rf"dimension\((\d+)\*?\w*\)[^\n]*:: {name}\b",
                                           body.group(0))}

    props = constant("material_prop_count")
    for routine in ("blank_create", "material_update", "material_update_mixed",
                    "material_hardening", "material_check", "yield_landing"):
        assert sizes("props", routine) == {props}, routine
    assert sizes("alpha_in", "solid_assemble") == sizes("alpha", "solid_assemble") == {
        constant("shell_modes")}
    assert sizes("coef", "bezier_power_coefficients") == {constant("bezier_stride")}
    assert sizes("coef", "nagata_evaluate") == {constant("nagata_stride")}
    assert sizes("values", "solver_info") == {constant("solver_info_values")}
    assert sizes("flops", "solver_info") == {constant("solver_flops")}
    assert sizes("history", "problem_history") == {constant("history_width")}
    width = sizes("names", "core_constants").pop()
    assert max(len(name) for name in CORE) < width  # no name cut to the width


@pytest.mark.parametrize("family", ["outcome_", "line_search_", "contact_", "discretization_",
                                    "projection_", "refusal_", "solver_", "hold_",
                                    "history_", "element_", "info_", "flops_"])
def test_the_codes_of_one_kind_are_distinct(family: str) -> None:
    codes = {name: value for name, value in CORE.items() if name.startswith(family)
             and not name.endswith(("_info_values", "_width", "_flops"))
             and name not in ("element_hexahedron", "element_solid_shell")}
    assert len(set(codes.values())) == len(codes), codes


def test_a_constant_the_core_lacks_is_named() -> None:
    assert core_constants() == dict(CORE)
    with pytest.raises(KeyError, match="no constant 'outcome_lost'"):
        constant("outcome_lost")
