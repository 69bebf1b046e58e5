"""Solver settings and files that cannot work are refused before any computation (exit 2, one line)."""

import pytest
import tomli_w

from conftest import assert_refused, half_disc_case, run_cli, snapshot_tree


@pytest.mark.parametrize("value", ["1e308", "1e-300", "1e30"])
def test_an_augmentation_far_from_the_stiffness_is_refused(tmp_path, value):
    """r enters A0 = A + r NᵀN: 1e308 overflows it, 1e-300 leaves A0 singular to working precision."""
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(half_disc_case(h=0.25)))
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out", "--set", f"solver.augmentation={value}")
    assert_refused(status, err, f"solver.augmentation = {float(value):g}", "times the normal stiffness", "auto",
                   untouched=[(tmp_path, before)])


def test_an_augmentation_near_the_stiffness_is_used(tmp_path):
    import vpcontact

    case = half_disc_case(h=0.25)
    automatic = vpcontact.solve(case)
    case["solver"]["augmentation"] = 10 * automatic.augmentation
    chosen = vpcontact.solve(case)
    assert chosen.status == "complete" and chosen.augmentation == 10 * automatic.augmentation
    assert abs(chosen.series("penetration_probe")[-1] - automatic.series("penetration_probe")[-1]) < 1e-10


@pytest.mark.parametrize("content", [b"\xff\xfe\x00not text", b'base = "\xff"\n'])
def test_a_study_file_that_is_not_text_is_refused(tmp_path, content):
    path = tmp_path / "study.toml"
    path.write_bytes(content)
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("study", path, "--out", tmp_path / "out")
    assert_refused(status, err, "study file", "cannot be read", untouched=[(tmp_path, before)])
