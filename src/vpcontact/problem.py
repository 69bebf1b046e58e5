"""From a case to the discrete problem: mesh, spaces, operators, loads and the contact law.

Everything that can fail on user input (mesh file, part names, rigid motions left free, loads that
are not finite at a time step, outputs that would not fit in memory, Python objects of the API that
are not laws) fails here, before any computation and before anything is written.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial
from typing import Callable

import numpy as np
import scipy.sparse as sp
from skfem import Basis

from . import mesh as meshes
from .assembly import Density, ExpressionDensity, LoadVector, displacement_basis, stiffness, stress_force
from .case import Case, _brief
from .contact import (CallableLaw, ConstantStiffness, ContactLaw, ContactSurface, ExponentialStiffness, PositivePart,
                      Power, PowerStiffness, contact_surface, empty_surface)
from .errors import CaseError, quoted
from .expressions import parse_expression
from .material import Elasticity, Perzyna, Relaxation
from .results import check_memory
from .rigid_modes import RigidModes
from .space import component, coordinates
from .time_grid import TimeGrid




@dataclass
class Problem:
    """The discrete problem of a case: Problem P_V of the paper on P1 × P0 with node-to-rigid contact."""

    case: Case
    mesh: meshes.Mesh
    basis: Basis
    elasticity: Elasticity
    A: sp.csr_matrix  # the elastic stiffness on all dofs
    free: np.ndarray  # dofs not fixed by Dirichlet conditions
    loads: LoadVector
    surface: ContactSurface  # no nodes when the case has no contact
    law: ContactLaw
    probe: int | None  # index of the reported contact node
    viscoplastic: Callable | None = None  # 𝒢(σ, ε) over arrays (d, d, nelements); None: 𝒢 = 0
    timings: dict = field(default_factory=dict)  # seconds: mesh, assembly, build
    initial_stress: np.ndarray | None = None  # σ_0 (uniform, d × d; None: 0); u_0 = 0
    times: TimeGrid = field(init=False)  # t_1, …, t_steps

    def __post_init__(self):
        self.times = TimeGrid(self.case.time.T, self.case.time.steps)

    @property
    def k(self) -> float:
        return self.case.time.T / self.case.time.steps

    def __repr__(self) -> str:
        """One line: the sizes (not the operators)."""
        return (f"Problem(dofs={self.basis.N}, free_dofs={self.free.size}, elements={self.mesh.mesh.t.shape[1]}, "
                f"nodes={self.mesh.mesh.p.shape[1]}, contact_nodes={self.surface.size}, steps={len(self.times)}, "
                f"k={self.k:g})")


def build_problem(case: Case, *, p: Callable | None = None, stiffness_law: Callable | None = None,
                  tractions: Mapping | None = None, body_force: Density | None = None,
                  viscoplastic: Callable | None = None) -> Problem:
    """Assemble the problem of ``case``; the keyword arguments replace parts of the case by Python objects:

    - ``p``, ``stiffness_law``: the laws p(r) and K(ξ) of the contact, vectorized over NumPy arrays; an
      object with a ``derivative`` method is used as it is (see :mod:`vpcontact.contact`), a plain
      function is wrapped in :class:`~vpcontact.contact.CallableLaw` (central-difference derivative);
    - ``tractions``: {part: f(x, y, t) -> (fx, fy)} (in 3D f(x, y, z, t) -> (fx, fy, fz)): f replaces the
      case's traction on that part (the case's tractions on other parts stay);
    - ``body_force``: f(x, y, t) -> (fx, fy) (in 3D f(x, y, z, t) -> (fx, fy, fz)) replaces the case's
      body forces;
    - ``viscoplastic``: 𝒢(σ, ε) of (2.1), vectorized over element arrays of shape (d, d, nelements) (it
      replaces ``material.viscoplastic``).

    Each is tried before the run (a law at 0 and 10⁻³, a load at every step time, 𝒢 at (σ_0, 0)): one
    that is not callable, returns the wrong shape or a value that is not finite is a CaseError."""
    started = time.perf_counter()
    if case.contact is None and (p is not None or stiffness_law is not None):
        raise CaseError("p and stiffness_law are laws of the contact, and the case has no [contact]")
    p = None if p is None else _api_law(p, "p")
    stiffness_law = None if stiffness_law is None else _api_law(stiffness_law, "stiffness_law")
    mesh = _make_mesh(case)
    meshed = time.perf_counter()
    dim = mesh.dim
    _check_dimension(case, dim)
    elasticity = Elasticity(case.material.E, case.material.nu,
                            (case.material.hypothesis or "plane_strain") if dim == 2 else None)
    with np.errstate(all="ignore"):  # a stiffness that is not finite is reported below
        basis = displacement_basis(mesh)
        A = stiffness(basis, elasticity)
    if not np.all(np.isfinite(A.data)):
        raise CaseError(f"material.E = {_brief(case.material.E)}: the stiffness matrix is not finite in float64 (the "
                        f"moduli or the sizes of the triangles are out of its range); state them in other units")

    fixed = np.zeros(basis.N, dtype=bool)
    for item in case.boundary.dirichlet:
        components = [component(c) for c in (item.components or coordinates(dim))]
        fixed[basis.nodal_dofs[components][:, mesh.nodes(item.part)]] = True
    free = np.flatnonzero(~fixed)

    body_terms = [(f"boundary.body_force[{i}].value", _density(f.value, f"boundary.body_force[{i}].value"))
                  for i, f in enumerate(case.boundary.body_force)]
    if body_force is not None:
        body_terms = [("body_force", body_force)]
    loads = LoadVector(basis, mesh, _traction_terms(case, mesh, tractions), body_terms)

    surface, probe = empty_surface(basis.N, dim), None
    law = ContactLaw(PositivePart(), ConstantStiffness(0.0), np.inf)
    if case.contact is not None:
        c = case.contact
        gap = parse_expression(c.gap, coordinates(dim), where="contact.gap")
        surface = contact_surface(mesh, c.part, basis.nodal_dofs, gap, None if c.normal == "body" else c.normal)
        law = ContactLaw(p=p or _p_law(case), stiffness=stiffness_law or _stiffness_law(case, surface),
                         g=_layer_parameter("g", c.g, 0.0, surface=surface, strict=True), rho=c.rho)
        target = c.probe if c.probe is not None else surface.coordinates.mean(axis=1)
        probe = surface.nearest_node(target)
    _check_contact_can_move(case, mesh, basis, free, surface)
    _check_rigid_motions(mesh, basis, free, surface)

    elements = mesh.mesh.t.shape[1]
    initial_stress = np.zeros((dim, dim)) if case.initial.stress is None else np.array(case.initial.stress, dtype=float)
    law_name = "material.viscoplastic" if viscoplastic is None else "viscoplastic"
    if viscoplastic is None:
        viscoplastic = _viscoplastic_law(case)
    elif not callable(viscoplastic):
        raise CaseError(f"viscoplastic = {_brief(viscoplastic)}: expected a function G(sigma, strain) of arrays of "
                        f"shape (d, d, elements)")
    check_memory(case, mesh.mesh.p.shape[1], elements, surface.size,
                 history=viscoplastic is not None or bool(np.any(initial_stress != 0.0)), dim=dim)
    loads.check(TimeGrid(case.time.T, case.time.steps))
    _check_first_history(basis, initial_stress, viscoplastic, law_name, case.time.T / case.time.steps)
    done = time.perf_counter()
    timings = {"mesh": meshed - started, "assembly": done - meshed, "build": done - started}
    return Problem(case, mesh, basis, elasticity, A, free, loads, surface, law, probe, viscoplastic, timings,
                   initial_stress=initial_stress)


def _make_mesh(case: Case) -> meshes.Mesh:
    m = case.mesh
    if m.file is not None:
        return meshes.read_mesh(case.mesh_path)
    if m.shape == "half_disc":
        return meshes.half_disc(m.h, m.radius, m.coating)
    if m.shape == "quarter_ball":
        return meshes.quarter_ball(m.h, m.radius, m.h_bottom, m.coating)
    if m.shape == "block":
        return meshes.block(m.width, m.depth, m.height, m.h)
    return meshes.rectangle(m.width, m.height, m.h)


def _check_dimension(case: Case, dim: int) -> None:
    """Refuse vectors and tensors of the case that do not have the mesh's dimension d, a plane
    hypothesis in 3D, and the coordinate z in 2D."""
    names = coordinates(dim)
    where = f"the mesh is {dim}D"
    give = f"give {dim} ({', '.join(names)})"
    loads = [(f"boundary.traction[{i}].value", t.value) for i, t in enumerate(case.boundary.traction)]
    loads += [(f"boundary.body_force[{i}].value", f.value) for i, f in enumerate(case.boundary.body_force)]
    vectors = list(loads)
    if case.contact is not None:
        vectors += [("contact.probe", case.contact.probe), ("contact.normal", case.contact.normal)]
    for key, value in vectors:
        if isinstance(value, list) and len(value) != dim:
            raise CaseError(f"{key} has {len(value)} components and {where}: {give}")
    if case.initial.stress is not None and len(case.initial.stress) != dim:
        raise CaseError(f"initial.stress is {len(case.initial.stress)} x {len(case.initial.stress)} and {where}: "
                        f"give a {dim} x {dim} table")
    if dim == 3 and case.material.hypothesis is not None:
        raise CaseError(f"material.hypothesis = \"{case.material.hypothesis}\" is a 2D reduction and {where} (3D "
                        f"uses the full isotropic tensor): remove material.hypothesis")
    for i, item in enumerate(case.boundary.dirichlet):
        extra = [c for c in item.components or () if c not in names]
        if extra:
            raise CaseError(f"boundary.dirichlet[{i}].components names \"{extra[0]}\" and {where}: use "
                            f"{', '.join(repr(n) for n in names)}")
    expressions = [(f"{key}[{c}]", source) for key, value in loads for c, source in enumerate(value)]
    if case.contact is not None:
        expressions.append(("contact.gap", case.contact.gap))
    for key, source in expressions:
        unknown = parse_expression(source, ("x", "y", "z", "t"), where=key).depends_on - {*names, "t"}
        if unknown:
            raise CaseError(f"{key} = {quoted(str(source))} uses {sorted(unknown)[0]} and {where}: the coordinates "
                            f"are {', '.join(names)}")


def _density(values, where: str) -> ExpressionDensity:
    """The density of the d expressions ``values`` (one per component) of the case key ``where``."""
    names = coordinates(len(values))
    return ExpressionDensity(*(parse_expression(v, (*names, "t"), where=f"{where}[{i}]") for i, v in enumerate(values)))


def _traction_terms(case: Case, mesh: meshes.Mesh, tractions: Mapping | None) -> list[tuple[str, object, Density]]:
    """(name, part, density) of the case's tractions, those of ``tractions`` replacing the case's on their part."""
    terms = [(f"boundary.traction[{i}].value", t.part, _density(t.value, f"boundary.traction[{i}].value"))
             for i, t in enumerate(case.boundary.traction)]
    if tractions is None:
        return terms
    if not isinstance(tractions, Mapping):
        raise CaseError(f"tractions = {_brief(tractions)}: expected a dict {{part: f(x, y, (z,) t) -> (fx, fy, (fz))}}")
    for part, density in tractions.items():
        if not (isinstance(part, (str, int)) and str(part) in mesh.parts):
            raise CaseError(f"tractions: unknown part {_brief(part)}; the mesh has parts: {', '.join(mesh.part_names)}")
        facets = mesh.facets(part)
        terms = [term for term in terms if not np.array_equal(mesh.facets(term[1]), facets)]
        terms.append((f"tractions[{_brief(part)}]", part, density))
    return terms


#: Where a law of the API is tried before the run: at 0 and just above (a penetration, a history ξ ≥ 0).
_LAW_SAMPLE = (0.0, 1e-3)


def _api_law(law, name: str) -> Callable:
    """A law p or K of the API: an object with a ``derivative`` method as it is, a plain function wrapped
    in CallableLaw; both tried at _LAW_SAMPLE (elementwise, finite), else CaseError."""
    if not callable(law):
        raise CaseError(f"{name} = {_brief(law)}: expected a function f(r) of a NumPy array (optionally with a "
                        f"method f.derivative(r))")
    derivative = getattr(law, "derivative", None)
    for what, f in ((name, law), (f"{name}.derivative", derivative)) if callable(derivative) else ((name, law),):
        sample = np.array(_LAW_SAMPLE)
        with np.errstate(all="ignore"):  # a non-finite value is reported below
            values = f(sample.copy())
        _check_returned(what, f"{what}({', '.join(map(str, _LAW_SAMPLE))})", values, sample.shape)
    return law if callable(derivative) else CallableLaw(law)


def _check_returned(name: str, call: str, values, shape: tuple) -> None:
    """CaseError unless ``values`` (what ``call`` returned) are finite numbers broadcasting to ``shape``."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise CaseError(f"{name}: {call} returned a value of type {type(values).__name__}, not numbers") from None
    try:
        broadcast = np.broadcast_shapes(array.shape, shape) == shape
    except ValueError:
        broadcast = False
    if not broadcast:
        raise CaseError(f"{name}: {call} returned an array of shape {array.shape} for arguments of shape {shape}; "
                        f"expected that shape (elementwise)")
    if not np.all(np.isfinite(array)):
        raise CaseError(f"{name}: {call} is not finite ({array.ravel()[~np.isfinite(array.ravel())][0]})")


