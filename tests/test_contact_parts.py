"""Γ3 made of several contact parts, each with its own layer (contact.parts), in 2D and 3D: a layer
whose parameters are piecewise constant along Γ3 equals the same problem stated as two parts with
constants; the rule at the junction of two parts; Python laws of the nodes' coordinates; the local
layer parameters in contact.csv and the contact VTU."""

import csv
import math

import meshio
import numpy as np
import pytest
import tomli_w

import vpcontact
from conftest import assert_refused, half_disc_case, run_cli, snapshot_tree
from test_3d import block_case, states
from vpcontact.mesh import block, half_disc
from vpcontact import build_problem

HISTORIES = ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid")


def write_split_mesh(path, mesh, part, a):
    """``mesh`` as a gmsh 2.2 file with its parts, and ``part`` split at x = a into "<part>_below"
    (its facets whose centroid has x < a) and "<part>_above" (the others)."""
    skmesh, dim = mesh.mesh, mesh.dim
    facets = mesh.facets(part)
    below = skmesh.p[0, skmesh.facets[:, facets]].mean(axis=0) < a
    groups = {name: mesh.facets(name) for name in mesh.part_names}
    groups |= {f"{part}_below": facets[below], f"{part}_above": facets[~below]}
    tags = {name: i + 1 for i, name in enumerate(groups)}
    cells = np.hstack([skmesh.facets[:, f] for f in groups.values()]).T
    physical = np.concatenate([np.full(f.size, tags[name]) for name, f in groups.items()])
    body, facet = ("triangle", "line") if dim == 2 else ("tetra", "triangle")
    elements = skmesh.t.shape[1]
    meshio.write(path, meshio.Mesh(skmesh.p.T, [(body, skmesh.t.T), (facet, cells)],
                                   cell_data={"gmsh:physical": [np.zeros(elements, int), physical],
                                              "gmsh:geometrical": [np.zeros(elements, int), physical]},
                                   field_data={name: np.array([tag, dim - 1]) for name, tag in tags.items()}),
                 file_format="gmsh22", binary=False)


def split_case(tmp_path, dim):
    """(case, contact part, split abscissa a): the half disc (2D) or the block (3D) read from a file whose
    contact part is also split at x = a, a node abscissa (2D) or a grid plane (3D)."""
    if dim == 2:
        mesh, part, case = half_disc(0.1), "bottom_arc", half_disc_case(h=0.1, load=60.0)
        x = mesh.mesh.p[0, mesh.nodes(part)]
        a = float(x[np.argmin(np.abs(x - 0.5))])
    else:
        mesh, part, case, a = block(1.0, 1.0, 0.5, 0.25), "bottom", block_case(), 0.5
    write_split_mesh(tmp_path / "split.msh", mesh, part, a)
    case["mesh"] = {"file": str(tmp_path / "split.msh")}
    return case, part, a


