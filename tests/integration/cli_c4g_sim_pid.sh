#!/usr/bin/env bash
# Modes 1 and 2 against the simulator: the PC closes the loops (currents) without a following-error
# fault; mode 1 is left by the PC after --open-time, mode 2 by the robot program. Soft control
# switching: the robot stays still through T1..T3 in and out (no SCS_ROBOT_MOVED), with the default
# intervals, with longer ones given to both sides, and with the reducer in the PC; a move that does
# not wait T1 + T2 + T3 after the switch is caught by the simulator.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app pid --open-time 0.6 --amplitude 0.5 --frequency 1
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: 1, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "mode 1: simulator exit code $SIM_RC"
grep -q "SCS_ROBOT_MOVED" "$TMP/sim.err" && fail "mode 1: the robot moved while switching"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "mode 1: serve exit code $SERVE_RC"
grep -q "pid: done" "$TMP/serve.out" || fail "mode 1: not done"
grep -q "Safety: none" "$TMP/serve.out" || fail "mode 1: a safety fault"

start_c4g_serve --app pid
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 2, arms: [1]}
  - delay: 0.2
  - move: {arm: 1, deg: [3, 0, 0, 0, 0, 0], duration: 0.5}
  - delay: 0.1
  - go_open: {type: A, mode: 12, arms: [1]}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "mode 2: simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "mode 2: serve exit code $SERVE_RC"
grep -q "pid: closing the loops" "$TMP/serve.out" || fail "mode 2: loops not closed"
grep -q "Safety: none" "$TMP/serve.out" || fail "mode 2: a safety fault"
grep -q "SCS_ROBOT_MOVED" "$TMP/sim.err" && fail "mode 2: the robot moved while switching"

# Longer intervals on both sides (T1 + T2 + T3 = 0.5 s) and the reducer in the PC.
start_c4g_serve --app pid --open-time 0.3 --switch-t1-ms 100 --switch-t2-ms 300 --switch-t3-ms 100 --reduce-in-pc
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: 1, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open" --switch-t1-ms 100 --switch-t2-ms 300 --switch-t3-ms 100 --switch-reducer pc
[ "$SIM_RC" = 0 ] || fail "mode 1, long switch: simulator exit code $SIM_RC"
grep -q "SCS_ROBOT_MOVED" "$TMP/sim.err" && fail "mode 1, long switch: the robot moved while switching"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "mode 1, long switch: serve exit code $SERVE_RC"
grep -q "pid: done" "$TMP/serve.out" || fail "mode 1, long switch: not done"
grep -q "pid: soft switching: max following error 0.000" "$TMP/serve.out" || fail "mode 1, long switch: moved"

# A move right after GO OPEN (no DELAY of T1 + T2 + T3): the simulator stops the robot.
start_c4g_serve --app pid
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 2, arms: [1]}
  - move: {arm: 1, deg: [5, 0, 0, 0, 0, 0], duration: 0.3}
  - exit_open"
[ "$SIM_RC" = 1 ] || fail "move during the switch: simulator exit code $SIM_RC (expected 1: scenario error)"
grep -q "SCS_ROBOT_MOVED" "$TMP/sim.err" || fail "move during the switch: no SCS_ROBOT_MOVED"
kill "$SERVE_PID" 2>/dev/null; wait "$SERVE_PID" 2>/dev/null || true
echo ok
