"""From a model and a mesh to the discrete problem: spaces, operators, loads and the contact law.

Everything that can fail on user input (mesh file, part names, rigid motions left free, loads that
are not finite at a time step, outputs that would not fit in memory, Python objects of the API that
are not laws) fails here, before any computation and before anything is written.
"""

from __future__ import annotations

import inspect
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp
from skfem import Basis

from .. import mesh as meshes
from ..fem.assembly import (Density, ExpressionDensity, LoadVector, displacement_basis, element_strain, stiffness,
                       stress_force)
from ..case.schema import Case, MeshSection, Model, OutputSection, _brief, _material_keys, section
from ..laws.contact import (AtNodes, CallableLaw, ConstantStiffness, ContactLaw, ContactSurface, ExponentialStiffness,
                      PositivePart, Power, PowerStiffness, contact_surface, empty_surface, merged_law, per_node)
from ..errors import CaseError, point, quoted
from ..case.expressions import parse_expression, values_at
from .initial import InitialState, initial_state
from ..laws.elasticity import Elasticity
from ..laws.materials import AtCentroids, Materials, body_materials
from ..progress import SILENT, Progress
from ..fem.rigid_modes import RigidModes
from ..fem.space import component, coordinates
from ..mesh.cells import SIMPLICES
from .time_grid import TimeGrid




@dataclass
class Problem:
    """The discrete problem of a model on a mesh: Problem P_V of the paper on P1 × P0 with node-to-rigid
    contact. ``model`` and ``objects`` (the Python objects that replace parts of it, see
    :func:`build_problem`) are what it was built from: :meth:`on` builds the same problem on another mesh."""

    model: Model
    objects: dict  # the keyword arguments of build_problem that replace parts of the model
    mesh: meshes.Mesh
    basis: Basis
    materials: Materials  # the material of each element, ℰ per element and the case's 𝒢
    A: sp.csr_matrix  # the elastic stiffness on all dofs
    free: np.ndarray  # dofs not fixed by Dirichlet conditions
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
    times: TimeGrid = field(init=False)  # t_1, …, t_steps

    def __post_init__(self):
        start = 0.0 if self.initial is None else self.initial.start
        self.times = TimeGrid(self.model.time.T, self.model.time.steps, start)

    @property
    def elasticity(self) -> Elasticity:
        """ℰ of (2.1): E, ν numbers for one homogeneous material, arrays over the elements otherwise."""
        return self.materials.elasticity

    @property
    def k(self) -> float:
        """The time step (T − t_0) / steps."""
        return self.times.k

    @property
    def solver(self):
        """The options of the step solver (:class:`~vpcontact.case.schema.SolverSection`)."""
        return self.model.solver

    def on(self, mesh: meshes.Mesh, progress: Progress = SILENT) -> "Problem":
        """The same problem on ``mesh`` (a refinement, with the same parts and regions): the model and the
        Python objects again, except arrays of an initial state, which belong to the mesh they were given on;
        ``progress`` hears of its assembly."""
        given = [name for name in INITIAL_ARRAYS if self.objects.get(name) is not None]
        if given:
            raise CaseError(f"{given[0]} is an array on the mesh the problem was built on: a problem with initial "
                            f"arrays cannot be built on another mesh; give the initial state by expressions instead")
        return build_problem(self.model, mesh=mesh, progress=progress, **self.objects)

    def solve(self, *, output=None, progress: bool | Progress = False):
        """The :class:`~vpcontact.results.result.Result` of the time loop (:func:`~vpcontact.timeloop.loop.solve_problem`);
        ``output``: the ``[output]`` table (a dict, or an :class:`~vpcontact.case.schema.OutputSection`); ``progress``:
        True for lines on stderr (:mod:`vpcontact.progress`), or a reporter."""
        from ..timeloop.loop import solve_problem

        output = section(OutputSection, output, "output")
        return solve_problem(self, output=output, progress=progress)

    def __repr__(self) -> str:
        """One line: the sizes (not the operators)."""
        return (f"Problem(dofs={self.basis.N}, free_dofs={self.free.size}, elements={self.mesh.mesh.t.shape[1]}, "
                f"nodes={self.mesh.mesh.p.shape[1]}, contact_nodes={self.surface.size}, steps={len(self.times)}, "
                f"k={self.k:g})")


