#!/usr/bin/env bash
# Runs COMMAND under a virtual X display of its own. Xvfb takes the display
# itself (it refuses a number whose lock another server holds, and then
# the next number is tried), so nothing is left between finding a free
# number and taking it, the race `xvfb-run -a` has. Numbers are drawn at
# random from 100-899 rather than the lowest free one: a test right after
# another got :0 again as the earlier server went, and pvpython met "bad X
# server connection" there in full clean-clone runs, three attempts in a
# row, never alone. The server is stopped when the command ends; its log
# goes to $XVFB_LOG when set (appended, one line per display tried).
#   with_xvfb.sh COMMAND [ARGS...]
set -euo pipefail
chosen=$(mktemp)
server=
trap 'if [[ -n "$server" ]]; then kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; fi; rm -f "$chosen"' EXIT
log=${XVFB_LOG:-/dev/null}
for _ in $(seq 20); do
  number=$((100 + RANDOM % 800))
  echo "with_xvfb.sh: trying :$number" >>"$log"
  : >"$chosen"
  Xvfb ":$number" -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$chosen" 2>>"$log" &
  server=$!
  # The server writes its display number once it accepts connections, or exits.
  for _ in $(seq 300); do
    [[ -s "$chosen" ]] && break
    kill -0 "$server" 2>/dev/null || break
    sleep 0.1
  done
  if [[ -s "$chosen" ]]; then
    DISPLAY=":$(head -1 "$chosen")" "$@"
    exit $?
  fi
  if kill -0 "$server" 2>/dev/null; then
    echo "with_xvfb.sh: Xvfb took no display within 30 s" >&2
    exit 1
  fi
  wait "$server" 2>/dev/null || true
  server=
done
echo "with_xvfb.sh: Xvfb took none of 20 displays tried (see \$XVFB_LOG)" >&2
exit 1
