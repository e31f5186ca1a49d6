#!/usr/bin/env bash
# Mode 7 fed over real UDP with values beyond the correction limits: 90 deg, 9999 deg and 1e308 deg
# between good 0.3 deg readings. `axon c4g serve --app correct --feed` in one process, the
# simulated controller in another, the sensor in a third. The bad readings must be refused and
# counted, never applied (the motors never see more than the good 0.3 deg), and the correction ends
# cleanly; a sine or a file beyond the limit is refused before anything is served.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app correct --feed 127.0.0.1:0 --units deg --open-time 2 --ramp 0.2
FEED_PORT=$(wait_for_line "$TMP/serve.out" '^correct: feed listening on ' | sed -E 's/.*:([0-9]+) .*/\1/')
[ -n "$FEED_PORT" ] || fail "no feed port"
(
  wait_for_line "$TMP/serve.out" 'correct: correction started' >/dev/null
  for bad in '90 0 0 0 0 0' '0 9999 0 0 0 0' '0 0 1e308 0 0 0'; do
    for i in $(seq 1 10); do printf '0.3 0 0 0 0 0\n' >/dev/udp/127.0.0.1/"$FEED_PORT"; sleep 0.02; done
    printf '%s\n' "$bad" >/dev/udp/127.0.0.1/"$FEED_PORT"
    sleep 0.1
  done
  for i in $(seq 1 20); do printf '0.3 0 0 0 0 0\n' >/dev/udp/127.0.0.1/"$FEED_PORT"; sleep 0.02; done
) &
SENDER=$!
PIDS+=($SENDER)
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 7, arms: [1]}
  - move: {arm: 1, deg: [2, 0, 0, 0, 0, 0], duration: 0.5}
  - wait_for_pc: {timeout: 15}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
wait "$SENDER" 2>/dev/null || true
grep -q "correct: done" "$TMP/serve.out" || fail "not done"
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault"
grep -Eq "3 readings refused beyond the limits" "$TMP/serve.out" || fail "refusals not counted: $(grep 'feed on port' "$TMP/serve.out")"
grep -q "feed reading refused: a value is beyond the correction limit" "$TMP/serve.out" || fail "no refusal event"
grep -q "last refused reading: axis 3 = 1e+308 deg, beyond the correction limit 5 deg" "$TMP/serve.out" || fail "last refusal not named"
# Motor-side corrections in the status lines: 0.3 deg on axis 1 is about 0.15 turns; 90 deg would
# be 45 turns.
awk '/correction\[turns\]/ { split($0, a, "correction\\[turns\\]"); split(a[2], v, " ");
       for (i = 1; i <= 6; i++) if (v[i] + 0 > 0.2 || v[i] + 0 < -0.2) { print "too large: " $0; exit 1 } }' \
  "$TMP/serve.out" || fail "a refused value was applied"
grep -Eq "correcting .*correction\[turns\] -?0\.1[0-9]*" "$TMP/serve.out" || fail "the good correction was not applied"

# Sources that exceed the limit are refused before serving (a usage error, not a run).
RC=0
"$AXON" c4g serve --listen 127.0.0.1:0 --app correct --amplitude 0,90 >"$TMP/sine.out" 2>"$TMP/sine.err" || RC=$?
[ "$RC" != 0 ] || fail "a 90 deg sine was accepted"
grep -q "sine amplitude 90 deg on axis 2 exceeds the correction limit 5 deg" "$TMP/sine.err" || fail "sine: $(cat "$TMP/sine.err")"
grep -q "^listening c4g" "$TMP/sine.out" && fail "served with a 90 deg sine"
printf 't,a,b,c,d,e,f\n0,0,0,0,0,0,0\n1,0,0,9999,0,0,0\n' >"$TMP/big.csv"
RC=0
"$AXON" c4g serve --listen 127.0.0.1:0 --app correct --units deg --file "$TMP/big.csv" >"$TMP/file.out" 2>"$TMP/file.err" || RC=$?
[ "$RC" != 0 ] || fail "a 9999 deg file was accepted"
grep -q "asks 9999 deg on axis 3, beyond the correction limit 5 deg" "$TMP/file.err" || fail "file: $(cat "$TMP/file.err")"
# The limit is one option away.
RC=0
"$AXON" c4g serve --listen 127.0.0.1:0 --app correct --amplitude 0,9 --max-correction 10 --duration 0.2 \
  >"$TMP/wide.out" 2>"$TMP/wide.err" || RC=$?
[ "$RC" = 0 ] || fail "--max-correction 10 refused a 9 deg sine: $(cat "$TMP/wide.err")"
echo ok