def checked_problem(problem) -> Problem:
    """``problem`` if it is a :class:`Problem`, else CaseError (a time loop or an adaptation given something else)."""
    if not isinstance(problem, Problem):
        raise CaseError(f"problem = {_brief(problem)}: expected a vpcontact.Problem (vpcontact.compose or "
                        f"vpcontact.build_problem)")
    return problem


#: The keyword arguments of build_problem that are arrays on the mesh.
INITIAL_ARRAYS = ("initial_displacement", "initial_stress", "initial_xi")


def build_problem(model: Model, *, mesh: meshes.Mesh | None = None, p: Callable | None = None,
                  stiffness_law: Callable | None = None, tractions: Mapping | None = None,
                  body_force: Density | None = None, viscoplastic: Callable | None = None, initial_displacement=None,
                  initial_stress=None, initial_xi=None, progress: Progress = SILENT) -> Problem:
    """Assemble the problem of ``model`` (a :class:`~vpcontact.model.Model`, or a whole
    :class:`~vpcontact.model.Case`, whose outputs and adaptive meshes are not part of the problem) on
    ``mesh``; the other keyword arguments replace parts of the model by Python objects:

    - ``mesh``: the mesh to solve on (:mod:`vpcontact.mesh`: a built-in shape or a file); by default the
      one the case's ``[mesh]`` makes (a Model without a mesh needs it);

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
    (the operators, the loads, the contact surface and every check above)."""
    started = time.perf_counter()
    objects = {name: value for name, value in dict(
        p=p, stiffness_law=stiffness_law, tractions=tractions, body_force=body_force, viscoplastic=viscoplastic,
        initial_displacement=initial_displacement, initial_stress=initial_stress, initial_xi=initial_xi).items()
        if value is not None}
    if not isinstance(model, Model):
        raise CaseError(f"build_problem: {_brief(model)} is not a model: expected a vpcontact.Case "
                        f"(vpcontact.load_case) or a vpcontact.case.schema.Model")
    if mesh is not None and not isinstance(mesh, meshes.Mesh):
        raise CaseError(f"mesh = {_brief(mesh)}: expected a vpcontact.mesh.Mesh (vpcontact.mesh.half_disc, "
                        f"quarter_ball, rectangle, block or read_mesh)")
    source = model.to_toml() if isinstance(model, Case) and mesh is None else None
    if mesh is None:
        if not isinstance(model, Case):
            raise CaseError("a model without [mesh] needs a mesh: build_problem(model, mesh=...)")
        with progress.phase("mesh", mesh_words(model.mesh)) as phase:
            mesh = make_mesh(model.mesh, model.base_dir)
            phase.done(_mesh_size(mesh))
    model = model.model if isinstance(model, Case) else model
    if model.contact is None and (p is not None or stiffness_law is not None):
        raise CaseError("p and stiffness_law are laws of the contact, and the case has no [contact]")
    p = None if p is None else _api_law(p, "p")
    stiffness_law = None if stiffness_law is None else _api_law(stiffness_law, "stiffness_law")
    meshed = time.perf_counter()
    with progress.phase("assembly", "stiffness, loads, contact surface and checks") as phase:
        problem = _assembled(model, mesh, p, stiffness_law, tractions, body_force, viscoplastic, initial_displacement,
                             initial_stress, initial_xi)
        phase.done(f"{problem.free.size:,} free dofs of {problem.basis.N:,}, {problem.surface.size:,} contact nodes, "
                   f"a stiffness of {problem.A.nnz:,} entries")
    done = time.perf_counter()
    problem.objects, problem.source = objects, source
    problem.timings = {"mesh": meshed - started, "assembly": done - meshed, "build": done - started}
    return problem