#: two layers, below (x < a) and above (x ≥ a) the split: of one family (K power, p power on both), or
#: of two (K power with p = r⁺ below, K constant with p = (r⁺)^1.5 above). Each a dict of the keys of
#: a contact part, with its number for each key, and the same layer written with K power and p power
#: (constant K = value: c_v = value, α = 0, β = 1; p = r⁺: exponent 1).
LAYERS = {
    "one family": (
        {"g": 0.2, "gap": 0.0, "p": "power", "exponent": 1.0,
         "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}},
        {"g": 0.12, "gap": 0.01, "p": "power", "exponent": 2.0,
         "stiffness": {"law": "power", "c_v": 400.0, "alpha": 5.0, "beta": 1.0}}),
    "two families": (
        {"g": 0.2, "gap": 0.0, "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}},
        {"g": 0.12, "gap": 0.01, "p": "power", "exponent": 1.5, "stiffness": {"law": "constant", "value": 300.0}}),
}


def as_power(layer):
    """The numbers (g, gap, exponent, c_v, alpha, beta) of a layer of LAYERS written with K and p power."""
    s = layer["stiffness"]
    c_v, alpha, beta = (s["value"], 0.0, 1.0) if s["law"] == "constant" else (s["c_v"], s["alpha"], s["beta"])
    return {"g": layer["g"], "gap": layer["gap"], "exponent": layer.get("exponent", 1.0), "c_v": c_v,
            "alpha": alpha, "beta": beta}


def piecewise(a, below, above):
    """An expression equal to ``below`` where x ≤ a and to ``above`` where x > a, exactly (heaviside(0) = 0:
    the junction node x = a takes ``below``, the first part listed)."""
    step = f"heaviside(x - {a!r})"
    return f"{below!r}*(1 - {step}) + {above!r}*{step}"


def one_part_form(case, part, a, layers):
    """The case with one contact part whose layer is piecewise constant: expressions in x."""
    below, above = (as_power(layer) for layer in layers)
    value = {key: piecewise(a, below[key], above[key]) for key in below}
    case["contact"] = {"part": part, "probe": case["contact"].get("probe", [0.0] * 3), "p": "power",
                       **{key: value[key] for key in ("g", "gap", "exponent")},
                       "stiffness": {"law": "power", **{key: value[key] for key in ("c_v", "alpha", "beta")}}}
    return case


def two_parts_form(case, part, layers, order=("below", "above")):
    """The case with the two parts of the split, each with its layer of constants, listed in ``order``."""
    entries = dict(zip(("below", "above"), layers))
    case["contact"] = {"probe": case["contact"].get("probe", [0.0] * 3),
                       "parts": [{"part": f"{part}_{side}", **entries[side]} for side in order]}
    return case


@pytest.mark.parametrize("family", LAYERS)
@pytest.mark.parametrize("dim", [2, 3])
def test_a_piecewise_constant_layer_equals_two_contact_parts(tmp_path, dim, family):
    """The same problem two ways: one contact part with (g, gap, m, c_v, α, β) piecewise constant in x,
    and the two parts of the split each with its constants (laws of different families merged in a
    PiecewiseLaw): the same displacements and contact histories to rounding (1e-12)."""
    case, part, a = split_case(tmp_path, dim)
    if dim == 2:
        case["contact"]["probe"] = [0.0, 0.0]
    one = vpcontact.solve(one_part_form(dict(case), part, a, LAYERS[family]))
    two = vpcontact.solve(two_parts_form(dict(case), part, LAYERS[family]))
    assert one.status == two.status == "complete", (one.message, two.message)
    assert two.discretization.surface.parts == (f"{part}_below", f"{part}_above")
    np.testing.assert_array_equal(one.discretization.surface.nodes, two.discretization.surface.nodes)
    scale = np.abs(one.final.displacement).max()
    np.testing.assert_allclose(two.final.displacement, one.final.displacement, rtol=0, atol=1e-12 * scale)
    for name in HISTORIES:
        reference = one.contact_history(name)
        np.testing.assert_allclose(two.contact_history(name), reference, rtol=0,
                                   atol=1e-12 * np.abs(reference).max(), err_msg=name)
    np.testing.assert_array_equal(two.contact_history("status"), one.contact_history("status"))
    _, in_compliance, at_limit = states(one)[-1]
    assert in_compliance > 0 and at_limit > 0, (in_compliance, at_limit)
    below = one.discretization.surface.coordinates[0] <= a  # both layers carry the load
    assert one.contact_history("K")[-1][below].max() > 0 and one.contact_history("K")[-1][~below].max() > 0


def test_a_node_where_two_parts_meet_takes_the_layer_of_the_first_listed(tmp_path):
    case, part, a = split_case(tmp_path, 2)
    layers = LAYERS["two families"]
    for order in (("below", "above"), ("above", "below")):
        problem = build_problem(vpcontact.load_case(two_parts_form(dict(case), part, layers, order)))
        surface = problem.surface
        junction = np.flatnonzero(surface.coordinates[0] == a)
        assert junction.size == 1
        first = dict(zip(("below", "above"), layers))[order[0]]
        assert surface.parts[surface.owner[junction[0]]] == f"{part}_{order[0]}"
        assert problem.law.limit(junction)[0] == first["g"]
        assert surface.gap0[junction[0]] == first["gap"]
        assert problem.law.stiffness(np.zeros(surface.size))[junction[0]] == as_power(first)["c_v"]


BAD_PARTS = [
    ({"g": 0.2}, ["contact.g is given with contact.parts", "move contact.g into the entries"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "rho": 2.0, "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[0]: rho is one value for the whole contact", "state it once in [contact]"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "probe": [0, 0],
                 "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[0]: probe is one value for the whole contact"]),
    ({"parts": [{"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0}},
                {"part": "bottom_arc", "g": 0.1, "stiffness": {"law": "constant", "value": 2.0}}]},
     ["contact.parts[1].part = \"bottom_arc\" is also contact.parts[0].part"]),
    ({"parts": [{"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0}},
                {"part": "bottom_arc_above", "g": 0.1, "stiffness": {"law": "constant", "value": 2.0}}]},
     ["contact parts 'bottom_arc' and 'bottom_arc_above' share", "facets", "one layer"]),
    ({"parts": [{"part": "bottom_arc_below", "stiffness": {"law": "constant", "value": 1.0}}]},
     ["missing required value 'contact.parts[0].g'"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0, "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[0].g = 0: must be > 0"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "p": "power", "stiffness": {"law": "constant", "value": 1.0}}]},
     ["missing required value 'contact.parts[0].exponent' (needed by contact.parts[0].p = \"power\")"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0}},
                {"part": "bottom_arc_above", "g": 0.2, "p": "power", "exponent": "3 - 3*x",
                 "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[1].exponent = \"3 - 3*x\" is 0.87868 at the contact node (x, y) = (0.707107, 0.292893)",
      "expected a finite number >= 1"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "stiffness": {"law": "constant", "value": "x - 0.1"}},
                {"part": "bottom_arc_above", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[0].stiffness.value = \"x - 0.1\" is -0.1 at the contact node (x, y) = (0, 0)"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0}},
                {"part": "bottom_arc_above", "g": 0.2, "gap": "1/(1 - x)",
                 "stiffness": {"law": "constant", "value": 1.0}}]},
     ["contact.parts[1].gap = \"1/(1 - x)\": not finite"]),
    ({"parts": [{"part": "bottom_arc_below", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0, "c_v": 2}}]},
     ["unknown key 'contact.parts[0].stiffness.c_v'"]),
]


