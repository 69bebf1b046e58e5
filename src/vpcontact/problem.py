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


def _check_rigid_motions(mesh: meshes.Mesh, basis: Basis, free: np.ndarray, surface: ContactSurface):
    """Refuse a body whose rigid motions are held neither by Dirichlet conditions nor by contact."""
    x, y = mesh.mesh.p
    rigid = np.zeros((basis.N, 3))
    rigid[basis.nodal_dofs[0], 0] = 1.0
    rigid[basis.nodal_dofs[1], 1] = 1.0
    rigid[basis.nodal_dofs[0], 2] = -y
    rigid[basis.nodal_dofs[1], 2] = x
    fixed = np.setdiff1d(np.arange(basis.N), free)
    held = [rigid[fixed], surface.operator @ rigid]
    scale = np.abs(rigid).max()
    if np.linalg.matrix_rank(np.vstack(held), tol=1e-9 * scale) < 3:
        where = "the Dirichlet conditions and the contact part" if surface.size else "the Dirichlet conditions"
        raise CaseError(f"{where} leave a rigid motion of the body free: add boundary.dirichlet entries")