def _assembled(model: Model, mesh: meshes.Mesh, p, stiffness_law, tractions, body_force, viscoplastic,
               initial_displacement, initial_stress, initial_xi) -> Problem:
    """The problem of ``model`` on ``mesh`` (the laws of the API already wrapped; see build_problem), without
    its timings, the objects of the API and the source."""
    dim = mesh.dim
    _check_dimension(model, dim)
    materials = body_materials(model, mesh)
    with np.errstate(all="ignore"):  # a stiffness that is not finite is reported below
        basis = displacement_basis(mesh)
        A = stiffness(basis, materials.elasticity)
    if not np.all(np.isfinite(A.data)):
        moduli = ", ".join(f"{key}.E = {_brief(entry.E)}" for key, entry in _material_keys(model))
        raise CaseError(f"{moduli}: the stiffness matrix is not finite in float64 (the moduli or the sizes of the "
                        f"{SIMPLICES[dim].plural} are out of its range); state them in other units")

    fixed = np.zeros(basis.N, dtype=bool)
    for item in model.boundary.dirichlet:
        components = [component(c) for c in (item.components or coordinates(dim))]
        fixed[basis.nodal_dofs[components][:, mesh.nodes(item.part)]] = True
    free = np.flatnonzero(~fixed)

    body_terms = [(f"boundary.body_force[{i}].value", _density(f.value, f"boundary.body_force[{i}].value"))
                  for i, f in enumerate(model.boundary.body_force)]
    if body_force is not None:
        _check_density_arguments("body_force", body_force, mesh.dim)
        body_terms = [("body_force", body_force)]
    loads = LoadVector(basis, mesh, _traction_terms(model, mesh, tractions), body_terms)

    surface, probe = empty_surface(basis.N, dim), None
    law = ContactLaw(PositivePart(), ConstantStiffness(0.0), np.inf)
    if model.contact is not None:
        c = model.contact
        layers = c.layers()
        gaps = [parse_expression(layer.gap, coordinates(dim), where=f"{key}.gap") for key, layer in layers]
        surface = contact_surface(mesh, [layer.part for _, layer in layers], basis.nodal_dofs, gaps,
                                  None if c.normal == "body" else c.normal)
        law = _contact_law(model, surface, p, stiffness_law)
        target = c.probe if c.probe is not None else surface.coordinates.mean(axis=1)
        probe = surface.nearest_node(target)
    _check_contact_can_move(model, mesh, basis, free, surface)
    _check_rigid_motions(mesh, basis, free, surface)

    initial = initial_state(model, mesh, basis, surface, law, displacement=initial_displacement, stress=initial_stress,
                            xi=initial_xi)
    strain0 = element_strain(basis, initial.dofs(basis))
    z0 = initial.stress - materials.elasticity.stress(strain0)
    law_name = "material.viscoplastic" if viscoplastic is None else "viscoplastic"
    if viscoplastic is None:
        viscoplastic = materials.viscoplastic
    else:
        viscoplastic = _api_viscoplastic(viscoplastic, mesh)
    grid = TimeGrid(model.time.T, model.time.steps, initial.start)
    loads.check(grid)
    _check_first_history(basis, initial, model.initial.stress, strain0, z0, viscoplastic, law_name, grid.k)
    return Problem(model, {}, mesh, basis, materials, A, free, loads, surface, law, probe, viscoplastic,
                   initial=initial, initial_strain=strain0, initial_history=z0)


def mesh_words(m: MeshSection) -> str:
    """The mesh a ``[mesh]`` section makes, in words: "reading FILE", or the shape and its sizes."""
    if m.file is not None:
        return f"reading {m.file}"
    sizes = [f"{key} = {getattr(m, key):g}" for key in ("h", "h_bottom", "radius", "width", "depth", "height",
                                                         "coating") if getattr(m, key) is not None]
    return f"{m.shape.replace('_', ' ')}, {', '.join(sizes)}"


def _mesh_size(mesh: meshes.Mesh) -> str:
    """The sizes of a mesh, in words: nodes, elements, dofs."""
    nodes, elements = mesh.mesh.p.shape[1], mesh.mesh.t.shape[1]
    return f"{nodes:,} nodes, {elements:,} {SIMPLICES[mesh.dim].plural}, {mesh.dim * nodes:,} dofs"


def _api_viscoplastic(G, mesh: meshes.Mesh) -> Callable:
    """𝒢 of the API: G(sigma, strain) of arrays (d, d, elements), or G(sigma, strain, x) of the element
    centroids x (d, elements) too (𝒢(x, σ, ε) of (2.17)), bound to the mesh's centroids; else CaseError."""
    if not callable(G):
        raise CaseError(f"viscoplastic = {_brief(G)}: expected a function G(sigma, strain) of arrays of shape "
                        f"(d, d, elements), or G(sigma, strain, x) with x the element centroids (d, elements)")
    required = _required_arguments(G)
    if len(required) > 3 or not (len(required) == 3 or _accepts(G, 2)):
        raise CaseError(f"viscoplastic takes {_parameters(G)}: expected G(sigma, strain) or G(sigma, strain, x)")
    if len(required) == 3:
        return AtCentroids(G, mesh.centroids)
    return G


