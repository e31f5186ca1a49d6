#!/usr/bin/env bash
# Mode 7 with a live sensor feed: a separate sender streams correction values over UDP to
# `axon c4g serve --app correct --feed`, the simulated controller runs in its own process. The
# correction must reach the robot (status lines show it), a malformed datagram is counted and
# rejected, and the correction fades out and the arm leaves the open mode cleanly.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app correct --feed 127.0.0.1:0 --units deg --open-time 1.5 --ramp 0.2
FEED_PORT=$(wait_for_line "$TMP/serve.out" '^correct: feed listening on ' | sed -E 's/.*:([0-9]+) .*/\1/')
[ -n "$FEED_PORT" ] || fail "no feed port"
(
  printf 'not numbers\n' >/dev/udp/127.0.0.1/"$FEED_PORT"
  for i in $(seq 1 150); do
    printf '0.3 0 0 0 0 0\n' >/dev/udp/127.0.0.1/"$FEED_PORT"
    sleep 0.01
  done
) &
SENDER=$!
PIDS+=($SENDER)
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 7, arms: [1]}
  - move: {arm: 1, deg: [2, 0, 0, 0, 0, 0], duration: 0.5}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "serve exit code $SERVE_RC"
wait "$SENDER" 2>/dev/null || true
grep -q "correct: correction started" "$TMP/serve.out" || fail "not started"
grep -q "correct: done" "$TMP/serve.out" || fail "not done"
grep -q "Safety: none" "$TMP/serve.out" || fail "a safety fault"
grep -Eq "correcting .*correction\[turns\] -?0\.[0-9]*[1-9]" "$TMP/serve.out" || grep -Eq "correcting .*correction\[turns\] -?[1-9]" "$TMP/serve.out" \
  || fail "no correction applied in the status lines: $(grep correcting "$TMP/serve.out" | head -3)"
grep -Eq "feed on port [0-9]+: [1-9][0-9]* datagrams accepted, 1 rejected" "$TMP/serve.out" \
  || fail "feed counts: $(grep 'feed on port' "$TMP/serve.out")"
grep -q "last rejected datagram .*not a number" "$TMP/serve.out" || fail "reject reason missing"
echo ok
