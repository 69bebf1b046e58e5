"""Prescribed displacements (issue 28, item 1): ``[[boundary.dirichlet]] value = [...]`` and ``compose(dirichlet=
{part: {component: value}})``.

Checked against what must hold whatever the solver: the held nodes carry exactly u_D(t) (read from the files the
run writes, by VTK's reader and pandas), an expression and a Python function of the same u_D give the same run bit
for bit, the three methods agree, a viscoplastic block pulled at a fixed speed relaxes as an independent scalar time
loop of the same scheme says; and every wrong value is refused in one line before anything is written.
"""

import numpy as np
import pandas as pd
import pytest
import tomli_w

import vpcontact
from vpcontact import mesh as meshes
from conftest import assert_refused, run_cli, snapshot_tree

E, NU = 1000.0, 0.3
#: The constrained modulus E(1 − ν)/((1 + ν)(1 − 2ν)): σ_zz / ε_zz in uniaxial strain.
M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))


def block_case(value="-0.004*t", steps=8, **changes) -> dict:
    """A 3D block 1 × 1 × 0.5 on rollers, its top pressed down by the prescribed u_z = ``value``, on a layer."""
    case = {
        "mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.25},
        "material": {"E": E, "nu": NU},
        "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}, {"part": "right", "components": ["x"]},
                                   {"part": "front", "components": ["y"]}, {"part": "back", "components": ["y"]},
                                   {"part": "top", "components": ["z"], "value": [value]}]},
        "contact": {"part": "bottom", "g": 0.01,
                    "stiffness": {"law": "power", "c_v": 1.0e4, "alpha": 50.0, "beta": 1.0}},
        "time": {"T": 1.0, "steps": steps},
        "solver": {"tolerance": 1e-12},
        "output": {"field_steps": "all"},
    }
    case.update(changes)
    return case


def write(tmp_path, case, name="case.toml"):
    path = tmp_path / name
    path.write_text(tomli_w.dumps(case))
    return path


# --- the held nodes carry u_D, read through the user's tools ------------------------------------------------------
def test_the_top_nodes_carry_the_prescribed_displacement_in_the_files_vtk_reads(tmp_path):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    case = block_case(value="-0.004*t*(1 + 0.5*x*y)")
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", tmp_path / "run", "--quiet")
    assert status == 0, stderr
    history = pd.read_csv(tmp_path / "run" / "history.csv")
    reader = vtk.vtkXMLUnstructuredGridReader()
    for n in (3, 8):
        reader.SetFileName(str(tmp_path / "run" / "fields" / f"body_{n:05d}.vtu"))
        reader.Update()
        grid = reader.GetOutput()
        points = vtk_to_numpy(grid.GetPoints().GetData())
        u = vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
        top = np.isclose(points[:, 2], 0.5)
        t = n / 8
        expected = -0.004 * t * (1 + 0.5 * points[top, 0] * points[top, 1])
        np.testing.assert_allclose(u[top, 2], expected, rtol=1e-13, atol=1e-18)  # float32 coordinates: exact u_D
        # the mean of the part's u_z is the history's, the x and y rollers keep u_x, u_y at 0 on their faces
        assert history.loc[n - 1, "displacement_top_z"] == pytest.approx(expected.mean(), rel=1e-12)
        assert np.all(u[np.isclose(points[:, 0], 0.0), 0] == 0.0) and np.all(u[np.isclose(points[:, 1], 1.0), 1] == 0.0)


