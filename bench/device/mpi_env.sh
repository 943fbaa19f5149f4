# Sourced on the GPU machine after pack_mpi.sh's bundle is unpacked into
# $T/mpi: points Open MPI and PMIx at their relocated files (Debian builds
# them for /usr and /etc) and puts mpirun on the PATH.
#   T=/tmp; tar -C $T -xJf .gpu/mpi.tar.xz; source bench/device/mpi_env.sh
arch=x86_64-linux-gnu
export OPAL_PREFIX=$T/mpi/usr
export OPAL_LIBDIR=$T/mpi/usr/lib/$arch/openmpi/lib
export OPAL_PKGDATADIR=$T/mpi/usr/share/openmpi
export OPAL_SYSCONFDIR=$T/mpi/etc/openmpi
export PMIX_PREFIX=$T/mpi/usr/lib/$arch/pmix2
export PMIX_LIBDIR=$T/mpi/usr/lib/$arch/pmix2/lib
export PMIX_PKGLIBDIR=$T/mpi/usr/lib/$arch/pmix2/lib/pmix
export PMIX_PKGDATADIR=$T/mpi/usr/lib/$arch/pmix2/share/pmix
export LD_LIBRARY_PATH=$T/mpi/lib:$T/mpi/usr/lib/$arch/openmpi/lib:$T/mpi/usr/lib/$arch/pmix2/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export PATH=$T/mpi/usr/bin:$PATH
export MPIRUN=orterun  # (Debian names it mpirun through alternatives, not packed)
