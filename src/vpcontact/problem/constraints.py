"""The Dirichlet conditions of a problem resolved on its mesh: the dofs they hold, and the displacement u_D(t)
they prescribe there.

An entry of ``boundary.dirichlet`` holds the listed components (all of them by default) at the nodes of its part,
at u_D = 0 or at the values of its expressions in the coordinates and t (a prescribed displacement, e.g. a punch
pressed by ``value = ["-0.4*t"]``); a Python function f(x, y, (z,) t) of the API may give a component's value
instead (``build_problem(displacements={part: {component: f}})``). At every time level the held dofs carry
u = u_D(t), and the step problem is solved for the free dofs f with the right-hand side

    b = F_f(t) − Bᵀz − A_fh u_D(t)      (A_fh: the stiffness's coupling of the free and the held dofs),

so that every method keeps its operators: the condensed method keeps its factor of A0 and only its right-hand side
changes (the coupling reaches the free neighbours of the moving nodes: the load's support grows by those rows).

Refused before the run, each in one line naming the entries: two entries holding a dof at different values; a
prescribed value that moves a contact node along its normal (its penetration is the contact's unknown, it cannot
also be imposed); a Python function with the wrong arguments; a value that is not finite at a node at a step time.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError, brief, point, quoted
from ..expressions.parse import Expression, parse_expression
from ..fem.assembly import CHECK_CHUNK, NonFiniteLoad
from ..laws.python_laws import accepts, parameters_in_words
from ..mesh.cells import component, coordinates
from ..mesh.mesh import Mesh
from ..mesh.node_sets import nearest_node, nodes_where
from .options import ProblemOptions

#: A contact node moves along its normal with a held component when the normal's component is above this.
NORMAL_COMPONENT = 1e-12


class PrescribedValue:
    """u_D of one component of one entry: an expression of the case, or a Python function f(x, y, (z,) t) of the
    API, evaluated at the entry's nodes (``points``: (d, n)); ``key`` names it in messages."""

    def __init__(self, value: Expression | Callable, points: np.ndarray, key: str):
        self.value, self.points, self.key = value, points, key
        self.names = coordinates(points.shape[0])

    @property
    def identity(self):
        """What two entries holding one dof must share to agree: the expression's text, or the function itself."""
        return ("expression", self.value.source) if isinstance(self.value, Expression) else ("function", id(self.value))

    def __call__(self, t: float) -> np.ndarray:
        """u_D at the nodes at time t, (n,); NonFiniteLoad where a value is not finite (a sub-step time of a cut
        step: the step times are checked before the run)."""
        values = self._evaluate(t)
        self._check_finite(values[None, :], np.array([t]), 0)
        return values

    def _evaluate(self, t):
        n = self.points.shape[1]
        with np.errstate(all="ignore"):  # a value that is not finite is reported by the caller
            if isinstance(self.value, Expression):
                return np.broadcast_to(self.value(**dict(zip(self.names, self.points)), t=t), (n,)).astype(float)
            try:
                values = self.value(*self.points, t)
            except CaseError:
                raise
            except Exception as error:  # noqa: BLE001 - a user's function may raise anything
                raise CaseError(f"{self.key} = {brief(self.value)}: f({', '.join(self.names)}, t) at t = {t:.10g} "
                                f"raised {type(error).__name__}: {error}") from error
        array = np.asarray(values)
        if array.dtype.kind not in "iuf" or array.shape not in ((), (1,), (n,)):
            raise CaseError(f"{self.key} = {brief(self.value)}: f({', '.join(self.names)}, t) must return the "
                            f"displacement at the nodes, a number or an array of x's shape ({n},); it returned "
                            f"{array.dtype} values of shape {array.shape}")
        return np.broadcast_to(array, (n,)).astype(float)

    def check(self, times: np.ndarray) -> None:
        """NonFiniteLoad naming the first time of ``times`` (the step times) and a node where u_D is not finite:
        an expression over the times in chunks of nodes × times, a function once per time."""
        if not isinstance(self.value, Expression):
            for start, t in enumerate(times):
                self._check_finite(self._evaluate(t)[None, :], times[start:start + 1], start)
            return
        chunk = max(1, CHECK_CHUNK // max(1, self.points.shape[1]))
        rows = {name: x[None, :] for name, x in zip(self.names, self.points)}
        for start in range(0, len(times), chunk):
            t = times[start:start + chunk]
            with np.errstate(all="ignore"):
                values = np.broadcast_to(self.value(**rows, t=t[:, None]), (t.size, self.points.shape[1]))
            self._check_finite(values, t, start)

    def _check_finite(self, values: np.ndarray, times: np.ndarray, first: int) -> None:
        bad = ~np.isfinite(values)
        if bad.any():
            step, node = np.unravel_index(np.argmax(bad), bad.shape)
            what = (f"{self.key} = {quoted(self.value.source)}" if isinstance(self.value, Expression)
                    else f"{self.key} = {brief(self.value)}")
            raise NonFiniteLoad(f"{what}: not finite ({values[step, node]}) at ({', '.join(self.names)}) = "
                                f"{point(self.points[:, node])}, t = {times[step]:.10g} (step {first + step + 1}); "
                                f"a prescribed displacement must be finite")


@dataclass(frozen=True)
class HeldEntry:
    """One entry of ``boundary.dirichlet`` or ``boundary.point`` on the mesh: its key, its name (the columns of its
    reaction and mean displacement), what it holds in words (``description``: "part 'top'", "the nodes where …",
    "the node at (…) nearest to (…)"), its nodes, the components it holds and u_D of each (None: 0)."""

    key: str
    label: str
    description: str
    nodes: np.ndarray
    components: tuple[int, ...]
    values: tuple[PrescribedValue | None, ...]


class DirichletConditions:
    """The dofs the Dirichlet conditions hold (``held``, ascending) and those they leave free (``free``), and
    u_D(t) at the held ones (``self(t)``); ``moves``: some held dof has a nonzero u_D."""

    def __init__(self, entries: list[HeldEntry], nodal_dofs: np.ndarray):
        self.entries = entries
        ndofs = nodal_dofs.size
        owner = np.full(ndofs, -1)  # the entry that gave each dof its value (-1: none holds it)
        value_of = np.full(ndofs, -1)  # the code of that value: 0 for u_D = 0, one code per expression or function
        codes: dict = {None: 0}
        for index, entry in enumerate(entries):
            for c, value in zip(entry.components, entry.values):
                dofs = nodal_dofs[c, entry.nodes]
                code = codes.setdefault(None if value is None else value.identity, len(codes))
                clash = dofs[(owner[dofs] >= 0) & (value_of[dofs] != code)]
                if clash.size:
                    other = entries[owner[clash[0]]]
                    raise CaseError(f"{other.key} and {entry.key} both hold u_{coordinates(nodal_dofs.shape[0])[c]} "
                                    f"at {clash.size} node(s) with different values: a node has one displacement; "
                                    f"give the shared nodes one value (the same expression) or hold them in one entry")
                owner[dofs], value_of[dofs] = index, code
        self.held, self.free = np.flatnonzero(owner >= 0), np.flatnonzero(owner < 0)
        position = np.full(ndofs, -1)
        position[self.held] = np.arange(self.held.size)
        #: (positions in ``held``, u_D) of every entry's component with a nonzero value
        self._moving = [(position[nodal_dofs[c, entry.nodes]], value) for entry in entries
                        for c, value in zip(entry.components, entry.values) if value is not None]
        self.moves = bool(self._moving)

    def __call__(self, t: float) -> np.ndarray:
        """u_D(t) at the held dofs, (held dofs,)."""
        values = np.zeros(self.held.size)
        for positions, value in self._moving:
            values[positions] = value(t)
        return values

    def moving_dofs(self) -> np.ndarray:
        """The held dofs with a nonzero u_D (ascending)."""
        if not self.moves:
            return np.zeros(0, dtype=int)
        return self.held[np.unique(np.concatenate([positions for positions, _ in self._moving]))]

    def check(self, times: Sequence[float]) -> None:
        """NonFiniteLoad for a u_D that is not finite at a node at one of ``times`` (the step times)."""
        times = np.asarray(times, dtype=float)
        for _, value in self._moving:
            value.check(times)

    def check_contact(self, operator: sp.csr_matrix, coordinates_of_nodes: np.ndarray,
                      contact_nodes: np.ndarray) -> None:
        """Refuse a nonzero u_D on a component along which a contact node moves with its normal (``operator``: N,
        contact nodes × dofs): that node's penetration would be imposed, and it is the contact's unknown."""
        moving = self.moving_dofs()
        if moving.size == 0 or operator.shape[0] == 0:
            return
        touched = np.abs(operator[:, moving]).max(axis=1).toarray().ravel() > NORMAL_COMPONENT
        if not touched.any():
            return
        node = contact_nodes[np.argmax(touched)]
        dim = coordinates_of_nodes.shape[0]
        entry = next(e for e in self.entries if node in e.nodes and any(v is not None for v in e.values))
        raise CaseError(f"{entry.key}.value moves {int(touched.sum())} contact node(s) along their normal (the first "
                        f"at {point(coordinates_of_nodes[:, node])}, {dim}D): a contact node's penetration is the "
                        f"contact's unknown and cannot be prescribed; prescribe the displacement on a part away from "
                        f"the contact, or only components along the contact surface")


def dirichlet_conditions(options: ProblemOptions, mesh: Mesh, nodal_dofs: np.ndarray,
                         displacements: Mapping | None = None) -> DirichletConditions:
    """The Dirichlet conditions of ``options`` on ``mesh``; ``displacements``: {part: {component: f}}, Python
    functions f(x, y, (z,) t) of the API that give u_D of a component an entry of that part holds."""
    dim, p = mesh.dim, mesh.mesh.p
    functions = _functions(options, displacements, dim)
    entries = []
    for item in options.boundary.dirichlet:
        key = item.key
        nodes, description = held_nodes(item, mesh)
        names = item.components or coordinates(dim)
        sources = item.value if item.value is not None else (0.0,) * len(names)
        if len(sources) != len(names):
            raise CaseError(f"{key}.value has {len(sources)} expressions and the entry holds {len(names)} components "
                            f"({', '.join(names)}): give one expression in {', '.join(coordinates(dim))}, t per "
                            f"component")
        values = []
        for j, (name, source) in enumerate(zip(names, sources)):
            whole_part = item.where is None and item.at is None
            function = functions.get((str(item.part), name)) if whole_part else None
            if function is not None:
                values.append(PrescribedValue(function, p[:, nodes], f"displacements[{brief(item.part)}][\"{name}\"]"))
                continue
            expression = parse_expression(source, (*coordinates(dim), "t"), where=f"{key}.value[{j}]")
            zero = not expression.depends_on and expression() == 0.0
            values.append(None if zero else PrescribedValue(expression, p[:, nodes], f"{key}.value[{j}]"))
        label = item.name if item.name is not None else str(item.part) if item.where is None and item.at is None \
            else key.replace("boundary.", "").replace("[", "").replace("]", "")
        entries.append(HeldEntry(key, label, description, nodes, tuple(component(c) for c in names), tuple(values)))
    return DirichletConditions(entries, nodal_dofs)


def held_nodes(item, mesh: Mesh) -> tuple[np.ndarray, str]:
    """The nodes an entry holds (sorted) and what they are in words: those of its part, those where its condition
    holds (among its part's, with both), or the node nearest to its point."""
    if item.at is not None:
        node, distance = nearest_node(mesh, list(item.at), f"{item.key}.at")
        return np.array([node]), (f"the node at {point(mesh.mesh.p[:, node])}, {distance:.3g} from {item.key}.at"
                                  if distance > 0 else f"the node at {point(mesh.mesh.p[:, node])}")
    if item.where is None:
        return mesh.nodes(item.part), f"part '{item.part}'"
    nodes = nodes_where(mesh, item.where, f"{item.key}.where", within=None if item.part is None else str(item.part))
    within = "" if item.part is None else f" of part '{item.part}'"
    return nodes, f"the {nodes.size} node(s){within} where {quoted(item.where)}"


def _functions(options: ProblemOptions, displacements: Mapping | None, dim: int) -> dict:
    """{(part, component): f} of ``displacements``, each checked: a part and component that an entry holds, f a
    function of the coordinates and t."""
    if displacements is None:
        return {}
    if not isinstance(displacements, Mapping):
        raise CaseError(f"displacements = {brief(displacements)}: expected {{part: {{component: f(x, y, (z,) t)}}}}")
    held = {(str(item.part), name) for item in options.boundary.dirichlet if item.where is None and item.at is None
            for name in item.components or coordinates(dim)}
    functions = {}
    for part, by_component in displacements.items():
        if not isinstance(by_component, Mapping):
            raise CaseError(f"displacements[{brief(part)}] = {brief(by_component)}: expected {{component: "
                            f"f({', '.join(coordinates(dim))}, t)}}")
        for name, function in by_component.items():
            where = f"displacements[{brief(part)}][{brief(name)}]"
            if (str(part), name) not in held:
                raise CaseError(f"{where}: no boundary.dirichlet entry holds component {brief(name)} of part "
                                f"{brief(part)}; add one (its value is then this function)")
            if not callable(function) or not accepts(function, dim + 1):
                takes = parameters_in_words(function) if callable(function) else "is not a function"
                raise CaseError(f"{where} = {brief(function)} {'takes ' + takes if callable(function) else takes}: "
                                f"expected f({', '.join(coordinates(dim))}, t) -> the displacement at the nodes")
            functions[(str(part), name)] = function
    return functions