def make_mesh(m: MeshSection, base_dir: str | os.PathLike = ".") -> meshes.Mesh:
    """The mesh of a ``[mesh]`` section: a built-in shape, or a mesh file (relative to ``base_dir``)."""
    if m.file is not None:
        return meshes.read_mesh(Path(base_dir) / m.file)
    if m.shape == "half_disc":
        return meshes.half_disc(m.h, m.radius, m.coating)
    if m.shape == "quarter_ball":
        return meshes.quarter_ball(m.h, m.radius, m.h_bottom, m.coating)
    if m.shape == "block":
        return meshes.block(m.width, m.depth, m.height, m.h)
    return meshes.rectangle(m.width, m.height, m.h)


def _check_dimension(model: Model, dim: int) -> None:
    """Refuse vectors and tensors of the case that do not have the mesh's dimension d, a plane
    hypothesis in 3D, and the coordinate z in 2D."""
    names = coordinates(dim)
    where = f"the mesh is {dim}D"
    give = f"give {dim} ({', '.join(names)})"
    loads = [(f"boundary.traction[{i}].value", t.value) for i, t in enumerate(model.boundary.traction)]
    loads += [(f"boundary.body_force[{i}].value", f.value) for i, f in enumerate(model.boundary.body_force)]
    vectors = list(loads)
    if model.contact is not None:
        vectors += [("contact.probe", model.contact.probe), ("contact.normal", model.contact.normal)]
    vectors.append(("initial.displacement", model.initial.displacement))
    for key, value in vectors:
        if isinstance(value, list) and len(value) != dim:
            raise CaseError(f"{key} has {len(value)} components and {where}: {give}")
    if model.initial.stress is not None and len(model.initial.stress) != dim:
        raise CaseError(f"initial.stress is {len(model.initial.stress)} x {len(model.initial.stress)} and {where}: "
                        f"give a {dim} x {dim} table")
    for key, entry in _material_keys(model):
        if dim == 3 and entry.hypothesis is not None:
            raise CaseError(f"{key}.hypothesis = \"{entry.hypothesis}\" is a 2D reduction and {where} (3D uses the "
                            f"full isotropic tensor): remove {key}.hypothesis")
    for i, item in enumerate(model.boundary.dirichlet):
        extra = [c for c in item.components or () if c not in names]
        if extra:
            raise CaseError(f"boundary.dirichlet[{i}].components names \"{extra[0]}\" and {where}: use "
                            f"{', '.join(repr(n) for n in names)}")
    expressions = [(f"{key}[{c}]", source) for key, value in loads for c, source in enumerate(value)]
    if model.contact is not None:
        expressions += [(f"{key}.gap", layer.gap) for key, layer in model.contact.layers()]
    expressions += [(f"{key}.{name}", getattr(entry, name)) for key, entry in _material_keys(model) for name in ("E", "nu")]
    initial = model.initial
    expressions += [(f"initial.displacement[{c}]", source) for c, source in enumerate(initial.displacement or ())]
    expressions += [(f"initial.stress[{i}][{j}]", source) for i, row in enumerate(initial.stress or ())
                    for j, source in enumerate(row)]
    if initial.xi is not None:
        expressions.append(("initial.xi", initial.xi))
    for key, source in expressions:
        unknown = parse_expression(source, ("x", "y", "z", "t"), where=key).depends_on - {*names, "t"}
        if unknown:
            raise CaseError(f"{key} = {quoted(str(source))} uses {sorted(unknown)[0]} and {where}: the coordinates "
                            f"are {', '.join(names)}")


def _density(values, where: str) -> ExpressionDensity:
    """The density of the d expressions ``values`` (one per component) of the case key ``where``."""
    names = coordinates(len(values))
    return ExpressionDensity(*(parse_expression(v, (*names, "t"), where=f"{where}[{i}]") for i, v in enumerate(values)))


