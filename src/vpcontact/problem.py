"""From a case to the discrete problem: mesh, spaces, operators, loads and the contact law.

Everything that can fail on user input (mesh file, part names, rigid motions left free) fails
here, before any computation and before anything is written.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
from skfem import Basis

from . import mesh as meshes
from .assembly import Density, LoadVector, displacement_basis, stiffness
from .case import Case
from .contact import (ConstantStiffness, ContactLaw, ContactSurface, ExponentialStiffness, PositivePart, Power,
                      PowerStiffness, contact_surface, empty_surface)
from .errors import CaseError
from .expressions import parse_expression
from .material import Elasticity, Perzyna, Relaxation
from .rigid_modes import RigidModes


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
    viscoplastic: Callable | None = None  # 𝒢(σ, ε) over arrays (2, 2, nelements); None: 𝒢 = 0
    timings: dict = field(default_factory=dict)  # seconds: mesh, assembly, build
    initial_stress: np.ndarray = field(default_factory=lambda: np.zeros((2, 2)))  # σ_0 (uniform); u_0 = 0
    times: np.ndarray = field(init=False)

    def __post_init__(self):
        self.times = np.linspace(0.0, self.case.time.T, self.case.time.steps + 1)[1:]

    @property
    def k(self) -> float:
        return self.case.time.T / self.case.time.steps


def build_problem(case: Case, *, p: Callable | None = None, stiffness_law: Callable | None = None,
                  tractions: dict | None = None, body_force: Density | None = None,
                  viscoplastic: Callable | None = None) -> Problem:
    """Assemble the problem of ``case``; the keyword arguments replace the case's laws by Python
    objects (see :mod:`vpcontact.contact` for the protocol: ``f(r)`` and ``f.derivative(r)``) and
    its traction or body force densities by callables ``f(x, y, t) -> (fx, fy)``; ``viscoplastic``
    is 𝒢(σ, ε) of (2.1), vectorized over element arrays of shape (2, 2, nelements) (it replaces
    ``material.viscoplastic``)."""
    started = time.perf_counter()
    mesh = _make_mesh(case)
    meshed = time.perf_counter()
    basis = displacement_basis(mesh)
    elasticity = Elasticity(case.material.E, case.material.nu, case.material.hypothesis)
    A = stiffness(basis, elasticity)

    fixed = [np.zeros(0, dtype=np.int64)]
    for item in case.boundary.dirichlet:
        components = [{"x": 0, "y": 1}[c] for c in (item.components or ["x", "y"])]
        fixed.append(basis.nodal_dofs[components][:, mesh.nodes(item.part)].ravel())
    free = np.setdiff1d(np.arange(basis.N), np.concatenate(fixed))

    traction_terms = [(t.part, _density(t.value, f"boundary.traction[{i}].value")) for i, t in enumerate(case.boundary.traction)]
    for part, density in (tractions or {}).items():
        mesh.facets(part)
        traction_terms.append((part, density))
    body_terms = [_density(f.value, f"boundary.body_force[{i}].value") for i, f in enumerate(case.boundary.body_force)]
    if body_force is not None:
        body_terms.append(body_force)
    loads = LoadVector(basis, mesh, traction_terms, body_terms)

    surface, law, probe = empty_surface(basis.N), ContactLaw(PositivePart(), ConstantStiffness(0.0), np.inf), None
    if case.contact is not None:
        c = case.contact
        gap = parse_expression(c.gap, ("x", "y"), where="contact.gap")
        surface = contact_surface(mesh, c.part, basis.nodal_dofs, gap)
        law = ContactLaw(p=p or _p_law(case), stiffness=stiffness_law or _stiffness_law(case), g=c.g, rho=c.rho)
        target = c.probe if c.probe is not None else surface.coordinates.mean(axis=1)
        probe = surface.nearest_node(target)
    _check_contact_can_move(case, mesh, basis, free, surface)
    _check_rigid_motions(mesh, basis, free, surface)
    done = time.perf_counter()
    timings = {"mesh": meshed - started, "assembly": done - meshed, "build": done - started}
    if viscoplastic is None:
        viscoplastic = _viscoplastic_law(case)
    return Problem(case, mesh, basis, elasticity, A, free, loads, surface, law, probe, viscoplastic, timings,
                   initial_stress=np.array(case.initial.stress, dtype=float))


def _make_mesh(case: Case) -> meshes.Mesh:
    m = case.mesh
    if m.file is not None:
        return meshes.read_mesh(case.mesh_path)
    if m.shape == "half_disc":
        return meshes.half_disc(m.h, m.radius)
    return meshes.rectangle(m.width, m.height, m.h)


def _density(values, where: str) -> Density:
    fx, fy = (parse_expression(v, ("x", "y", "t"), where=f"{where}[{i}]") for i, v in enumerate(values))
    return lambda x, y, t: (fx(x=x, y=y, t=t), fy(x=x, y=y, t=t))


def _p_law(case: Case):
    c = case.contact
    return PositivePart() if c.p == "positive_part" else Power(c.exponent)


def _stiffness_law(case: Case):
    s = case.contact.stiffness
    if s.law == "power":
        return PowerStiffness(s.c_v, s.alpha, s.beta)
    if s.law == "constant":
        return ConstantStiffness(s.value)
    return ExponentialStiffness(s.c_v, s.alpha)


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
        names = item.components or ["x", "y"]
        components = [{"x": 0, "y": 1}[c] for c in names]
        if np.intersect1d(basis.nodal_dofs[components][:, mesh.nodes(item.part)], contact_dofs).size:
            entries.append(f"boundary.dirichlet[{i}] (part '{item.part}', components {', '.join(names)})")
    raise CaseError(f"contact part '{case.contact.part}' is clamped: {' and '.join(entries)} fix every contact node "
                    f"along its normal, so the contact force cannot change whatever the load; remove the contact part "
                    f"from boundary.dirichlet or fix only components along the contact surface")


def _check_rigid_motions(mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
    """Refuse a body, or a separate part of the mesh, whose rigid motions are held neither by
    Dirichlet conditions nor by contact: the motions of each connected part (the two translations
    and the rotation about its centroid scaled by its size, :mod:`vpcontact.rigid_modes`) must stay
    independent on the fixed dofs and the contact normals of that part."""
    x, y = mesh.mesh.p
    modes = RigidModes.of_mesh(mesh.mesh.p, mesh.mesh.t, basis.nodal_dofs)
    fixed = np.ones(basis.N, dtype=bool)
    fixed[free] = False
    free_motions, least_held = modes.unheld(sp.eye(basis.N, format="csr")[fixed], surface.operator)
    loose = np.flatnonzero(free_motions)
    if loose.size == 0:
        return
    b, count = loose[0], modes.count
    (cx, cy), size = modes.centroid[:, b], modes.size[b]
    nodes = np.bincount(modes.body, minlength=count)
    where = "the Dirichlet conditions and the contact part" if surface.size else "the Dirichlet conditions"
    vector = least_held[b]
    tx, ty, spin = vector * np.sign(vector[np.argmax(np.abs(vector))])
    if free_motions[b] > 1:
        motion = "all three" if free_motions[b] == 3 else "two of the three"
    elif abs(spin) < 1e-9:
        motion = f"a translation along ({np.round(tx, 9) + 0.0:.3g}, {np.round(ty, 9) + 0.0:.3g})"
    else:
        center = np.array([cx - ty * size / spin, cy + tx * size / spin])
        center = np.round(center / size, 9) * size + 0.0  # no round-off digits around 0
        motion = f"a rotation about ({center[0]:.6g}, {center[1]:.6g})"
    if count == 1:
        raise CaseError(f"{where} leave a rigid motion of the body free ({motion}): add boundary.dirichlet entries")
    inside = np.flatnonzero(modes.body == b)
    point = inside[np.argmin((x[inside] - cx) ** 2 + (y[inside] - cy) ** 2)]
    raise CaseError(f"the mesh has {count} separate parts; {where} leave a rigid motion of the part of {nodes[b]} "
                    f"nodes through the node at ({x[point]:.6g}, {y[point]:.6g}) free ({motion})"
                    f"{f' (and of {loose.size - 1} more)' if loose.size > 1 else ''}: add boundary.dirichlet "
                    f"entries on it, or join it to the rest of the mesh")