def _check_first_history(basis: Basis, initial_stress: np.ndarray, G: Callable | None, law_name: str,
                         k: float) -> None:
    """Refuse initial data whose first step cannot be finite: 𝒢(σ_0, 0) (of the shape of σ, finite), the
    history z_1 = σ_0 + k 𝒢(σ_0, 0) of (2.28) and its nodal forces Bᵀz_1 in the right-hand side."""
    if G is None and not np.any(initial_stress != 0.0):
        return
    sigma = np.repeat(initial_stress[:, :, None], basis.mesh.t.shape[1], axis=2)
    rate = 0.0
    if G is not None:
        with np.errstate(all="ignore"):  # a value that is not finite is reported
            rate = G(sigma.copy(), np.zeros_like(sigma))
        _check_returned(law_name, "G(initial.stress, 0)", rate, sigma.shape)
    with np.errstate(all="ignore"):  # an overflow is reported below
        z = sigma + k * np.asarray(rate, dtype=float)
        force = stress_force(basis, z) if np.all(np.isfinite(z)) else None
    if force is None:
        raise CaseError(f"{law_name}: the history after the first step, initial.stress + k G(initial.stress, 0), is "
                        f"not finite: is the time step k = {k:g} small against the law's relaxation time?")
    if not np.all(np.isfinite(force)):
        raise CaseError(f"initial.stress = {_brief(initial_stress.tolist())}: its nodal forces are not finite in "
                        f"float64; state the stresses in other units")