def _traction_terms(model: Model, mesh: meshes.Mesh, tractions: Mapping | None) -> list[tuple[str, object, Density]]:
    """(name, part, density) of the case's tractions, those of ``tractions`` replacing the case's on their part."""
    terms = [(f"boundary.traction[{i}].value", t.part, _density(t.value, f"boundary.traction[{i}].value"))
             for i, t in enumerate(model.boundary.traction)]
    if tractions is None:
        return terms
    if not isinstance(tractions, Mapping):
        raise CaseError(f"tractions = {_brief(tractions)}: expected a dict {{part: f(x, y, (z,) t) -> (fx, fy, (fz))}}")
    for part, density in tractions.items():
        if not (isinstance(part, (str, int)) and str(part) in mesh.parts):
            raise CaseError(f"tractions: unknown part {_brief(part)}; the mesh has parts: {', '.join(mesh.part_names)}")
        _check_density_arguments(f"tractions[{_brief(part)}]", density, mesh.dim)
        facets = mesh.facets(part)
        terms = [term for term in terms if not np.array_equal(mesh.facets(term[1]), facets)]
        terms.append((f"tractions[{_brief(part)}]", part, density))
    return terms


#: Where a law of the API is tried before the run: at 0 and just above (a penetration, a history ξ ≥ 0).
_LAW_SAMPLE = (0.0, 1e-3)


def _api_law(law, name: str):
    """A law p or K of the API: a law f(r) tried at _LAW_SAMPLE (elementwise, finite), an object with a
    ``derivative`` method as it is, a plain function wrapped in CallableLaw; a law f(r, x) of the nodes'
    coordinates x is a LawOfNodes, tried when the contact nodes are known; else CaseError."""
    if not callable(law):
        raise CaseError(f"{name} = {_brief(law)}: expected a function f(r) of a NumPy array (optionally with a "
                        f"method f.derivative(r)), or f(r, x) with x the coordinates of the contact nodes")
    derivative = getattr(law, "derivative", None)
    derivative = derivative if callable(derivative) else None
    arguments = _arguments(law, name)
    if derivative is not None and (other := _arguments(derivative, f"{name}.derivative")) != arguments:
        raise CaseError(f"{name} takes {arguments} argument(s) and {name}.derivative {other}: give both f(r) or "
                        f"both f(r, x)")
    if arguments == 2:
        return LawOfNodes(law, derivative, name)
    for what, f in ((name, law), (f"{name}.derivative", derivative)) if derivative else ((name, law),):
        sample = np.array(_LAW_SAMPLE)
        call = f"{what}({', '.join(map(str, _LAW_SAMPLE))})"
        _check_returned(what, call, _tried(what, call, f, sample.copy()), sample.shape)
    return law if derivative else CallableLaw(law)


def _arguments(law: Callable, name: str) -> int:
    """The arguments ``law`` takes, from its signature: 2 when it requires two (r, x), else 1 (r); CaseError when
    it requires more, or cannot take one (lambda: 1)."""
    required = _required_arguments(law)
    if len(required) > 2 or not (len(required) == 2 or _accepts(law, 1)):
        raise CaseError(f"{name} takes {_parameters(law)}: expected f(r), or f(r, x) with x the coordinates of the "
                        f"contact nodes")
    return 2 if len(required) == 2 else 1


def _check_density_arguments(name: str, density, dim: int) -> None:
    """CaseError unless a load density of the API takes the coordinates and the time, f(x, y, t) (f(x, y, z, t) in
    3D), as far as its signature tells (a NumPy ufunc or a builtin does not; a value that is not a function is
    refused where the load is made)."""
    if callable(density) and not _accepts(density, dim + 1):
        names = coordinates(dim)
        raise CaseError(f"{name} = {_brief(density)} takes {_parameters(density)}: expected "
                        f"f({', '.join(names)}, t) -> ({', '.join('f' + c for c in names)})")


def _accepts(function: Callable, count: int) -> bool:
    """May ``function`` be called with ``count`` positional arguments, as far as its signature tells (True when
    Python cannot tell, for a NumPy ufunc or some builtins)?"""
    try:
        inspect.signature(function).bind(*range(count))
    except TypeError:
        return False
    except ValueError:  # no signature
        return True
    return True


