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
# Segments by motion type: the program sets motion type 1 before opening (out by 4 deg on axis 1),
# switches to 2 inside the open mode (back, relative to where segment 1 ended), tries 7 (no
# segment: hold), then clears it (0): exit from open.
printf '# units: deg\nt,a,b,c,d,e,f\n0,0,0,0,0,0,0\n0.3,4,0,0,0,0,0\n' >"$TMP/seg1.csv"
printf '# units: deg\nt,a,b,c,d,e,f\n0,0,0,0,0,0,0\n0.3,-4,0,0,0,0,0\n' >"$TMP/seg2.csv"
start_c4g_serve --app stream --mode 4 --relative --segment "1=$TMP/seg1.csv" --segment "2=$TMP/seg2.csv"
run_sim_c4g "steps:
  - drive_on
  - cmd: {arm: 1, value: 1}
  - go_open: {type: A, mode: 4, arms: [1]}
  - delay: 0.5
  - cmd: {arm: 1, value: 2}
  - delay: 0.5
  - cmd: {arm: 1, value: 7}
  - delay: 0.2
  - cmd: {arm: 1, value: 0}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || { cat "$TMP/sim.err"; fail "segments: simulator exit code $SIM_RC"; }
wait_serve
[ "$SERVE_RC" = 0 ] || { cat "$TMP/serve.out"; fail "segments: serve exit code $SERVE_RC"; }
order=$(grep -oE 'segment for motion type [0-9]+ started|no segment for motion type [0-9]+|motion type 0: the segments are over|stream: done' "$TMP/serve.out" | tr '\n' '|')
expected='segment for motion type 1 started|segment for motion type 2 started|no segment for motion type 7|motion type 0: the segments are over|stream: done|'
[ "$order" = "$expected" ] || { cat "$TMP/serve.out"; fail "segments: sequence $order"; }
grep -q "Safety: none" "$TMP/serve.out" || fail "segments: a safety fault"
grep -q "open type A (mode 4) ended" "$TMP/sim.err" || { cat "$TMP/sim.err"; fail "segments: open phase not ended by the PC"; }
echo ok
