#!/usr/bin/env bash
# Builds Monado, an OpenXR runtime, headless, for tests that need a real
# OpenXR runtime without a headset, a display or a GPU: the in-process
# runtime only (no monado-service, no IPC), the null compositor (it takes the
# frames and throws them away, pacing at a fixed 20 Hz) and the simulated HMD
# (2 views of 320x240, stereo, opaque blend mode). Vulkan only (no OpenGL,
# GLX, EGL, SDL, X11, Wayland), no other drivers, GUI, tracing, tests or docs.
#   bash scripts/monado.sh PREFIX   -> PREFIX/openxr_monado.json (reused when present)
# The manifest is also installed at PREFIX/share/openxr/1/openxr_monado.json;
# the runtime itself is PREFIX/lib/libopenxr_monado.so (needs only libvulkan).
# The source is Debian 13 (trixie)'s source package monado, MONADO_VERSION
# (default below), fetched through apt with a private configuration (a
# deb-src list and state of its own; the system's apt setup is not touched).
# Only its orig tarball is built (upstream's release, less what Debian strips
# from it), checked against the trixie Sources index.
# JOBS=N sets the build's parallelism (default: nproc); ccache is used when
# present.
#
# Run a test against it with (all of these are read by the runtime itself):
#   XR_RUNTIME_JSON=PREFIX/openxr_monado.json   the OpenXR loader loads Monado
#   SIMULATED_ENABLE=1                          required: picks the simulated-devices
#                                               builder (HMD with orientation and position
#                                               tracking); without it Monado falls back to
#                                               its legacy prober, which also ends at a
#                                               simulated HMD but reports no tracking
#   VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
#   VK_ICD_FILENAMES=(the same)                 lavapipe, for the runtime's Vulkan device and
#                                               the app's (the older variable is for Vulkan
#                                               loaders before 1.3.207); optional where
#                                               lavapipe is the only driver that works
#   XDG_CONFIG_HOME=a scratch folder            optional, for hermetic runs: Monado reads
#                                               (and may create) $XDG_CONFIG_HOME/monado/
#                                               (else $HOME/.config/monado/); a user's config
#                                               there can change which devices it picks.
#                                               Without HOME or XDG_CONFIG_HOME it logs an
#                                               error and carries on.
#   SIMULATED_LEFT=, SIMULATED_RIGHT=simple|wmr|ml2   optional: simulated controllers (none by
#                                               default); the simulated HMD's pose wobbles
#                                               (by up to 10 cm and 7 degrees, over 4-16 s)
# Optional, for quieter logs (levels are trace, debug, info, warn, error; "warning" is
# not one of them and silently means the default):
#   XRT_LOG=warn PROBER_LOG=warn XRT_COMPOSITOR_LOG=warn   (and OXR_NO_PRINTING=1 to drop the
#   per-call "LOG in xr...:" lines, which also drops the text of API errors)
# Not needed: XRT_COMPOSITOR_NULL (this build has only the null compositor, so it is the
# default; XRT_COMPOSITOR_NULL=0 makes xrCreateInstance fail), XRT_NO_STDIN (service only),
# XDG_RUNTIME_DIR (IPC only), P_OVERRIDE_ACTIVE_CONFIG (knows only remote/tracking),
# U_PACING_* (U_PACING_APP_IMMEDIATE_WAIT_FRAME_RETURN=1 makes xrWaitFrame return at once,
# but frames still take the compositor's 50 ms: xrEndFrame then blocks instead).
# Run as root (or with an RLIMIT_RTPRIO), the runtime raises its compositor thread to
# SCHED_FIFO 99; it sleeps between frames.
set -euo pipefail
prefix=${1:?usage: monado.sh PREFIX}
prefix=$(realpath -m "$prefix")
version=${MONADO_VERSION:-25.0.0+dfsg-2}
manifest=$prefix/openxr_monado.json
if [[ -f "$prefix/.built-$version" && -f "$manifest" ]]; then
  echo "Monado $version, headless: $manifest (built earlier)"
  exit 0
fi

