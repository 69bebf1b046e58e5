"""``vpcontact check CASE``: a case validated without solving, and a description of what would run.

:func:`check_case` does what ``vpcontact run`` does before its first step, and so refuses a case with
the same CaseError: the case is built into its problem (mesh, materials, assembly, loads at every step
time, contact surface, initial state, the memory of the outputs: :func:`~vpcontact.problem.build.build_problem`),
the method is chosen (``solver.method = "auto"``: :func:`~vpcontact.solvers.choice.chosen_method`), the
augmentation r and the chosen method's memory are checked, and an adaptive run's first mesh is checked
against ``adapt.max_dofs``. What it skips: the step solver's setup, i.e. the factorization of the stiffness
(PARDISO's own estimate of its factor's memory comes from the analysis that precedes it), the condensed
operator and the multigrid hierarchy — the costly part of a run's setup, which :mod:`vpcontact.solvers.time_estimate`
estimates instead. Nothing is written.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..case.schema import Case, _material_keys
from ..memory import available_memory
from ..mesh.quality import edge_lengths, mean_ratio, smallest_angles
from ..problem.build import build_problem
from ..results.footprint import check_memory, memory_needed
from ..results.steps import field_step_numbers
from ..solvers import augmentation_parameter
from ..solvers.choice import check_iterative_memory, chosen_method, iterative_memory
from ..solvers.condensed import check_condensed_memory, condensed_memory
from ..solvers.time_estimate import estimate_seconds


@dataclass(frozen=True)
class Part:
    """A boundary part: its name and its numbers of facets and nodes."""

    name: str
    facets: int
    nodes: int


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
class Region:
    """A region of the mesh (a group of elements), its size and the material key its elements have."""

    name: str
    elements: int
    material: str


@dataclass(frozen=True)
class CaseCheck:
    """What a run of the case would be (see the module's docstring). Sizes are counts; ``quality_*`` the mean
    ratio of :mod:`vpcontact.mesh.quality`; ``h_*`` the smallest and largest longest edge of an element;
    ``memory_bytes``: the outputs kept until written, by part (:func:`~vpcontact.results.footprint.memory_needed`:
    "history rows", "contact rows", "fields", "writing"), and the step method's own algebra ("solver": the
    condensed method's dense algebra or the iterative method's peak; None for the full method, not
    estimated); ``time_seconds``: "build" (mesh, assembly, checks) measured here, "solver setup", "time loop" and "total" estimated
    (:mod:`vpcontact.solvers.time_estimate`)."""

    dim: int
    nodes: int
    elements: int
    dofs: int
    free_dofs: int
    quality_min: float
    quality_median: float
    smallest_angle_degrees: float | None  # 2D only
    h_min: float
    h_max: float
    parts: list[Part]
    regions: list[Region]
    materials: list[Material]
    contact_nodes: int
    contact_nodes_by_part: dict[str, int]
    start: float
    T: float
    steps: int
    k: float
    field_steps: int
    method: str
    method_reason: str
    memory_bytes: dict[str, int | None]
    memory_available_bytes: int
    time_seconds: dict[str, float]

    def as_dict(self) -> dict:
        """Plain JSON values (``vpcontact check --json``)."""
        return asdict(self)


def check_case(case: Case) -> CaseCheck:
    """Build the problem of ``case``, make every check ``vpcontact run`` makes before its first step except
    the step solver's setup (CaseError as there), and describe what would run."""
    problem = build_problem(case)
    mesh, surface, free = problem.mesh, problem.surface, problem.free
    if case.adapt is not None:
        from ..estimate.adapt import check_start

        check_start(problem, case.adapt)
    A, N = problem.A[free][:, free].tocsr(), surface.operator[:, free].tocsr()
    augmentation_parameter(A, N, case.solver.augmentation)
    method, reason = chosen_method(case.solver.method, A, N, mesh.dim)
    solver_memory = None
    if method == "condensed":
        check_condensed_memory(N, A.shape[0])
        solver_memory = condensed_memory(N, A.shape[0])
    elif method == "iterative":
        check_iterative_memory(A)
        solver_memory = iterative_memory(A)

    points, cells = mesh.mesh.p, mesh.mesh.t
    quality = mean_ratio(points, cells)
    sizes = edge_lengths(points, cells).max(axis=0)
    history = problem.viscoplastic is not None or bool(np.any(problem.initial_history != 0.0))
    times = problem.times
    check_memory(len(times), case.output, points.shape[1], cells.shape[1], surface.size, history, mesh.dim)
    field_steps = len(field_step_numbers(case.output.field_steps, len(times)))
    outputs = memory_needed(len(times), field_steps, points.shape[1], cells.shape[1], surface.size, history, mesh.dim,
                            estimate=case.output.error_estimate)
    counts = np.bincount(surface.owner, minlength=len(surface.parts)) if surface.size else []
    return CaseCheck(
        dim=mesh.dim, nodes=points.shape[1], elements=cells.shape[1], dofs=int(problem.basis.N), free_dofs=free.size,
        quality_min=float(quality.min()), quality_median=float(np.median(quality)),
        smallest_angle_degrees=float(np.degrees(smallest_angles(points, cells).min())) if mesh.dim == 2 else None,
        h_min=float(sizes.min()), h_max=float(sizes.max()),
        parts=[Part(name, mesh.facets(name).size, mesh.nodes(name).size) for name in mesh.part_names],
        regions=_regions(case, mesh, problem.materials.owner), materials=_materials(case, problem.materials.owner),
        contact_nodes=surface.size, contact_nodes_by_part=dict(zip(surface.parts, map(int, counts))),
        start=float(times.start), T=float(times.T), steps=len(times), k=float(times.k), field_steps=field_steps,
        method=method, method_reason=reason,
        memory_bytes={**outputs, "solver": solver_memory},
        memory_available_bytes=available_memory(),
        time_seconds=estimate_seconds(method, mesh.dim, free.size, len(times), history, problem.timings["build"]))


def _materials(case: Case, owner: np.ndarray) -> list[Material]:
    """The case's material entries with the number of elements each covers."""
    covered = np.bincount(owner, minlength=len(_material_keys(case)))
    return [Material(key, entry.regions, int(covered[i]), entry.E, entry.nu,
                     None if entry.viscoplastic is None else entry.viscoplastic.law)
            for i, (key, entry) in enumerate(_material_keys(case))]


def _regions(case: Case, mesh, owner: np.ndarray) -> list[Region]:
    """The mesh's regions, each with the material keys of its elements (one, unless the entries name other
    regions that split it)."""
    keys = [key for key, _ in _material_keys(case)]
    return [Region(name, elements.size, ", ".join(keys[i] for i in np.unique(owner[elements])))
            for name, elements in sorted(mesh.regions.items())]
