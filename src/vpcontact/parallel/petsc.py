"""PETSc in this process, through petsc4py, initialized once (for the iterative method's GAMG, on one rank or
several)."""

import os
import sys

from .ranks import RANK_VARIABLES, SIZE_VARIABLES


def petsc():
    """petsc4py's PETSc module, initialized the first time (a module the caller imported before is taken as it is):

    - without the process's command line and without PETSc's signal handlers: the run's own (a SIGTERM stops it
      after the step, :mod:`vpcontact.drivers.signals`) stay in place;
    - its library bound to the BLAS and LAPACK it was built with, whatever the process loaded before
      (``RTLD_DEEPBIND``, where it is safe: :func:`deep_binding_is_safe`; without it, as on macOS, a library is
      bound to its own dependencies anyway). Where it is not, PETSc's symbols are bound when it is loaded
      (``RTLD_NOW``) to the BLAS loaded by then: its own, unless MKL (PARDISO) was loaded before. MKL, which
      PARDISO loads, gives its BLAS to the whole process under the common names: PETSc's vector operations called
      MKL's in a session that had used PARDISO first and the reference BLAS in one that had not, and the same run
      differed in the last bits with what its process had done before (a run resumed in such a session was not
      the uninterrupted one);
    - as an MPI process of its own (Open MPI's isolated singleton; the backend needs no other process): Open MPI 4
      otherwise starts a daemon at initialization, in a session of its own, that holds the run's standard output
      and error, so that a signal to the run's process group does not reach it and whoever reads the run's
      output to its end waits for the daemon too. Its PMIx component is named too (``isolated``): left to
      choose, Open MPI 4.1.4 (Debian 12's) sets it in the environment itself in a way that frees the
      environment's memory twice, which aborted the process in a small environment (a CI container's:
      ``free(): double free detected`` in ``opal_setenv``, during ``PetscInitialize``, where the Python was also
      one of :func:`deep_binding_is_safe`'s unsafe ones). A process an MPI launcher started (``mpiexec``) is not a
      singleton, and its MPI is left as the launcher set it."""
    if "petsc4py.PETSc" not in sys.modules:
        import petsc4py

        alone = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pmix": "isolated"}
        launched = any(name in os.environ for name in (*SIZE_VARIABLES, *RANK_VARIABLES))
        set_here = [] if launched else [name for name in alone if name not in os.environ]
        os.environ.update({name: alone[name] for name in set_here})
        flags = sys.getdlopenflags()
        deep = getattr(os, "RTLD_DEEPBIND", 0) if deep_binding_is_safe() else 0
        sys.setdlopenflags(flags | os.RTLD_NOW | deep)
        try:
            petsc4py.init(["vpcontact", "-no_signal_handler"])
        finally:
            sys.setdlopenflags(flags)
            for name in set_here:  # read at initialization only; an mpiexec started later must not inherit them
                os.environ.pop(name, None)
    from petsc4py import PETSc

    return PETSc


def deep_binding_is_safe() -> bool:
    """Whether a library loaded with ``RTLD_DEEPBIND`` sees the process's environment: where the interpreter runs
    from a shared libpython (python.org's, pyenv's, conda's builds). A python executable with libpython linked in
    (Debian's ``/usr/bin/python3``) holds its own copy of libc's ``environ``, and a library bound deeply binds to
    libc's original, which nothing updates: Open MPI, loaded so, freed the environment's memory twice at
    initialization (``free(): double free detected``) and crashed at exit. There, PETSc is loaded as any library
    is, and takes the BLAS the process loaded first (MKL's, once PARDISO has run): a resumed run may then differ
    from the uninterrupted one in the last bits."""
    try:
        with open("/proc/self/maps") as maps:
            return any("libpython" in line for line in maps)
    except OSError:
        return False