def _p_law(case: Case):
    c = case.contact
    return PositivePart() if c.p == "positive_part" else Power(c.exponent)


def _stiffness_law(case: Case, surface: ContactSurface):
    """K(x, ξ) of ``contact.stiffness`` (2.18): each parameter a number, or an expression in the
    coordinates evaluated at the contact nodes (an array with one value per node)."""
    s = case.contact.stiffness
    at = partial(_layer_parameter, surface=surface)
    if s.law == "power":
        return PowerStiffness(at("stiffness.c_v", s.c_v, 0.0), at("stiffness.alpha", s.alpha, 0.0),
                              at("stiffness.beta", s.beta))
    if s.law == "constant":
        return ConstantStiffness(at("stiffness.value", s.value, 0.0))
    return ExponentialStiffness(at("stiffness.c_v", s.c_v, 0.0), at("stiffness.alpha", s.alpha))


def _layer_parameter(name: str, value, minimum: float | None = None, *, surface: ContactSurface,
                     strict: bool = False):
    """``contact.<name>``: a number as it is; an expression's values at the contact nodes, refused
    (naming the node) where they are not finite or below ``minimum`` (or equal to it, when ``strict``)."""
    if not isinstance(value, str):
        return float(value)
    where = f"contact.{name}"
    names = coordinates(surface.coordinates.shape[0])
    expression = parse_expression(value, names, where=where)
    with np.errstate(all="ignore"):  # values that are not finite are reported below
        values = np.broadcast_to(expression(**dict(zip(names, surface.coordinates))), (surface.size,)).astype(float)
    if minimum is None:
        wrong = ~np.isfinite(values)
    else:
        wrong = ~np.isfinite(values) | ~(values > minimum if strict else values >= minimum)
    if wrong.any():
        node = np.flatnonzero(wrong)[0]
        at = ", ".join(f"{c:.6g}" for c in surface.coordinates[:, node])
        expected = "finite" if minimum is None else f"a finite number {'>' if strict else '>='} {minimum:g}"
        raise CaseError(f"{where} = {quoted(value)} is {values[node]:g} at the contact node ({', '.join(names)}) = "
                        f"({at}) ({wrong.sum()} of {surface.size} nodes): expected {expected} at every node of the "
                        f"contact part")
    return values.copy()


