#!/usr/bin/env bash
# PC-side safety from the command line, server and simulator in separate processes: a mode 4
# trajectory that runs past the stroke end set with --stroke-end is refused with the manual's drive
# off request (505): the controller reports the PC's drive off, the server ends in a safety stop
# (exit code 4). The same trajectory inside wider stroke ends plays to the end.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
cat >"$TMP/traj.csv" <<CSV
# units: deg
t,j1,j2,j3,j4,j5,j6
0,0,0,0,0,0,0
0.5,8,0,0,0,0,0
1.0,0,0,0,0,0,0
CSV
program="steps:
  - drive_on
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
start_c4g_serve --app stream --file "$TMP/traj.csv" --mode 4 --relative --stroke-end 1=-5:5 --stop-timeout 2
run_sim_c4g "$program"
wait_serve
[ "$SERVE_RC" = 4 ] || { cat "$TMP/serve.out"; fail "beyond the stroke end: serve exit code $SERVE_RC"; }
grep -q "Safety: commanded position beyond a stroke end (axis 0)" "$TMP/serve.out" || { cat "$TMP/serve.out"; fail "no stroke-end fault"; }
grep -q "ERR_C4GOPEN_DRIVEOFF_SERVER" "$TMP/sim.err" || { cat "$TMP/sim.err"; fail "the controller saw no drive off from the PC"; }
start_c4g_serve --app stream --file "$TMP/traj.csv" --mode 4 --relative --stroke-end 1=-10:10
run_sim_c4g "$program"
[ "$SIM_RC" = 0 ] || fail "inside the stroke ends: simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || { cat "$TMP/serve.out"; fail "inside the stroke ends: serve exit code $SERVE_RC"; }
grep -q "Safety: none" "$TMP/serve.out" || fail "inside the stroke ends: a safety fault"
"$AXON" c4g serve --app monitor --stroke-end 1=5:-5 >"$TMP/bad.out" 2>&1 && fail "a bad stroke end was accepted"
grep -q "MIN must be below MAX" "$TMP/bad.out" || { cat "$TMP/bad.out"; fail "no reason for the bad stroke end"; }
echo ok
