"""The refusals of a problem that could not be run, made before its first step: vectors and tables of the case
in another dimension than the mesh's, a contact part clamped along its normal, rigid motions held by nothing,
and initial data whose first step cannot be finite."""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError, brief, point, quoted
from ..expressions.parse import parse_expression
from ..fem.assembly import stress_force
from ..fem.rigid_modes import RigidModes
from ..mesh.cells import coordinates
from ..fem.contact_surface import ContactSurface
from ..fem.space import DisplacementSpace
from ..laws.python_laws import check_returned, tried
from ..mesh.mesh import Mesh
from .free_motions import free_motions_in_words
from .initial import InitialState
from .constraints import DirichletConditions
from .options import ProblemOptions


def check_dimension(options: ProblemOptions, dim: int) -> None:
    """Refuse vectors and tensors of the case that do not have the mesh's dimension d, a plane
    hypothesis in 3D, and the coordinate z in 2D."""
    names = coordinates(dim)
    where = f"the mesh is {dim}D"
    give = f"give {dim} ({', '.join(names)})"
    loads = [(f"boundary.traction[{i}].value", t.value) for i, t in enumerate(options.boundary.traction)]
    loads += [(f"boundary.body_force[{i}].value", f.value) for i, f in enumerate(options.boundary.body_force)]
    vectors = list(loads)
    if options.contact is not None:
        vectors += [("contact.probe", options.contact.probe), ("contact.normal", options.contact.normal)]
    vectors.append(("initial.displacement", options.initial.displacement))
    prescribed = [(f"{item.key}.value", item) for item in options.boundary.dirichlet if item.value is not None]
    vectors += [(key, list(item.value)) for key, item in prescribed if item.components is None]  # all components
    vectors += [(f"{item.key}.at", list(item.at)) for item in options.boundary.dirichlet if item.at is not None]
    loads += [(key, list(item.value)) for key, item in prescribed]
    for key, value in vectors:
        if isinstance(value, list) and len(value) != dim:
            raise CaseError(f"{key} has {len(value)} components and {where}: {give}")
    if options.initial.stress is not None and len(options.initial.stress) != dim:
        raise CaseError(f"initial.stress is {len(options.initial.stress)} x {len(options.initial.stress)} and {where}: "
                        f"give a {dim} x {dim} table")
    for entry in options.materials:
        key = entry.key
        if dim == 3 and entry.hypothesis is not None:
            raise CaseError(f"{key}.hypothesis = \"{entry.hypothesis}\" is a 2D reduction and {where} (3D uses the "
                            f"full isotropic tensor): remove {key}.hypothesis")
    for item in options.boundary.dirichlet:
        extra = [c for c in item.components or () if c not in names]
        if extra:
            raise CaseError(f"{item.key}.components names \"{extra[0]}\" and {where}: use "
                            f"{', '.join(repr(n) for n in names)}")
    expressions = [(f"{key}[{c}]", source) for key, value in loads for c, source in enumerate(value)]
    if options.contact is not None:
        expressions += [(f"{layer.key}.gap", layer.gap) for layer in options.contact.layers]
    expressions += [(f"{entry.key}.{name}", getattr(entry, name)) for entry in options.materials
                    for name in ("E", "nu")]
    initial = options.initial
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


