"""The initial state of a run (2.7), (2.21): u_0 at the nodes, σ_0 per element, ξ_0 at the contact nodes
and the start time t_0.

Where each comes from, the first that applies:

1. the arrays of the Python API (``build_problem(..., initial_displacement=, initial_stress=,
   initial_xi=)``);
2. a restart, ``initial.from_run`` at ``initial.step``: u_0, σ_0 and ξ_0 of that field step of the run's
   ``solution.npz`` (the mesh and the contact nodes must be the same); t_0 is the time of that step
   unless ``time.start`` is given;
3. the case's expressions in the coordinates: ``initial.displacement`` at the nodes, ``initial.stress``
   at the element centroids, ``initial.xi`` at the contact nodes;
4. zero (t_0 = ``time.start``, default 0).

u_0 must lie in V: zero on the Dirichlet components, or the prescribed u_D(t_0) where an entry has a value
(values within rounding of it, 1e-12 of the largest |u_0|, are set to it; a body at rest, u_0 = 0, may start away
from u_D(t_0), its first step moves the held nodes there) and admissible on Γ3, u_0·ν − g0 ≤ g at every contact node (to the
solver's complementarity tolerance, ``solver.tolerance`` × the body's size: the state a run reached is
admissible); ξ_0 ≥ 0; everything finite. A refusal is a CaseError naming the worst node or element.
"""

from __future__ import annotations

import os
import zipfile
import zlib
from dataclasses import dataclass

import numpy as np

from ..errors import CaseError, brief, point, quoted
from ..expressions.parse import values_at
from ..fem.contact_surface import ContactSurface
from ..fem.space import DisplacementSpace
from ..inputs import check_regular_file
from ..laws.contact import ContactLaw
from ..mesh.mesh import Mesh
from ..mesh.cells import SIMPLICES, coordinates
from .constraints import DirichletConditions
from .options import ProblemOptions
from .time_grid import check_time_span

#: |u_0| below this fraction of the largest |u_0| is rounding: such values on a Dirichlet component are 0.
ROUNDING = 1e-12


@dataclass(repr=False)
class InitialState:
    """u_0 (nnodes, d), σ_0 (d, d, nelements), ξ_0 (m,) and t_0 of a run; ``names``: how the messages
    name the source of each field (a case key, an argument of the API, or the run restarted from)."""

    displacement: np.ndarray
    stress: np.ndarray
    xi: np.ndarray
    start: float
    names: dict

    def __repr__(self) -> str:
        return (f"InitialState(displacement{self.displacement.shape}, stress{self.stress.shape}, xi{self.xi.shape}, "
                f"start={self.start!r})")

    def dofs(self, basis: DisplacementSpace) -> np.ndarray:
        """u_0 as a vector of the basis' dofs."""
        u = np.zeros(basis.N)
        u[basis.nodal_dofs] = self.displacement.T
        return u

    @property
    def moves(self) -> bool:
        """Is u_0 ≠ 0?"""
        return bool(np.any(self.displacement != 0.0))


@dataclass
class RunState:
    """A field step of a run directory: u, σ (as stored in solution.npz), ξ (None: not stored) and t."""

    displacement: np.ndarray  # (nnodes, d)
    stress: np.ndarray  # (nelements, d, d)
    xi: np.ndarray | None  # (m,)
    time: float


