#!/usr/bin/env bash
# One exit-code scheme for every command (docs/getting-started.md): 0 done, 1 failed, 2 usage error
# (parse errors included), 3 internal error, 4 safety stop, 128+N stopped by signal N. Range errors
# are said in words, and a dump or a server ended by Ctrl-C ends normally.
source "$(dirname "$0")/lib.sh"

# expect CODE CMD...: runs CMD, fails unless it exits with CODE; stderr is kept in $TMP/last.err.
expect() {
  local want=$1; shift
  set +e; "$@" >"$TMP/last.out" 2>"$TMP/last.err"; local got=$?; set -e
  [ "$got" = "$want" ] || fail "'$*' exited $got, expected $want: $(cat "$TMP/last.err")"
}

expect 0 "$AXON" --help
expect 0 "$AXON" --version
expect 2 "$AXON" --no-such-option
expect 2 "$AXON" no-such-command
expect 2 "$AXON" can send --bus virtual:vcan0 --repeat -1 123#00
grep -q "must be > 0, got -1" "$TMP/last.err" || fail "range error not in words: $(cat "$TMP/last.err")"
if grep -Eq '[0-9]{30}|e\+308|e-308' "$TMP/last.err"; then fail "range error prints the limits of a double"; fi
expect 2 "$AXON" can send --bus virtual:vcan0 --interval nan 123#00
expect 2 "$AXON" can send --bus no-such-transport:x 123#00
expect 2 "$AXON" can replay --bus virtual:vcan0 "$TMP/no-such-file.log"

# A server ended by SIGTERM/SIGINT/SIGHUP ends normally (its documented way to stop).
for sig in TERM INT HUP; do
  start_bridge --listen 127.0.0.1:0
  kill -s "$sig" "$BRIDGE_PID"
  set +e; wait "$BRIDGE_PID"; rc=$?; set -e
  [ "$rc" = 0 ] || fail "bridge stopped by SIG$sig exited $rc"
done

# A dump runs until Ctrl-C: 0. A command interrupted before it finished its work: 128+N.
start_bridge --listen 127.0.0.1:0
bus="socketcand://127.0.0.1:$SCD_PORT/vcan0"
"$AXON" can dump --bus "$bus" >"$TMP/dump.out" 2>"$TMP/dump.err" &
d=$!; PIDS+=($d)
wait_for_line "$TMP/dump.err" 'receiving on' >/dev/null
kill -INT "$d"
set +e; wait "$d"; rc=$?; set -e
[ "$rc" = 0 ] || fail "dump stopped by SIGINT exited $rc"

"$AXON" can send --bus "$bus" --repeat 100000 --interval 10 123#00 >"$TMP/send.out" 2>"$TMP/send.err" &
s=$!; PIDS+=($s)
sleep 0.5
kill -TERM "$s"
set +e; wait "$s"; rc=$?; set -e
[ "$rc" = 143 ] || fail "send interrupted by SIGTERM exited $rc, expected 143"
echo "PASS"
