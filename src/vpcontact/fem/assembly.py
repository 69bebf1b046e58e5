"""Finite element operators on P1 displacements and P0 stresses.

- the elastic stiffness A: (ℰε(u), ε(v))_Q, the bulk term of (3.3);
- the load vector F(t) of (2.24): ∫_Ω f0·v dx + ∫_Γ2 f2·v da;
- element strains ε(u) (constant on each element) and the nodal force Bᵀz of a P0 stress z.

Triangles in 2D, tetrahedra in 3D: the element comes from the mesh, everything else is the same.
The displacement space (space.py) numbers the dofs as scikit-fem does; scikit-fem gives the quadrature
of the loads; the bulk operators are the vectorized kernels of kernels.py (the same matrices as
scikit-fem's forms, to rounding, in a fraction of the time and memory), and each load term is one sparse map, built once, from the density
at its quadrature points to the nodal loads.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp
from skfem import Basis
from skfem.assembly.basis import AbstractBasis

from ..errors import CaseError, point, quoted
from ..expressions.parse import Expression
from ..laws.elasticity import Elasticity
from ..mesh.mesh import Mesh
from .facet_basis import facet_basis
from .kernels import elastic_stiffness, geometry, strains, stress_work
from .space import DisplacementSpace
from ..mesh.cells import coordinates

#: A load density: f(x, y, t) -> (fx, fy) in 2D, f(x, y, z, t) -> (fx, fy, fz) in 3D, each an array
#: broadcastable to x's shape.
Density = Callable[..., tuple]


def displacement_space(mesh: Mesh) -> DisplacementSpace:
    """The P1 vector space of ``mesh`` (dofs of node i: ``space.nodal_dofs[:, i]``)."""
    return DisplacementSpace.of(mesh.mesh)


def stiffness(basis: DisplacementSpace, elasticity: Elasticity, nodes: np.ndarray | None = None) -> sp.csr_matrix:
    """The elastic stiffness matrix A_ij = (ℰε(φ_j), ε(φ_i))_Q; the Lamé parameters are numbers (one
    material) or arrays with one value per element (ℰ(x) of (2.16), constant on each element). ``nodes``: a mask
    over the mesh's nodes whose rows alone are assembled, each whole, from the elements that touch them, the other
    rows left empty (one MPI rank's rows); None: every row."""
    g, count = geometry(basis), basis.mesh.p.shape[1]
    if nodes is None:
        lam, mu = elasticity.lame
        return elastic_stiffness(g, lam, mu, count, basis.nodal_dofs)
    touching = np.flatnonzero(nodes[g.cells].any(axis=0))
    lam, mu = elasticity.on(touching).lame
    rows = np.zeros(basis.N, dtype=bool)
    rows[basis.nodal_dofs[:, nodes]] = True
    return rows_of(elastic_stiffness(g.of(touching), lam, mu, count, basis.nodal_dofs), rows)


def rows_of(matrix: sp.csr_matrix, rows: np.ndarray) -> sp.csr_matrix:
    """``matrix`` with its rows outside the mask ``rows`` emptied (its shape kept)."""
    lengths = np.where(rows, np.diff(matrix.indptr), 0)
    kept = np.repeat(rows, np.diff(matrix.indptr))
    return sp.csr_matrix((matrix.data[kept], matrix.indices[kept], np.concatenate([[0], np.cumsum(lengths)])),
                         shape=matrix.shape)


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


def _load_map(basis: AbstractBasis) -> tuple[np.ndarray, sp.csr_matrix]:
    """The nodes of a scalar P1 ``basis`` (of facets or elements) and M (those nodes × cells·points)
    with (M f)_i = Σ_q φ_i(x_q) f(x_q) w_q: the integral ∫ f φ_i of a density known at the quadrature
    points x_q. Only the nodes the cells touch are rows, so a load on a boundary part costs its own
    nodes, not the mesh's."""
    cells, points = basis.dx.shape
    values = np.stack([np.asarray(basis.basis[i][0]) * basis.dx for i in range(basis.Nbfun)])  # (functions, cells, points)
    nodes, rows = np.unique(basis.element_dofs, return_inverse=True)
    rows = np.broadcast_to(rows.reshape(basis.element_dofs.shape)[:, :, None], values.shape)
    columns = np.broadcast_to(np.arange(cells * points).reshape(cells, points), values.shape)
    return nodes, sp.csr_matrix((values.ravel(), (rows.ravel(), columns.ravel())), shape=(nodes.size, cells * points))


class _Term:
    """One load density and where it is applied: the quadrature points of its facets or elements, and
    the map from the density's values there to the nodal loads of one component."""

    def __init__(self, name: str, basis: AbstractBasis, nodes: np.ndarray | None, density: Density):
        """``basis``: the scalar P1 basis of the facets or elements with the load's quadrature; ``nodes``: the
        mesh's nodes that its nodes are (None: the same numbers)."""
        self.points = np.asarray(basis.global_coordinates())  # (d, cells, points of a cell)
        self.names = coordinates(self.points.shape[0])
        self.signature = f"f({', '.join(self.names)}, t)"
        self.returns = f"({', '.join('f' + n for n in self.names)})"
        if not callable(density):
            raise CaseError(f"{name} = {type(density).__name__}: expected a function {self.signature} -> {self.returns}")
        self.name, self.density = name, density
        self.nodes, self.map = _load_map(basis)
        if nodes is not None:
            self.nodes = nodes[self.nodes]

    def values(self, t: float, step: int | None = None) -> np.ndarray:
        """The density's components at the quadrature points at time t (of time step ``step``, if
        given), shape (d, cells, points); NonFiniteLoad where a value is not finite."""
        d, shape = self.points.shape[0], self.points.shape[1:]
        with np.errstate(all="ignore"):  # a non-finite value is reported below, with where it is
            try:
                values = self.density(*self.points, t)
            except Exception as error:  # noqa: BLE001 - a user's function may raise anything
                raise CaseError(f"{self.name}: {self.signature} at t = {t:.10g} raised {type(error).__name__}: "
                                f"{error}") from error
            try:
                if len(values) != d:
                    raise ValueError
                values = np.stack([np.broadcast_to(_real(f), shape) for f in values])
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

    def message(self, component: int, value: float, index: int | None, when: str) -> str:
        """``<key> = "<source>": not finite (inf) at (x, y) = (…), t = …``: the one line of NonFiniteLoad, at the
        quadrature point ``index`` (None: at every point)."""
        if isinstance(self.density, ExpressionDensity):
            f = self.density.components[component]
            what = f"{f.where} = {quoted(f.source)}"
        else:
            what = f"{self.name} (f{self.names[component]})"
        if index is None:
            where = "every point"
        else:
            where = f"({', '.join(self.names)}) = {point(self.points.reshape(len(self.names), -1)[:, index])}"
        return f"{what}: not finite ({value}) at {where}, {when}; a load must be finite wherever it is applied"


def _real(value) -> np.ndarray:
    """``value`` (a component a user's function returned) as floats; TypeError unless it holds real numbers (a
    complex value would lose its imaginary part, a boolean is no load)."""
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"not real numbers: {array.dtype}")
    return array.astype(float)


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

    def __init__(self, basis: DisplacementSpace, mesh: Mesh, tractions: list[tuple[str, object, Density]],
                 body_forces: list[tuple[str, Density]]):
        """``tractions``: (name, part, density); ``body_forces``: (name, density); a name is the key of
        the density in messages, e.g. ``boundary.traction[0].value``."""
        self._ndofs, self._nodal_dofs = basis.N, basis.nodal_dofs
        scalar = basis.elem.elem
        #: (facets of the part, density) of each traction and the density of each body force, for the
        #: residual of an error estimate (:mod:`vpcontact.estimate.residual`)
        self.tractions = [(mesh.facets(part), f) for _, part, f in tractions]
        self.body_forces = [f for _, f in body_forces]
        self._terms = [_Term(name, *facet_basis(mesh.mesh, mesh.facets(part), scalar, 4), f)
                       for name, part, f in tractions]
        self._terms += [_Term(name, Basis(mesh.mesh, scalar, intorder=4), None, f) for name, f in body_forces]
        self._everywhere = self.on(np.arange(self._ndofs))

    def __call__(self, t: float) -> np.ndarray:
        """F(t) at every nodal dof."""
        return self._everywhere(t)

    def on(self, dofs: np.ndarray) -> "LoadOnDofs":
        """t ↦ F(t)[dofs], computed at the dofs the loads reach only."""
        return LoadOnDofs(self._terms, self._nodal_dofs, self._ndofs, dofs)

    def check(self, times: Sequence[float]) -> None:
        """Refuse (NonFiniteLoad) a density that is not finite at a point where it is applied at one of
        ``times`` (the step times t_n: a run evaluates the loads there, and at the sub-step times of a
        step it cuts, which ``F(t)`` checks as they come)."""
        for term in self._terms:
            term.check(times)


