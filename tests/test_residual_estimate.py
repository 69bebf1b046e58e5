"""The residual a posteriori error estimator (vpcontact.estimate.residual): exact on patch tests, each
term's value and scaling on fields where it is known by hand, the effectivity index against a finer
reference in 2D and 3D, and its outputs (output.error_estimate)."""

import copy
import csv
import dataclasses

import meshio
import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, half_disc_case, rectangle_case, resumed_after, run_cli, snapshot_tree, solved
from vpcontact.estimate.indicators import Level
from vpcontact.results.norms import element_energies, energy_norm, transfer
from vpcontact.estimate.residual import TERMS, ResidualEstimator, estimate
from vpcontact.results.columns import estimate_columns, history_columns
from vpcontact.results.footprint import memory_needed

ESTIMATE_COLUMNS = estimate_columns(TERMS)  # the history columns of the residual estimate

E, NU = 1000.0, 0.3
MU = E / (2 * (1 + NU))


def solve(data: dict, **overrides):
    """(problem, result) of the case ``data``."""
    return solved(vpcontact.Case.model_validate(copy.deepcopy(data)), **overrides)


def with_fields(data: dict, steps="all") -> dict:
    data = copy.deepcopy(data)
    data["output"] = {"field_steps": steps}
    return data


def block_3d() -> dict:
    """The block [0, 1]² × [0, 0.5] on rollers at its four sides pushed by 100 t onto the layer (uniform state)."""
    sides = [("left", "x"), ("right", "x"), ("front", "y"), ("back", "y")]
    return {
        "mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.25},
        "material": {"E": E, "nu": NU},
        "boundary": {"dirichlet": [{"part": part, "components": [c]} for part, c in sides],
                     "traction": [{"part": "top", "value": ["0", "0", "-100*t"]}]},
        "contact": {"part": "bottom", "g": 0.2, "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-13},
        "output": {"field_steps": "all"},
    }


def energy_error(result, reference, step: int) -> float:
    """‖I_ref u_h − u_ref‖_E on the reference mesh at a step (the effectivity's denominator)."""
    mine, theirs = result.snapshot(step), reference.snapshot(step)
    moved = transfer(mine, theirs.points, theirs.elements)
    return energy_norm(theirs.points, theirs.elements, moved.displacement - theirs.displacement,
                       reference.discretization.elasticity.lame)


# --- exactness: a uniform state that P1 × P0 represents exactly ----------------------------------------
@pytest.mark.parametrize("beta", [1.0, -1.0])  # both reach the rigid base: its multiplier enters
def test_the_estimate_vanishes_on_the_uniform_block_in_2d(beta):
    data = with_fields(rectangle_case(stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}))
    problem, result = solve(data)
    energy = 0.5 * (100 * 1.1) ** 2 / (2 * MU)  # ‖σ‖² / 2μ of the final state: the units of η²
    for step in (1, 6, 11):
        indicators = estimate(Level.of(result, step, problem))
        assert set(indicators.terms) == set(TERMS)
        # η² at rounding level: the complementarity term is linear in the room g − d (0 to rounding at
        # the nodes at the limit), the others are squares of residuals that vanish to rounding
        assert indicators.total**2 < 1e-14 * energy, {k: v.sum() for k, v in indicators.terms.items()}
        assert max(indicators.terms[term].sum() for term in TERMS if term != "complementarity") < 1e-24 * energy
    assert result.series("nodes_at_limit")[-1] == result.contact_nodes  # the rigid part carries load at t = 1.1
    assert result.series("nodes_at_limit")[0] == 0


def test_the_estimate_vanishes_on_the_uniform_block_in_3d():
    problem, result = solve(block_3d())
    assert result.series("nodes_at_limit")[-1] == result.contact_nodes
    energy = 0.5 * (100 * 1.1) ** 2 / (2 * MU)
    for step in (3, 11):
        indicators = estimate(Level.of(result, step, problem))
        assert indicators.total**2 < 1e-14 * energy
        assert max(indicators.terms[term].sum() for term in TERMS if term != "complementarity") < 1e-24 * energy


