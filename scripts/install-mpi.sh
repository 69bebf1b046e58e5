#!/bin/sh
# PETSc and MPI for one solve across MPI ranks (`mpiexec -n N vpcontact run`), on Debian or Ubuntu, into the
# active Python environment: the distribution's PETSc (with Open MPI) and petsc4py built against it, then
# `pip install ".[mpi]"` brings mpi4py and pymetis. Needs root (or sudo) for apt-get and a C compiler.
# Elsewhere (conda-forge, an HPC module), install petsc4py and mpi4py matching the PETSc and MPI you have.
set -eu
if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends libpetsc-real-dev python3-dev \
    > /dev/null
# PETSc's real build of the installed version: the directory that holds include/petscconf.h.
variables=$(dpkg -L "$(dpkg-query -W -f '${Depends}' libpetsc-real-dev | sed 's/[ ,(].*//')" \
    | grep '/lib/petsc/conf/petscvariables$' | head -n 1)
PETSC_DIR=${variables%/lib/petsc/conf/petscvariables}
version=$(sed -n 's/^#define PETSC_VERSION_\(MAJOR\|MINOR\|SUBMINOR\) *\([0-9]*\)/\2/p' \
    "$PETSC_DIR/include/petscversion.h" | paste -sd.)
echo "PETSc $version in $PETSC_DIR: building petsc4py $version against it (under a minute)"
# petsc4py's build needs setuptools' bdist_wheel, and fails to link with setuptools 80 and later. Its C is only the
# wrapper (PETSc itself is the distribution's optimized build): unoptimized, it builds in 41 s instead of 89 s (-O1).
pip install -q "setuptools>=69.5,<70" "wheel>=0.43" cython numpy
PETSC_DIR=$PETSC_DIR PETSC_ARCH="" CFLAGS="-O0 -g0" pip install -q --no-build-isolation "petsc4py==$version"