@pytest.mark.parametrize("contact, words", BAD_PARTS, ids=[w[0][:40] for _, w in BAD_PARTS])
def test_contact_parts_that_are_ambiguous_or_wrong_are_refused(tmp_path, contact, words):
    case, _, _ = split_case(tmp_path, 2)
    case["contact"] = {"probe": [0.0, 0.0], **({"parts": [{"part": "bottom_arc_below", "g": 0.2, "stiffness": {
        "law": "constant", "value": 1.0}}]} if "parts" not in contact else {}), **contact}
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out")
    assert_refused(status, err, *words, untouched=[(tmp_path, before)])


def test_a_case_with_contact_parts_runs_again_from_its_resolved_case(tmp_path):
    """case.resolved.toml of a case with contact.parts is a valid case giving the same run, and an
    override reaches one part's layer (contact.parts[1].g)."""
    case, part, _ = split_case(tmp_path, 2)
    case = two_parts_form(case, part, LAYERS["two families"])
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    status, _, err = run_cli("run", path, "--out", tmp_path / "first", "--quiet")
    assert status == 0, err
    status, _, err = run_cli("run", tmp_path / "first" / "case.resolved.toml", "--out", tmp_path / "again", "--quiet")
    assert status == 0, err
    assert (tmp_path / "first" / "contact.csv").read_bytes() == (tmp_path / "again" / "contact.csv").read_bytes()
    changed = vpcontact.load_case(path, ["contact.parts[1].g=0.15"])
    assert changed.contact.parts[1].g == 0.15 and changed.contact.parts[0].g == 0.2