def test_an_expression_and_a_python_function_of_the_same_displacement_give_the_same_run():
    common = dict(material={"E": E, "nu": NU}, time={"T": 1.0, "steps": 6},
                  contact={"part": "bottom", "g": 0.01, "stiffness": {"law": "power", "c_v": 1e4, "alpha": 50.0,
                                                                       "beta": 1.0}})
    rollers = {"left": "x", "right": "x", "front": "y", "back": "y"}
    block = meshes.block(1.0, 1.0, 0.5, 0.25)
    by_text = vpcontact.solve(vpcontact.compose(block, dirichlet={**rollers, "top": {"z": "-0.004*t*(1 + x)"}},
                                                **common))
    by_function = vpcontact.solve(vpcontact.compose(
        block, dirichlet={**rollers, "top": {"z": lambda x, y, z, t: -0.004 * t * (1 + x)}}, **common))
    assert by_text.status == by_function.status == "complete"
    pd.testing.assert_frame_equal(by_text.history.drop(columns="wall_time_s", errors="ignore"),
                                  by_function.history.drop(columns="wall_time_s", errors="ignore"))
    np.testing.assert_array_equal(by_text.final.displacement, by_function.final.displacement)


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
def test_a_load_that_reverses_in_every_method_matches_the_full_method(method):
    """Press, lift off the layer and press again by displacement alone: the three methods agree to the solver's
    tolerance, and the layer's history ξ grows only while the block presses it."""
    def case(method):
        case = block_case(value="-0.012*sin(pi*t)**2 + 0.002*t", steps=16, solver={"tolerance": 1e-12,
                                                                                   "method": method})
        case["contact"]["g"] = 0.001
        return vpcontact.Case.model_validate(case)

    mine, full = vpcontact.solve(case(method)).history, vpcontact.solve(case("full")).history
    for column in ("reaction_top_z", "displacement_top_z", "contact_area", "limit_area", "K_max", "max_penetration"):
        scale = np.abs(full[column]).max()
        np.testing.assert_allclose(mine[column], full[column], rtol=0, atol=1e-9 * scale, err_msg=column)
    assert full["reaction_top_z"].min() < 0 and full["contact_area"].iloc[-1] == 0.0  # pressed, then lifted off
    assert full["limit_area"].max() == pytest.approx(1.0)  # the rigid base reached mid-run


# --- a viscoplastic block relaxes while it is pulled ---------------------------------------------------------------
def pulled_reference(rate, T, steps, eta, yield_stress):
    """σ_zz at t_1 … t_steps of the uniform block pulled at u_z = rate · t on its top (its other faces on rollers),
    from the paper's scheme written for one element: z_n = z_{n−1} + k 𝒢(σ_{n−1}, ε_{n−1}) (z_0 = 0), σ_n = ℰε_n + z_n
    with ε_n = diag(0, 0, rate t_n / H) (uniaxial strain), 𝒢 = −(1/η)(σ − P σ), P the projection onto
    ‖dev σ‖ ≤ σ_y (Frobenius norm): the Perzyna law of the case."""
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    k, height = T / steps, 0.5
    sigma, z, out = np.zeros((3, 3)), np.zeros((3, 3)), []
    for n in range(1, steps + 1):
        deviator = sigma - np.trace(sigma) / 3 * np.eye(3)
        size = np.linalg.norm(deviator)
        if size > yield_stress:
            z = z - k / eta * (1 - yield_stress / size) * deviator
        strain = np.diag([0.0, 0.0, rate * n * k / height])
        sigma = lam * np.trace(strain) * np.eye(3) + 2 * mu * strain + z
        out.append(sigma[2, 2])
    return np.array(out)


@pytest.mark.parametrize("method", ["condensed", "full"])
def test_a_viscoplastic_block_pulled_at_a_fixed_speed_relaxes_as_its_scalar_scheme_says(method):
    case = block_case(value="0.01*t", steps=20)
    del case["contact"]
    case["boundary"]["dirichlet"].append({"part": "bottom", "components": ["z"]})
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 1.0}
    case["solver"]["method"] = method
    result = vpcontact.solve(vpcontact.Case.model_validate(case))
    assert result.status == "complete"
    expected = pulled_reference(0.01, 1.0, 20, 0.5, 1.0)
    history = result.history
    np.testing.assert_allclose(history["reaction_top_z"], expected * 1.0, rtol=1e-10)  # σ_zz times the top's area
    np.testing.assert_allclose(history["reaction_bottom_z"], -expected, rtol=1e-10)
    assert expected[-1] < 0.85 * M * 0.02  # it did relax: below the elastic stress M ε
    np.testing.assert_allclose(result.final.stress[:, 2, 2], expected[-1], rtol=1e-10)


# --- refusals, before anything is written ------------------------------------------------------------------------
def rectangle_case(value) -> dict:
    return {"mesh": {"shape": "rectangle", "width": 1.0, "height": 0.5, "h": 0.25},
            "material": {"E": E, "nu": NU},
            "boundary": {"dirichlet": [{"part": "bottom"}, {"part": "top", "value": value}]},
            "time": {"T": 1.0, "steps": 4}}


def with_entry(case, **entry):
    case["boundary"]["dirichlet"].append(entry)
    return case


