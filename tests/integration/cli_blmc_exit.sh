#!/usr/bin/env bash
# Every way out of an `axon blmc` command that enabled the board leaves it disabled at zero current,
# with a non-zero exit code: a failed enable, an enable interrupted during the alignment, a closed
# stdout (`| head -1`), SIGINT/SIGTERM/SIGHUP during control, and a second SIGINT that stops the
# event loop at once. After each, the board (`axon sim blmc` in another process) reports the system
# and both motors off with no error latched (a clean disable, not its receive timeout tripping),
# and the last frames the host sent were IqRef = 0 then the disables. Bad option values (`--rate 0`
# among them, which used to leave the board enabled) are usage errors said in words, before
# anything is sent.
source "$(dirname "$0")/lib.sh"
# The control cases run with a stale limit of 0.5 s: a loaded machine must not end them in a safety
# stop before the exit path under test.
# Alignment takes 6 s on this board: long enough to interrupt an enable in the middle of it.
printf 'alignment_s: 6\n' >"$TMP/board.yaml"
"$AXON" sim blmc --socketcand 127.0.0.1:0 --config "$TMP/board.yaml" >"$TMP/sim.out" 2>"$TMP/sim.err" &
SIM=$!
PIDS+=($SIM)
PORT=$(wait_for_line "$TMP/sim.out" '^listening socketcand ' | sed 's/.*://')
BUS="socketcand://127.0.0.1:$PORT/can0"
BLMC=("$AXON" blmc --bus "$BUS" --no-realtime)
blmc() { "${BLMC[@]}" "$@"; }

# Every command frame (000) and current reference (005) on the bus, from every host connection.
"$AXON" can dump --bus "$BUS" --filter 000:7FF --filter 005:7FF >"$TMP/bus.out" 2>"$TMP/bus.err" &
PIDS+=($!)
wait_for_line "$TMP/bus.err" 'receiving on' >/dev/null

# start_case NAME ARGS...: runs `axon blmc ... ARGS` in the background as $CASE_PID (the process
# itself, not a subshell: signals go to it); bus lines before it: $MARK. The caller acts on it and
# calls end_case.
start_case() {
  CASE=$1
  shift
  MARK=$(wc -l <"$TMP/bus.out")
  "${BLMC[@]}" "$@" >"$TMP/$CASE.out" 2>"$TMP/$CASE.err" &
  CASE_PID=$!
  PIDS+=($CASE_PID)
}
# end_case WANT_RC: waits for the command, checks its exit code, then the board's state.
end_case() {
  local want=$1 rc=0
  wait "$CASE_PID" || rc=$?
  [ "$rc" = "$want" ] || fail "$CASE exited $rc, expected $want"
  board_is_off
}
# board_is_off: the board's status says system and motors off, no error; the host's last frames
# were IqRef = 0, ENABLE_MTR1=0, ENABLE_MTR2=0, ENABLE_SYS=0.
board_is_off() {
  blmc status >"$TMP/status.txt" 2>"$TMP/status.err" || fail "$CASE: status failed"
  grep -Eq '^sys-off MTR1\((-|ready)\) MTR2\((-|ready)\) error=NONE ' "$TMP/status.txt" \
    || fail "$CASE: board not off: $(cat "$TMP/status.txt")"
  sleep 0.2  # the dump prints what it received
  local tail4
  tail4=$(awk '{print $3}' "$TMP/bus.out" | tail -4 | xargs)
  [ "$tail4" = "005#0000000000000000 000#0000000000000002 000#0000000000000003 000#0000000000000001" ] \
    || fail "$CASE: last frames on the bus: $tail4"
}
# wait_bus REGEX: until a frame matching REGEX went over the bus since the case started.
wait_bus() {
  local i=0
  while [ $i -lt 400 ]; do
    tail -n +"$((MARK + 1))" "$TMP/bus.out" | grep -Eq "$1" && return 0
    sleep 0.05
    i=$((i + 1))
  done
  fail "$CASE: no /$1/ on the bus"
}
# wait_rows FILE: until the command prints a table row with the motors on (control is running).
wait_rows() { wait_for_line "$1" '\| SYS MTR1\(enabled,ready\)' 30 >/dev/null; }

# ---- a failed start: the motors do not align within --ready-timeout: exit 1, board off.
start_case failed_enable --ready-timeout 1.5 current 1 0.3 --duration 5
end_case 1
grep -q 'not ready' "$TMP/failed_enable.err" || fail "no reason given: $(cat "$TMP/failed_enable.err")"

