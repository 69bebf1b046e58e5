"""Finite element operators on P1 displacements and P0 stresses (scikit-fem forms).

- the elastic stiffness A: (ℰε(u), ε(v))_Q, the bulk term of (3.3);
- the load vector F(t) of (2.24): ∫_Ω f0·v dx + ∫_Γ2 f2·v da;
- element strains ε(u) (constant on each element) and the nodal force Bᵀz of a P0 stress z.

Triangles in 2D, tetrahedra in 3D: the element comes from the mesh, everything else is the same.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp
from skfem import (Basis, BilinearForm, ElementTetP1, ElementTriP1, ElementVector, FacetBasis, LinearForm, MeshTet1,
                   asm)
from skfem.helpers import ddot, eye, sym_grad, trace
from skfem.models.elasticity import linear_elasticity

from .errors import CaseError, quoted
from .expressions import Expression
from .material import Elasticity
from .mesh import Mesh
from .space import coordinates

#: A load density: f(x, y, t) -> (fx, fy) in 2D, f(x, y, z, t) -> (fx, fy, fz) in 3D, each an array
#: broadcastable to x's shape.
Density = Callable[..., tuple]


def _centroid_rule(dim: int) -> tuple[np.ndarray, np.ndarray]:
    """The centroid rule of the reference simplex: exact for the bulk forms of P1 × P0 (their
    integrands are constant per element); its weight is the simplex's volume 1/d!."""
    return np.full((dim, 1), 1.0 / (dim + 1)), np.array([1.0 / math.factorial(dim)])


def displacement_basis(mesh: Mesh) -> Basis:
    """The P1 vector basis (dofs of node i: ``basis.nodal_dofs[:, i]``) with the centroid rule."""
    element = ElementTetP1() if isinstance(mesh.mesh, MeshTet1) else ElementTriP1()
    return Basis(mesh.mesh, ElementVector(element), quadrature=_centroid_rule(mesh.dim))


@BilinearForm
def _elastic_form(u, v, w):
    strain = sym_grad(u)
    return ddot(2.0 * w["mu"] * strain + w["lam"] * eye(trace(strain), strain.shape[0]), sym_grad(v))


def stiffness(basis: Basis, elasticity: Elasticity) -> sp.csr_matrix:
    """The elastic stiffness matrix A_ij = (ℰε(φ_j), ε(φ_i))_Q; the Lamé parameters are numbers (one
    material) or arrays with one value per element (ℰ(x) of (2.16), constant on each element)."""
    lam, mu = elasticity.lame
    if np.ndim(lam) == 0 and np.ndim(mu) == 0:
        return asm(linear_elasticity(lam, mu), basis).tocsr()
    points = basis.X.shape[-1]
    per_element = {name: np.repeat(np.broadcast_to(value, (basis.nelems,))[:, None], points, axis=1)
                   for name, value in (("lam", lam), ("mu", mu))}
    return asm(_elastic_form, basis, **per_element).tocsr()


@LinearForm
def _density_form(v, w):
    return sum(w["f"][i] * v[i] for i in range(v.shape[0]))


class ExpressionDensity:
    """The density (fx, fy[, fz]) of d expressions in the coordinates and t of a case (their keys name
    them in messages)."""

    def __init__(self, *components: Expression):
        self.components = components
        self.names = coordinates(len(components))

    def __call__(self, *coordinates_and_time) -> tuple[np.ndarray, ...]:
        *points, t = coordinates_and_time
        return tuple(f(**dict(zip(self.names, points)), t=t) for f in self.components)


class NonFiniteLoad(CaseError):
    """A load density that is not finite at a point where it is applied, at a time of the run."""


#: Most values of one expression evaluated at once when the loads are checked over the time grid.
CHECK_CHUNK = 2**20