@pytest.mark.parametrize("case, words", [
    (with_entry(block_case(), part="top", components=["z", "x"], value=["-0.01*t"]),
     ["boundary.dirichlet[5]", "value has 1 expressions and components lists 2"]),
    (with_entry(block_case(), part="top", value=["0", "-0.01*t"]),
     ["boundary.dirichlet[5].value has 2 components and the mesh is 3D"]),
    (rectangle_case(["0", "-0.01*z*t"]), ["boundary.dirichlet[1].value[1]", "z"]),
    (with_entry(block_case(), part="top", components=["z"], value=["-0.02*t"]),
     ["boundary.dirichlet[4] and boundary.dirichlet[5] both hold u_z", "different values"]),
    (with_entry(block_case(), part="front", components=["z"], value=["-0.004*t"]),
     ["boundary.dirichlet[5].value moves 5 contact node(s) along their normal", "(0, 0, 0)"]),
    (block_case(value="-0.01*t/(t - 0.5)"), ["boundary.dirichlet[4].value[0]", "not finite", "t = 0.5 (step 4)"]),
    (block_case(value="-0.01*t", time={"T": 1.0, "steps": 4, "start": 0.5},
                initial={"displacement": ["0", "0", "-0.001*z"]}),
     ["u_z = -0.0005", "boundary.dirichlet[4]", "must equal the prescribed displacement", "-0.005 at t_0 = 0.5"]),
])
def test_a_wrong_prescribed_displacement_is_refused_in_one_line_and_nothing_is_written(tmp_path, case, words):
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", out)
    assert_refused(status, stderr, *words, untouched=[(out, snapshot_tree(out))])


def test_the_python_api_refuses_a_displacement_function_it_cannot_call():
    block = meshes.block(1.0, 1.0, 0.5, 0.5)
    common = dict(material={"E": E, "nu": NU}, time={"T": 1.0, "steps": 2})
    with pytest.raises(vpcontact.CaseError, match=r"displacements\['top'\]\['z'\] = .* takes 2 arguments \(x, t\)"):
        vpcontact.compose(block, dirichlet={"bottom": None, "top": {"z": lambda x, t: -0.01 * t}}, **common)
    with pytest.raises(vpcontact.CaseError, match=r"must return the displacement at the nodes"):
        vpcontact.compose(block, dirichlet={"bottom": None, "top": {"z": lambda x, y, z, t: [1.0, 2.0]}}, **common)
    case = {**rectangle_case(None), "mesh": {"shape": "block", "h": 0.5}}
    case["boundary"]["dirichlet"] = [{"part": "bottom"}]
    case = vpcontact.Case.model_validate(case)
    with pytest.raises(vpcontact.CaseError, match=r"no boundary.dirichlet entry holds component 'x' of part 'left'"):
        vpcontact.build_problem(case, displacements={"left": {"x": lambda x, y, z, t: 0 * x}})


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
def test_mixed_control_traction_on_one_part_displacement_on_another_balances(method):
    """The top moved down by a prescribed displacement while the right side is pulled by a traction that reverses:
    along x only the left rollers hold the body (their reaction balances the applied force), along y only the top
    and the layer (the top's reaction balances the contact force); the methods agree."""
    def solved(method):
        return vpcontact.solve(vpcontact.compose(
            meshes.rectangle(1.0, 0.5, 0.125), {"E": E, "nu": NU},
            dirichlet={"left": "x", "top": {"y": "-0.01*t"}}, traction={"right": ["20*sin(2*pi*t)", "0"]},
            contact={"part": "bottom", "g": 0.001, "normal": [0, -1],
                     "stiffness": {"law": "power", "c_v": 1e4, "alpha": 50.0, "beta": -1.0}},
            time={"T": 1.0, "steps": 8}, solver={"method": method, "tolerance": 1e-12}))

    result, full = solved(method), solved("full")
    history = result.history
    force = np.abs(history["reaction_top_y"]).max()
    assert result.status == "complete" and history["limit_area"].max() > 0  # the layer's limit reached
    np.testing.assert_allclose(history["reaction_left_x"], -history["applied_force_x"], rtol=0, atol=1e-9 * force)
    np.testing.assert_allclose(history["reaction_top_y"], -history["contact_force_y"], rtol=0, atol=1e-9 * force)
    assert np.abs(history["applied_force_x"]).max() == pytest.approx(20.0 * 0.5 * np.sin(2 * np.pi * 0.25))
    for column in ("reaction_top_y", "reaction_left_x", "displacement_left_y", "contact_area"):
        np.testing.assert_allclose(history[column], full.history[column], rtol=0,
                                   atol=1e-9 * max(np.abs(full.history[column]).max(), 1e-300), err_msg=column)
