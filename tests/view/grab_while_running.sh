#!/bin/sh
# grab_while_running.sh X11_GRAB OUT.png MIN_PIXELS SECONDS -- COMMAND [ARGS...]
# Starts COMMAND (a program with a live 3D window) in the background and grabs
# the X screen once a second with x11_grab until it shows MIN_PIXELS of the
# trajectory (exit 0) or SECONDS have passed (exit 1); stops COMMAND either way.
grab=$1 out=$2 min=$3 seconds=$4
shift 5
"$@" &
pid=$!
rc=1
i=0
while [ "$i" -lt "$seconds" ]; do
  sleep 1
  if "$grab" "$out" "$min"; then rc=0; break; fi
  i=$((i + 1))
done
kill "$pid" 2>/dev/null
wait
exit "$rc"
