"""From the options of a case and a mesh to the discrete problem: spaces, operators, loads and the contact law.

Everything that can fail on user input (mesh file, part names, rigid motions left free, loads that
are not finite at a time step, outputs that would not fit in memory, Python objects of the API that
are not laws) fails here, before any computation and before anything is written.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .. import mesh as meshes
from ..errors import CaseError, brief
from ..expressions.parse import parse_expression
from ..fem.assembly import Density, LoadVector, displacement_space, element_strain, stiffness
from ..fem.contact_surface import ContactSurface, contact_surface, empty_surface
from ..fem.space import DisplacementSpace
from ..laws.compliance.positive_part import PositivePart
from ..laws.contact import ContactLaw
from ..laws.stiffness.constant import ConstantStiffness
from ..laws.elasticity import Elasticity
from ..laws.materials import Materials, body_materials
from ..laws.python_laws import api_law, api_viscoplastic
from ..mesh.cells import SIMPLICES, coordinates
from ..parallel.partition import NodePartition
from ..parallel.ranks import ALONE, Ranks
from ..progress import SILENT, Progress
from ..solvers.factorization import check_installed
from ..solvers.linear import check_multigrid
from .constraints import DirichletConditions, dirichlet_conditions
from .checks import check_contact_can_move, check_dimension, check_first_history, check_rigid_motions
from .initial import InitialState, initial_state
from .layers import contact_law
from .loads import check_density_arguments, expression_density, traction_terms
from .options import MeshSource, ProblemOptions
from .time_grid import TimeGrid


@dataclass
class Problem:
    """The discrete problem of a case on a mesh: Problem P_V of the paper on P1 × P0 with node-to-rigid
    contact. ``options`` (:class:`~vpcontact.problem.options.ProblemOptions`) and ``objects`` (the Python objects
    that replace parts of them, see :func:`build_problem`) are what it was built from: :meth:`on` builds the same
    problem on another mesh."""

    options: ProblemOptions
    objects: dict  # the keyword arguments of build_problem that replace parts of the options
    mesh: meshes.Mesh
    basis: DisplacementSpace
    materials: Materials  # the material of each element, ℰ per element and the case's 𝒢
    A: sp.csr_matrix  # the elastic stiffness on all dofs (on MPI ranks, this rank's rows: those of its nodes)
    free: np.ndarray  # dofs not held by Dirichlet conditions
    loads: LoadVector
    surface: ContactSurface  # no nodes when the case has no contact
    law: ContactLaw
    probe: int | None  # index of the reported contact node
    viscoplastic: Callable | None = None  # 𝒢(σ, ε) over arrays (d, d, nelements); None: 𝒢 = 0
    timings: dict = field(default_factory=dict)  # seconds: mesh, assembly, build
    initial: InitialState | None = None  # u_0, σ_0, ξ_0 and t_0 (build_problem sets it)
    initial_strain: np.ndarray | None = None  # ε(u_0) per element (d, d, nelements)
    initial_history: np.ndarray | None = None  # z_0 = σ_0 − ℰε(u_0) of (2.28) per element (d, d, nelements)
    source: str | None = None  # the resolved case (TOML) it was built from, for case.resolved.toml and checkpoints
    constraints: DirichletConditions | None = None  # the held dofs and u_D(t) there (build_problem sets it)
    partition: NodePartition | None = None  # the nodes shared among MPI ranks (None: one process)
    times: TimeGrid = field(init=False)  # t_1, …, t_steps

    def __post_init__(self):
        start = 0.0 if self.initial is None else self.initial.start
        self.times = TimeGrid(self.options.time.T, self.options.time.steps, start)

    @property
    def elasticity(self) -> Elasticity:
        """ℰ of (2.1): E, ν numbers for one homogeneous material, arrays over the elements otherwise."""
        return self.materials.elasticity

    @property
    def ranks(self) -> Ranks:
        """The MPI ranks the problem is shared among (ALONE: one process)."""
        return ALONE if self.partition is None else self.partition.ranks

    @property
    def stiffness_entries(self) -> int:
        """The entries of the whole stiffness A, every rank's rows together (a collective call on MPI ranks)."""
        return int(self.ranks.sum(self.A.nnz))

    @property
    def k(self) -> float:
        """The time step (T − t_0) / steps."""
        return self.times.k

    @property
    def solver(self):
        """The options of the step solver (:class:`~vpcontact.problem.options.SolverOptions`)."""
        return self.options.solver

    def on(self, mesh: meshes.Mesh, progress: Progress = SILENT) -> "Problem":
        """The same problem on ``mesh`` (a refinement, with the same parts and regions): the options and the
        Python objects again, except arrays of an initial state, which belong to the mesh they were given on;
        ``progress`` hears of its assembly."""
        given = [name for name in INITIAL_ARRAYS if self.objects.get(name) is not None]
        if given:
            raise CaseError(f"{given[0]} is an array on the mesh the problem was built on: a problem with initial "
                            f"arrays cannot be built on another mesh; give the initial state by expressions instead")
        return build_problem(self.options, mesh=mesh, progress=progress, ranks=self.ranks, **self.objects)

    def __repr__(self) -> str:
        """One line: the sizes (not the operators)."""
        return (f"Problem(dofs={self.basis.N}, free_dofs={self.free.size}, elements={self.mesh.mesh.t.shape[1]}, "
                f"nodes={self.mesh.mesh.p.shape[1]}, contact_nodes={self.surface.size}, steps={len(self.times)}, "
                f"k={self.k:g})")


