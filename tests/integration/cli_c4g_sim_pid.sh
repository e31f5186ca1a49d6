#!/usr/bin/env bash
# Modes 1 and 2 against the simulator: the PC closes the loops (currents) without a following-error
# fault; mode 1 is left by the PC after --open-time, mode 2 by the robot program.
source "$(dirname "$0")/lib.sh"
skip_without_sim_c4g
start_c4g_serve --app pid --open-time 0.6 --amplitude 0.5 --frequency 1
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: A, mode: 1, arms: [1]}
  - wait_for_pc: {timeout: 10}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "mode 1: simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "mode 1: serve exit code $SERVE_RC"
grep -q "pid: done" "$TMP/serve.out" || fail "mode 1: not done"
grep -q "Safety: none" "$TMP/serve.out" || fail "mode 1: a safety fault"

start_c4g_serve --app pid
run_sim_c4g "steps:
  - drive_on
  - go_open: {type: B, mode: 2, arms: [1]}
  - move: {arm: 1, deg: [3, 0, 0, 0, 0, 0], duration: 0.5}
  - go_open: {type: A, mode: 12, arms: [1]}
  - exit_open"
[ "$SIM_RC" = 0 ] || fail "mode 2: simulator exit code $SIM_RC"
wait_serve
[ "$SERVE_RC" = 0 ] || fail "mode 2: serve exit code $SERVE_RC"
grep -q "pid: closing the loops" "$TMP/serve.out" || fail "mode 2: loops not closed"
grep -q "Safety: none" "$TMP/serve.out" || fail "mode 2: a safety fault"
echo ok