def _viscoplastic_law(case: Case) -> Callable | None:
    """𝒢 of ``material.viscoplastic`` (None: 𝒢 = 0)."""
    v = case.material.viscoplastic
    if v is None:
        return None
    if v.law == "perzyna":
        return Perzyna(v.eta, v.yield_stress)
    return Relaxation(v.mu, Elasticity(v.E_inf, v.nu_inf, case.material.hypothesis))


def _check_contact_can_move(case: Case, mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
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
    for i, item in enumerate(case.boundary.dirichlet):
        names = item.components or coordinates(mesh.dim)
        components = [component(c) for c in names]
        if np.intersect1d(basis.nodal_dofs[components][:, mesh.nodes(item.part)], contact_dofs).size:
            entries.append(f"boundary.dirichlet[{i}] (part '{item.part}', components {', '.join(names)})")
    raise CaseError(f"contact part '{case.contact.part}' is clamped: {' and '.join(entries)} fix every contact node "
                    f"along its normal, so the contact force cannot change whatever the load; remove the contact part "
                    f"from boundary.dirichlet or fix only components along the contact surface")


def _check_rigid_motions(mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
    """Refuse a body, or a separate part of the mesh, whose rigid motions are held neither by
    Dirichlet conditions nor by contact: the motions of each connected part (the d translations and
    the rotations about its centroid scaled by its size, :mod:`vpcontact.rigid_modes`) must stay
    independent on the fixed dofs and the contact normals of that part."""
    modes = RigidModes.of_mesh(mesh.mesh.p, mesh.mesh.t, basis.nodal_dofs)
    fixed = np.ones(basis.N, dtype=bool)
    fixed[free] = False
    free_motions, least_held = modes.unheld(sp.eye(basis.N, format="csr")[fixed], surface.operator)
    loose = np.flatnonzero(free_motions)
    if loose.size == 0:
        return
    b, count, d = loose[0], modes.count, mesh.dim
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
    """A rigid motion in words, from its coefficients on the modes of :mod:`vpcontact.rigid_modes`:
    d translations, then the rotations in the planes xy (2D), or xy, yz, zx (3D), about ``centroid``
    and scaled by ``size``: "a translation along (…)", "a rotation about (…)" (2D) or "a rotation about
    the axis through (…) along (…)" (3D)."""
    d = centroid.size
    combination = combination * np.sign(combination[np.argmax(np.abs(combination))])
    translation, rotation = combination[:d], combination[d:]
    if np.linalg.norm(rotation) < 1e-9:
        return f"a translation along {_point(translation / np.linalg.norm(translation), '.3g')}"
    if d == 2:  # u = t + ω e_z × (x − c)/size vanishes at x = c + size (−t_y, t_x)/ω
        center = centroid + size * np.array([-translation[1], translation[0]]) / rotation[0]
        return f"a rotation about {_point(np.round(center / size, 9) * size)}"
    axis = rotation[[1, 2, 0]]  # rotations in the planes yz, zx, xy: the axis components x, y, z
    point = centroid + size * np.cross(axis, translation) / (axis @ axis)
    return (f"a rotation about the axis through {_point(np.round(point / size, 9) * size)} along "
            f"{_point(axis / np.linalg.norm(axis), '.3g')}")


def _point(x: np.ndarray, style: str = ".6g") -> str:
    """(x, y[, z]) with the given format, without signed zeros."""
    return f"({', '.join(format(c + 0.0, style) for c in np.round(x, 12))})"