# --- each term where its value is known -----------------------------------------------------------------
def test_a_shear_stress_added_to_the_uniform_block_shows_on_the_free_components_of_the_boundary():
    """σ_xy = δ added everywhere: no jump; σ_h n − f2 = δ in the free component of every facet of the top
    (x), of the rollers left and right (y: x is fixed there) and σ_τ = δ on Γ3, so with facets of length
    h: neumann = (W + 2H) h δ² / 2μ, contact_tangential = W h δ² / 2μ, contact_normal = 0."""
    problem, result = solve(with_fields(rectangle_case(), [11]))
    level = Level.of(result, 11, problem)
    delta, h, W, H = 3.0, 0.125, 1.0, 0.5
    stress = level.fields.stress.copy()
    stress[:, 0, 1] += delta
    stress[:, 1, 0] += delta
    sheared = dataclasses.replace(level, fields=dataclasses.replace(level.fields, stress=stress))
    terms = {name: values.sum() for name, values in estimate(sheared).terms.items()}
    assert terms["neumann"] == pytest.approx((W + 2 * H) * h * delta**2 / (2 * MU), rel=1e-9)
    assert terms["contact_tangential"] == pytest.approx(W * h * delta**2 / (2 * MU), rel=1e-9)
    assert terms["jump"] < 1e-18 and terms["contact_normal"] < 1e-18 and terms["body_force"] == 0.0


def test_the_normal_term_is_the_gap_between_the_normal_stress_and_the_layer_pressure():
    """σ_yy lowered by δ: −σ_ν,h ≠ the layer's pressure by δ on Γ3, and the top's traction by δ."""
    problem, result = solve(with_fields(rectangle_case(), [11]))
    level = Level.of(result, 11, problem)
    delta, h, W = 2.0, 0.125, 1.0
    stress = level.fields.stress.copy()
    stress[:, 1, 1] -= delta
    changed = dataclasses.replace(level, fields=dataclasses.replace(level.fields, stress=stress))
    terms = {name: values.sum() for name, values in estimate(changed).terms.items()}
    assert terms["contact_normal"] == pytest.approx(W * h * delta**2 / (2 * MU), rel=1e-9)
    assert terms["neumann"] == pytest.approx(W * h * delta**2 / (2 * MU), rel=1e-9)  # the top, σ_yy − f2_y
    assert terms["contact_tangential"] < 1e-18


def test_the_body_force_term_is_h_squared_times_the_force_and_scales_as_h():
    """f0 = (0, −10): Σ_K h_K² |K| |f0|² / 2μ with h_K = √2 h (the diagonal of a square cell) = 2 h² |Ω| 100 / 2μ."""
    values = {}
    for h in (0.125, 0.0625):
        data = with_fields(rectangle_case(), [11])
        data["mesh"]["h"] = h
        data["boundary"]["body_force"] = [{"value": ["0", "-10"]}]
        problem, result = solve(data)
        body = estimate(Level.of(result, 11, problem)).terms["body_force"]
        assert body.sum() == pytest.approx(2 * h**2 * 0.5 * 100 / (2 * MU), rel=1e-9)
        values[h] = np.sqrt(body.sum())
    assert values[0.0625] / values[0.125] == pytest.approx(0.5, rel=1e-9)


