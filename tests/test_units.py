"""docs/units.md, "The time scale of K(ξ)", by computation: the page's case and commands run through the
command line, their history.csv and contact.csv read by pandas. ξ integrates the penetration over time (ξ_n =
ξ_{n−1} + k d_n⁺ at every node), K follows K(ξ) = c_v (1 + αξ) at every node and level, the final K is the
root of the uniaxial recurrence c_v (1 + αξ_n)(ξ_n − ξ_{n−1}) = k q(t_n); the same load path over ten times
the duration multiplies ξ by 10 when K is constant, ends with the page's larger K when it hardens, and
(T, α) → (10 T, α / 10) changes nothing but ξ. The numbers the page prints are those of the runs."""

import re
import shlex
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import run_cli

PAGE = Path(__file__).resolve().parents[1] / "docs" / "units.md"
SECTION = PAGE.read_text().split("## The time scale of K(ξ)")[1]
PROSE = " ".join(SECTION.split())  # the section's words, whatever the line breaks
C_V, ALPHA, Q_MAX, STEPS = 1e10, 2000.0, 1e7, 30


def written(x: float) -> str:
    """A number as the page writes it: 4 decimals, the exponent without + and leading zeros (3.7540e-4)."""
    mantissa, exponent = f"{x:.4e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def run(folder: Path, command: list[str], *changes: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The page's ``vpcontact run`` command (its words after ``vpcontact``) with more ``--set changes``, in
    ``folder``: (history.csv, contact.csv)."""
    extra = [word for change in changes for word in ("--set", change)]
    status, _, stderr = run_cli(*command[1:], "--quiet", *extra, cwd=folder)
    assert status == 0, stderr
    out = folder / command[command.index("--out") + 1]
    return pd.read_csv(out / "history.csv"), pd.read_csv(out / "contact.csv")


@pytest.fixture(scope="module")
def page_runs(tmp_path_factory):
    """The page's case saved as block.toml and its two commands (T = 3 s and T = 30 s), and the run over 30 s
    with α / 10 and both runs with K constant (α = 0): {name: (history, contact)}."""
    folder = tmp_path_factory.mktemp("units")
    (folder / "block.toml").write_text(re.search(r"```toml\n(.*?)```", SECTION, re.S).group(1))
    commands = [shlex.split(line) for line in re.search(r"```bash\n(.*?)```", SECTION, re.S).group(1).splitlines()]
    assert [c[:2] for c in commands] == [["vpcontact", "run"]] * 2
    runs = {"T3": run(folder, commands[0]), "T30": run(folder, commands[1]),
            "T30 alpha/10": run(folder, elsewhere(commands[1], "_alpha"), "contact.stiffness.alpha=200"),
            "T3 constant": run(folder, elsewhere(commands[0], "_constant"), "contact.stiffness.alpha=0"),
            "T30 constant": run(folder, elsewhere(commands[1], "_constant"), "contact.stiffness.alpha=0")}
    return runs


def elsewhere(command: list[str], suffix: str) -> list[str]:
    """``command`` with ``suffix`` added to its --out directory."""
    command = list(command)
    command[command.index("--out") + 1] += suffix
    return command


def recurrence(T: float, alpha: float = ALPHA) -> float:
    """ξ at t = T of a node pressed by q(t) = Q_MAX t/T, by the implicit rectangle rule: ξ_n the positive root
    of c_v (1 + αξ)(ξ − ξ_{n−1}) = k q(t_n)."""
    k, xi = T / STEPS, 0.0
    for n in range(1, STEPS + 1):
        b, c = 1.0 - alpha * xi, -xi - k * Q_MAX * n / STEPS / C_V
        xi = (-b + np.sqrt(b * b - 4.0 * alpha * c)) / (2.0 * alpha)
    return xi


@pytest.mark.parametrize("name, T", [("T3", 3.0), ("T30", 30.0)])
def test_xi_integrates_over_time_and_K_follows_it(page_runs, name, T):
    history, contact = page_runs[name]
    assert history.t.iloc[-1] == pytest.approx(T, rel=1e-14)
    assert history.contact_force_z.iloc[-1] == pytest.approx(Q_MAX * 0.02 * 0.02, rel=1e-9)  # 4000 N
    # ξ at every node and level: the sum of k times the penetrations of the levels before and this one
    np.testing.assert_allclose(history.k, T / STEPS, rtol=1e-14)  # no step cut
    ordered = contact.sort_values(["node", "step"])
    summed = (T / STEPS * ordered.penetration.clip(lower=0.0)).groupby(ordered.node).cumsum()
    np.testing.assert_allclose(ordered.xi, summed, rtol=1e-12)
    np.testing.assert_allclose(contact.K, C_V * (1.0 + ALPHA * contact.xi), rtol=1e-12)
    # every node alike (uniform state): the recurrence's ξ and K at the end
    last = contact[contact.step == STEPS]
    np.testing.assert_allclose(last.xi, recurrence(T), rtol=1e-9)
    np.testing.assert_allclose(history.K_probe.iloc[-1], C_V * (1.0 + ALPHA * recurrence(T)), rtol=1e-9)
    # the page's table prints these numbers on the run's row
    row = next(line for line in SECTION.splitlines() if line.startswith(f"| T = {T:g} s |"))
    for value in (history.penetration_probe.iloc[-1], last.xi.mean(), history.K_probe.iloc[-1]):
        assert written(value) in row, (written(value), row)


def test_the_same_load_path_ten_times_slower(page_runs):
    """At every level of the same load path: with K constant, the penetrations are the same and ξ is 10 times
    larger; with the hardening K, ξ and K are larger, and the page's numbers are the runs' (ratio, continuous
    limit)."""
    (_, fast), (_, slow) = page_runs["T3 constant"], page_runs["T30 constant"]
    np.testing.assert_array_equal(fast.step, slow.step)
    np.testing.assert_allclose(slow.penetration, fast.penetration, rtol=1e-12)
    np.testing.assert_allclose(slow.xi, 10.0 * fast.xi, rtol=1e-12)
    assert np.all(slow.K == C_V) and np.all(fast.K == C_V)
    (fast_history, fast), (slow_history, slow) = page_runs["T3"], page_runs["T30"]
    assert np.all(slow.xi.to_numpy() > fast.xi.to_numpy()) and np.all(slow.K.to_numpy() > fast.K.to_numpy())
    np.testing.assert_allclose(slow_history.contact_force_z, fast_history.contact_force_z, rtol=1e-9)
    ratio = slow_history.K_probe.iloc[-1] / fast_history.K_probe.iloc[-1]
    assert f"K ends {ratio:.2f} times larger" in PROSE
    for T in (3.0, 30.0):  # K(T)² = c_v² (1 + α q_max T / c_v), the continuous-time limit of the recurrence
        assert written(C_V * np.sqrt(1.0 + ALPHA * Q_MAX * T / C_V)) in SECTION


def test_only_alpha_times_the_time_scale_counts(page_runs):
    """T × 10 with α / 10: the same K and penetrations at every node and level (to rounding), ξ × 10."""
    (_, fast), (history, slow) = page_runs["T3"], page_runs["T30 alpha/10"]
    np.testing.assert_allclose(slow.K, fast.K, rtol=1e-12)
    np.testing.assert_allclose(slow.penetration, fast.penetration, rtol=1e-12)
    np.testing.assert_allclose(slow.xi, 10.0 * fast.xi, rtol=1e-12)
    assert f"with `alpha = 200` ends with K = {written(history.K_probe.iloc[-1])} Pa/m" in PROSE
