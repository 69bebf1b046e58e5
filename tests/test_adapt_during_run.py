"""Adapting the mesh during one run (adapt.mode = "run", vpcontact.adaptivity.during_run): the refinement's lineage,
what the transfer of a level conserves, and runs that refine at their first step and in the middle of the history."""

import json

import meshio
import numpy as np
import pytest

import vpcontact
from conftest import block_3d_case, run_cli
from vpcontact import adapt, build_problem
from vpcontact.adaptivity.during_run import RunAdaptation, _Watcher, energy_norm
from vpcontact.adaptivity.options import AdaptOptions
from vpcontact.adaptivity.transfer import Transfer
from vpcontact.estimate.estimators import ESTIMATORS
from vpcontact.estimate.indicators import Level
from vpcontact.mesh.refinement import refine_with_lineage
from vpcontact.mesh.simplex import measures
from vpcontact.progress import SILENT
from vpcontact.results import norms
from vpcontact.timeloop.loop import TimeLoop
from vpcontact.timeloop.snapshot import LoopSnapshot
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


def punch_case(h=0.25, late=20.0) -> dict:
    """A viscoplastic unit square on a hardening layer with a rigid step under its right half (gap 0.02 (x − ½)⁺),
    on a roller on its left side, pressed down from t = 0 and pushed sideways from t = 0.5 (``late`` N/m)."""
    return {"mesh": {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": h},
            "material": {"E": 1000.0, "nu": 0.3, "viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}},
            "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}],
                         "traction": [{"part": "top", "value": [f"{late}*max(t-0.5,0)", "-20*t"]}]},
            "contact": {"part": "bottom", "gap": "0.02*max(x - 0.5, 0)", "g": 0.05,
                        "stiffness": {"law": "power", "c_v": 1000.0, "alpha": 20.0, "beta": 1.0}},
            "time": {"T": 1.1, "steps": 11}, "solver": {"tolerance": 1e-12}, "output": {"field_steps": [3, 11]}}


def block_case() -> dict:
    """conftest's 3D block on its curved gap, its body viscoplastic."""
    case = block_3d_case()
    return {**case, "material": {**case["material"], "viscoplastic": {"law": "perzyna", "eta": 0.5,
                                                                          "yield_stress": 3.0}}}


def a_refinement(case: dict, seed: int, share: float = 0.3):
    """(problem, its loop after 3 steps with its snapshot, the problem on a refinement of random elements, lineage)."""
    loaded = vpcontact.load_case(case)
    problem = build_problem(loaded)
    loop = TimeLoop(problem, loaded.output)
    loop.run(stop=lambda: "enough" if loop.state.step == 3 else None)
    elements = problem.mesh.mesh.t.shape[1]
    marked = np.random.default_rng(seed).choice(elements, max(1, int(share * elements)), replace=False)
    mesh, lineage = refine_with_lineage(problem.mesh, marked)
    return problem, loop.snapshot(), problem.on(mesh), lineage


@pytest.mark.parametrize("case", [punch_case(), block_case()], ids=["2d", "3d"])
def test_the_lineage_interpolates_affine_fields_exactly_and_the_children_lie_in_their_parents(case):
    problem, _, new, lineage = a_refinement(case, seed=1)
    old_p, new_p = problem.mesh.mesh.p, new.mesh.mesh.p
    gradient = np.arange(1.0, old_p.shape[0] + 1.0)
    np.testing.assert_allclose(lineage.interpolation @ (gradient @ old_p + 0.5), gradient @ new_p + 0.5,
                               rtol=0, atol=1e-13)
    assert np.array_equal(lineage.interpolation[:old_p.shape[1]].toarray(), np.eye(old_p.shape[1]))
    area = np.bincount(lineage.parent, measures(new_p, new.mesh.mesh.t))
    np.testing.assert_allclose(area, measures(old_p, problem.mesh.mesh.t), rtol=1e-12)
    assert new.basis.N > problem.basis.N


@pytest.mark.parametrize("case", [punch_case(), block_case()], ids=["2d", "3d"])
def test_a_uniform_state_survives_any_refinement_bit_for_bit(case):
    problem, snapshot, new, lineage = a_refinement(case, seed=2)
    dim, m = problem.mesh.dim, problem.surface.size
    uniform = {"xi": np.full(m, 0.1 / 3), "previous_d": np.full(m, -1 / 7),
               "previous_lam": np.full(m, 2 / 3) * problem.surface.weights}
    tensor = np.array([[1 / 3, 2 / 7], [2 / 7, -5 / 11]]) if dim == 2 else np.full((3, 3), 1 / 3)
    z = np.broadcast_to(tensor[:, :, None], snapshot.arrays["z"].shape).copy()  # (d, d, elements)
    arrays = {**snapshot.arrays, **uniform, "z": z}
    rows = arrays["contact_xi"].shape[0]
    arrays.update({f"contact_{name}": np.full((rows, m), value) for name, value in
                   (("xi", 0.1 / 3), ("penetration", 1 / 7), ("pressure_compliance", 4 / 3), ("pressure_rigid", 0.0))})
    carried = Transfer(problem, new, lineage).snapshot(LoopSnapshot(arrays, snapshot.meta, snapshot.fields)).arrays
    assert np.all(carried["xi"] == 0.1 / 3) and np.all(carried["previous_d"] == -1 / 7)
    assert np.all(carried["contact_xi"] == 0.1 / 3) and np.all(carried["contact_pressure_compliance"] == 4 / 3)
    assert np.array_equal(carried["z"], np.broadcast_to(tensor[:, :, None], carried["z"].shape))
    np.testing.assert_allclose(carried["previous_lam"], 2 / 3 * new.surface.weights, rtol=1e-15)
    np.testing.assert_array_equal(carried["contact_K"], new.law.K(np.full(new.surface.size, 0.1 / 3))[None, :]
                                  .repeat(rows, axis=0))


def test_the_transfer_conserves_xi_the_contact_force_and_z_along_a_flat_contact_part():
    problem, snapshot, new, lineage = a_refinement(punch_case(), seed=3, share=0.5)
    rng = np.random.default_rng(4)
    m = problem.surface.size
    arrays = {**snapshot.arrays, "xi": rng.random(m)}
    arrays["contact_pressure_compliance"] = rng.random(arrays["contact_xi"].shape)
    carried = Transfer(problem, new, lineage).snapshot(LoopSnapshot(arrays, snapshot.meta, snapshot.fields))
    old_w, new_w = problem.surface.weights, new.surface.weights
    assert new.surface.size > m
    np.testing.assert_allclose(new_w @ carried.arrays["xi"], old_w @ arrays["xi"], rtol=1e-14)
    np.testing.assert_allclose(carried.arrays["contact_pressure_compliance"] @ new_w,
                               arrays["contact_pressure_compliance"] @ old_w, rtol=1e-14)
    old_area, new_area = measures(problem.mesh.mesh.p, problem.mesh.mesh.t), measures(new.mesh.mesh.p, new.mesh.mesh.t)
    np.testing.assert_allclose(np.einsum("e,ije->ij", new_area, carried.arrays["z"]),
                               np.einsum("e,ije->ij", old_area, arrays["z"]), rtol=1e-13, atol=1e-15)
    for step, fields in snapshot.fields.items():
        moved = carried.fields[step]
        if "error_indicator" in fields:
            np.testing.assert_allclose(np.sum(moved["error_indicator"] ** 2), np.sum(fields["error_indicator"] ** 2),
                                       rtol=1e-13)
        np.testing.assert_allclose(np.einsum("e,eij->ij", new_area, moved["stress"]),
                                   np.einsum("e,eij->ij", old_area, fields["stress"]), rtol=1e-13, atol=1e-15)


def test_refining_at_the_first_step_only_is_a_run_on_the_last_mesh():
    case = vpcontact.load_case({**punch_case(late=0.0), "output": {"field_steps": [3, 11]}})
    adaptation = adapt(build_problem(case), {"mode": "run", "tolerance": 0.6, "theta": 0.5}, case.output)
    refined = [row["step"] for row in adaptation.rows if row["refined"]]
    assert refined and set(refined) == {1} and adaptation.status == "complete"
    plain = vpcontact.solve(build_problem(case, mesh=adaptation.mesh), output=case.output)
    result = adaptation.result
    mesh, final = adaptation.mesh.mesh, result.fields[11]  # the last row's norm, as the norms module computes it
    lame = adaptation.problem.elasticity.lame
    np.testing.assert_allclose(adaptation.rows[-1]["energy_norm"],
                               norms.energy_norm(mesh.p, mesh.t, final.displacement, lame), rtol=1e-12)
    assert len(result.rows) == len(plain.rows) == 11 and result.dofs == plain.dofs
    for column in ("contact_force_y", "max_penetration", "K_max", "reaction_left_x"):
        np.testing.assert_allclose(result.series(column), plain.series(column), rtol=1e-9, atol=1e-12)
    for step in (3, 11):
        np.testing.assert_allclose(result.fields[step].displacement, plain.fields[step].displacement, rtol=0,
                                   atol=1e-10 * np.abs(plain.fields[step].displacement).max())
        np.testing.assert_allclose(result.fields[step].z, plain.fields[step].z, rtol=0,
                                   atol=1e-9 * np.abs(plain.fields[step].z).max())


def test_the_levels_not_estimated_are_within_the_tolerance_the_trend_predicts():
    """After its refinement at the first step the run estimates only the levels its trend asks for (the wait doubles
    while the estimate extrapolated from the two last estimates stays within the tolerance); every level of its
    history, estimated afterwards on its last mesh, is within the tolerance, and the levels estimated are fewer than
    the steps."""
    case = vpcontact.load_case({**punch_case(late=0.0), "time": {"T": 1.1, "steps": 22},
                                "output": {"field_steps": "all"}})
    tolerance = 0.6
    adaptation = adapt(build_problem(case), {"mode": "run", "tolerance": tolerance, "theta": 0.5}, case.output)
    assert {row["step"] for row in adaptation.rows if row["refined"]} == {1} and adaptation.status == "complete"
    estimated = [row["step"] for row in adaptation.rows if not row["refined"]]
    assert estimated[0] == 1 and estimated[-1] == 22 and len(estimated) <= 22 // 3, estimated
    assert max(b - a for a, b in zip(estimated, estimated[1:])) >= 4  # the waits grew
    problem, result = adaptation.problem, adaptation.result
    estimator = ESTIMATORS["residual"].prepare(problem)
    largest = 0.0
    for step in range(1, 23):
        eta = np.sqrt(estimator(Level.of(result, step, problem)).squared.sum())
        largest = max(largest, energy_norm(problem, result.fields[step].displacement))
        assert eta <= tolerance * largest, (step, eta / largest)


@pytest.mark.parametrize("levels, waits", [
    ([(1, 0.08), (2, 0.08), (4, 0.08), (8, 0.08), (16, 0.08)], [1, 2, 4, 8, 8]),  # flat within: doubles to the longest
    ([(1, 0.04), (3, 0.03)], [2, 4]),  # at most half the tolerance, then falling
    ([(1, 0.05), (2, 0.07), (3, 0.085)], [2, 1, 1]),  # rising: (0.1 - 0.07) / 0.02 = 1.5 steps, then 1
    ([(1, 0.06), (2, 0.065), (4, 0.07), (8, 0.083)], [1, 2, 4, 5]),  # rising slowly, then faster: 0.017 / 0.00325
    ([(1, 0.02), (3, 0.09)], [2, 1]),  # rising fast from under half the tolerance
])
def test_the_wait_to_the_next_estimate_follows_the_trend_of_the_estimate(levels, waits):
    """The steps from an accepted level to the next estimate (tolerance 0.1, one mesh): twice the last while the
    estimate extrapolated linearly from the two last accepted levels stays within the tolerance, else as many as it
    stays within it, at least one; from a first level, twice the last when it is at most half the tolerance."""
    settings = AdaptOptions(cycles=None, theta=0.5, max_dofs=10**6, functional="max", estimator="residual",
                            mode="run", tolerance=0.1)
    watcher = _Watcher(settings, RunAdaptation(), set(), SILENT, None)
    found = []
    for step, relative in levels:
        watcher.wait = watcher._next_wait(step, relative, dofs=1000)
        found.append(watcher.wait)
    assert found == waits
    assert watcher._next_wait(30, 0.09, dofs=4000) == 1  # a new mesh: no trend yet, over half the tolerance


def test_a_refinement_in_the_middle_of_the_history_keeps_the_balance_and_conserves_the_history():
    case = vpcontact.load_case(punch_case(h=0.125, late=60.0))  # η/‖u‖ 0.49 at t_1, 0.16 at t_5, 0.60 at t_7
    recorded = {}

    def remember(loop):  # ∫_Γ3 ξ and ∫_Ω z of each accepted level, on the mesh it was computed on
        area = measures(loop.problem.mesh.mesh.p, loop.problem.mesh.mesh.t)
        recorded[loop.state.step] = (loop.problem.surface.weights @ loop.state.xi,
                                     np.einsum("e,ije->ij", area, loop.state.z))

    adaptation = adapt(build_problem(case), {"mode": "run", "tolerance": 0.5}, case.output, after_step=remember)
    refined = sorted({row["step"] for row in adaptation.rows if row["refined"]})
    assert adaptation.status == "complete" and refined and refined[0] >= 6, adaptation.rows  # the sideways push
    result, last = adaptation.result, adaptation.problem
    rows = result.rows
    applied = np.abs(result.series("applied_force_y")).max()
    for row in rows:  # the body's balance at every level, before and after each refinement
        assert abs(row["contact_force_y"] + row["applied_force_y"] + row["reaction_left_y"]) < 1e-9 * applied
        assert abs(row["contact_force_x"] + row["applied_force_x"] + row["reaction_left_x"]) < 1e-9 * applied
    w = last.surface.weights
    xi = result.contact_history("xi")
    np.testing.assert_allclose(xi @ w, [recorded[n][0] for n in range(1, 12)], rtol=1e-12)
    force = (result.contact_history("pressure_compliance") + result.contact_history("pressure_rigid")) @ w
    np.testing.assert_allclose(force, result.series("contact_force_y"), rtol=1e-12)
    area = measures(last.mesh.mesh.p, last.mesh.mesh.t)
    np.testing.assert_allclose(np.einsum("e,eij->ij", area, result.fields[3].z), recorded[3][1], rtol=1e-12,
                               atol=1e-15)
    dofs = [row["dofs"] for row in adaptation.rows]
    assert dofs == sorted(dofs) and result.dofs == dofs[-1] == last.basis.N


WIDTH, HEIGHT = 0.04, 0.02  # m: a 40 × 20 mm pad


def pad_case(yield_stress: float, time: dict) -> dict:
    """The gmsh pad of :func:`pad_mesh` ("pad.msh") in SI units: a Perzyna body (``yield_stress``, Pa) pressed down
    30 µm and lifted by its top (u_y = −3e-5 sin(πt)) onto a hardening layer 0.1 mm thick with a rigid step under
    x > 20 mm, on the time grid ``time``, its fields at every step."""
    return {"mesh": {"file": "pad.msh"},
            "material": {"E": 5e6, "nu": 0.45,
                         "viscoplastic": {"law": "perzyna", "eta": 0.2, "yield_stress": yield_stress}},
            "boundary": {"dirichlet": [{"part": "left", "components": ["x"]},
                                       {"part": "top", "components": ["y"], "value": ["-3e-5*sin(pi*t)"]}]},
            "contact": {"part": "bottom", "gap": "2e-3*max(x - 0.02, 0)", "g": 1e-4,
                        "stiffness": {"law": "power", "c_v": 2e10, "alpha": 1e4, "beta": 1.0}},
            "time": time, "output": {"field_steps": "all"}}


def pad_mesh(path):
    """A pad meshed in gmsh and written to ``path`` as a user would: its sides named "bottom", "top", "left",
    "right", its surface "pad"."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("pad")
        surface = gmsh.model.occ.addRectangle(0, 0, 0, WIDTH, HEIGHT)
        gmsh.model.occ.synchronize()
        for _, tag in gmsh.model.getBoundary([(2, surface)], oriented=False):
            xmin, ymin, _, xmax, ymax, _ = gmsh.model.getBoundingBox(1, tag)
            name = ("bottom" if ymax < 1e-6 else "top" if ymin > HEIGHT - 1e-6 else  # OCC boxes are padded
                    "left" if xmax < 1e-6 else "right")
            gmsh.model.addPhysicalGroup(1, [tag], name=name)
        gmsh.model.addPhysicalGroup(2, [surface], name="pad")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 5e-3)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def test_a_gmsh_pad_pressed_released_and_lifted_adapts_during_its_run_from_the_command_line(tmp_path):
    """SI units, a gmsh file, displacement control that presses, releases and lifts the pad off; run by the command
    line off a terminal; its files read by pandas, meshio and VTK. The pad meets a rigid step under its right half
    (the layer's edge at x = 20 mm): the mesh is refined there, the top's reaction balances the contact force at
    every level, and a plain run on the written final mesh repeats its history (it was refined at its first step)."""
    import pandas
    import tomli_w

    pad_mesh(tmp_path / "pad.msh")
    case = {**pad_case(yield_stress=2e5, time={"T": 1.5, "steps": 15}),
            "adapt": {"mode": "run", "tolerance": 0.15}}
    (tmp_path / "pad.toml").write_text(tomli_w.dumps(case))
    out = tmp_path / "run"
    status, stdout, stderr = run_cli("run", "pad.toml", "--out", "run", cwd=tmp_path)
    assert status == 0, stderr
    assert "refinement" in stderr and "adapt.csv" in stdout
    adapted = pandas.read_csv(out / "adapt.csv")
    assert list(adapted.columns) == ["step", "t", "dofs", "contact_nodes", "estimate", "energy_norm",
                                     "relative_estimate", "refined"]
    accepted = list(adapted.loc[~adapted["refined"], "step"])  # the estimated levels: 1, then as often as needed
    assert accepted[0] == 1 and accepted[-1] == 15 and accepted == sorted(set(accepted))
    assert adapted["refined"].sum() >= 1 and adapted["dofs"].is_monotonic_increasing
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["adaptation"]["refinements"] == adapted["refined"].sum()
    assert summary["dofs"] == adapted["dofs"].iloc[-1]

    history = pandas.read_csv(out / "history.csv")
    assert len(history) == 15
    scale = history["reaction_top_y"].abs().max()
    assert scale > 0 and history["nodes_separated"].iloc[-1] == summary["contact_nodes"]  # lifted off at the end
    np.testing.assert_allclose(history["reaction_top_y"] + history["contact_force_y"], 0.0, atol=1e-8 * scale)

    final = meshio.read(out / "final_mesh.msh")
    assert 2 * len(final.points) == summary["dofs"]
    # the layer's edge pulls the refinement to it: every refinement at the first step, as measured (142 -> 8,120 dofs)
    assert set(adapted.loc[adapted["refined"], "step"]) == {1}
    again = {**case, "mesh": {"file": "run/final_mesh.msh"}}
    again.pop("adapt")
    (tmp_path / "again.toml").write_text(tomli_w.dumps(again))
    status, _, stderr = run_cli("run", "again.toml", "--out", "again", cwd=tmp_path)
    assert status == 0, stderr
    plain = pandas.read_csv(tmp_path / "again" / "history.csv")  # the whole history on the last mesh: the same
    np.testing.assert_allclose(history["reaction_top_y"], plain["reaction_top_y"], rtol=1e-8, atol=1e-9 * scale)
    for step in (5, 15):
        mine, theirs = (vtu_displacement(folder / "fields" / f"body_{step:05d}.vtu")
                        for folder in (out, tmp_path / "again"))
        assert mine.shape == (len(final.points), 3)
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max())


def vtu_displacement(path) -> np.ndarray:
    """The point data "displacement" of a VTU file, as VTK reads it."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("displacement"))


def test_refining_towards_the_dofs_an_estimate_asks_for_grades_the_mesh_at_the_largest_indicator():
    """Rounds of Dörfler marking on predicted indicators (vpcontact.adaptivity.marking): the mesh reaches the dofs
    wanted, within the most allowed, with its smallest elements at the one element whose indicator dominates; the
    lineage composed over the rounds still interpolates affine fields exactly."""
    from vpcontact.adaptivity.marking import refine_towards, wanted_dofs

    problem = build_problem(vpcontact.load_case(punch_case()))
    mesh = problem.mesh
    squared = np.full(mesh.mesh.t.shape[1], 1e-6)
    corner = int(np.argmin(np.linalg.norm(mesh.mesh.p[:, mesh.mesh.t].mean(axis=1) - [[0.5], [0.0]], axis=0)))
    squared[corner] = 1.0
    wanted = wanted_dofs(problem.basis.N, 3.0, 2)
    assert wanted == 4 * problem.basis.N  # 3² = 9 times the dofs, at most GROWTH = 4 in one go
    refined, lineage = refine_towards(mesh, squared, wanted, most=10 * wanted, theta=0.5)
    dofs = 2 * refined.mesh.p.shape[1]
    assert wanted <= dofs <= 10 * wanted
    area = measures(refined.mesh.p, refined.mesh.t)
    assert lineage.parent[np.argmin(area)] == corner and area.min() < area.max() / 100  # several levels deeper there
    p, new_p = mesh.mesh.p, refined.mesh.p
    np.testing.assert_allclose(lineage.interpolation @ (p[0] - 2 * p[1]), new_p[0] - 2 * new_p[1], atol=1e-14)
    assert refine_towards(mesh, squared, wanted, most=problem.basis.N + 1, theta=0.5) is None  # nothing fits
