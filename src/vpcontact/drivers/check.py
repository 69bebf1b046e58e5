"""``vpcontact check CASE``: a case validated without solving, and a description of what would run.

:func:`check_case` does what ``vpcontact run`` does before its first step, and so refuses a case with
the same CaseError: the case is built into its problem (mesh, materials, assembly, loads at every step
time, contact surface, initial state: :func:`~vpcontact.problem.build.build_problem`), an adaptive run's first
mesh is checked against ``adapt.max_dofs``, and the run's plan is made (:mod:`vpcontact.timeloop.plan`: the memory
of the outputs, the augmentation r, the method ``solver.method = "auto"`` chooses and its memory, the time
estimate), the one the time loop of ``vpcontact run`` makes and runs by, and the MPI ranks the case wants for the
memory of machines like this one (:mod:`vpcontact.solvers.ranks_wanted`). What it skips: the step solver's setup,
i.e. the factorization of the stiffness (PARDISO's own estimate of its factor's memory comes from the analysis
that precedes it), the condensed operator and the multigrid hierarchy — the costly part of a run's setup, which the
cost model (:mod:`vpcontact.solvers.cost`) predicts instead, for every method. Nothing is written.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, make_dataclass

import numpy as np

from ..case.model import Case
from ..case.translate import translate
from ..mesh.cells import SIMPLICES
from ..mesh.quality import mean_ratio, smallest_angles
from ..mesh.simplex import longest_edges
from ..problem.build import build_problem
from ..progress import duration, size
from ..solvers.cost import iterative_memory, matrix_bytes
from ..solvers.ranks_wanted import ranks_wanted
from ..timeloop.state import element_history_bytes
from ..timeloop.plan import RunPlan, free_operators, plan_run

#: A boundary part: its name and its numbers of facets and nodes.
Part = make_dataclass("Part", [("name", str), ("facets", int), ("nodes", int)], frozen=True)
#: A region of the mesh (a group of elements), its number of elements and the material keys its elements have.
Region = make_dataclass("Region", [("name", str), ("elements", int), ("material", str)], frozen=True)


@dataclass(frozen=True)
class Material:
    """A material entry of the case (``key``: "material" or "material[i]") and the elements it covers."""

    key: str
    regions: list[str]  # empty: the whole body
    elements: int
    E: float | str  # a number, or an expression in the coordinates
    nu: float | str
    viscoplastic: str | None  # the law's name; None: linear elasticity


@dataclass(frozen=True)
class CaseCheck(RunPlan):
    """What a run of the case would be: the plan of its run (:class:`~vpcontact.timeloop.plan.RunPlan`: sizes,
    time grid, method, memory, time), and its mesh and materials: ``quality_*`` the mean ratio of
    :mod:`vpcontact.mesh.quality`, ``smallest_angle_degrees`` (2D only), ``h_*`` the smallest and largest longest
    edge of an element, the boundary parts, the regions, the material entries and the contact nodes of each part
    of the contact."""

    quality_min: float
    quality_median: float
    smallest_angle_degrees: float | None  # 2D only
    h_min: float
    h_max: float
    parts: list[Part]
    regions: list[Region]
    materials: list[Material]
    contact_nodes_by_part: dict[str, int]
    ranks_wanted: int | None  # the MPI ranks whose memory holds the run, one a machine like this one (None: none)
    ranks_reason: str

    def as_dict(self) -> dict:
        """Plain JSON values (``vpcontact check --json``)."""
        return asdict(self)

    def lines(self) -> list[str]:
        """The description as lines of text (``vpcontact check``)."""
        elements = SIMPLICES[self.dim].plural
        angle = f", smallest angle {self.smallest_angle_degrees:.1f}°" if self.smallest_angle_degrees is not None else ""
        lines = [f"{self.dim}D body: {self.nodes:,} nodes, {self.elements:,} {elements}, {self.dofs:,} dofs "
                 f"({self.free_dofs:,} free)",
                 f"element quality (mean ratio, 1 = equilateral): min {self.quality_min:.3f}, median "
                 f"{self.quality_median:.3f}{angle}; element size (longest edge) {self.h_min:.3g} to {self.h_max:.3g}",
                 "parts: " + ", ".join(f"{p.name} ({p.facets:,} facets, {p.nodes:,} nodes)" for p in self.parts)]
        if self.regions:
            lines.append("regions: " + ", ".join(f"{r.name} ({r.elements:,} {elements}: {r.material})"
                                                 for r in self.regions))
        for m in self.materials:
            where = f"regions {', '.join(m.regions)}" if m.regions else "the whole body"
            law = f"viscoplastic ({m.viscoplastic})" if m.viscoplastic else "elastic"
            lines.append(f"{m.key}: E = {m.E}, nu = {m.nu}, {law}, on {where} ({m.elements:,} {elements})")
        if self.contact_nodes:
            lines.append(f"contact: {self.contact_nodes:,} nodes (" +
                         ", ".join(f"{part}: {count:,}" for part, count in self.contact_nodes_by_part.items()) + ")")
        else:
            lines.append("contact: none")
        lines.append(f"time: {self.steps:,} steps of k = {self.k:.6g} from t = {self.start:g} to T = {self.T:g}; "
                     f"fields written at {self.field_steps:,} steps")
        lines.append(f"method: {self.method} ({self.method_reason})")
        for name, cost in sorted(self.predicted.items(), key=lambda item: item[1]["total_s"]):
            lines.append(f"  {name}: " + (f"set-up {duration(cost['setup_s'])} + time loop {duration(cost['loop_s'])} "
                                          f"= {duration(cost['total_s'])}, peak {size(cost['memory_bytes'])}"
                                          if cost["fits"] else "does not fit in the memory available"))
        outputs = {part: nbytes for part, nbytes in self.memory_bytes.items() if part != "solver"}
        solver = self.memory_bytes["solver"]
        lines.append(f"memory: outputs {size(sum(outputs.values()))} (" +
                     ", ".join(f"{part} {size(nbytes)}" for part, nbytes in outputs.items()) + "), solver " +
                     (f"{size(solver)}" if solver is not None else "not estimated") +
                     f"; peak about {size(self.memory_peak_bytes)} of {size(self.memory_available_bytes)} available")
        lines.append(f"ranks: {self.ranks_reason}")
        t = self.time_seconds
        lines.append(f"time: about {duration(t['total'])} (build {duration(t['build'])}, measured; solver setup "
                     f"{duration(t['solver setup'])} and time loop {duration(t['time loop'])}, predicted)")
        return lines


def check_case(case: Case) -> CaseCheck:
    """Build the problem of ``case``, make every check ``vpcontact run`` makes before its first step except
    the step solver's setup (CaseError as there), and describe what would run."""
    options = translate(case)
    problem = build_problem(options.problem)
    if options.adapt is not None:
        from ..adaptivity.cycles import check_start

        check_start(problem, options.adapt)
    A, N = free_operators(problem)
    plan = plan_run(problem, options.output, A, N)
    elements = problem.mesh.mesh.t.shape[1]
    # on ranks, each holds its rows of the stiffness (as assembled, and on the free dofs) and of the solver's algebra
    shared = (iterative_memory(A) + matrix_bytes(problem.A) + matrix_bytes(A) +
              (element_history_bytes(elements, problem.mesh.dim) if plan.history else 0))
    wanted = ranks_wanted(plan.predicted["iterative"]["memory_bytes"] - shared + sum(
        nbytes for part, nbytes in plan.memory_bytes.items() if part != "solver" and nbytes), shared,
        plan.memory_available_bytes, os.cpu_count() or 1)
    mesh, surface = problem.mesh, problem.surface
    points, cells = mesh.mesh.p, mesh.mesh.t
    quality = mean_ratio(points, cells)
    sizes = longest_edges(points, cells)
    counts = np.bincount(surface.owner, minlength=len(surface.parts)) if surface.size else []
    return CaseCheck(
        **vars(plan), quality_min=float(quality.min()), quality_median=float(np.median(quality)),
        smallest_angle_degrees=float(np.degrees(smallest_angles(points, cells).min())) if mesh.dim == 2 else None,
        h_min=float(sizes.min()), h_max=float(sizes.max()),
        parts=[Part(name, mesh.facets(name).size, mesh.nodes(name).size) for name in mesh.part_names],
        regions=_regions(case, mesh, problem.materials.owner), materials=_materials(case, problem.materials.owner),
        contact_nodes_by_part=dict(zip(surface.parts, map(int, counts))), ranks_wanted=wanted.ranks,
        ranks_reason=wanted.reason)


def _materials(case: Case, owner: np.ndarray) -> list[Material]:
    """The case's material entries with the number of elements each covers."""
    covered = np.bincount(owner, minlength=len(case.keyed_materials()))
    return [Material(key, entry.regions, int(covered[i]), entry.E, entry.nu,
                     None if entry.viscoplastic is None else entry.viscoplastic.law)
            for i, (key, entry) in enumerate(case.keyed_materials())]


def _regions(case: Case, mesh, owner: np.ndarray) -> list[Region]:
    """The mesh's regions, each with the material keys of its elements (one, unless the entries name other
    regions that split it)."""
    keys = [key for key, _ in case.keyed_materials()]
    return [Region(name, elements.size, ", ".join(keys[i] for i in np.unique(owner[elements])))
            for name, elements in sorted(mesh.regions.items())]
