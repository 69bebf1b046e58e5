"""Parameter studies: many runs of one base case, on a local process pool or a Dask cluster.

A study file (TOML) names a base case and its runs:

    base = "../paper_ball.toml"            # relative to the study file
    [set]                                  # overrides applied to every run
    "output.field_steps" = "none"
    [[vary]]                               # one axis of the grid; keys in one axis vary together
    "mesh.h" = [0.1, 0.05, 0.025]
    "time.steps" = [11, 22, 44]
    [[vary]]                               # the grid is the Cartesian product of the axes
    "contact.stiffness.beta" = [1.0, -1.0]
    [[runs]]                               # runs listed one by one, added to the grid
    id = "signorini"
    "contact.stiffness" = {law = "constant", value = 0.0}
    [compare]                              # difference norms against a run of the study
    reference = "signorini"
    times = [1.1]

Each run writes the standard outputs to DIR/runs/<id>/ (an explicit id is a single path component:
letters, digits and ``= . , + - _``, not starting with "."; ids are unique, letter case aside; the
ids made from the varied values get a suffix -2, -3, ... where they would collide); DIR/study.csv has
a row per run. A run whose directory holds a complete result of the same resolved case is not run
again; a run that fails is retried once; a stopped study (``stop``, SIGINT/SIGTERM on the command
line) writes study.csv with its unfinished runs "interrupted", and a rerun does them. Runs execute
through a ``concurrent.futures`` executor: a local process pool, or the executor of a
``distributed.Client`` (a shared file system is assumed). The numbers do not depend on the executor.

:mod:`.file` reads a study file into its runs (the grid, the ids), :mod:`.running` runs them (locally or on
Dask), :mod:`.members` launches a run on several MPI ranks (``--ranks``), :mod:`.table` writes study.csv with the
difference norms.
"""

from .file import RunSpec, Study, load_study
from .running import run_study
from ...results.norms import COMPARED, norm_column
from .table import write_study_table

__all__ = ["COMPARED", "RunSpec", "Study", "load_study", "norm_column", "run_study", "write_study_table"]
