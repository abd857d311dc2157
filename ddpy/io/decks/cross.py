"""Checks across the decks and the build of the validated :class:`ddpy.io.case.Case`: the tools of
the phases and their motions (control.dat against tools.dat and the mesh), the node sets and
constraints of bc.dat on the mesh, springback constraints, augmentation against the blank.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy.io.case import (
    BlankMaterial,
    BoundaryConditions,
    Case,
    Constraint,
    Control,
    HoldForce,
    HoldGap,
    Move,
    NodeSet,
    Phase,
    Tool,
    blank_thickness,
    rigid_body_modes_free,
    summarize_alike,
)
from ddpy.io.decks.boundary import _BcDraft, _select
from ddpy.io.decks.control import (
    DEFAULT_INCREMENT_FRACTION,
    DEFAULT_OUTPUT_EVERY,
    _ControlDraft,
    _PhaseDraft,
)
from ddpy.io.decks.lines import NAME_PATTERN, Deck, guard
from ddpy.io.decks.tools import _ToolDraft
from ddpy.model.control import IncrementLimits, NewtonSettings, check_max_increment
from ddpy.model.forming import blank_stiffness
from ddpy.model.mesh import HEX_EDGES, HexMesh
from ddpy.model.tool import BARRIER_DEPTH


class _Cross:
    """Checks across decks and the build of the Case."""

    def __init__(self, decks: dict[str, Deck], folder: Path) -> None:
        self.decks = decks
        self.folder = folder
        self.control = decks["control.dat"]
        self.bc = decks["bc.dat"]
        self.tools_deck = decks["tools.dat"]
        self.mesh_deck = decks["mesh.dat"]
        #: Forming phases whose max_increment exceeds the lead tool's travel: (line of
        #: max_increment, phase, max_increment, travel, lead tool), warned about together.
        self.long_increments: list[tuple[int | None, str, float, float, str]] = []

    def build(self, control: _ControlDraft, mesh: HexMesh, mesh_sets: dict[str, NDArray[np.int64]],
              bc: _BcDraft, material: BlankMaterial, tool_drafts: list[_ToolDraft]
              ) -> Case | None:
        tools = self._tools(tool_drafts, mesh)
        phases = self._phases(control, {t.name: t for t in tools}, mesh)
        boundary = self._boundary(bc, mesh, mesh_sets, [p.name for p in control.phases])
        if any(d.errors for d in self.decks.values()) or boundary is None:
            return None
        self._springback_constraints(phases, control, boundary, mesh)
        used = {name for p in phases for name in p.tools}
        # Only a tool that sets its augmentation needs the blank's stiffness to compare it with.
        stiffness = blank_stiffness(mesh.nodes, mesh.elements, material.material.E) \
            if mesh.elements.size and any("augmentation" in d.values for d in tool_drafts) \
            else 0.0
        for t, draft in zip(tools, tool_drafts, strict=True):
            if t.name not in used:
                self.tools_deck.warn(draft.line, f"tool '{t.name}' is active in no phase")
            r = draft.values.get("augmentation")
            if r is not None and stiffness > 0.0 and not 1e-3 <= r / stiffness <= 1e3:
                self.tools_deck.warn(draft.seen["augmentation"], f"augmentation {r:g} N/mm is "
                                     f"{r / stiffness:.3g} times the blank's stiffness E t^2 / "
                                     f"h = {stiffness:.4g} N/mm (the default): far from it, "
                                     "contact states flip on tiny gaps or forces")
        title = control.title or self.folder.resolve().name
        warnings = tuple(w for d in self.decks.values() for w in d.warnings)
        return Case(self.folder, Control(title, tuple(phases), str(self.control.path),
                                         control.tuning), mesh,
                    boundary, material, tuple(tools), warnings)

    # tools ----------------------------------------------------------------------------------

    def _tools(self, drafts: list[_ToolDraft], mesh: HexMesh) -> list[Tool]:
        tools = []
        normal = np.array(mesh.normal)
        for d in drafts:
            side, facing = d.values["contact"]
            if side == "top":
                facing = tuple(normal)
            elif side == "bottom":
                facing = tuple(-normal)
            tool = Tool(d.name, d.values["description"], d.values["file"],
                        d.values["friction"], side if side != "facing" else
                        "surface facing (" + ", ".join(f"{c:.3g}" for c in facing) + ")",
                        facing, d.values.get("augmentation"), self.tools_deck.where(d.line),
                        d.values.get("discretization", "gauss"), d.values.get("penalty"),
                        d.values.get("points"), d.values.get("barrier", BARRIER_DEPTH))
            if d.model is not None:
                object.__setattr__(tool, "_model", d.model)
            if tool.contact_nodes(mesh).size == 0:
                self.tools_deck.error(d.seen["contact"], f"tool '{d.name}' has no contact "
                                      f"partner: no boundary face of the blank faces "
                                      f"({', '.join(f'{c:.3g}' for c in facing)})")
            tools.append(tool)
        return tools

    # phases ---------------------------------------------------------------------------------

    def _phases(self, control: _ControlDraft, tools: dict[str, Tool], mesh: HexMesh
                ) -> list[Phase]:
        deck = self.control
        names: dict[str, int] = {}
        phases = []
        thickness = blank_thickness(mesh)
        for p in control.phases:
            if p.name in names:
                deck.error(p.line, f"phase '{p.name}' defined twice (first at line "
                           f"{names[p.name]})")
                continue
            names[p.name] = p.line
            # The first phase of the deck, not the first one read without an error: a
            # forming phase with an error is not followed by a second one about springback.
            if p is control.phases[0] and p.kind == "springback":
                deck.error(p.line, f"the first phase '{p.name}' is a springback phase: there is "
                           "nothing to release yet (expected a forming phase first)")
                continue
            phase = (self._springback(p, control) if p.kind == "springback"
                     else self._forming(p, control, tools, thickness))
            if phase is not None:
                phases.append(phase)
        deck.warnings += summarize_alike(
            [f"{deck.where(line)}: phase '{name}': max_increment {largest:g} mm exceeds the "
             f"travel {travel:g} mm of the lead tool '{lead}'"
             for line, name, largest, travel, lead in self.long_increments],
            "phases whose max_increment exceeds their lead tool's travel")
        return phases

    def _setting(self, p: _PhaseDraft, control: _ControlDraft, key: str, default: Any) -> Any:
        if key in p.settings:
            return p.settings[key][0]
        if key in control.settings:
            return control.settings[key][0]
        return default

    def _common(self, p: _PhaseDraft, control: _ControlDraft) -> dict[str, Any]:
        s = lambda key, default: self._setting(p, control, key, default)  # noqa: E731
        r, n = IncrementLimits(), NewtonSettings()
        contact = s("rmin_contact", r.first_touch)
        return dict(
            limits=IncrementLimits(
                strain=s("rmin_strain", r.strain), rotation_deg=s("rmin_rotation", r.rotation_deg),
                yield_tolerance=s("rmin_yield", r.yield_tolerance), first_touch=contact,
                touch=s("rmin_touch", r.touch),
                release=r.release if contact else None,
                release_share=s("rmin_release", r.release_share),
                release_redos=s("rmin_release_redos", r.release_redos)),
            newton=NewtonSettings(s("newton_force", n.force_tolerance),
                                  s("newton_displacement", n.displacement_tolerance),
                                  s("max_iterations", n.max_iterations),
                                  s("cutback", n.cutback),
                                  s("penetration_limit", n.penetration),
                                  s("gauss_augmentation", n.augment)),
            output_every=s("output_every", DEFAULT_OUTPUT_EVERY),
            origin=self.control.where(p.line))

    def _springback(self, p: _PhaseDraft, control: _ControlDraft) -> Phase | None:
        deck = self.control
        wrong = [k for k in ("tools", "move", "gap", "lead", "output_at") if k in p.seen]
        wrong += [k for k in ("max_increment", "min_increment") if k in p.settings]
        lines = [p.seen.get(k) or p.settings[k][1] for k in wrong]
        if p.moves:
            wrong.append("move")
            lines.append(p.moves[0][2])
        if p.gaps:
            wrong.append("gap")
            lines.append(p.gaps[0][3])
        if p.forces:
            wrong.append("force")
            lines.append(p.forces[0][3])
        if wrong:
            deck.error(lines[0], f"phase '{p.name}' is a springback phase: the tools are removed,"
                       f" so '{wrong[0]}' does not apply (expected only 'increments' and solver "
                       "settings)")
            return None
        increments = p.increments[0] if p.increments else 1
        return Phase(p.name, "springback", increments=increments, **self._common(p, control))

    def _forming(self, p: _PhaseDraft, control: _ControlDraft, tools: dict[str, Tool],
                 thickness: float | None) -> Phase | None:
        deck = self.control
        errors_before = len(deck.errors)
        if p.increments is not None:
            deck.error(p.increments[1], f"'increments' applies to springback phases; phase "
                       f"'{p.name}' is a forming phase (its increments follow max_increment)")
        if not p.tools:
            deck.error(p.line, f"phase '{p.name}' has no active tool: expected 'tools TOOL...'")
            return None
        for name in p.tools:
            if name not in tools:
                deck.error(p.tools_line, f"unknown tool '{name}' in phase '{p.name}': tools.dat "
                           f"defines {', '.join(tools) or 'none'}")
        active = set(p.tools)
        motions: list[Move | HoldGap | HoldForce] = []
        moved: dict[str, int] = {}
        for tool, vector, line in p.moves:
            if self._motion_target(p, tool, line, active, tools, moved):
                motions.append(Move(tool, vector, deck.where(line)))
        for tool, other, gap, line in p.gaps:
            if not self._motion_target(p, tool, line, active, tools, moved):
                continue
            if other not in active:
                what = "an unknown tool" if other not in tools else "not active in the phase"
                deck.error(line, f"phase '{p.name}': gap partner '{other}' is {what}: expected "
                           f"one of the tools of the phase ({', '.join(p.tools)})")
                continue
            a, b = tools[tool].facing, tools[other].facing
            if float(np.dot(a, b)) > -0.5:
                deck.error(line, f"phase '{p.name}': '{tool}' and '{other}' touch the same side "
                           "of the blank: a gap is held between tools on opposite sides")
                continue
            if thickness is not None and gap < thickness * (1 - 1e-6):
                deck.error(line, f"phase '{p.name}': gap {gap:g} mm is smaller than the blank "
                           f"thickness {thickness:.4g} mm")
                continue
            motions.append(HoldGap(tool, other, gap, deck.where(line)))
        for tool, force, ramp, line in p.forces:
            if not self._motion_target(p, tool, line, active, tools, moved):
                continue
            if not any(tools[tool].facing):
                deck.error(line, f"phase '{p.name}': tool '{tool}' has no facing direction "
                           "(tools.dat contact): a force needs the axis it presses along")
                continue
            motions.append(HoldForce(tool, force, ramp, deck.where(line)))
        gaps = {m.tool: m.other for m in motions if isinstance(m, HoldGap)}
        for start in gaps:
            seen, tool = {start}, gaps[start]
            while tool in gaps:
                if tool in seen:
                    deck.error(moved[start], f"phase '{p.name}': the gaps of {sorted(seen)} "
                               "refer to each other in a loop: one of them must move or stay")
                    break
                seen.add(tool)
                tool = gaps[tool]
            else:
                continue
            break
        if len(deck.errors) > errors_before:
            return None
        moving = [m for m in motions if isinstance(m, Move) and m.travel > 0]
        if not moving:
            deck.error(p.line, f"phase '{p.name}' moves no tool: expected a 'move TOOL DX DY DZ' "
                       "with a non-zero displacement")
            return None
        if p.lead is not None:
            lead, line = p.lead
            if any(isinstance(m, HoldForce) and m.tool == lead for m in motions):
                deck.error(line, f"phase '{p.name}': lead tool '{lead}' is held under a force: "
                           "its travel is not known beforehand; expected a tool that moves "
                           f"({', '.join(m.tool for m in moving)})")
                return None
            if lead not in {m.tool for m in moving}:
                deck.error(line, f"phase '{p.name}': lead tool '{lead}' must be a tool that "
                           f"moves in the phase ({', '.join(m.tool for m in moving)})")
                return None
        else:
            lead = max(moving, key=lambda m: m.travel).tool
        travel = next(m.travel for m in moving if m.tool == lead)
        max_inc = self._setting(p, control, "max_increment",
                                travel * DEFAULT_INCREMENT_FRACTION)
        try:  # FormingProblem.run's check of the largest increment
            check_max_increment(max_inc, travel)
        except ValueError as error:
            deck.error(self._line_of(p, control, "max_increment") or p.line,
                       f"phase '{p.name}': lead tool '{lead}': {error}")
            return None
        min_inc = self._setting(p, control, "min_increment",
                                max_inc * IncrementLimits().min_fraction)
        line = self._line_of(p, control, "min_increment") or p.line
        try:  # the range of min / max is IncrementLimits' own check
            limits = replace(self._common(p, control)["limits"], min_fraction=min_inc / max_inc)
        except ValueError as error:
            deck.error(line, f"phase '{p.name}': min_increment {min_inc:g} mm over "
                       f"max_increment {max_inc:g} mm: {error}")
            return None
        if max_inc > travel:
            self.long_increments.append((self._line_of(p, control, "max_increment"), p.name,
                                         max_inc, travel, lead))
        output_at: tuple[float, ...] = ()
        if p.output_at is not None:
            values, line = p.output_at
            if values[-1] > travel * (1 + 1e-12):
                deck.error(line, f"phase '{p.name}': output_at {values[-1]:g} mm is beyond the "
                           f"travel {travel:g} mm of the lead tool '{lead}'")
                return None
            output_at = tuple(values)
        common = self._common(p, control)
        common["limits"] = limits
        return Phase(p.name, "forming", tuple(p.tools), tuple(motions), lead, max_inc, min_inc,
                     output_at=output_at, **common)

    def _motion_target(self, p: _PhaseDraft, tool: str, line: int, active: set[str],
                       tools: dict[str, Tool], moved: dict[str, int]) -> bool:
        deck = self.control
        if tool not in tools:
            deck.error(line, f"unknown tool '{tool}' in phase '{p.name}': tools.dat defines "
                       f"{', '.join(tools) or 'none'}")
            return False
        if tool not in active:
            deck.error(line, f"phase '{p.name}' moves tool '{tool}', which is not active in it: "
                       f"add it to 'tools' (now: {', '.join(p.tools)})")
            return False
        if tool in moved:
            deck.error(line, f"phase '{p.name}': tool '{tool}' already has a motion at line "
                       f"{moved[tool]} (expected one 'move', 'gap' or 'force' per tool)")
            return False
        moved[tool] = line
        return True

    @staticmethod
    def _line_of(p: _PhaseDraft, control: _ControlDraft, key: str) -> int | None:
        if key in p.settings:
            return p.settings[key][1]
        if key in control.settings:
            return control.settings[key][1]
        return None

    # boundary conditions --------------------------------------------------------------------

    def _boundary(self, bc: _BcDraft, mesh: HexMesh, mesh_sets: dict[str, NDArray[np.int64]],
                  phase_names: list[str]) -> BoundaryConditions | None:
        deck = self.bc
        tol = bc.tolerance[0] if bc.tolerance else 1e-4
        x = mesh.nodes
        if bc.tolerance and mesh.elements.size:
            # A tolerance that reaches the next row of nodes selects it too (100 mm fixed
            # every node of a blank).
            pairs = HEX_EDGES.reshape(-1, 2)
            edges = np.linalg.norm(x[mesh.elements[:, pairs[:, 0]]]
                                   - x[mesh.elements[:, pairs[:, 1]]], axis=2)
            shortest = float(edges.min())
            if tol >= 0.5 * shortest:
                deck.error(bc.tolerance[1], f"tolerance {tol:g} mm is not below half the "
                           f"shortest element edge ({shortest:.3g} mm): a plane or box would "
                           "also select the next row of nodes")
                return None
        sets: dict[str, NodeSet] = {}
        lines: dict[str, int] = {}
        for name, nodes in mesh_sets.items():
            sets[name] = NodeSet(name, nodes, f"{mesh.source} (node set of the mesh file)")
        for name, kind, args, line in bc.nodesets:
            if name in sets:
                first = f"line {lines[name]}" if name in lines else sets[name].origin
                deck.error(line, f"node set '{name}' defined twice (first at {first})")
                continue
            lines[name] = line
            selected = guard(deck, line, lambda k=kind, a=args: _select(k, a, mesh, tol))
            if selected is None:
                continue
            if selected.size == 0:
                deck.error(line, f"node set '{name}' ({kind} {' '.join(args)}) selects no node "
                           f"of the mesh (tolerance {tol:g} mm)")
                continue
            sets[name] = NodeSet(name, selected, deck.where(line))
        constraints = []
        for axis, target, line in bc.symmetries:
            if NAME_PATTERN.fullmatch(target):
                if target not in sets:
                    self._unknown_set(line, target, sets)
                    continue
                nodes, label = sets[target].nodes, f"symmetry {'xyz'[axis]} on {target}"
            else:
                value = float(target)
                nodes = np.flatnonzero(np.abs(x[:, axis] - value) <= tol)
                label = f"symmetry {'xyz'[axis]} = {value:g}"
                if nodes.size == 0:
                    deck.error(line, f"symmetry plane {'xyz'[axis]} = {value:g} holds no node of "
                               f"the mesh (tolerance {tol:g} mm; the blank spans "
                               f"{x[:, axis].min():.4g} to {x[:, axis].max():.4g})")
                    continue
            constraints.append(Constraint(label, nodes, (axis,), (), deck.where(line),
                                          symmetry=True))
        for name, comps, phases, line in bc.fixes:
            if name not in sets:
                self._unknown_set(line, name, sets)
                continue
            unknown = [q for q in phases if q not in phase_names]
            if unknown:
                deck.error(line, f"unknown phase '{unknown[0]}': control.dat defines "
                           f"{', '.join(phase_names)}")
                continue
            label = f"fix {name} {''.join('xyz'[c] for c in comps)}"
            constraints.append(Constraint(label, sets[name].nodes, comps, tuple(phases),
                                          deck.where(line)))
        if deck.errors:
            return None
        return BoundaryConditions(sets, tuple(constraints), tol)

    def _unknown_set(self, line: int, name: str, sets: dict[str, NodeSet]) -> None:
        known = ", ".join(sorted(sets)) or "none"
        self.bc.error(line, f"unknown node set '{name}': expected one defined by 'nodeset' "
                      f"before it or in the mesh file (known: {known})")

    def _springback_constraints(self, phases: list[Phase], control: _ControlDraft,
                                boundary: BoundaryConditions, mesh: HexMesh) -> None:
        for p in phases:
            if not p.is_springback:
                continue
            free = rigid_body_modes_free(mesh.nodes, boundary.dofs(p.name))
            if free:
                line = next(d.line for d in control.phases if d.name == p.name)
                self.control.error(line, f"springback phase '{p.name}' removes the tools, and the "
                                   f"constraints of bc.dat leave rigid-body motion free ("
                                   f"{', '.join(free)}): fix more components in that phase, "
                                   f"e.g. 'fix NODESET COMPONENTS phase {p.name}'")
