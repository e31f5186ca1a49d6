#!/usr/bin/env bash
# Stopping the robots when the host stops caring, over real processes: `axon sim fps` (six robots,
# two gateways, real time) in one process, `axon fps plane ... move --duration 20` in another.
#   1. SIGINT, SIGTERM and SIGHUP in the middle of the move: every robot is stopped, the host says
#      what it stopped and names the signal, and exits 128+N;
#   2. another client takes gateway 2 over in the middle of a move: the host says so, stops every
#      robot (those behind gateway 2 through one reconnection) and exits 4 (safety stop);
#   3. a duration the robots cannot make is refused before anything moves, with the duration that
#      would do, in a few lines; --fit-duration uses it;
#   4. --json: status and move print one JSON document on stdout and nothing else.
source "$(dirname "$0")/lib.sh"

"$AXON" sim fps --layout "$SMALL_PLANE" --folded --time-scale 1 --write-layout "$TMP/p.yaml" >"$TMP/sim.out" 2>"$TMP/sim.err" &
PIDS+=($!)
wait_for_line "$TMP/sim.out" '^ready$' >/dev/null
GW1=$(grep '^listening gateway 1 ' "$TMP/sim.out" | awk '{print $4}')
GW2=$(grep '^listening gateway 2 ' "$TMP/sim.out" | awk '{print $4}')

# positions: "ID ALPHA BETA" per robot, read through both gateways.
positions() {
  "$AXON" fps --bus "cannet://$GW1/1" --bus "cannet://$GW1/2" --bus "cannet://$GW2/1" --bus "cannet://$GW2/2" \
    position 2>>"$TMP/pos.err" | awk '{print $1, $3, $5}'
}

# move_and_signal SIGNAL ALPHA: a 20 s move to ALPHA, the signal 1.5 s after the robots started.
move_and_signal() {
  local sig=$1 alpha=$2
  rm -f "$TMP/move.out" "$TMP/move.err"
  "$AXON" fps plane --layout "$TMP/p.yaml" move --alpha "$alpha" --beta 150 --duration 20 \
    >"$TMP/move.out" 2>"$TMP/move.err" &
  local pid=$!
  wait_for_line "$TMP/move.err" '^moving 6 robots: ' >/dev/null
  sleep 1.5
  kill -s "$sig" "$pid"
  MOVE_RC=0
  wait "$pid" || MOVE_RC=$?
}

# assert_stopped: every robot answers and none moves any more (two readings 0.6 s apart agree).
assert_stopped() {
  local what=$1
  positions >"$TMP/p1.txt"
  sleep 0.6
  positions >"$TMP/p2.txt"
  [ "$(wc -l <"$TMP/p1.txt")" = 6 ] || fail "$what: expected 6 robots' positions, got: $(cat "$TMP/p1.txt")"
  cmp -s "$TMP/p1.txt" "$TMP/p2.txt" || fail "$what: robots still moving: $(paste "$TMP/p1.txt" "$TMP/p2.txt")"
}

# 1. Signals.
alpha=40
for sig in INT TERM HUP; do
  case $sig in INT) code=130 name='SIGINT (Ctrl-C)';; TERM) code=143 name='SIGTERM';; HUP) code=129 name='SIGHUP';; esac
  move_and_signal "$sig" "$alpha"
  [ "$MOVE_RC" = "$code" ] || fail "SIG$sig: exit code $MOVE_RC, expected $code"
  grep -qF "axon: $name received: stopped 6 robots (6 of them moving under this host) with TRAJECTORY_ABORT on 4 of 4 buses" \
    "$TMP/move.err" || fail "SIG$sig: no stop report naming the signal"
  grep -qxF "stopped: $name received" "$TMP/move.out" || fail "SIG$sig: the outcome does not name the signal"
  grep -qx '6 stopped' "$TMP/move.out" || fail "SIG$sig: not every robot is reported stopped"
  grep -qi 'collision' "$TMP/move.out" "$TMP/move.err" && fail "SIG$sig: the stop is called a collision"
  assert_stopped "SIG$sig"
  # Stopped on the way, not at the end of the move.
  awk -v a="$alpha" '$2 > a - 1 { exit 1 }' "$TMP/p1.txt" || fail "SIG$sig: a robot reached the end: $(cat "$TMP/p1.txt")"
  alpha=$((alpha + 40))