def checked_problem(problem) -> Problem:
    """``problem`` if it is a :class:`Problem`, else CaseError (a time loop or an adaptation given something else)."""
    if not isinstance(problem, Problem):
        raise CaseError(f"problem = {brief(problem)}: expected a vpcontact.Problem (vpcontact.compose or "
                        f"vpcontact.build_problem)")
    return problem


#: The keyword arguments of build_problem that are arrays on the mesh.
INITIAL_ARRAYS = ("initial_displacement", "initial_stress", "initial_xi")


def build_problem(options: ProblemOptions, *, mesh: meshes.Mesh | None = None, p: Callable | None = None,
                  stiffness_law: Callable | None = None, tractions: Mapping | None = None,
                  body_force: Density | None = None, displacements: Mapping | None = None,
                  viscoplastic: Callable | None = None, initial_displacement=None, initial_stress=None,
                  initial_xi=None, progress: Progress = SILENT, ranks: Ranks = ALONE) -> Problem:
    """Assemble the problem of ``options`` (a case translated by :mod:`vpcontact.case.translate`: from a
    :class:`~vpcontact.Case`, whose outputs and adaptive meshes are not part of the problem, or from a
    :class:`~vpcontact.Model`) on ``mesh``; the other keyword arguments replace parts of the case by Python objects:

    - ``mesh``: the mesh to solve on (:mod:`vpcontact.mesh`: a built-in shape or a file); by default the
      one the case's ``[mesh]`` makes (a Model has none: it needs one);

    - ``p``, ``stiffness_law``: the laws p(r) and K(ξ) of the contact, vectorized over NumPy arrays; an
      object with a ``derivative`` method is used as it is (see :mod:`vpcontact.laws.contact`), a plain
      function is wrapped in :class:`~vpcontact.laws.contact.CallableLaw` (central-difference derivative).
      A law of two arguments, p(r, x) or K(ξ, x) (and its derivative of the same two), gets x = the
      (d, m) coordinates of the contact nodes with r of shape (m,): a law that varies along Γ3. They
      replace the case's laws on every contact part;
    - ``tractions``: {part: f(x, y, t) -> (fx, fy)} (in 3D f(x, y, z, t) -> (fx, fy, fz)): f replaces the
      case's traction on that part (the case's tractions on other parts stay);
    - ``body_force``: f(x, y, t) -> (fx, fy) (in 3D f(x, y, z, t) -> (fx, fy, fz)) replaces the case's
      body forces;
    - ``displacements``: {part: {component: f(x, y, (z,) t)}}: f gives the prescribed displacement u_D of that
      component on that part (an entry of the case's boundary.dirichlet must hold it), at the part's nodes
      (:mod:`vpcontact.problem.constraints`);
    - ``viscoplastic``: 𝒢(σ, ε) of (2.1), vectorized over element arrays of shape (d, d, nelements), or
      𝒢(σ, ε, x) with x the element centroids (d, nelements) (𝒢(x, σ, ε) of (2.17)); it replaces the
      viscoplastic laws of the case's materials, in every region;
    - ``initial_displacement`` (nodes, d), ``initial_stress`` (elements, d, d) or (d, d) (uniform),
      ``initial_xi`` (contact nodes,): arrays of the initial state u_0, σ_0, ξ_0 that replace the case's
      (``initial.*``, see :mod:`vpcontact.problem.initial`; checked alike: shapes, finite, u_0 in V and admissible
      on Γ3, ξ_0 ≥ 0).

    Each is tried before the run (a law at 0 and 10⁻³ (at every contact node for a law of x), a load at
    every step time, 𝒢 at (σ_0, ε(u_0))): one that is not callable, takes other arguments, returns the wrong
    shape or a value that is not finite is a CaseError.

    ``progress`` (:mod:`vpcontact.progress`) hears of the two phases: the mesh (when made here) and the assembly
    (the operators, the loads, the contact surface and every check above).

    On several MPI ranks (``ranks``, :mod:`vpcontact.parallel`), every rank builds the problem: the mesh's nodes
    are partitioned among them (METIS), and each rank assembles only its rows of the stiffness A, from the elements
    that touch its nodes; the rest (mesh, loads, contact surface, checks) is whole on every rank."""
    started = time.perf_counter()
    objects = {name: value for name, value in dict(
        p=p, stiffness_law=stiffness_law, tractions=tractions, body_force=body_force, displacements=displacements,
        viscoplastic=viscoplastic,
        initial_displacement=initial_displacement, initial_stress=initial_stress, initial_xi=initial_xi).items()
        if value is not None}
    check_installed(options.solver.factorization)
    check_multigrid(options.solver.multigrid)
    if mesh is not None and not isinstance(mesh, meshes.Mesh):
        raise CaseError(f"mesh = {brief(mesh)}: expected a vpcontact.mesh.Mesh (vpcontact.mesh.half_disc, "
                        f"quarter_ball, rectangle, block or read_mesh)")
    source = options.source if mesh is None else None
    if mesh is None:
        if options.mesh is None:
            raise CaseError("a model without [mesh] needs a mesh: build_problem(model, mesh=...)")
        with progress.phase("mesh", mesh_words(options.mesh)) as phase:
            mesh = make_mesh(options.mesh)
            phase.done(_mesh_size(mesh))
    if options.contact is None and (p is not None or stiffness_law is not None):
        raise CaseError("p and stiffness_law are laws of the contact, and the case has no [contact]")
    p = None if p is None else api_law(p, "p")
    stiffness_law = None if stiffness_law is None else api_law(stiffness_law, "stiffness_law")
    meshed = time.perf_counter()
    with progress.phase("assembly", "stiffness, loads, contact surface and checks") as phase:
        partition = None if ranks.size == 1 else NodePartition.of(mesh.mesh.t, mesh.mesh.nvertices, ranks)
        problem = _assembled(options, mesh, p, stiffness_law, tractions, body_force, displacements, viscoplastic,
                             initial_displacement, initial_stress, initial_xi, partition)
        phase.done(f"{problem.free.size:,} free dofs of {problem.basis.N:,}, {problem.surface.size:,} contact nodes, "
                   f"a stiffness of {problem.stiffness_entries:,} entries{_shared(ranks)}")
    done = time.perf_counter()
    problem.objects, problem.source = objects, source
    problem.timings = {"mesh": meshed - started, "assembly": done - meshed, "build": done - started}
    return problem


