"""PETSc in this process, through petsc4py, initialized once (for the iterative method's GAMG, on one rank or
several)."""

import os
import sys


def petsc():
    """petsc4py's PETSc module, initialized the first time (a module the caller imported before is taken as it is):

    - without the process's command line and without PETSc's signal handlers: the run's own (a SIGTERM stops it
      after the step, :mod:`vpcontact.drivers.signals`) stay in place;
    - its library bound to the BLAS and LAPACK it was built with, whatever the process loaded before
      (``RTLD_DEEPBIND``; without it, as on macOS, a library is bound to its own dependencies anyway). MKL, which
      PARDISO loads, gives its BLAS to the whole process under the common names: PETSc's vector operations called
      MKL's in a session that had used PARDISO first and the reference BLAS in one that had not, and the same run
      differed in the last bits with what its process had done before (a run resumed in such a session was not
      the uninterrupted one);
    - as an MPI process of its own (Open MPI's isolated singleton; the backend needs no other process): Open MPI 4
      otherwise starts a daemon at initialization, in a session of its own, that holds the run's standard output
      and error, so that a signal to the run's process group does not reach it and whoever reads the run's
      output to its end waits for the daemon too."""
    if "petsc4py.PETSc" not in sys.modules:
        import petsc4py

        os.environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")
        flags = sys.getdlopenflags()
        sys.setdlopenflags(flags | getattr(os, "RTLD_DEEPBIND", 0))
        try:
            petsc4py.init(["vpcontact", "-no_signal_handler"])
        finally:
            sys.setdlopenflags(flags)
    from petsc4py import PETSc

    return PETSc
