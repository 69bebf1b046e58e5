"""The plan of a reproduction: its sizes (the full one, or the coarse ``--quick`` one), the level rule
that ties a level's h and k (Fig. 10), and the runs solved in this process (Figs. 2–7, the load)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .paper import CALIBRATED_LOAD, CONTACT_CONDITIONS, FIGURE_TIMES, PRINTED_LOAD, T, load_overrides


def level_overrides(level: int) -> dict:
    """The level rule: h = 1/level, element edge √2·h (the paper's sizes), steps = round(T/h), k = T/steps
    (h = k = 1/level up to that rounding)."""
    h = 1.0 / level
    return {"mesh.h": math.sqrt(2.0) * h, "time.steps": round(T / h)}


@dataclass(frozen=True)
class Plan:
    """The sizes of a reproduction: the full one, or the coarse `--quick` one."""

    quick: bool
    figure_h: float
    """Element size of the mesh of Figs. 2–9 (the example's 0.0125; quick: 0.05)."""
    steps_coarse: int = 11
    """k = 0.1: the paper's data (N = 11)."""
    steps_fine: int = level_overrides(128)["time.steps"]
    """k ≈ 1/128: the level rule's 141 steps of level 128 (1.1·128 = 140.8 is not an integer)."""
    rho: tuple = (1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
    fig9_rho: tuple = (1.0, 1e-1, 1e-2, 1e-3)
    levels: tuple = (4, 8, 16, 32, 64, 128, 256)
    """h = k = 1/level: the levels compared with the reference."""
    reference_level: int = 512
    h_levels: tuple = (4, 8, 16, 32, 64)
    """The rate in h alone: h = 1/level, every level and the reference with ``h_steps`` steps."""
    h_reference_level: int = 256
    h_steps: int = 35
    k_steps: tuple = (4, 9, 18, 35, 70, 141)
    """The rate in k alone: k = 1.1/steps, every run and the reference on the mesh of ``k_level``."""
    k_reference_steps: int = 563
    k_level: int = 32
    adapt_level: int = 8
    """Adaptive meshes from h = 1/adapt_level, on the rate in h's time grid and against its reference."""
    adapt_cycles: int = 12
    adapt_max_dofs: int = 20_000

    @property
    def mode(self) -> str:
        return "quick" if self.quick else "full"


def make_plan(quick: bool) -> Plan:
    if quick:
        return Plan(True, figure_h=0.05, rho=(1.0, 1e-1, 1e-2, 1e-3, 1e-4), levels=(4, 8, 16, 32), reference_level=64,
                    h_levels=(4, 8, 16), h_reference_level=64, h_steps=9, k_steps=(4, 9, 18, 35),
                    k_reference_steps=141, k_level=16, adapt_level=4, adapt_cycles=6, adapt_max_dofs=1_500)
    return Plan(False, figure_h=0.0125)


def level_step(level: int) -> float:
    """k of a level (see ``level_overrides``)."""
    return T / level_overrides(level)["time.steps"]


def figure_step(t: float, steps: int) -> int:
    """The step n with t_n = t on a grid of ``steps`` steps up to T."""
    return round(t / (T / steps))


@dataclass(frozen=True)
class CaseSpec:
    """One run solved in this process: its name (a directory under DIR/cases), label and overrides."""

    name: str
    label: str
    overrides: dict
    group: str


def figure_cases(plan: Plan) -> list[CaseSpec]:
    """Figs. 2–7: the four contact conditions, with k = 0.1 (fields at t = 0.2, 0.5, 0.8, 1.1) and k ≈ 1/128."""
    specs = []
    for steps, suffix in ((plan.steps_coarse, "k0.1"), (plan.steps_fine, "k1_128")):
        fields = [figure_step(t, steps) for t in FIGURE_TIMES] if steps == plan.steps_coarse else "final"
        for name, (label, overrides) in CONTACT_CONDITIONS.items():
            specs.append(
                CaseSpec(
                    f"{name}_{suffix}",
                    label,
                    {"mesh.h": plan.figure_h, "time.steps": steps, "output.field_steps": fields, **overrides},
                    suffix,
                )
            )
    return specs


def load_cases(plan: Plan) -> list[CaseSpec]:
    """The printed load 1000 t N/m, k = 0.1: β = ±1 (against Figs. 2–4) and ρ = 0.01 (against Fig. 9)."""
    common = {
        "mesh.h": plan.figure_h,
        "time.steps": plan.steps_coarse,
        "output.field_steps": "final",
        **load_overrides(PRINTED_LOAD),
    }
    return [
        CaseSpec("printed_beta+1", "printed load, β = 1", {**common, "contact.stiffness.beta": 1.0}, "printed"),
        CaseSpec("printed_beta-1", "printed load, β = −1", {**common, "contact.stiffness.beta": -1.0}, "printed"),
        CaseSpec("printed_rho0.01", "printed load, β = 1, ρ = 0.01", {**common, "contact.rho": 0.01}, "printed"),
    ]


def settings(plan: Plan) -> dict:
    """The plan as reproduce.json and the report state it."""
    return {
        "mode": plan.mode,
        "figure_mesh_h": plan.figure_h,
        "steps_coarse": plan.steps_coarse,
        "k_coarse": T / plan.steps_coarse,
        "steps_fine": plan.steps_fine,
        "k_fine": T / plan.steps_fine,
        "rho": list(plan.rho),
        "fig9_rho": list(plan.fig9_rho),
        "hk_levels": list(plan.levels),
        "hk_reference_level": plan.reference_level,
        "h_levels": list(plan.h_levels),
        "h_reference_level": plan.h_reference_level,
        "h_steps": plan.h_steps,
        "k_steps": list(plan.k_steps),
        "k_reference_steps": plan.k_reference_steps,
        "k_level": plan.k_level,
        "adapt_level": plan.adapt_level,
        "adapt_cycles": plan.adapt_cycles,
        "adapt_max_dofs": plan.adapt_max_dofs,
        "printed_load": PRINTED_LOAD,
        "calibrated_load": CALIBRATED_LOAD,
        "figure_times": list(FIGURE_TIMES),
    }