def test_the_complementarity_term_is_the_rigid_pressure_times_the_room_left_between_nodes():
    """On one Γ3 segment with the rigid pressure a at one end and the room g − d = b at the other (and 0,
    0 at the opposite ends): ∫ λ_h (g − d_h)⁺ = |E| (0 + a·b) / 6."""
    problem, result = solve(with_fields(half_disc_case(h=0.25, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0,
                                                                              "beta": -1.0}, load=40.0), [11]))
    level = Level.of(result, 11, problem)
    surface = result.discretization.surface
    contact = {name: values.copy() for name, values in level.contact.items()}
    i, j = surface.facets[:, 0]
    contact["pressure_rigid"][:] = 0.0
    contact["penetration"][:] = 0.2  # at the limit everywhere: no room
    contact["pressure_rigid"][i], contact["penetration"][j] = 5.0, 0.2 - 0.03
    term = estimate(dataclasses.replace(level, contact=contact)).terms["complementarity"]
    length = np.linalg.norm(np.diff(surface.coordinates[:, [i, j]], axis=1))
    assert term.sum() == pytest.approx(length * 5.0 * 0.03 / 6, rel=1e-9)
    assert np.count_nonzero(term) == 1


# --- effectivity: η / ‖u − u_h‖_E against a finer reference, the same time grid ---------------------
@pytest.mark.parametrize("beta", [1.0, -1.0])
def test_the_effectivity_on_the_paper_example_stays_in_the_measured_band(beta):
    """Measured (benchmarks/effectivity.py): 3.2–4.0 for h = 1/8 … 1/64 against 1/256, t = 0.5 and 1.1;
    3.2–3.9 on h = 1/4, 1/8 against 1/32 (this test)."""
    def run(n):
        case = vpcontact.load_case("examples/paper_ball.toml", {"mesh.h": 1 / n, "contact.stiffness.beta": beta,
                                                               "output.field_steps": [5, 11]})
        return solved(case)

    _, reference = run(32)
    effectivities = []
    for n in (4, 8):
        problem, result = run(n)
        estimator = ResidualEstimator(problem)
        for step in (5, 11):
            eta = estimator(Level.of(result, step, problem)).total
            effectivities.append(eta / energy_error(result, reference, step))
    assert 3.0 < min(effectivities) and max(effectivities) < 4.2, effectivities
    assert max(effectivities) / min(effectivities) < 1.25, effectivities


def test_the_local_indicators_follow_the_local_error():
    """log η_K against log e_K (the reference's error energy in K) on the paper's example at h = 1/8 against
    1/32: correlated (measured 0.93–0.98 over h = 1/8 … 1/64 against 1/256)."""
    from vpcontact.mesh.locate import containing_elements

    def run(n):
        return solved(vpcontact.load_case("examples/paper_ball.toml", {"mesh.h": 1 / n, "output.field_steps": [11]}))

    (_, reference), (problem, result) = run(32), run(8)
    theirs = reference.snapshot(11)
    moved = transfer(result.snapshot(11), theirs.points, theirs.elements)
    energy = element_energies(theirs.points, theirs.elements, moved.displacement - theirs.displacement,
                              reference.discretization.elasticity.lame)
    mesh = result.discretization.mesh.mesh
    owner = containing_elements(mesh.p, mesh.t, theirs.points[:, theirs.elements].mean(axis=1))
    local = np.bincount(owner, weights=energy, minlength=mesh.t.shape[1])
    eta = estimate(Level.of(result, 11, problem)).squared
    assert np.corrcoef(np.log(eta), np.log(local))[0, 1] > 0.85


def test_the_3d_quarter_ball_estimate_has_every_term_and_a_bounded_effectivity():
    """examples/quarter_ball.toml at h = 0.6 and 0.4 against 0.2: effectivity measured 5.8 and 5.3."""
    def run(h):
        case = vpcontact.load_case("examples/quarter_ball.toml", {"mesh.h": h, "output.field_steps": [11]})
        return solved(case)

    _, reference = run(0.2)
    values = []
    for h in (0.6, 0.4):
        problem, result = run(h)
        indicators = estimate(Level.of(result, 11, problem))
        assert all(np.all(np.isfinite(v)) and np.all(v >= 0) for v in indicators.terms.values())
        for term in ("jump", "neumann", "contact_tangential", "contact_normal"):
            assert indicators.terms[term].sum() > 0, term
        values.append(indicators.total / energy_error(result, reference, 11))
    assert all(4.5 < value < 6.5 for value in values), values


