#!/usr/bin/env bash
# Runs COMMAND under a virtual X display whose number the server picks
# itself (Xvfb -displayfd): nothing is left between finding a free number
# and taking it, the race `xvfb-run -a` has (seen as pvpython's "bad X
# server connection"). The server is stopped when the command ends; its log
# goes to $XVFB_LOG when set.
#   with_xvfb.sh COMMAND [ARGS...]
set -euo pipefail
chosen=$(mktemp)
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$chosen" 2>"${XVFB_LOG:-/dev/null}" &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -f "$chosen"' EXIT
# The server writes its display number once it accepts connections.
for _ in $(seq 300); do
  [[ -s "$chosen" ]] && break
  kill -0 "$server" 2>/dev/null || { echo "with_xvfb.sh: Xvfb exited before taking a display" >&2; exit 1; }
  sleep 0.1
done
[[ -s "$chosen" ]] || { echo "with_xvfb.sh: Xvfb took no display within 30 s" >&2; exit 1; }
DISPLAY=":$(head -1 "$chosen")" "$@"
