"""A problem composed in Python, in the order a mechanician writes it: the body's mesh, its material,
the boundary conditions, the contact law, the time grid and the solver options.

    >>> import vpcontact
    >>> from vpcontact import mesh
    >>> problem = vpcontact.compose(
    ...     mesh.half_disc(h=0.05),
    ...     material={"E": 1000.0, "nu": 0.3},
    ...     dirichlet={"axis": "x"},
    ...     traction={"top_arc": lambda x, y, t: (0 * x, -18.0 * t + 0 * y)},
    ...     contact={"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0],
    ...              "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
    ...     time={"T": 1.1, "steps": 11},
    ... )
    >>> result = vpcontact.solve(problem)

Each piece is given as the table of the case file holds it (the same keys, the same checks, the same
one-line :class:`~vpcontact.errors.CaseError` naming the key), or as a Python object where one is
natural: a :class:`~vpcontact.mesh.Mesh` (or a mesh file's name), a traction or body force f(x, y, t)
(f(x, y, z, t) in 3D), a stiffness law K(ξ) or a law p(r) (with a ``derivative`` method, or a
central difference is used; K(ξ, x) of the contact nodes' coordinates x too), a viscoplastic law
𝒢(σ, ε), and NumPy arrays of the initial state. A case file is one way to state the same problem:
``vpcontact.build_problem(vpcontact.load_case(path))``; :func:`compose` another. Either way the tables are
validated as a :class:`~vpcontact.case.model.Model`, translated once (:mod:`vpcontact.case.translate`), and the
problem keeps their options (``problem.options``) and the Python objects (``problem.objects``), so that
:meth:`~vpcontact.problem.build.Problem.on` builds it again on a refined mesh.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from pydantic import ValidationError

from .. import mesh as meshes
from .body import MeshSection
from .load import check_expressions, check_tree, plain, section
from .messages import describe
from .model import Model
from ..errors import CaseError, brief
from ..mesh.memory import from_object
from ..problem.build import Problem, build_problem, make_mesh
from .translate import mesh_source, problem_options

#: The contact keys that may be Python laws instead of tables, and the build_problem argument each becomes.
PYTHON_LAWS = {"stiffness": "stiffness_law", "p": "p"}
#: The initial fields that may be NumPy arrays instead of expressions, and the build_problem argument of each.
INITIAL_ARRAYS = {"displacement": "initial_displacement", "stress": "initial_stress", "xi": "initial_xi"}


def compose(mesh, material, *, time, dirichlet=(), points=(), traction=None, body_force=None, contact=None,
            solver=None, initial=None, viscoplastic: Callable | None = None) -> Problem:
    """The problem of a body on ``mesh`` made of ``material``, held by ``dirichlet``, loaded by ``traction`` and
    ``body_force``, in ``contact`` with the foundation, over the time grid ``time``, solved with ``solver``:

    - ``mesh``: a :class:`~vpcontact.mesh.Mesh` (``vpcontact.mesh.half_disc(h)``, ``quarter_ball``,
      ``rectangle``, ``block``, ``read_mesh(path)``), a mesh file's name, a ``[mesh]`` table, or a mesh in
      memory, checked as a file is: a ``meshio.Mesh``, a scikit-fem ``MeshTri1`` / ``MeshTet1`` with named
      boundaries (the parts) and subdomains (the regions), or the ``gmsh`` module (its open model, its
      physical groups the parts and regions; ``vpcontact.mesh.from_gmsh()``);
    - ``material``: a ``[material]`` table ({"E": ..., "nu": ..., "hypothesis": ..., "viscoplastic": {...}}), or
      a list of them, each with its ``region``; ``viscoplastic``: a Python law 𝒢(σ, ε) (or 𝒢(σ, ε, x)) for the
      whole body instead of the tables' laws;
    - ``dirichlet``: {part: components} (components "x", ["x", "y"], or None for all: u = 0 there), {part:
      {component: value}} (a prescribed displacement: value an expression in x, y, (z,) t such as "-0.4*t", a
      number, or a Python function f(x, y, (z,) t) of the part's nodes), or the list of ``[[boundary.dirichlet]]``
      tables (a table may hold the nodes ``where`` a condition on the coordinates holds instead of a part);
    - ``points``: the list of ``[[boundary.point]]`` tables, each holding components at the node nearest to its
      point ``at`` ({"at": [0, 0, 0.01], "components": ["x", "y"]}, optional "value" and "name"): a full model
      held against its rigid motions;
    - ``traction``: {part: value}, value the list of d expressions in x, y, (z,) t, or a Python function
      f(x, y, (z,) t) -> (fx, fy, (fz)); ``body_force``: one such value for the whole body;
    - ``contact``: the ``[contact]`` table; its ``stiffness`` may be a Python law K(ξ) and its ``p`` a law p(r);
    - ``time``: the ``[time]`` table ({"T": ..., "steps": ..., "start": ...}); ``solver``: the ``[solver]`` table;
    - ``initial``: the ``[initial]`` table; its ``displacement`` (nodes, d), ``stress`` (elements, d, d) or
      (d, d) and ``xi`` (contact nodes,) may be NumPy arrays.

    Numbers may be NumPy numbers, lists NumPy arrays or tuples (see :func:`vpcontact.case.load.plain`). Every
    value is checked before anything is assembled: a bad one, or one the problem would not use, is a
    CaseError naming it."""
    mesh = _mesh(mesh)
    objects = {} if viscoplastic is None else {"viscoplastic": viscoplastic}
    tables = {"material": material, "time": time, "solver": {} if solver is None else solver, "boundary": {}}
    tables["boundary"]["dirichlet"], objects["displacements"] = _dirichlet(dirichlet)
    if isinstance(points, Mapping) or isinstance(points, str) or not isinstance(points, Sequence):
        raise CaseError(f"points = {brief(points)}: expected a list of [[boundary.point]] tables, e.g. "
                        f"[{{\"at\": [0, 0, 0.01], \"components\": [\"x\", \"y\"]}}]")
    tables["boundary"]["point"] = list(points)
    tables["boundary"]["traction"], objects["tractions"] = _tractions(traction)
    tables["boundary"]["body_force"], objects["body_force"] = _body_force(body_force)
    python_laws: list[str] = []
    if contact is not None:
        contact = _table("contact", contact)
        for key, argument in PYTHON_LAWS.items():
            if callable(contact.get(key)):
                objects[argument] = contact.pop(key)
                python_laws.append(key)
        tables["contact"] = contact
    if initial is not None:
        initial = _table("initial", initial)
        for key, argument in INITIAL_ARRAYS.items():
            if isinstance(initial.get(key), np.ndarray) and initial[key].ndim > 0:
                objects[argument] = initial.pop(key)
        tables["initial"] = initial
    tables = plain(tables)
    check_tree(tables)
    try:
        model = Model.model_validate(tables, context={"python_laws": python_laws})
    except ValidationError as error:
        raise CaseError(describe(error.errors()[0])) from None
    check_expressions(model)
    if viscoplastic is not None:
        tabled = [key for key, entry in model.keyed_materials() if entry.viscoplastic is not None]
        if tabled:
            raise CaseError(f"{tabled[0]}.viscoplastic and viscoplastic = {brief(viscoplastic)}: the Python law "
                            f"replaces the tables' laws on the whole body, so {tabled[0]}.viscoplastic would not be "
                            f"used; give one of them")
    return build_problem(problem_options(model), mesh=mesh,
                         **{name: value for name, value in objects.items() if value is not None})


def _mesh(mesh) -> meshes.Mesh:
    """The mesh of ``compose``'s argument: a Mesh as it is, a file name read, a [mesh] table made, a mesh in
    memory (a meshio.Mesh, a scikit-fem mesh, the gmsh module's open model) checked as a file is."""
    if isinstance(mesh, meshes.Mesh):
        return mesh
    if isinstance(mesh, (str, os.PathLike)):
        return meshes.read_mesh(mesh)
    if isinstance(mesh, Mapping):
        return make_mesh(mesh_source(section(MeshSection, mesh, "mesh")))
    in_memory = from_object(mesh)
    if in_memory is not None:
        return in_memory
    raise CaseError(f"mesh = {brief(mesh)}: expected a vpcontact.mesh.Mesh (vpcontact.mesh.half_disc, quarter_ball, "
                    f"rectangle, block or read_mesh), a mesh file's name, a [mesh] table, a meshio.Mesh, a "
                    f"scikit-fem MeshTri1 or MeshTet1 with named boundaries, or the gmsh module (its open model)")


def _table(key: str, value) -> dict:
    """A copy of the table ``value`` of ``key``, or CaseError."""
    if not isinstance(value, Mapping):
        raise CaseError(f"{key} = {brief(value)}: expected a table (dict) of the [{key}] keys")
    return dict(value)


def _dirichlet(dirichlet) -> tuple[list, dict | None]:
    """The [[boundary.dirichlet]] tables of {part: components} (or of the tables themselves), and the Python
    functions among their values ({part: {component: f}}, None when there is none): u = 0 on the part's components,
    "x", ["x", "y"] (a list, tuple or array of names) or None for all; u = value for {component: value}."""
    if isinstance(dirichlet, Mapping):
        tables, functions = [], {}
        for part, components in dirichlet.items():
            if isinstance(components, Mapping):
                table, given = _prescribed(part, components)
                tables.append(table)
                if given:
                    functions[part] = given
            else:
                tables.append({"part": part, **_components(part, components)})
        return tables, functions or None
    if isinstance(dirichlet, Sequence) and not isinstance(dirichlet, str):
        return list(dirichlet), None
    raise CaseError(f"dirichlet = {brief(dirichlet)}: expected {{part: components}} (components \"x\", [\"x\", \"y\"] "
                    f"or None for all), {{part: {{component: value}}}} or a list of [[boundary.dirichlet]] tables")


def _prescribed(part, values: Mapping) -> tuple[dict, dict]:
    """The [[boundary.dirichlet]] table of ``dirichlet[part] = {component: value}``, and its Python functions
    ({component: f}: their value in the table is 0, build_problem's ``displacements`` replace it)."""
    if not values:
        raise CaseError(f"dirichlet[{brief(part)}] = {{}}: no component; give {{component: value}}, e.g. "
                        f"{{\"z\": \"-0.01*t\"}}")
    functions = {name: value for name, value in values.items() if callable(value)}
    table = {"part": part, "components": list(values),
             "value": [0.0 if callable(value) else value for value in values.values()]}
    return table, functions


def _components(part, components) -> dict:
    """The "components" key of the [[boundary.dirichlet]] table of ``dirichlet[part] = components``."""
    where = f"dirichlet[{brief(part)}] = {brief(components)}"
    if components is None:
        return {}
    if isinstance(components, str):
        return {"components": [components]}
    if isinstance(components, (Sequence, np.ndarray)):
        return {"components": list(components)}
    raise CaseError(f"{where}: expected the components held at 0: \"x\", [\"x\", \"y\"] or None for all")


def _tractions(traction) -> tuple[list, dict | None]:
    """The [[boundary.traction]] tables of the expressions in ``traction`` ({part: value}), and the Python
    functions in it ({part: f}, or None when there is none)."""
    if traction is None:
        return [], None
    if not isinstance(traction, Mapping):
        raise CaseError(f"traction = {brief(traction)}: expected {{part: value}}, value a list of expressions or a "
                        f"function f(x, y, (z,) t) -> (fx, fy, (fz))")
    functions = {part: value for part, value in traction.items() if callable(value)}
    tables = [{"part": part, "value": value} for part, value in traction.items() if not callable(value)]
    return tables, functions or None


def _body_force(body_force) -> tuple[list, Callable | None]:
    """The [[boundary.body_force]] tables of ``body_force`` (a list of expressions), or the Python function."""
    if body_force is None:
        return [], None
    if callable(body_force):
        return [], body_force
    return [{"value": body_force}], None