def initial_state(options: ProblemOptions, mesh: Mesh, basis: DisplacementSpace, surface: ContactSurface,
                  law: ContactLaw, constraints: DirichletConditions, *, displacement=None, stress=None, xi=None) -> InitialState:
    """The checked initial state of ``options`` (see the module's docstring) held by ``constraints``;
    ``displacement``, ``stress``, ``xi``: arrays of the API that replace the case's."""
    d, nodes, elements = mesh.dim, mesh.mesh.p.shape[1], mesh.mesh.t.shape[1]
    given = options.initial
    names = {"displacement": "initial.displacement", "stress": "initial.stress", "xi": "initial.xi"}
    start = options.time.start
    if given.from_run is not None:
        run = read_run_state(options, mesh, surface)
        label = f"initial.from_run = {quoted(given.from_run)} at step {given.step}"
        u0, sigma0 = run.displacement, np.moveaxis(run.stress, 0, -1)
        names.update(displacement=f"{label} (u)", stress=f"{label} (stress)")
        if start is None:
            start = run.time
        if run.xi is not None and given.xi is not None:
            raise CaseError(f"initial.xi and {label}: the run's solution.npz holds xi, which the restart takes; "
                            f"remove initial.xi")
        if run.xi is None and surface.size and given.xi is None:
            raise CaseError(f"{label}: the run's solution.npz holds no xi (a run without contact, or written by an "
                            f"earlier vpcontact): give the layer's history initial.xi (e.g. 0)")
        xi0 = run.xi if run.xi is not None else _at_contact_nodes(given.xi, surface)
        if run.xi is not None:
            names["xi"] = f"{label} (xi)"
    else:
        u0 = _at_nodes(given.displacement, mesh)
        sigma0 = _at_centroids(given.stress, mesh)
        xi0 = _at_contact_nodes(given.xi, surface)
    if surface.size == 0 and given.xi is not None:
        raise CaseError("initial.xi is the history of the contact layer and the case has no [contact]: remove it")
    if displacement is not None:
        u0, names["displacement"] = _api_array("initial_displacement", displacement, [(nodes, d)],
                                               "(nodes, d)"), "initial_displacement"
    if stress is not None:
        sigma0 = _api_array("initial_stress", stress, [(elements, d, d), (d, d)], "(elements, d, d) or (d, d)")
        sigma0 = np.moveaxis(np.broadcast_to(sigma0, (elements, d, d)), 0, -1).copy()
        names["stress"] = "initial_stress"
        _check_symmetric(sigma0)
    if xi is not None:
        if surface.size == 0:
            raise CaseError("initial_xi is the history of the contact layer and the case has no [contact]")
        xi0, names["xi"] = _api_array("initial_xi", xi, [(surface.size,)], "(contact nodes,)"), "initial_xi"
    if start is None:
        start = 0.0
    else:
        try:
            check_time_span(start, options.time.T, options.time.steps, "time.start" if options.time.start is not None
                            else f"the time of step {given.step} of initial.from_run")
        except ValueError as error:
            raise CaseError(str(error)) from None
    state = InitialState(np.array(u0, dtype=float), np.array(sigma0, dtype=float), np.array(xi0, dtype=float),
                         float(start), names)
    _check_finite(state, mesh, surface)
    _check_dirichlet(state, constraints, mesh)
    _check_admissible(state, options, mesh, basis, surface, law)
    _check_history(state, surface)
    return state


# --- the case's expressions ------------------------------------------------------------------------
def _at_nodes(sources, mesh: Mesh) -> np.ndarray:
    """u_0 of initial.displacement at the nodes (nnodes, d); 0 when not given."""
    p = mesh.mesh.p
    if sources is None:
        return np.zeros((p.shape[1], mesh.dim))
    names = coordinates(mesh.dim)
    return np.column_stack([values_at(source, f"initial.displacement[{i}]", p, names)
                            for i, source in enumerate(sources)])


def _at_centroids(sources, mesh: Mesh) -> np.ndarray:
    """σ_0 of initial.stress at the element centroids (d, d, nelements); 0 when not given. A number is
    the same float at every element as the expression of its text."""
    d, elements = mesh.dim, mesh.mesh.t.shape[1]
    sigma = np.zeros((d, d, elements))
    if sources is None:
        return sigma
    for i, row in enumerate(sources):
        for j, source in enumerate(row):
            sigma[i, j] = values_at(source, f"initial.stress[{i}][{j}]", mesh.centroids, coordinates(d))
    return sigma


def _at_contact_nodes(source, surface: ContactSurface) -> np.ndarray:
    """ξ_0 of initial.xi at the contact nodes (m,); 0 when not given."""
    if source is None or surface.size == 0:
        return np.zeros(surface.size)
    return values_at(source, "initial.xi", surface.coordinates, coordinates(surface.coordinates.shape[0]))