# Build dependencies, skipping those present (as scripts/deps.sh does).
packages=(build-essential cmake pkg-config python3 xz-utils libvulkan-dev glslang-tools libeigen3-dev libudev-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "monado.sh: installing ${missing[*]}"
  sudo=()
  [[ $(id -u) -eq 0 ]] || sudo=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

start=$SECONDS
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
apt_dir=$work/apt
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
source "$(dirname "${BASH_SOURCE[0]}")/debian_mirrors.sh"
debian_source_list trixie > "$apt_dir/sources.list"
o=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o Dir::Etc::SourceParts=/dev/null
   -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache")
# (apt warns that it downloads as root, unsandboxed, into a private folder.)
apt-get "${o[@]}" update -qq 2>&1 | grep -v "unsandboxed" || true
# Only the orig tarball is used. apt may fail on the .dsc and the Debian
# tarball (some mirrors do not serve them, 404) while the orig tarball
# arrives, so its exit status is not what counts, and its output is shown
# only when the orig tarball is missing.
(cd "$work" && apt-get "${o[@]}" source --download-only -qq "monado=$version") >"$work/source.log" 2>&1 || true
origs=("$work"/monado_"${version%-*}".orig.tar.*)
orig=${origs[0]}
[[ -f "$orig" ]] || orig=
if [[ -z "$orig" ]]; then
  grep -v "unsandboxed" "$work/source.log" >&2 || true
  echo "monado.sh: apt did not fetch the orig tarball of monado $version from trixie; the index has:" >&2
  apt-cache "${o[@]}" showsrc --only-source monado 2>/dev/null | grep '^Version:' >&2 || true
  echo "monado.sh: (set MONADO_VERSION to one of them)" >&2
  exit 1
fi
# The orig tarball must be the one the trixie Sources index (signed through
# its InRelease) names for this version.
want=$(apt-cache "${o[@]}" showsrc --only-source monado 2>/dev/null |
  awk -v v="$version" -v f="$(basename "$orig")" 'BEGIN {RS = ""; FS = "\n"}
    { ver = ""; sum = ""; on = 0
      for (i = 1; i <= NF; i++) {
        if ($i ~ /^Version:/) { split($i, a, " "); ver = a[2] }
        if ($i ~ /^Checksums-Sha256:/) { on = 1; continue }
        if (on && $i ~ /^ /) { split($i, a, " "); if (a[3] == f) sum = a[1] } else on = 0
      }
      if (ver == v && sum != "" && found == "") found = sum }
    END { print found }')
have=$(sha256sum "$orig" | cut -d' ' -f1)
if [[ -z "$want" || "$want" != "$have" ]]; then
  echo "monado.sh: $(basename "$orig") does not match the trixie source index (sha256 there: ${want:-no entry}; of the file: $have)" >&2
  exit 1
fi
mkdir "$work/src"
tar -xf "$orig" -C "$work/src" --strip-components=1

# v25.0.0's OpenXR target links comp_main even when the main compositor is
# not built (it needs XCB or Wayland); an empty stand-in, defined right after
# the top-level project(XRT) call, satisfies that link.
cat > "$work/stub_comp_main.cmake" <<'CMAKE'
if(NOT TARGET comp_main)
  add_library(comp_main INTERFACE)
endif()
CMAKE
off=()
for d in ANDROID ARDUINO DAYDREAM DEPTHAI EUROC HANDTRACKING HDK HYDRA ILLIXR NS OHMD OPENGLOVES PSMV PSSENSE PSVR \
         QWERTY REALSENSE REMOTE RIFT_S ROKID SIMULAVR STEAMVR_LIGHTHOUSE SURVIVE TWRAP ULV2 ULV5 VF VIVE WMR XREAL_AIR; do
  off+=("-DXRT_BUILD_DRIVER_$d=OFF")
done
for h in BLUETOOTH DBUS EGL GST HIDAPI JPEG LIBBSD LIBUDEV LIBUSB LIBUVC ONNXRUNTIME OPENCV OPENGL OPENGLES OPENGL_GLX \
         OPENVR PERCETTO REALSENSE SDL2 SYSTEMD SYSTEM_CJSON TRACY WAYLAND WAYLAND_DIRECT XCB XLIB XRANDR; do
  off+=("-DXRT_HAVE_$h=OFF")
done
for f in DEBUG_GUI RENDERDOC SERVICE SLAM STEAMVR_PLUGIN TRACING WINDOW_PEEK; do
  off+=("-DXRT_FEATURE_$f=OFF")
done
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # The scratch folder's name changes from run to run: paths relative to it
  # let a later build hit the cache.
  export CCACHE_BASEDIR=$work CCACHE_NOHASHDIR=1
fi
log=$work/build.log
if ! { cmake -S "$work/src" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$prefix" \
         -DCMAKE_PROJECT_XRT_INCLUDE="$work/stub_comp_main.cmake" "${launcher[@]}" -DGIT_DESC="$version" \
         -DBUILD_TESTING=OFF -DBUILD_DOC=OFF -DXRT_BUILD_SAMPLES=OFF \
         -DXRT_MODULE_IPC=OFF -DXRT_MODULE_COMPOSITOR_MAIN=OFF -DXRT_MODULE_COMPOSITOR_NULL=ON \
         -DXRT_MODULE_MONADO_CLI=OFF -DXRT_MODULE_MONADO_GUI=OFF -DXRT_MODULE_AUX_VIVE=OFF \
         -DXRT_BUILD_DRIVER_SIMULATED=ON "${off[@]}" &&
       cmake --build "$work/build" -j "${JOBS:-$(nproc)}" --target openxr_monado &&
       cmake --install "$work/build"; } >"$log" 2>&1; then
  tail -50 "$log" >&2
  echo "monado.sh: building Monado $version failed" >&2
  exit 1
fi
# A manifest at a fixed place, next to lib/ (a library_path with a slash is
# taken relative to the manifest's folder).
cat > "$manifest" <<JSON
{
    "file_format_version": "1.0.0",
    "runtime": {
        "name": "Monado",
        "library_path": "./lib/libopenxr_monado.so"
    }
}
JSON
touch "$prefix/.built-$version"
echo "Monado $version, headless: $manifest (built in $((SECONDS - start)) s)"