done

# 2. Another client takes gateway 2 over in the middle of a move.
rm -f "$TMP/move.out" "$TMP/move.err"
"$AXON" fps plane --layout "$TMP/p.yaml" move --alpha 10 --beta 170 --duration 20 >"$TMP/move.out" 2>"$TMP/move.err" &
pid=$!
wait_for_line "$TMP/move.err" '^moving 6 robots: ' >/dev/null
sleep 1
"$AXON" fps --bus "cannet://$GW2/1" status >"$TMP/other.out" 2>"$TMP/other.err" || true
rc=0
wait "$pid" || rc=$?
[ $rc = 4 ] || fail "take-over: exit code $rc, expected 4 (safety stop)"
grep -q 'another client has probably taken the gateway over' "$TMP/move.out" || fail "take-over: not said"
grep -q '^gateway 2: reconnected and sent TRAJECTORY_ABORT on channel(s) 1, 2: 3 of 3 robots acknowledged' \
  "$TMP/move.out" || fail "take-over: the robots behind gateway 2 were not stopped through a reconnection"
assert_stopped "take-over"

# 3. A duration the robots cannot make (about 290 deg at 30 deg/s needs about 10 s).
set +e
"$AXON" fps plane --layout "$TMP/p.yaml" move --alpha 300 --beta 180 --duration 2 >"$TMP/fast.out" 2>"$TMP/fast.err"
rc=$?
set -e
[ $rc = 2 ] || fail "an impossible duration: exit code $rc, expected 2"
grep -Eq '6 of 6 robots cannot make 2 s at 30 deg/s .*: the slowest robot \(positioner [0-9]+\) needs ([0-9.]+) s; use --duration \1 or --fit-duration' \
  "$TMP/fast.err" || fail "the needed duration is not said"
[ "$(cat "$TMP/fast.out" "$TMP/fast.err" | wc -c)" -lt 1000 ] || fail "too much output for one refusal"
assert_stopped "impossible duration"
# ... and --fit-duration uses it (a short move: about 60 deg, 2 s).
"$AXON" fps plane --layout "$TMP/p.yaml" move --alpha 60 --beta 170 --duration 0.5 --fit-duration \
  >"$TMP/fit.out" 2>"$TMP/fit.err" || fail "--fit-duration: exit code $?"
grep -q 'using --duration ' "$TMP/fit.err" || fail "--fit-duration: the duration used is not said"
grep -q '^completed: 6 robots at their targets' "$TMP/fit.out" || fail "--fit-duration: the move did not complete"

# 4. JSON.
"$AXON" fps plane --layout "$TMP/p.yaml" --json status >"$TMP/st.json" 2>"$TMP/st.err" || fail "status --json: exit code $?"
"$AXON" fps plane --layout "$TMP/p.yaml" move --alpha 50 --beta 170 --duration 0.5 --fit-duration --json \
  >"$TMP/mv.json" 2>"$TMP/mv.err" || fail "move --json: exit code $?"
/usr/bin/python3 - "$TMP/st.json" "$TMP/mv.json" <<'PY' || fail "--json output is not one JSON document as expected"
import json, sys
st = json.load(open(sys.argv[1]))
assert st["robots"] == 6 and st["states"] == {"ready": 6} and st["silent"] == [], st
mv = json.load(open(sys.argv[2]))
assert mv["completed"] and len(mv["robots"]) == 6, mv
assert all(r["state"] == "completed" and abs(r["reached"]["alpha"] - 50) < 0.2 for r in mv["robots"]), mv["robots"]
PY
echo PASS