def check_contact_can_move(constraints: DirichletConditions, mesh: Mesh, basis: DisplacementSpace,
                           surface: ContactSurface):
    """Refuse a contact part on which the Dirichlet conditions leave no node free to move along its
    normal: its contact force would be 0 (or fixed) whatever the load. (A few clamped nodes, such as
    the corners the contact part shares with a clamped part, are fine.)"""
    if surface.size == 0:
        return
    on_free = np.zeros(basis.N)
    on_free[constraints.free] = 1.0
    normal_freedom = np.sqrt(np.asarray((surface.operator @ sp.diags(on_free)).power(2).sum(axis=1)).ravel())
    if np.any(normal_freedom > 1e-6):
        return
    contact_dofs = basis.nodal_dofs[:, surface.nodes].ravel()
    entries = []
    for entry in constraints.entries:
        if np.intersect1d(basis.nodal_dofs[list(entry.components)][:, entry.nodes], contact_dofs).size:
            names = ", ".join(coordinates(mesh.dim)[c] for c in entry.components)
            entries.append(f"{entry.key} ({entry.description}, components {names})")
    parts = f"part '{surface.parts[0]}' is" if len(surface.parts) == 1 else \
        f"parts {', '.join(repr(part) for part in surface.parts)} are"
    raise CaseError(f"contact {parts} clamped: {' and '.join(entries)} fix every contact node "
                    f"along its normal, so the contact force cannot change whatever the load; remove the contact part "
                    f"from boundary.dirichlet or fix only components along the contact surface")


def check_rigid_motions(mesh: Mesh, basis: DisplacementSpace, free: np.ndarray, surface: ContactSurface):
    """Refuse a body, or a separate part of the mesh, whose rigid motions are held neither by
    Dirichlet conditions nor by contact: the motions of each connected part (the d translations and
    the rotations about its centroid scaled by its size, :mod:`vpcontact.fem.rigid_modes`) must stay
    independent on the fixed dofs and the contact normals of that part. The refusal names the free
    motions (:mod:`vpcontact.problem.free_motions`) and how to hold them."""
    modes = RigidModes.of_mesh(mesh.mesh.p, mesh.mesh.t, basis.nodal_dofs)
    fixed = np.ones(basis.N, dtype=bool)
    fixed[free] = False
    free_motions, combinations = modes.unheld(sp.eye(basis.N, format="csr")[fixed], surface.operator)
    loose = np.flatnonzero(free_motions)
    if loose.size == 0:
        return
    b, count = loose[0], modes.count
    where = "the Dirichlet conditions and the contact part" if surface.size else "the Dirichlet conditions"
    motions = free_motions_in_words(combinations[b][:, :free_motions[b]], modes.centroid[:, b], modes.size[b])
    them = "them" if free_motions[b] > 1 else "it"
    if count == 1:
        raise CaseError(f"{where} leave {motions} of the body free: hold {them} with boundary.dirichlet entries on "
                        f"parts that block {them} (holding a component on a part blocks the translation along it; a "
                        f"rotation needs a part held off its axis in the direction it turns there), e.g. rollers on "
                        f"the symmetry planes of a half or quarter model, or with boundary.point entries that hold "
                        f"components at single nodes (a full model: the translations at one point, the rotation at a "
                        f"second one off its axis)")
    p = mesh.mesh.p
    inside = np.flatnonzero(modes.body == b)
    point = inside[np.argmin(np.sum((p[:, inside] - modes.centroid[:, b:b + 1]) ** 2, axis=0))]
    nodes = np.bincount(modes.body, minlength=count)
    raise CaseError(f"the mesh has {count} separate parts; {where} leave {motions} of the part of {nodes[b]} "
                    f"nodes through the node at {_point(p[:, point])} free"
                    f"{f' (and motions of {loose.size - 1} more parts)' if loose.size > 1 else ''}: hold {them} "
                    f"with boundary.dirichlet entries on parts of it that block {them}, or join it to the rest of "
                    f"the mesh")


def _point(x: np.ndarray, digits: int = 6) -> str:
    """The point x as a message shows it (:func:`~vpcontact.errors.point`), without its round-off below 1e-12."""
    return point(np.round(x, 12), digits)


def check_first_history(basis: DisplacementSpace, initial: InitialState, written, strain0: np.ndarray, z0: np.ndarray,
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
        rate = tried(law_name, call, G, sigma.copy(), strain0.copy())
        check_returned(law_name, call, rate, sigma.shape)
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
            source += f" = {brief(written)}"
        raise CaseError(f"{source}: its nodal forces are not finite in float64; state the stresses in other units")