def _parameters(function: Callable) -> str:
    """The parameters of ``function`` in words: "2 arguments (x, y)", "1 argument (r)", "no argument"."""
    try:
        names = list(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return "other arguments"
    count = f"{len(names)} argument{'s' * (len(names) != 1)}"
    return f"{count} ({', '.join(names)})" if names else "no argument"


def _required_arguments(function: Callable) -> list[str]:
    """The names of the positional arguments ``function`` requires, from its signature; none when Python
    cannot tell (a NumPy ufunc) or when it takes any number (*args)."""
    try:
        parameters = list(inspect.signature(function).parameters.values())
    except (TypeError, ValueError):
        return []
    if any(p.kind == p.VAR_POSITIONAL for p in parameters):
        return []
    return [p.name for p in parameters if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty]


@dataclass(frozen=True)
class LawOfNodes:
    """A law f(r, x) of the API (and its derivative df(r, x), or None), waiting for the contact nodes."""

    function: Callable
    derivative: Callable | None
    name: str

    def at(self, points: np.ndarray) -> CallableLaw:
        """The law at the contact nodes ``points`` (d, m), tried at r = 0 and 10⁻³ at every node."""
        m = points.shape[1]
        for what, f in ((self.name, self.function), (f"{self.name}.derivative", self.derivative)):
            if f is None:
                continue
            for r in _LAW_SAMPLE:
                call = f"{what}({r}, x) at the {m} contact nodes"
                _check_returned(what, call, _tried(what, call, f, np.full(m, r), points.copy()), (m,))
        derivative = None if self.derivative is None else AtNodes(self.derivative, points)
        return CallableLaw(AtNodes(self.function, points), derivative)


def _tried(name: str, call: str, function: Callable, *arguments):
    """``function(*arguments)``, the trial ``call`` of the API's law ``name`` (values that are not finite are
    reported by the caller); CaseError, caused by the function's own exception, when it raises one."""
    try:
        with np.errstate(all="ignore"):
            return function(*arguments)
    except CaseError:
        raise
    except Exception as error:  # noqa: BLE001 - a user's function may raise anything
        raise CaseError(f"{name}: {call} raised {type(error).__name__}: {error}") from error


def _check_returned(name: str, call: str, values, shape: tuple) -> None:
    """CaseError unless ``values`` (what ``call`` returned) are finite numbers broadcasting to ``shape``."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # a ragged list
        array = None
    if array is None or array.dtype.kind not in "iuf":  # complex, boolean, strings, objects: not real numbers
        what = f"ndarray of {array.dtype}" if isinstance(values, np.ndarray) else type(values).__name__
        raise CaseError(f"{name}: {call} returned a value of type {what}, not numbers")
    array = array.astype(float)
    try:
        broadcast = np.broadcast_shapes(array.shape, shape) == shape
    except ValueError:
        broadcast = False
    if not broadcast:
        raise CaseError(f"{name}: {call} returned an array of shape {array.shape} for arguments of shape {shape}; "
                        f"expected that shape (elementwise)")
    if not np.all(np.isfinite(array)):
        raise CaseError(f"{name}: {call} is not finite ({array.ravel()[~np.isfinite(array.ravel())][0]})")


def _check_first_history(basis: Basis, initial: InitialState, written, strain0: np.ndarray, z0: np.ndarray,
                         G: Callable | None, law_name: str, k: float) -> None:
    """Refuse initial data whose first step cannot be finite: 𝒢(σ_0, ε(u_0)) (of the shape of σ, finite),
    the history z_1 = σ_0 − ℰε(u_0) + k 𝒢(σ_0, ε(u_0)) of (2.28) and its nodal forces Bᵀz_1 in the
    right-hand side. ``written``: initial.stress as the case gives it (for the message)."""
    if G is None and not np.any(z0 != 0.0):
        return
    sigma = initial.stress
    rate = 0.0
    call = "G(initial.stress, 0)" if not initial.moves else "G(initial.stress, strain(initial.displacement))"
    if G is not None:
        rate = _tried(law_name, call, G, sigma.copy(), strain0.copy())
        _check_returned(law_name, call, rate, sigma.shape)
    with np.errstate(all="ignore"):  # an overflow is reported below
        z = z0 + k * np.asarray(rate, dtype=float)
        force = stress_force(basis, z) if np.all(np.isfinite(z)) else None
    if force is None:
        elastic = " - E strain(initial.displacement)" if initial.moves else ""
        raise CaseError(f"{law_name}: the history after the first step, initial.stress{elastic} + k {call}, is not "
                        f"finite: is the time step k = {k:g} small against the law's relaxation time?")
    if not np.all(np.isfinite(force)):
        source = initial.names["stress"]
        if source == "initial.stress":
            source += f" = {_brief(written)}"
        raise CaseError(f"{source}: its nodal forces are not finite in float64; state the stresses in other units")


def _contact_law(model: Model, surface: ContactSurface, p: Callable | None, stiffness_law: Callable | None) -> ContactLaw:
    """The layer of each contact part at the nodes it owns (its keys' numbers, or expressions evaluated
    there), merged into one law over the contact nodes (see contact.merged_law); ``p`` and
    ``stiffness_law`` of the API, when given, replace the case's on every part."""
    ps, stiffnesses, limits = [], [], []
    for j, (key, layer) in enumerate(model.contact.layers()):
        at = partial(_layer_parameter, points=surface.coordinates[:, surface.owner == j])
        if p is None:
            ps.append(PositivePart() if layer.p == "positive_part" else
                      Power(at(f"{key}.exponent", layer.exponent, 1.0)))
        if stiffness_law is None:
            stiffnesses.append(_stiffness_law(layer.stiffness, f"{key}.stiffness", at))
        limits.append(at(f"{key}.g", layer.g, 0.0, strict=True))
    owner = surface.owner
    p, stiffness_law = (law.at(surface.coordinates) if isinstance(law, LawOfNodes) else law
                        for law in (p, stiffness_law))
    return ContactLaw(p=merged_law(ps, owner) if p is None else p, g=per_node(limits, owner), rho=model.contact.rho,
                      stiffness=merged_law(stiffnesses, owner) if stiffness_law is None else stiffness_law)


def _stiffness_law(s, key: str, at: Callable):
    """K(x, ξ) of the stiffness table ``s`` (2.18) of the case key ``key``: each parameter a number, or an
    expression in the coordinates evaluated by ``at`` at the nodes of its part."""
    if s.law == "power":
        return PowerStiffness(at(f"{key}.c_v", s.c_v, 0.0), at(f"{key}.alpha", s.alpha, 0.0), at(f"{key}.beta", s.beta))
    if s.law == "constant":
        return ConstantStiffness(at(f"{key}.value", s.value, 0.0))
    return ExponentialStiffness(at(f"{key}.c_v", s.c_v, 0.0), at(f"{key}.alpha", s.alpha))


def _layer_parameter(where: str, value, minimum: float | None = None, *, points: np.ndarray, strict: bool = False):
    """The layer parameter of the case key ``where``: a number as it is; an expression's values at the
    contact nodes ``points`` (d, k), refused (naming the node) where they are not finite or below
    ``minimum`` (or equal to it, when ``strict``)."""
    if not isinstance(value, str):
        return float(value)
    names, count = coordinates(points.shape[0]), points.shape[1]
    values = values_at(value, where, points)
    if minimum is None:
        wrong = ~np.isfinite(values)
    else:
        wrong = ~np.isfinite(values) | ~(values > minimum if strict else values >= minimum)
    if wrong.any():
        node = np.flatnonzero(wrong)[0]
        expected = "finite" if minimum is None else f"a finite number {'>' if strict else '>='} {minimum:g}"
        raise CaseError(f"{where} = {quoted(value)} is {values[node]:g} at the contact node ({', '.join(names)}) = "
                        f"{point(points[:, node])} ({wrong.sum()} of {count} nodes): expected {expected} at every "
                        f"node of the contact part")
    return values.copy()


def _check_contact_can_move(model: Model, mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
    """Refuse a contact part on which the Dirichlet conditions leave no node free to move along its
    normal: its contact force would be 0 (or fixed) whatever the load. (A few clamped nodes, such as
    the corners the contact part shares with a clamped part, are fine.)"""
    if surface.size == 0:
        return
    on_free = np.zeros(basis.N)
    on_free[free] = 1.0
    normal_freedom = np.sqrt(np.asarray((surface.operator @ sp.diags(on_free)).power(2).sum(axis=1)).ravel())
    if np.any(normal_freedom > 1e-6):
        return
    contact_dofs = basis.nodal_dofs[:, surface.nodes].ravel()
    entries = []
    for i, item in enumerate(model.boundary.dirichlet):
        names = item.components or coordinates(mesh.dim)
        components = [component(c) for c in names]
        if np.intersect1d(basis.nodal_dofs[components][:, mesh.nodes(item.part)], contact_dofs).size:
            entries.append(f"boundary.dirichlet[{i}] (part '{item.part}', components {', '.join(names)})")
    parts = f"part '{surface.parts[0]}' is" if len(surface.parts) == 1 else \
        f"parts {', '.join(repr(part) for part in surface.parts)} are"
    raise CaseError(f"contact {parts} clamped: {' and '.join(entries)} fix every contact node "
                    f"along its normal, so the contact force cannot change whatever the load; remove the contact part "
                    f"from boundary.dirichlet or fix only components along the contact surface")


def _check_rigid_motions(mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
    """Refuse a body, or a separate part of the mesh, whose rigid motions are held neither by
    Dirichlet conditions nor by contact: the motions of each connected part (the d translations and
    the rotations about its centroid scaled by its size, :mod:`vpcontact.fem.rigid_modes`) must stay
    independent on the fixed dofs and the contact normals of that part."""
    modes = RigidModes.of_mesh(mesh.mesh.p, mesh.mesh.t, basis.nodal_dofs)
    fixed = np.ones(basis.N, dtype=bool)
    fixed[free] = False
    free_motions, least_held = modes.unheld(sp.eye(basis.N, format="csr")[fixed], surface.operator)
    loose = np.flatnonzero(free_motions)
    if loose.size == 0:
        return
    b, count = loose[0], modes.count
    where = "the Dirichlet conditions and the contact part" if surface.size else "the Dirichlet conditions"
    if free_motions[b] > 1:
        words = ("", "one", "two", "three", "four", "five", "six")
        motion = (f"all {words[modes.per_body]}" if free_motions[b] == modes.per_body
                  else f"{words[free_motions[b]]} of the {words[modes.per_body]}")
    else:
        motion = _rigid_motion(least_held[b], modes.centroid[:, b], modes.size[b])
    if count == 1:
        raise CaseError(f"{where} leave a rigid motion of the body free ({motion}): add boundary.dirichlet entries")
    p = mesh.mesh.p
    inside = np.flatnonzero(modes.body == b)
    point = inside[np.argmin(np.sum((p[:, inside] - modes.centroid[:, b:b + 1]) ** 2, axis=0))]
    nodes = np.bincount(modes.body, minlength=count)
    raise CaseError(f"the mesh has {count} separate parts; {where} leave a rigid motion of the part of {nodes[b]} "
                    f"nodes through the node at {_point(p[:, point])} free ({motion})"
                    f"{f' (and of {loose.size - 1} more)' if loose.size > 1 else ''}: add boundary.dirichlet "
                    f"entries on it, or join it to the rest of the mesh")


def _rigid_motion(combination: np.ndarray, centroid: np.ndarray, size: float) -> str:
    """A rigid motion in words, from its coefficients on the modes of :mod:`vpcontact.fem.rigid_modes`:
    d translations, then the rotations in the planes xy (2D), or xy, yz, zx (3D), about ``centroid``
    and scaled by ``size``: "a translation along (…)", "a rotation about (…)" (2D) or "a rotation about
    the axis through (…) along (…)" (3D)."""
    d = centroid.size
    combination = combination * np.sign(combination[np.argmax(np.abs(combination))])
    translation, rotation = combination[:d], combination[d:]
    if np.linalg.norm(rotation) < 1e-9:
        return f"a translation along {_point(translation / np.linalg.norm(translation), 3)}"
    if d == 2:  # u = t + ω e_z × (x − c)/size vanishes at x = c + size (−t_y, t_x)/ω
        center = centroid + size * np.array([-translation[1], translation[0]]) / rotation[0]
        return f"a rotation about {_point(np.round(center / size, 9) * size)}"
    axis = rotation[[1, 2, 0]]  # rotations in the planes yz, zx, xy: the axis components x, y, z
    point = centroid + size * np.cross(axis, translation) / (axis @ axis)
    return (f"a rotation about the axis through {_point(np.round(point / size, 9) * size)} along "
            f"{_point(axis / np.linalg.norm(axis), 3)}")


def _point(x: np.ndarray, digits: int = 6) -> str:
    """The point x as a message shows it (:func:`~vpcontact.errors.point`), without its round-off below 1e-12."""
    return point(np.round(x, 12), digits)