# --- Python laws of the coordinates ----------------------------------------------------------------------
C_V = "100 + 300*x*x"
ALPHA = "20 - 10*x"
EXPONENT = "1 + x*x"


def stiffness_of_x(xi, x):
    c_v, alpha = 100 + 300 * x[0] * x[0], 20 - 10 * x[0]
    return c_v * (1.0 + alpha * xi) ** -1.0


def stiffness_of_x_derivative(xi, x):
    c_v, alpha = 100 + 300 * x[0] * x[0], 20 - 10 * x[0]
    return c_v * alpha * -1.0 * (1.0 + alpha * xi) ** (-1.0 - 1.0)


stiffness_of_x.derivative = stiffness_of_x_derivative


def p_of_x(r, x):
    return np.maximum(r, 0.0) ** (1 + x[0] * x[0])


def test_python_laws_of_the_coordinates_equal_the_expression_form():
    """K(ξ, x) with its derivative and p(r, x) without (a central difference) against the same layer
    written as expressions: the same run to rounding."""
    expressions = half_disc_case(h=0.1, load=60.0, p="power", exponent=EXPONENT,
                                 stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": -1.0})
    laws = half_disc_case(h=0.1, load=60.0)
    a = vpcontact.solve(expressions)
    b = vpcontact.solve(laws, stiffness_law=stiffness_of_x, p=p_of_x)
    assert a.status == b.status == "complete"
    np.testing.assert_allclose(b.final.displacement, a.final.displacement, rtol=0,
                               atol=1e-10 * np.abs(a.final.displacement).max())
    for name in HISTORIES:
        reference = a.contact_history(name)
        np.testing.assert_allclose(b.contact_history(name), reference, rtol=0, atol=1e-10 * np.abs(reference).max())
    _, in_compliance, at_limit = states(a)[-1]
    assert in_compliance > 0 and at_limit > 0
    # with the derivative given for both, the same Newton iterates: equal to rounding
    exact = vpcontact.solve(half_disc_case(h=0.1, load=60.0, stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA,
                                                                        "beta": -1.0}), stiffness_law=stiffness_of_x)
    reference = vpcontact.solve(half_disc_case(h=0.1, load=60.0, stiffness={"law": "power", "c_v": C_V,
                                                                            "alpha": ALPHA, "beta": -1.0}))
    np.testing.assert_allclose(exact.final.displacement, reference.final.displacement, rtol=0,
                               atol=1e-12 * np.abs(reference.final.displacement).max())


def three(r, x, y):
    return r


def shape_of_x(r, x):
    return np.maximum(r, 0.0) + x  # (d, m): not one value per node


def nan_at_the_axis(r, x):
    return np.maximum(r, 0.0) / x[0] ** 0.0 * np.where(x[0] == 0.0, np.nan, 1.0)


def mixed(xi, x):
    return 1.0 + 0 * xi


mixed.derivative = lambda xi: 0 * xi


@pytest.mark.parametrize("name, law, words", [
    ("p", three, ["p takes 3 arguments (r, x, y)", "expected f(r), or f(r, x)"]),
    ("p", shape_of_x, ["p: p(0.0, x) at the", "contact nodes returned an array of shape (2, 9)"]),
    ("p", nan_at_the_axis, ["p: p(0.0, x) at the 9 contact nodes is not finite (nan)"]),
    ("stiffness_law", mixed, ["stiffness_law takes 2 argument(s) and stiffness_law.derivative 1",
                              "give both f(r) or both f(r, x)"]),
])
def test_a_python_law_of_the_coordinates_that_is_wrong_is_refused_before_the_run(name, law, words):
    with pytest.raises(vpcontact.CaseError) as error:
        build_problem(vpcontact.load_case(half_disc_case(h=0.2)), **{name: law})
    for word in words:
        assert word in str(error.value), (word, str(error.value))