def _assembled(options: ProblemOptions, mesh: meshes.Mesh, p, stiffness_law, tractions, body_force, displacements,
               viscoplastic, initial_displacement, initial_stress, initial_xi,
               partition: NodePartition | None) -> Problem:
    """The problem of ``options`` on ``mesh`` (the laws of the API already wrapped; see build_problem) with its
    nodes shared among MPI ranks by ``partition`` (None: one process), without its timings, the objects of the API
    and the source."""
    dim = mesh.dim
    check_dimension(options, dim)
    materials = body_materials(options.materials, mesh)
    with np.errstate(all="ignore"):  # a stiffness that is not finite is reported below
        basis = displacement_space(mesh)
        ranks = ALONE if partition is None else partition.ranks
        A = stiffness(basis, materials.elasticity, None if partition is None else partition.owner == ranks.rank)
    if not ranks.all(np.all(np.isfinite(A.data))):
        moduli = ", ".join(f"{entry.key}.E = {brief(entry.E)}" for entry in options.materials)
        raise CaseError(f"{moduli}: the stiffness matrix is not finite in float64 (the moduli or the sizes of the "
                        f"{SIMPLICES[dim].plural} are out of its range); state them in other units")

    constraints = dirichlet_conditions(options, mesh, basis.nodal_dofs, displacements)
    free = constraints.free

    body_terms = [(key, expression_density(f.value, key)) for key, f in
                  ((f"boundary.body_force[{i}].value", f) for i, f in enumerate(options.boundary.body_force))]
    if body_force is not None:
        check_density_arguments("body_force", body_force, mesh.dim)
        body_terms = [("body_force", body_force)]
    loads = LoadVector(basis, mesh, traction_terms(options, mesh, tractions), body_terms)

    surface, probe = empty_surface(basis.N, dim), None
    law = ContactLaw(PositivePart(), ConstantStiffness(0.0), np.inf)
    if options.contact is not None:
        c = options.contact
        gaps = [parse_expression(layer.gap, coordinates(dim), where=f"{layer.key}.gap") for layer in c.layers]
        surface = contact_surface(mesh, [layer.part for layer in c.layers], basis.nodal_dofs, gaps,
                                  None if c.normal == "body" else c.normal)
        law = contact_law(c, surface, p, stiffness_law)
        target = c.probe if c.probe is not None else surface.coordinates.mean(axis=1)
        probe = surface.nearest_node(target)
    check_contact_can_move(constraints, mesh, basis, surface)
    constraints.check_contact(surface.operator, mesh.mesh.p, surface.nodes)
    check_rigid_motions(mesh, basis, free, surface)

    initial = initial_state(options, mesh, basis, surface, law, constraints, displacement=initial_displacement,
                            stress=initial_stress, xi=initial_xi)
    strain0 = element_strain(basis, initial.dofs(basis))
    z0 = initial.stress - materials.elasticity.stress(strain0)
    law_name = "material.viscoplastic" if viscoplastic is None else "viscoplastic"
    if viscoplastic is None:
        viscoplastic = materials.viscoplastic
    else:
        viscoplastic = api_viscoplastic(viscoplastic, mesh)
    grid = TimeGrid(options.time.T, options.time.steps, initial.start)
    loads.check(grid)
    constraints.check(grid)
    check_first_history(basis, initial, options.initial.stress, strain0, z0, viscoplastic, law_name, grid.k)
    return Problem(options, {}, mesh, basis, materials, A, free, loads, surface, law, probe, viscoplastic,
                   initial=initial, initial_strain=strain0, initial_history=z0, constraints=constraints,
                   partition=partition)