def test_the_energy_norm_of_a_linear_field_is_exact():
    """u = (a x + b y, c x): ε constant, ∫ ℰε:ε = |Ω| (λ (tr ε)² + 2μ ε:ε)."""
    _, result = solve(with_fields(rectangle_case(), [11]))
    mesh = result.discretization.mesh.mesh
    a, b, c = 0.01, 0.02, -0.005
    u = np.column_stack([a * mesh.p[0] + b * mesh.p[1], c * mesh.p[0]])
    lam, mu = result.discretization.elasticity.lame
    strain = np.array([[a, (b + c) / 2], [(b + c) / 2, 0.0]])
    expected = 0.5 * (lam * np.trace(strain) ** 2 + 2 * mu * (strain**2).sum())
    assert energy_norm(mesh.p, mesh.t, u, (lam, mu)) ** 2 == pytest.approx(expected, rel=1e-12)


# --- outputs --------------------------------------------------------------------------------------------
def test_the_run_records_the_estimate_of_every_step_when_asked():
    data = half_disc_case(h=0.25, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}, load=40.0)
    data["output"] = {"field_steps": [5, 11], "error_estimate": True}
    problem, result = solve(data)
    assert result.columns == history_columns(2, ("axis",)) + ESTIMATE_COLUMNS
    eta = result.series("error_estimate")
    assert eta.size == result.steps and np.all(eta > 0)
    shares = np.array([result.series(f"error_estimate_{term}") for term in TERMS])
    np.testing.assert_allclose(np.sqrt((shares**2).sum(axis=0)), eta, rtol=1e-12)
    for step in (5, 11):
        indicators = estimate(Level.of(result, step, problem))
        assert eta[step - 1] == pytest.approx(indicators.total, rel=1e-12)
        np.testing.assert_allclose(result.fields[step].error_indicator, np.sqrt(indicators.squared), rtol=1e-12)
    data["output"]["error_estimate"] = False
    _, plain = solve(data)
    assert plain.columns == history_columns(2, ("axis",))
    assert plain.fields[11].error_indicator is None


def test_the_cli_writes_the_estimate_columns_and_cell_data(tmp_path):
    out = tmp_path / "run"
    status, _, stderr = run_cli("run", "examples/paper_ball.toml", "--set", "mesh.h=0.25", "--set",
                                "output.error_estimate=true", "--out", str(out), "--quiet")
    assert status == 0, stderr
    with open(out / "history.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert list(rows[0]) == list(history_columns(2, ("axis",)) + ESTIMATE_COLUMNS)
    body = meshio.read(out / "fields" / "body_00011.vtu")
    indicator = body.cell_data["error_indicator"][0]
    assert np.sqrt((indicator**2).sum()) == pytest.approx(float(rows[-1]["error_estimate"]), rel=1e-12)
    status, _, stderr = run_cli("run", "examples/paper_ball.toml", "--set", "mesh.h=0.25", "--out",
                                str(tmp_path / "plain"), "--quiet")
    assert status == 0, stderr
    with open(tmp_path / "plain" / "history.csv") as handle:
        assert next(csv.reader(handle)) == list(history_columns(2, ("axis",)))
    assert "error_indicator" not in meshio.read(tmp_path / "plain" / "fields" / "body_00011.vtu").cell_data


def test_a_value_that_is_not_a_boolean_is_refused(tmp_path):
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", "examples/paper_ball.toml", "--set", "output.error_estimate=maybe", "--out",
                                str(tmp_path / "run"))
    assert_refused(status, stderr, "output.error_estimate", untouched=[(tmp_path, before)])