class _Term:
    """One load density and where it is applied: the quadrature points of its facets or elements."""

    def __init__(self, name: str, basis: Basis, density: Density):
        self.points = np.asarray(basis.global_coordinates())  # (d, cells, points of a cell)
        self.names = coordinates(self.points.shape[0])
        self.signature = f"f({', '.join(self.names)}, t)"
        self.returns = f"({', '.join('f' + n for n in self.names)})"
        if not callable(density):
            raise CaseError(f"{name} = {type(density).__name__}: expected a function {self.signature} -> {self.returns}")
        self.name, self.basis, self.density = name, basis, density

    def values(self, t: float, step: int | None = None) -> np.ndarray:
        """The density's components at the quadrature points at time t (of time step ``step``, if
        given), shape (d, cells, points); NonFiniteLoad where a value is not finite."""
        d, shape = self.points.shape[0], self.points.shape[1:]
        with np.errstate(all="ignore"):  # a non-finite value is reported below, with where it is
            values = self.density(*self.points, t)
            try:
                if len(values) != d:
                    raise ValueError
                values = np.stack([np.broadcast_to(np.asarray(f, dtype=float), shape) for f in values])
            except (TypeError, ValueError):
                raise CaseError(f"{self.name}: {self.signature} must return {self.returns}, each a number or an "
                                f"array of x's shape {shape}; it returned {_kind(values)}") from None
        bad = ~np.isfinite(values)
        if bad.any():
            component, cell, point = np.unravel_index(np.argmax(bad), bad.shape)
            point = cell * shape[1] + point if self._uses_space(component) else None
            when = f"t = {t:.10g}" + ("" if step is None else f" (step {step})")
            raise NonFiniteLoad(self.message(component, values.reshape(d, -1)[component, point or 0], point, when))
        return values

    def _uses_space(self, component: int) -> bool:
        """Does the density's component depend on the coordinates (a Python function: it may)?"""
        if isinstance(self.density, ExpressionDensity):
            return bool(self.density.components[component].depends_on & set(self.names))
        return True

    def check(self, times: Sequence[float]) -> None:
        """NonFiniteLoad naming the first time of ``times`` and a point where the density is not finite."""
        if isinstance(self.density, ExpressionDensity):
            for component, f in enumerate(self.density.components):
                self._check_expression(component, f, times)
        else:
            for n, t in enumerate(times, start=1):
                self.values(t, n)

    def _check_expression(self, component: int, f: Expression, times: Sequence[float]) -> None:
        """Evaluate f only over the variables it uses: once if constant, over the times if it uses t
        alone, over the points if it uses the coordinates alone, over points × times in chunks
        otherwise."""
        points = dict(zip(self.names, self.points.reshape(len(self.names), -1)))
        size = self.points[0].size
        space, time = self._uses_space(component), "t" in f.depends_on
        chunk = max(1, CHECK_CHUNK // size) if space else CHECK_CHUNK
        with np.errstate(all="ignore"):
            if not time:
                values = f(**points) if space else np.array([f()])
                bad = np.flatnonzero(~np.isfinite(values))
                if bad.size:
                    point = int(bad[0]) if space else None
                    raise NonFiniteLoad(self.message(component, values[bad[0]], point, "every t"))
                return
            rows = {name: x[None, :] for name, x in points.items()}
            for start in range(0, len(times), chunk):
                t = np.asarray(times[start:start + chunk])
                values = f(**rows, t=t[:, None]) if space else f(t=t)[:, None]
                bad = ~np.isfinite(values)
                if bad.any():
                    step, point = np.unravel_index(np.argmax(bad), bad.shape)
                    raise NonFiniteLoad(self.message(component, values[step, point], point if space else None,
                                                     f"t = {t[step]:.10g} (step {start + step + 1})"))

    def message(self, component: int, value: float, point: int | None, when: str) -> str:
        """``<key> = "<source>": not finite (inf) at (x, y) = (…), t = …``: the one line of NonFiniteLoad."""
        if isinstance(self.density, ExpressionDensity):
            f = self.density.components[component]
            what = f"{f.where} = {quoted(f.source)}"
        else:
            what = f"{self.name} (f{self.names[component]})"
        if point is None:
            where = "every point"
        else:
            at = self.points.reshape(len(self.names), -1)[:, point]
            where = f"({', '.join(self.names)}) = ({', '.join(f'{c:.6g}' for c in at)})"
        return f"{what}: not finite ({value}) at {where}, {when}; a load must be finite wherever it is applied"


def _kind(value) -> str:
    """A short description of what a user's function returned."""
    if isinstance(value, (tuple, list)):
        return f"a {type(value).__name__} of {len(value)} values of shapes {[np.shape(v) for v in value]}"
    return f"a value of type {type(value).__name__} and shape {np.shape(value)}"


class LoadVector:
    """F(t) of (2.24) for traction densities on boundary parts and body force densities.

    The densities are evaluated at the quadrature points of the facets of their part (tractions) or of
    every element (body forces); :meth:`check` evaluates them at all those points at every time of a
    grid, ``F(t)`` at time t; both raise :class:`NonFiniteLoad` where a value is not finite.
    """

    def __init__(self, basis: Basis, mesh: Mesh, tractions: list[tuple[str, object, Density]],
                 body_forces: list[tuple[str, Density]]):
        """``tractions``: (name, part, density); ``body_forces``: (name, density); a name is the key of
        the density in messages, e.g. ``boundary.traction[0].value``."""
        self._ndofs = basis.N
        self._terms = [_Term(name, FacetBasis(mesh.mesh, basis.elem, facets=mesh.facets(part), intorder=4), f)
                       for name, part, f in tractions]
        self._terms += [_Term(name, Basis(mesh.mesh, basis.elem, intorder=4), f) for name, f in body_forces]

    def __call__(self, t: float) -> np.ndarray:
        F = np.zeros(self._ndofs)
        with np.errstate(all="ignore"):  # an overflow is reported below
            for term in self._terms:
                F += asm(_density_form, term.basis, f=term.values(t))
        if not np.all(np.isfinite(F)):
            raise NonFiniteLoad(f"the load vector F(t) at t = {t:.10g} is not finite: its densities are finite but "
                                f"too large for float64 once integrated")
        return F

    def check(self, times: Sequence[float]) -> None:
        """Refuse (NonFiniteLoad) a density that is not finite at a point where it is applied at one of
        ``times`` (the step times t_n: a run evaluates the loads there, and at the sub-step times of a
        step it cuts, which ``F(t)`` checks as they come)."""
        for term in self._terms:
            term.check(times)


def element_strain(basis: Basis, u: np.ndarray) -> np.ndarray:
    """ε(u) on each element, shape (d, d, nelements) (constant for P1)."""
    return sym_grad(basis.interpolate(u))[:, :, :, 0]


@LinearForm
def _stress_work(v, w):
    return ddot(w["z"], sym_grad(v))


def stress_force(basis: Basis, z: np.ndarray) -> np.ndarray:
    """The nodal force Bᵀz = ∫_Ω z : ε(v) dx of a P0 stress field z of shape (d, d, nelements)."""
    return asm(_stress_work, basis, z=np.repeat(z[..., None], basis.X.shape[-1], axis=-1))