class LoadOnDofs:
    """t ↦ F(t)[dofs]: the load vector of (2.24) at chosen dofs (the free ones of a time step).

    Each term adds its nodal loads at the dofs of its own nodes only, so a traction on a boundary part
    costs that part's nodes, not the mesh's; ``support`` holds the positions (in ``dofs``) where F can
    be nonzero, ascending: a solver may skip the rest (the condensed method's right-hand side reuse).
    """

    def __init__(self, terms: list[_Term], nodal_dofs: np.ndarray, ndofs: int, dofs: np.ndarray):
        position = np.full(ndofs, -1)
        position[dofs] = np.arange(len(dofs))
        self._size, self._terms, self._targets = len(dofs), terms, []
        for term in terms:  # per component: the term's rows that land on ``dofs``, and where
            at = [position[component[term.nodes]] for component in nodal_dofs]
            self._targets.append([(np.flatnonzero(p >= 0), p[p >= 0]) for p in at])
        reached = [p for targets in self._targets for _, p in targets]
        self.support = np.unique(np.concatenate(reached)) if reached else np.zeros(0, dtype=int)

    def __call__(self, t: float) -> np.ndarray:
        F = np.zeros(self._size)
        with np.errstate(all="ignore"):  # an overflow is reported below
            for term, targets in zip(self._terms, self._targets):
                for (rows, positions), f in zip(targets, term.values(t)):
                    F[positions] += (term.map @ f.ravel())[rows]
        if not np.all(np.isfinite(F[self.support])):
            raise NonFiniteLoad(f"the load vector F(t) at t = {t:.10g} is not finite: its densities are finite but "
                                f"too large for float64 once integrated")
        return F


def element_strain(basis: DisplacementSpace, u: np.ndarray) -> np.ndarray:
    """ε(u) on each element, shape (d, d, nelements) (constant for P1)."""
    return strains(geometry(basis), u)


def stress_force(basis: DisplacementSpace, z: np.ndarray) -> np.ndarray:
    """The nodal force Bᵀz = ∫_Ω z : ε(v) dx of a P0 stress field z of shape (d, d, nelements)."""
    return stress_work(geometry(basis), z)