def test_the_memory_guard_counts_the_estimate():
    """Its 9 columns in every row (and their copy) and η_K in every kept field (and its copy)."""
    steps, fields, nodes, elements, m = 1000, 10, 500, 900, 40
    off = memory_needed(steps, fields, nodes, elements, m, False)
    on = memory_needed(steps, fields, nodes, elements, m, False, estimate=True)
    assert on["history rows"] - off["history rows"] == steps * (1020 + 8 * len(ESTIMATE_COLUMNS))
    assert on["fields"] - off["fields"] == (fields + 1) * (112 + 2 * 8 * elements)
    assert on["contact rows"] == off["contact rows"]


def test_the_effectivity_benchmark_reports_its_table_and_figures(tmp_path):
    """benchmarks/effectivity.py --quick on the punch (h = 1/4 … 1/16 against 1/32): JSON rows, the band
    (measured 3.7–5.3) and the figure."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "effectivity.py"
    done = subprocess.run([sys.executable, str(script), "--quick", "--cases", "punch", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert [(row["n"], row["t"]) for row in report["rows"]] == [(n, t) for n in (4, 8, 16) for t in (0.5, 1.1)]
    for row in report["rows"]:
        assert row["effectivity"] == pytest.approx(row["estimate"] / row["error"])
        assert row["estimate"] == pytest.approx(np.sqrt(sum(v**2 for v in row["terms"].values())))
    assert 3.0 < report["bands"]["punch"]["min"] and report["bands"]["punch"]["max"] < 6.0
    assert (tmp_path / "effectivity_punch.png").stat().st_size > 0
    assert json.loads((tmp_path / "effectivity.json").read_text())["rows"] == report["rows"]


def estimating_half_disc(max_iterations: int = 50) -> dict:
    data = half_disc_case(h=0.25, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}, load=20.0)
    data["solver"]["max_iterations"] = max_iterations
    data["output"] = {"field_steps": "all", "error_estimate": True}
    return data


def test_a_sub_step_gets_the_estimate_of_its_own_time():
    """With Newton limited to 4 iterations step 4 is cut (as in tests/test_robustness.py): its sub-steps have
    rows with their own η, and the step's last row is the estimate of the level at t_4."""
    problem, result = solve(estimating_half_disc(max_iterations=4))
    assert result.status == "complete" and result.step_cuts > 0
    eta = result.series("error_estimate")
    assert eta.size == len(result.rows) > result.steps and np.all(eta > 0)
    ends = result.ends_step()
    np.testing.assert_allclose(eta[ends], [estimate(Level.of(result, n, problem)).total
                                            for n in range(1, result.steps + 1)], rtol=1e-12)
    inner = np.flatnonzero(~ends)
    assert np.all(np.diff(result.series("t")[inner[0]:inner[-1] + 2]) > 0)  # the sub-steps' rows, in time order


def test_a_resumed_run_keeps_the_estimate_columns_and_indicators(tmp_path):
    case = vpcontact.Case.model_validate(estimating_half_disc())
    whole = vpcontact.solve(case)
    resumed = resumed_after(case, 6, tmp_path).run()
    assert resumed.status == "complete" and resumed.columns == whole.columns
    np.testing.assert_allclose(resumed.series("error_estimate"), whole.series("error_estimate"), rtol=1e-10)
    for step in (3, 11):  # saved with the checkpoint, and computed after it
        np.testing.assert_allclose(resumed.fields[step].error_indicator, whole.fields[step].error_indicator, rtol=1e-10)


def test_a_3d_run_records_the_estimate():
    case = vpcontact.load_case("examples/quarter_ball.toml", {"mesh.h": 0.6, "output.field_steps": [11],
                                                             "output.error_estimate": True})
    problem, result = solved(case)
    assert result.columns == history_columns(3, ("sym_x", "sym_y")) + ESTIMATE_COLUMNS
    level = Level.of(result, 11, problem)
    assert result.series("error_estimate")[-1] == pytest.approx(estimate(level).total, rel=1e-12)
    assert result.fields[11].error_indicator.shape == (result.elements,)
