"""The parameter studies of the reproduction, as the study files it writes to DIR/studies/NAME.toml (each
can be rerun with ``vpcontact study DIR/studies/NAME.toml --out DIR/studies/NAME``): Figs. 8, 9 (ρ → 0),
Fig. 10 (h = k = 1/level, ``plan.level_overrides``) and the rates in h alone and in k alone."""

from __future__ import annotations

import tomli_w

from .paper import T
from .plan import Plan, level_overrides


def rho_study_text(plan: Plan) -> str:
    """Figs. 8, 9: K_ρ = ρK for each ρ against K ≡ 0 (the Signorini problem with gap g), at t = 1.1."""
    lines = [
        "# Figs. 8 and 9 of the paper, written by `vpcontact reproduce`.",
        'base = "../cases/paper_ball.toml"',
        "",
        "[set]",
        f'"mesh.h" = {plan.figure_h!r}',
        f'"time.steps" = {plan.steps_coarse}',
        '"output.field_steps" = "final"',
        "",
    ]
    for rho in plan.rho:
        lines += ["[[runs]]", f'id = "{rho_id(rho)}"', f'"contact.rho" = {rho!r}', ""]
    lines += [
        "[[runs]]",
        'id = "signorini"',
        '"contact.stiffness" = { law = "constant", value = 0.0 }',
        "",
        "[compare]",
        'reference = "signorini"',
        f"times = [{T!r}]",
        "",
    ]
    return "\n".join(lines)


def convergence_study_text(title: str, runs: list[tuple[str, dict]], settings: dict | None = None) -> str:
    """A study of the paper case's runs (id, overrides), each compared at t = 1.1 with the first one,
    the reference; ``settings``: overrides of every run. The reference is listed first: the longest run
    starts at once, and the other workers run the others meanwhile (listed last, it ran alone after them)."""
    common = {"output.field_steps": "final", **(settings or {})}
    lines = [f"# {title}, written by `vpcontact reproduce`.", 'base = "../cases/paper_ball.toml"', "", "[set]",
             *(f'"{key}" = {_toml(value)}' for key, value in common.items()), ""]
    for run_id, overrides in runs:
        lines += ["[[runs]]", f'id = "{run_id}"', *(f'"{key}" = {_toml(value)}' for key, value in overrides.items()),
                  ""]
    lines += ["[compare]", f'reference = "{runs[0][0]}"', f"times = [{T!r}]", ""]
    return "\n".join(lines)


def _toml(value) -> str:
    """A value as TOML writes it."""
    return tomli_w.dumps({"value": value}).partition("=")[2].strip()


def hk_study_text(plan: Plan) -> str:
    """Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 for h = k = 1/level against the reference level."""
    return convergence_study_text("Fig. 10 of the paper", [(level_id(level, plan), level_overrides(level))
                                                           for level in (plan.reference_level, *plan.levels)])


def h_study_text(plan: Plan) -> str:
    """The error in h alone: h = 1/level against 1/h_reference_level, all with the same time steps and
    the residual error estimate (the effectivity of the estimator: the spatial error of one time grid)."""
    levels = (plan.h_reference_level, *plan.h_levels)
    return convergence_study_text(
        f"The rate in h and the estimator's effectivity: every run with {plan.h_steps} time steps",
        [(h_id(level), {"mesh.h": level_overrides(level)["mesh.h"], "time.steps": plan.h_steps}) for level in levels],
        {"output.error_estimate": True})


def k_study_text(plan: Plan) -> str:
    """The error in k alone: k = 1.1/steps against k_reference_steps, all on the mesh of 1/k_level."""
    h = level_overrides(plan.k_level)["mesh.h"]
    return convergence_study_text(
        f"The rate in k: every run on the mesh of h = 1/{plan.k_level}",
        [(k_id(steps), {"mesh.h": h, "time.steps": steps}) for steps in (plan.k_reference_steps, *plan.k_steps)])


def level_id(level: int, plan: Plan) -> str:
    """The run id of a level in the h–k study."""
    return f"reference-1_{level}" if level == plan.reference_level else h_id(level)


def rho_id(rho: float) -> str:
    """The run id of K_ρ = ρK in the ρ study."""
    return f"rho={rho:g}"


def h_id(level: int) -> str:
    """The run id of h = 1/level in the rate in h (and of a level of the h–k study but its reference)."""
    return f"h=1_{level}"


def k_id(steps: int) -> str:
    """The run id of k = T/steps in the rate in k."""
    return f"steps={steps}"

