"""How long a run will take, before it runs: the estimate of ``vpcontact check``.

A run's wall time is its build (mesh, assembly, checks), the step method's setup (the condensed method's
factorization in Schur mode and its dense condensation; the full method's normal frame and symbolic
analysis; the iterative method's multigrid hierarchy, built at its first Newton iteration and so counted
in its time loop) and its time loop. The build is measured (``vpcontact check`` does it, as the first
build of its process, like a fresh ``vpcontact run``), and it is the rate of this machine now: the setup
and the time loop are estimated as multiples of it, power laws in the free dofs n fitted per method and
dimension:

    setup = build · a (n / 10⁵)^p,        time loop = build · steps · b (n / 10⁵)^q  (· HISTORY_FACTOR)

A machine twice as fast, or other work on it that halves the speed of this process, changes the build
and the rest alike (the build is vectorized NumPy, the rest mostly sparse and dense factorizations and
solves): fitted so, the runs of the fit, made under load averages of 2 to 14 on 2 cores, are within a
factor of 1.7 of their laws, where absolute rates (seconds for n dofs) missed some by factors up to 4.
The constants were fitted to runs of the examples (``python benchmarks/check_estimate.py`` and its
``--fit``), whose Newton iterations per step (about 2.6) are in b: a case whose steps take more iterations
takes longer in proportion, and a mesh file's build (read from disk) is not a built-in shape's. Against
runs not in the fit (``--validation``) the estimate was 0.86 to 2.1 times the time measured, under
load (docs/performance.md, "The time estimate of vpcontact check").
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Rate:
    """The fitted laws of one method in one dimension, in units of the build's time: the setup a (n / 10⁵)^p,
    each time step b (n / 10⁵)^q."""

    a: float
    p: float
    b: float
    q: float


#: (method, dimension) -> its Rate, fitted by ``benchmarks/check_estimate.py --fit`` (see the module docstring).
RATES = {
    ("condensed", 2): Rate(a=1.57, p=-0.17, b=0.0432, q=-0.21),  # 4 runs, 5.9k-372k free dofs
    ("condensed", 3): Rate(a=8.25, p=0.29, b=0.0696, q=0.07),  # 3 runs, 7.2k-69k free dofs
    ("full", 2): Rate(a=1.16, p=0.01, b=1.31, q=0.26),  # 5 runs, 5.9k-93k free dofs
    ("full", 3): Rate(a=0.227, p=-0.23, b=1.84, q=0.27),  # 4 runs, 7.2k-23k free dofs
    ("iterative", 2): Rate(a=0.184, p=-0.16, b=1.67, q=0.12),  # 2 runs, 23k-93k free dofs
    ("iterative", 3): Rate(a=0.429, p=0.62, b=0.714, q=-0.05),  # 3 runs, 7.2k-69k free dofs
}
#: How much longer a step of the condensed method takes with a viscoplastic history z (a solve with the factor
#: and the update of z at every step, where an elastic run solves only at its field steps): the ratio of the
#: paper's viscoplastic ball to its elastic ball per step (each over its build), on two meshes: 2.7 and 4.6.
HISTORY_FACTOR = 3.5


def estimate_seconds(method: str, dim: int, free_dofs: int, steps: int, history: bool,
                     build: float) -> dict[str, float]:
    """Seconds of a run by ``method`` in ``dim`` dimensions with ``free_dofs`` free dofs and ``steps`` time steps
    (``history``: with a viscoplastic history z), whose build took ``build`` seconds: "build", "solver setup",
    "time loop" and "total"."""
    rate = RATES[method, dim]
    size = free_dofs / 1e5
    setup = build * rate.a * size**rate.p
    loop = build * steps * rate.b * size**rate.q * (HISTORY_FACTOR if history and method == "condensed" else 1.0)
    return {"build": build, "solver setup": setup, "time loop": loop, "total": build + setup + loop}
