#!/usr/bin/env bash
# Packs Debian's Open MPI for the GPU machine (it has none): mpirun (orterun)
# and orted, Open MPI's and PMIx's plugins, their help texts and settings,
# and every library they link but glibc's. Relocated there by mpi_env.sh.
# Output: .gpu/mpi.tar.xz (ignored by git), carried by the device tool.
#   bash bench/device/pack_mpi.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
arch=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)
stage=$(mktemp -d)
m=$stage/mpi
mkdir -p "$m/lib" "$root/.gpu"
for p in /usr/bin/orterun /usr/bin/orted "/usr/lib/$arch/openmpi" "/usr/lib/$arch/pmix2" /usr/share/openmpi /etc/openmpi; do
  mkdir -p "$m$(dirname "$p")"
  cp -a "$p" "$m$p"
done
{ echo /usr/bin/orterun; echo /usr/bin/orted; find "/usr/lib/$arch/openmpi" "/usr/lib/$arch/pmix2" -name '*.so*'; } |
  xargs ldd 2>/dev/null | awk '{print $3}' | grep '^/' | sort -u |
  grep -v -E '/(libc|libm|libpthread|libdl|librt|libgcc_s|libstdc\+\+)\.so|ld-linux' | xargs -I{} cp -L {} "$m/lib/"
tar -C "$stage" -cf - mpi | xz -6 -T2 > "$root/.gpu/mpi.tar.xz"
rm -rf "$stage"
du -sh "$root/.gpu/mpi.tar.xz"
