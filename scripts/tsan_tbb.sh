#!/usr/bin/env bash
# Builds Debian's oneTBB (the source of the libtbb-dev this machine has) with
# ThreadSanitizer instrumentation, for the TSan stage of scripts/test.sh: an
# uninstrumented libtbb makes TSan report races inside TBB's own start-up that
# it cannot see the synchronisation of.
#   bash scripts/tsan_tbb.sh PREFIX      -> PREFIX/lib/cmake/TBB (reused when present)
# The source comes through apt with a private configuration (a deb-src list
# and state of its own; the system's apt setup is not touched).
set -euo pipefail
prefix=${1:?usage: tsan_tbb.sh PREFIX}
version=$(dpkg-query -W -f='${Version}' libtbb-dev)
if [[ -f "$prefix/.built-$version" ]]; then
  echo "oneTBB $version with TSan: $prefix (built earlier)"
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
apt_dir=$work/apt
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
codename=$(. /etc/os-release && echo "$VERSION_CODENAME")
source "$(dirname "${BASH_SOURCE[0]}")/debian_mirrors.sh"
debian_source_list "$codename" > "$apt_dir/sources.list"
o=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o Dir::Etc::SourceParts=/dev/null
   -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache")
# (apt warns that it downloads as root, unsandboxed, into a private folder.)
apt-get "${o[@]}" update -qq 2>&1 | grep -v "unsandboxed" || true
(cd "$work" && apt-get "${o[@]}" source --download-only -qq "onetbb=$version" 2>&1 | grep -v "unsandboxed" || true)
orig=$(ls "$work"/onetbb_*.orig.tar.* | head -1)
# The orig tarball must be the one the source index names (apt fetched it
# against that index's checksums; checked again here, in case a partial
# download was left behind).
dsc=$(ls "$work"/onetbb_*.dsc | head -1)
want=$(awk '/^Checksums-Sha256:/ {on=1; next} on && /^ / {print $1, $3} /^[^ ]/ && !/^Checksums-Sha256:/ {on=0}' "$dsc" |
  awk -v f="$(basename "$orig")" '$2 == f {print $1}')
have=$(sha256sum "$orig" | cut -d' ' -f1)
if [[ -z "$want" || "$want" != "$have" ]]; then
  echo "tsan_tbb.sh: $(basename "$orig") does not match the source index ($want vs $have)" >&2
  exit 1
fi
(cd "$work" && dpkg-source --no-check -x "$dsc" src >/dev/null)
# Its compiler warnings (TSan does not model atomic_thread_fence) go to a log,
# shown only if the build fails.
log=$work/build.log
if ! { cmake -S "$work/src" -B "$work/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_INSTALL_PREFIX="$prefix" \
         -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBB_STRICT=OFF -DTBB_SANITIZE=thread -DTBBMALLOC_BUILD=OFF \
         -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON &&
       cmake --build "$work/build" -j "${JOBS:-$(nproc)}" &&
       cmake --install "$work/build"; } >"$log" 2>&1; then
  tail -50 "$log" >&2
  echo "tsan_tbb.sh: building oneTBB $version failed" >&2
  exit 1
fi
touch "$prefix/.built-$version"
echo "oneTBB $version with TSan: $prefix"