# --- the arrays of the API -------------------------------------------------------------------------
def _api_array(name: str, value, shapes: list[tuple], expected: str) -> np.ndarray:
    """``value`` as a float array of one of ``shapes``, else CaseError (an array of complex numbers, booleans or
    strings too: they are not real numbers)."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # a ragged list
        array = None
    if array is None or array.dtype.kind not in "iuf":
        what = "" if array is None else f" (real numbers, not {array.dtype})"
        raise CaseError(f"{name} = {brief(value)}: expected an array of numbers of shape {expected}{what}")
    array = array.astype(float)
    if array.shape not in shapes:
        sizes = " or ".join(str(shape) for shape in shapes)
        raise CaseError(f"{name}: an array of shape {array.shape}; expected {expected} = {sizes}")
    return array


def _check_symmetric(sigma: np.ndarray) -> None:
    """σ_0 of the API symmetric to rounding at every element."""
    scale = np.abs(sigma).max(initial=0.0)
    asymmetry = np.abs(sigma - np.swapaxes(sigma, 0, 1)).max(axis=(0, 1))
    with np.errstate(invalid="ignore"):  # values that are not finite are reported by _check_finite
        wrong = asymmetry > ROUNDING * scale
    if np.any(wrong):
        element = int(np.argmax(np.where(wrong, asymmetry, -np.inf)))
        raise CaseError(f"initial_stress is not symmetric at element {element} (|sigma - sigma^T| = "
                        f"{asymmetry[element]:g}): give symmetric tensors")


# --- the checks --------------------------------------------------------------------------------------
def _check_finite(state: InitialState, mesh: Mesh, surface: ContactSurface) -> None:
    for key, values, points, where in (
            ("displacement", state.displacement.T, mesh.mesh.p, "node"),
            ("stress", state.stress.reshape(-1, state.stress.shape[-1]), mesh.centroids, "element centroid"),
            ("xi", state.xi[None, :], surface.coordinates, "contact node")):
        wrong = ~np.isfinite(values)
        if wrong.any():
            _, index = np.argwhere(wrong)[0]
            raise CaseError(f"{state.names[key]} is not finite ({values[:, index][wrong[:, index]][0]}) at the {where} "
                            f"{point(points[:, index])} ({int(wrong.any(axis=0).sum())} of {values.shape[1]}): "
                            f"expected finite values")


def _check_dirichlet(state: InitialState, constraints: DirichletConditions, mesh: Mesh) -> None:
    """u_0 = u_D(t_0) on the held components (u_0 ∈ V when u_D = 0); values within rounding of it are set to it. A
    body at rest (u_0 = 0) may start away from a prescribed u_D(t_0): its first step moves the held nodes there."""
    u = state.displacement
    p = mesh.mesh.p
    for entry in constraints.entries:
        for c, value in zip(entry.components, entry.values):
            if value is not None and not state.moves:
                continue
            expected = np.zeros(entry.nodes.size) if value is None else value(state.start)
            rounding = ROUNDING * max(np.abs(u).max(initial=0.0), np.abs(expected).max(initial=0.0))
            size = np.abs(u[entry.nodes, c] - expected)
            if np.any(size > rounding):
                node = int(np.argmax(size))
                name = coordinates(mesh.dim)[c]
                must = ("be 0 there (u_0 in V)" if value is None else
                        f"equal the prescribed displacement there, {entry.key}.value = {expected[node]:g} at "
                        f"t_0 = {state.start:g}")
                raise CaseError(f"{state.names['displacement']}: u_{name} = {u[entry.nodes[node], c]:g} at the node "
                                f"{point(p[:, entry.nodes[node]])} held by {entry.key} ({entry.description}, "
                                f"{int(np.sum(size > rounding))} of {entry.nodes.size} nodes): u_0 must {must}")
            u[entry.nodes, c] = expected


def _check_admissible(state: InitialState, options: ProblemOptions, mesh: Mesh, basis: DisplacementSpace,
                      surface: ContactSurface, law: ContactLaw) -> None:
    """u_0·ν − g0 ≤ g at every contact node (to the complementarity tolerance of the solver)."""
    if surface.size == 0 or not state.moves:
        return
    d0 = surface.operator @ state.dofs(basis) - surface.gap0
    g = np.broadcast_to(law.g, d0.shape)
    excess = d0 - g
    wrong = excess > options.solver.tolerance * mesh.diameter
    if wrong.any():
        node = int(np.argmax(excess))
        raise CaseError(f"{state.names['displacement']} penetrates the foundation beyond the layer: u_0.nu - gap = "
                        f"{d0[node]:.6g} > g = {g[node]:.6g} at the contact node {point(surface.coordinates[:, node])} "
                        f"({int(wrong.sum())} of {surface.size} nodes): u_0 must be admissible, u_0.nu - gap <= g on "
                        f"the contact part")


def _check_history(state: InitialState, surface: ContactSurface) -> None:
    """ξ_0 ≥ 0: a history of penetration."""
    wrong = state.xi < 0.0
    if wrong.any():
        node = int(np.argmin(state.xi))
        raise CaseError(f"{state.names['xi']} = {state.xi[node]:g} at the contact node "
                        f"{point(surface.coordinates[:, node])} ({int(wrong.sum())} of {surface.size} nodes): the "
                        f"history of penetration xi_0 must be >= 0")


# --- a restart from a run directory ----------------------------------------------------------------
#: The arrays of solution.npz a restart needs (besides the elements); ``xi``, ``contact_nodes`` are optional.
_NEEDED = ("points", "steps", "times", "displacement", "stress")
#: The largest solution.npz read (bytes): beyond, it is not one a run of vpcontact wrote for this mesh.
MAX_SOLUTION_BYTES = 2**36


def read_run_state(options: ProblemOptions, mesh: Mesh, surface: ContactSurface) -> RunState:
    """The state of the run directory initial.from_run at its field step initial.step, checked against
    the case's mesh (same nodes, coordinates and elements) and contact nodes; CaseError otherwise."""
    folder, step = options.initial.from_run_path, options.initial.step
    where = f"initial.from_run = {quoted(options.initial.from_run)}"
    if not os.path.isdir(folder):  # (False for a name the file system refuses, too long or with a NUL)
        raise CaseError(f"{where}: '{folder}' is not a run directory (give the --out folder of a vpcontact run)")
    path = folder / "solution.npz"
    if not os.path.lexists(path):
        raise CaseError(f"{where}: '{path}' not found: the run kept no fields (output.field_steps) or has not ended")
    check_regular_file(path, f"{where}: the file", MAX_SOLUTION_BYTES)
    cells = SIMPLICES[mesh.dim].plural
    arrays = _read_arrays(where, path, cells, mesh.dim)
    _check_same_mesh(where, arrays["points"], arrays[cells], mesh, cells)
    _check_shapes(where, path, arrays, mesh, cells)
    written = arrays["steps"].tolist()
    if step not in written:
        kept = ", ".join(map(str, written)) or "none"
        raise CaseError(f"initial.step = {step}: the run in {quoted(options.initial.from_run)} wrote its fields at the "
                        f"steps {kept} (its output.field_steps): give one of them")
    at = written.index(step)
    time = float(arrays["times"][at])
    if not np.isfinite(time):
        raise CaseError(f"{where}: '{path}' gives step {step} the time {time}: the file is damaged")
    xi = None
    if "xi" in arrays:
        run_nodes = arrays["contact_nodes"]
        if not np.array_equal(run_nodes, surface.nodes):
            parts = "', '".join(str(layer.part) for layer in options.contact.layers) if options.contact else ""
            ours = (f"the case's contact part '{parts}' has {surface.size} other nodes"
                    if options.contact is not None else "the case has no [contact]")
            raise CaseError(f"{where}: the run's contact part has {run_nodes.size} nodes and {ours}: a restart "
                            f"needs the same contact part")
        xi = arrays["xi"][at].astype(float)
    return RunState(arrays["displacement"][at].astype(float), arrays["stress"][at].astype(float), xi, time)


