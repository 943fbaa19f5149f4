#!/usr/bin/env bash
# Configures and builds sluice (Release) into build/ unless BUILD_DIR says otherwise.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
jobs=${JOBS:-$(nproc)}
# What is built and what is left out (and why) is said by the configure's
# "sluice:" lines, printed; the rest of its output is not.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" | { grep '^-- sluice:' || true; }
# CONFIGURE_ONLY=1: the caller builds the targets it needs.
[[ "${CONFIGURE_ONLY:-0}" == 1 ]] || cmake --build "$build" -j "$jobs"
