#!/usr/bin/env bash
# Modes 4 and 5 against the simulator: a relative trajectory streamed, then exit from open; the
# robot program waits for the PC and ends the exchange.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
cat >"$TMP/traj.csv" <<CSV
# units: deg
t,j1,j2,j3,j4,j5,j6
0,0,0,0,0,0,0
0.4,4,-2,1,0,5,0
0.8,0,0,0,0,0,0
CSV
for mode in 4 5; do
  start_c4g_serve --app stream --file "$TMP/traj.csv" --mode $mode --relative
  run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: $mode, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
  [ "$SIM_RC" = 0 ] || fail "mode $mode: simulator exit code $SIM_RC"
  wait_serve
  [ "$SERVE_RC" = 0 ] || fail "mode $mode: serve exit code $SERVE_RC"
  grep -q "stream: trajectory started (mode $mode" "$TMP/serve.out" || fail "mode $mode: not started"
  grep -q "stream: done" "$TMP/serve.out" || fail "mode $mode: not done"
  grep -q "Safety: none" "$TMP/serve.out" || fail "mode $mode: a safety fault"
done
# A trajectory that does not start where the robot is: refused, nothing moves, exit code 1.
printf 't,a,b,c,d,e,f\n0,1,1,1,1,1,1\n1,1,1,1,1,1,1\n' >"$TMP/far.csv"
start_c4g_serve --app stream --file "$TMP/far.csv" --mode 4 --stop-timeout 2
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
wait_serve
[ "$SERVE_RC" = 1 ] || fail "far start point: serve exit code $SERVE_RC"
grep -q "start point: axis 1 is at" "$TMP/serve.out" || fail "no start-point message"
echo ok