# ---- a signal during the alignment ends the enable at once (the alignment would take 6 s).
start_case enable_interrupted --stale-ms 500 current 1 0.3 --duration 5
wait_bus '000#0000000100000003$'  # ENABLE_MTR2=1 went out: the alignment runs
kill -INT "$CASE_PID"
end_case 130
ms=$(tail -n +"$((MARK + 1))" "$TMP/bus.out" | awk -F'[()]' 'NR == 1 {a = $2} {b = $2} END {printf "%d", (b - a) * 1000}')
[ "$ms" -lt 4000 ] || fail "the interrupted enable took $ms ms: it waited for the alignment (6 s)"

# Align once, so that the following cases reach the control loop at once.
blmc enable >/dev/null 2>"$TMP/enable.err" || fail "enable failed: $(cat "$TMP/enable.err")"

# ---- stdout closed under a running loop: the command stops (well before its 60 s), exits 1.
CASE=broken_pipe
MARK=$(wc -l <"$TMP/bus.out")
set +e
timeout 30 "$AXON" blmc --bus "$BUS" --no-realtime --stale-ms 500 current 1 0.3 --duration 60 2>"$TMP/pipe.err" | head -1 >/dev/null
rc=${PIPESTATUS[0]}
set -e
[ "$rc" = 1 ] || fail "broken pipe: exited $rc, expected 1: $(cat "$TMP/pipe.err")"
grep -q 'cannot write to stdout' "$TMP/pipe.err" || fail "broken pipe not reported: $(cat "$TMP/pipe.err")"
board_is_off

# ---- SIGINT, SIGTERM, SIGHUP during control: 128+N after the disable.
for sig in INT TERM HUP; do
  start_case "sig$sig" --stale-ms 500 current 1 0.3 --duration 60
  wait_rows "$TMP/sig$sig.out"
  kill -s "$sig" "$CASE_PID"
  case $sig in INT) want=130 ;; TERM) want=143 ;; HUP) want=129 ;; esac
  end_case $want
  grep -q 'board disabled, currents zero' "$TMP/sig$sig.err" || fail "SIG$sig: no disable reported"
done

# ---- a second SIGINT stops the event loop at once (rows every 2 s: it comes before the first
# signal is acted on). At zero current the board's receive timeout never arms: only the host's
# disable, over a new connection, turns it off.
start_case double_sigint --stale-ms 500 --refresh 0.5 current 1 0 --duration 60
wait_rows "$TMP/double_sigint.out"
kill -INT "$CASE_PID"
sleep 0.3
kill -INT "$CASE_PID"
end_case 130
grep -q 'disabling the board over a new connection' "$TMP/double_sigint.err" \
  || fail "double SIGINT: $(cat "$TMP/double_sigint.err")"

# ---- monitor runs until Ctrl-C: that is its normal end (exit 0); it never enabled anything.
start_case monitor monitor
wait_for_line "$TMP/monitor.out" '^ +[0-9.]+ \|' >/dev/null
kill -INT "$CASE_PID"
end_case 0

# ---- bad values are usage errors in words (exit 2), and nothing reaches the board.
expect_usage() {
  local want=$1
  shift
  local before rc=0
  before=$(wc -l <"$TMP/bus.out")
  blmc "$@" >"$TMP/usage.out" 2>"$TMP/usage.err" || rc=$?
  [ "$rc" = 2 ] || fail "'$*' exited $rc, expected 2: $(cat "$TMP/usage.err")"
  grep -qF -- "$want" "$TMP/usage.err" || fail "'$*': no '$want' in: $(cat "$TMP/usage.err")"
  sleep 0.2
  [ "$(wc -l <"$TMP/bus.out")" = "$before" ] || fail "'$*' sent frames"
}
CASE=rate0
expect_usage 'must be > 0, got 0' --rate 0 current 1 0.3
board_is_off  # (it used to start cyclic mode, fail on the period and leave the board enabled)
expect_usage 'must be > 0, got -5' --rate -5 pd
expect_usage "the board's receive timeout" --rate 10 pd
expect_usage 'must be > 0, got -1' --max-current -1 current 1 0.3
expect_usage 'must be > 0, got 0' --stale-ms 0 pd
expect_usage 'must be > 0, got -2' --ready-timeout -2 enable
expect_usage 'must be > 0, got 0' current 1 0.3 --duration 0
expect_usage 'must be >= 0, got -1' pd --kp -1
expect_usage 'must be >= 0, got -0.1' pd --kd -0.1
expect_usage 'must be > 0, got -1' home --timeout -1
expect_usage 'must be > 0, got 0' home --current 0
expect_usage 'must not be 0' home --speed 0
expect_usage 'must be >= 0, got -3' status --duration -3
board_is_off

# The simulator's own account at its end: no error latched, no current reference left.
kill -TERM "$SIM"
wait "$SIM" || true
grep -Eq 'can0: status sys-off MTR1\(ready\) MTR2\(ready\) error=NONE; IqRef 0 0 A' "$TMP/sim.err" \
  || fail "simulator end: $(grep 'can0: status' "$TMP/sim.err")"
echo "PASS"
