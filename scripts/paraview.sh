#!/usr/bin/env bash
# ParaView 5.11 from Debian 12's own packages (paraview, paraview-dev,
# python3-paraview), unpacked outside the system for the reader plugin's
# build and test:
#   bash scripts/paraview.sh PREFIX
#   -> PREFIX/usr/bin/pvpython and PREFIX/usr/lib/<arch>/cmake/paraview-5.11
# Reused while the packages' version stays the same.
#
# Why unpacked, not installed: python3-paraview (pvpython, and the Python
# files paraview-dev's CMake configuration checks for) conflicts with
# python3-vtk9, which libvtk9-dev (the VTK sluice's importer builds
# against) depends on; installing it removes libvtk9-dev. The libraries
# ParaView itself needs come from `apt-get install paraview` (scripts/
# deps.sh), which conflicts with nothing. Run pvpython from here with
#   LD_LIBRARY_PATH=PREFIX/usr/lib/<arch>
# so that it finds its Python modules under PREFIX rather than the
# system's VTK ones. The packages come through the system's apt
# configuration (`apt-get download`); no mirror is named here.
set -euo pipefail
prefix=${1:?usage: paraview.sh PREFIX}
[[ "$prefix" != / ]] || { echo "paraview.sh: not into /" >&2; exit 1; }
packages=(paraview paraview-dev python3-paraview)
version=$(apt-cache policy paraview-dev | awk '/Candidate:/ {print $2}')
if [[ -z "$version" || "$version" == "(none)" ]]; then
  echo "paraview.sh: apt knows no paraview-dev package (run apt-get update)" >&2
  exit 1
fi
if [[ -f "$prefix/version" && "$(cat "$prefix/version")" == "$version" && -x "$prefix/usr/bin/pvpython" ]]; then
  exit 0
fi
echo "paraview.sh: unpacking ${packages[*]} $version into $prefix"
rm -rf "$prefix" && mkdir -p "$prefix/debs"
# As root, apt's download sandbox user cannot write here: download as root.
(cd "$prefix/debs" && apt-get download -q -o APT::Sandbox::User=root "${packages[@]}" >/dev/null)
for deb in "$prefix"/debs/*.deb; do dpkg-deb -x "$deb" "$prefix"; done
rm -rf "$prefix/debs"
echo "$version" > "$prefix/version"