# --- the layer in the outputs ---------------------------------------------------------------------------
def read_contact(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


BEFORE = ["step", "t", "node", "x", "y", "normal_x", "normal_y", "weight", "penetration", "xi", "K",
          "pressure_compliance", "pressure_rigid", "status", "substep"]


def run_with_final_fields(tmp_path, case: dict) -> tuple[list, list]:
    """Run ``case`` with its final fields through the CLI into tmp_path/out: the header and rows of contact.csv."""
    case["output"]["field_steps"] = "final"
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    status, _, err = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 0, err
    return read_contact(tmp_path / "out" / "contact.csv")


def test_contact_csv_and_vtu_carry_the_local_layer_parameters(tmp_path):
    """The columns g, c_v, alpha, beta, exponent of contact.csv (after the former ones, in their order)
    equal the case's expressions evaluated at the coordinates x, y of the same rows; the contact VTU
    has them as point data."""
    case = half_disc_case(h=0.1, load=60.0, p="power", exponent=EXPONENT, g="0.2 - 0.1*x*y",
                          stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": -1.0})
    header, rows = run_with_final_fields(tmp_path, case)
    assert header == BEFORE + ["g", "c_v", "alpha", "beta", "exponent"]
    column = {name: np.array([float(row[i]) for row in rows]) for i, name in enumerate(header) if name != "status"}
    x, y = column["x"], column["y"]
    np.testing.assert_allclose(column["g"], 0.2 - 0.1 * x * y, rtol=1e-15)
    np.testing.assert_allclose(column["c_v"], 100 + 300 * x * x, rtol=1e-15)
    np.testing.assert_allclose(column["alpha"], 20 - 10 * x, rtol=1e-15)
    np.testing.assert_array_equal(column["beta"], -1.0)
    np.testing.assert_allclose(column["exponent"], 1 + x * x, rtol=1e-15)
    contact = meshio.read(tmp_path / "out" / "fields" / "contact_00011.vtu")
    last = column["step"] == 11
    np.testing.assert_array_equal(contact.points[:, 0], x[last])
    for name in ("g", "c_v", "alpha", "beta", "exponent"):
        np.testing.assert_array_equal(contact.point_data[name], column[name][last], err_msg=name)


def test_contact_csv_names_the_part_and_leaves_a_parameter_its_law_has_not_empty(tmp_path):
    """Two parts of different families: the part's name per row, c_v, alpha, beta empty where K is
    constant and value empty where it is the power law, exponent empty where p = r⁺; in the VTU the
    part's index in contact.parts and NaN."""
    case, part, a = split_case(tmp_path, 2)
    case = two_parts_form(case, part, LAYERS["two families"])
    header, rows = run_with_final_fields(tmp_path, case)
    assert header == BEFORE + ["g", "c_v", "alpha", "beta", "value", "exponent", "part"]
    cell = {name: [row[i] for row in rows] for i, name in enumerate(header)}
    x = np.array([float(v) for v in cell["x"]])
    below = x <= a  # the junction node x = a is the first part's
    assert [p for p, b in zip(cell["part"], below) if b] == [f"{part}_below"] * below.sum()
    assert [p for p, b in zip(cell["part"], below) if not b] == [f"{part}_above"] * (~below).sum()
    expected = {"g": (0.2, 0.12), "c_v": (100.0, ""), "alpha": (20.0, ""), "beta": (-1.0, ""), "value": ("", 300.0),
                "exponent": ("", 1.5)}
    for name, (on_below, on_above) in expected.items():
        assert {v for v, b in zip(cell[name], below) if b} == {str(on_below)}, name
        assert {v for v, b in zip(cell[name], below) if not b} == {str(on_above)}, name
    contact = meshio.read(tmp_path / "out" / "fields" / "contact_00011.vtu")
    last = np.array(cell["step"]) == "11"
    np.testing.assert_array_equal(contact.point_data["part"], np.where(below[last], 0.0, 1.0))
    np.testing.assert_array_equal(contact.point_data["value"], np.where(below[last], math.nan, 300.0))