def _shared(ranks: Ranks) -> str:
    """How the stiffness is shared among ``ranks``, in words ("" in one process)."""
    return "" if ranks.size == 1 else f", each of {ranks.size} MPI ranks assembling its rows"


def mesh_words(m: MeshSource) -> str:
    """The mesh a case's ``[mesh]`` makes, in words: "reading FILE", or the shape and its sizes."""
    if m.file is not None:
        return f"reading {m.file}"
    sizes = [f"{key} = {getattr(m, key):g}" for key in ("h", "h_bottom", "radius", "width", "depth", "height",
                                                         "coating") if getattr(m, key) is not None]
    return f"{m.shape.replace('_', ' ')}, {', '.join(sizes)}"


def _mesh_size(mesh: meshes.Mesh) -> str:
    """The sizes of a mesh, in words: nodes, elements, dofs."""
    nodes, elements = mesh.mesh.p.shape[1], mesh.mesh.t.shape[1]
    return f"{nodes:,} nodes, {elements:,} {SIMPLICES[mesh.dim].plural}, {mesh.dim * nodes:,} dofs"


def make_mesh(m: MeshSource) -> meshes.Mesh:
    """The mesh of a case's ``[mesh]``: a built-in shape, or a mesh file."""
    if m.path is not None:
        return meshes.read_mesh(m.path)
    if m.shape == "half_disc":
        return meshes.half_disc(m.h, m.radius, m.coating)
    if m.shape == "quarter_ball":
        return meshes.quarter_ball(m.h, m.radius, m.h_bottom, m.coating)
    if m.shape == "block":
        return meshes.block(m.width, m.depth, m.height, m.h)
    return meshes.rectangle(m.width, m.height, m.h)