#: The arrays of solution.npz a restart reads besides the elements, and whether they hold integers.
_INTEGERS = {"points": False, "steps": True, "times": False, "displacement": False, "stress": False,
             "contact_nodes": True, "xi": False}


def _read_arrays(where: str, path, cells: str, dim: int) -> dict[str, np.ndarray]:
    """The arrays of the solution.npz at ``path`` a restart reads, each of real numbers (integers where
    _INTEGERS says so, and the elements); CaseError for a file that is not such an archive, or damaged."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if not isinstance(data, np.lib.npyio.NpzFile):
                raise ValueError("not a NumPy .npz archive")
            names = [name for name in (*_INTEGERS, cells) if name in data.files]
            arrays = {name: data[name] for name in names}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error, AttributeError, TypeError) as error:
        # AttributeError, TypeError: np.load returned an array or an object (a .npy file), not an archive
        reason = error if not isinstance(error, (AttributeError, TypeError)) else "not a NumPy .npz archive"
        raise CaseError(f"{where}: '{path}' cannot be read ({reason})") from None
    missing = [name for name in (*_NEEDED, cells) if name not in arrays]
    if missing:
        raise CaseError(f"{where}: '{path}' has no array '{missing[0]}' (the case's mesh has {cells}): is it the "
                        f"solution of a {dim}D vpcontact run?")
    if ("xi" in arrays) != ("contact_nodes" in arrays):
        there, absent = ("xi", "contact_nodes") if "xi" in arrays else ("contact_nodes", "xi")
        raise CaseError(f"{where}: '{path}' has the array '{there}' and not '{absent}': the file is damaged")
    for name, array in arrays.items():
        integers = _INTEGERS.get(name, True)
        if not isinstance(array, np.ndarray):  # a member of the archive that is not a .npy file: its bytes
            raise CaseError(f"{where}: '{path}' holds '{name}' that is not a NumPy array: the file is damaged")
        if array.dtype.kind not in ("iu" if integers else "iuf"):
            raise CaseError(f"{where}: '{path}' holds '{name}' of type {array.dtype}, expected "
                            f"{'integers' if integers else 'real numbers'}: the file is damaged")
    return arrays


def _check_shapes(where: str, path, arrays: dict[str, np.ndarray], mesh: Mesh, cells: str) -> None:
    """CaseError unless the field arrays of a run on ``mesh`` (whose points and elements are the case's) have
    the shapes write_solution gives them: one row per step written, then nodes, elements, contact nodes."""
    d, nodes, elements = mesh.dim, mesh.mesh.p.shape[1], mesh.mesh.t.shape[1]
    steps = arrays["steps"]
    s = steps.shape[0] if steps.ndim == 1 else None
    expected = {"steps": ((s,), "(steps,)"), "times": ((s,), "(steps,)"),
                "displacement": ((s, nodes, d), "(steps, nodes, d)"),
                "stress": ((s, elements, d, d), "(steps, elements, d, d)")}
    if "xi" in arrays:
        m = arrays["contact_nodes"].shape[0] if arrays["contact_nodes"].ndim == 1 else None
        expected["contact_nodes"] = ((m,), "(contact nodes,)")
        expected["xi"] = ((s, m), "(steps, contact nodes)")
    for name, (shape, meaning) in expected.items():
        if arrays[name].shape != shape:
            wanted = ", ".join("?" if n is None else str(n) for n in shape)
            raise CaseError(f"{where}: '{path}' holds '{name}' of shape {arrays[name].shape}, and a run on the case's "
                            f"mesh writes ({wanted}{',' * (len(shape) == 1)}) {meaning}: the file is damaged or of "
                            f"another run")


def _check_same_mesh(where: str, points: np.ndarray, elements: np.ndarray, mesh: Mesh, cells: str) -> None:
    p, t = mesh.mesh.p, mesh.mesh.t
    if points.shape != p.shape or elements.shape != t.shape:
        nodes, count = (points.shape[1], elements.shape[1]) if points.ndim == 2 and elements.ndim == 2 else ("?", "?")
        raise CaseError(f"{where}: the run's mesh has {nodes} nodes and {count} {cells}, the case's {p.shape[1]} and "
                        f"{t.shape[1]}: a restart needs the same mesh")
    offset = np.abs(points - p).max(initial=0.0)
    if not (offset <= ROUNDING * mesh.diameter and np.array_equal(elements, t)):
        what = (f"nodes moved by up to {offset:g}" if not offset <= ROUNDING * mesh.diameter
                else f"other {cells} on the same nodes")
        raise CaseError(f"{where}: the run's mesh has the case's node and element counts but {what}: a restart "
                        f"needs the same mesh")
